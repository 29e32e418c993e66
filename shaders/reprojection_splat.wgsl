// Klein et al. 2005 §4.3–4.4: last frame's leap hits reprojected with this frame's camera as
// k×k-pixel splats, depth-tested so the splat nearest the eye wins. Each covered pixel gets its
// splat's texture-space position as this pixel's ray start (w = 1); pixels no splat covers keep
// (0,0,0,0) for hole_fill. Only the pixels of last frame's screen rectangle of the volume are
// drawn (the rectangle comes from the node, in `splat`). With `block` b > 1 one splat carries
// the nearest of a b×b block of hits over the block's projected bounding box grown by k/2: b²
// times fewer splats, each start at most as far as the hit it stands for.
//
// Two ways to draw the same splats (`method`):
// - quads (the paper's points; WebGPU has no point size): instanced quads pulling their point
//   from the `hits` texture, the depth buffer `depth` a Depth32Float target;
// - scatter (SCATTER): after a round that clears every pixel, one compute invocation per block
//   writes the splat's pixels itself, in two rounds over the same pixels — the nearest depth per
//   pixel by atomicMax into the `depth` buffer (~bits of a depth in [0, 1]: the nearer, the
//   larger; 0 = no splat), then the point of the splat whose depth won — with none of the rasterizer's per-quad setup, which is most of a
//   quad's cost where the graphics pipeline is slow (lavapipe, and the few SMs that run it on
//   an H100/H200). Pixel centres inside the quad are covered, as the rasterizer covers them.

#import "common/frame.wgsl"
#import "common/reprojected_hit.wgsl"

// Declared once in Rust (`SplatParams` in crates/passes/src/reprojection_splat.rs).
#import "params/SplatParams.wgsl"

// Hits per splat side (b), a pipeline constant: the b² loop below bounded by a uniform made
// lavapipe (Mesa 22.3) inline the uniform and recompile both scatter rounds at every dispatch
// — 2 LLVM compiles per frame; leap_iso on hydrogen took 142 ms a frame in one run against 39
// with the constant (bench/one-march-final.md, "Shaders recompiled at every bind").
override SPLAT_BLOCK: u32 = 1u;

// Last frame's leap hits: xyz texture space, w = 1 (surface) or 0.5 (exit point); w = 0 where
// there was no ray.
@group(0) @binding(auto) var hits: texture_2d<f32>;
@group(0) @binding(auto) var<uniform> splat: SplatParams;

// One block's splat: the nearest hit (xyz, w = 1; w = 0 when the block has none) at NDC depth
// `z`, and the NDC rectangle its quad covers (the hits' bounding box grown by k/2 pixels).
struct BlockSplat {
    point: vec4<f32>,
    z: f32,
    lo: vec2<f32>,
    hi: vec2<f32>,
}

// Blocks per row of last frame's rectangle.
fn blocks_x() -> u32 {
    let b = max(SPLAT_BLOCK, 1u);
    return max((splat.rect.z + b - 1u) / b, 1u);
}

// The splat of block `index` (row by row over last frame's rectangle).
fn block_splat(index: u32) -> BlockSplat {
    var out = BlockSplat(vec4<f32>(0.0), 2.0, vec2<f32>(3.0e38), vec2<f32>(-3.0e38));
    let b = max(SPLAT_BLOCK, 1u);
    let base = splat.rect.xy + vec2<u32>(index % blocks_x(), index / blocks_x()) * b;
    let end = splat.rect.xy + splat.rect.zw;
    for (var i = 0u; i < b * b; i += 1u) {
        let pixel = base + vec2<u32>(i % b, i / b);
        if (any(pixel >= end)) {
            continue;
        }
        let hit = reprojected_hit(pixel);
        if (!hit.valid) {
            continue;
        }
        out.lo = min(out.lo, hit.ndc.xy);
        out.hi = max(out.hi, hit.ndc.xy);
        if (hit.ndc.z < out.z) {
            out.z = hit.ndc.z;
            out.point = vec4<f32>(hit.texture, 1.0);
        }
    }
    // Half the splat edge in NDC units (y up).
    let half = splat.size * vec2<f32>(frame.viewport.z, frame.viewport.w);
    out.lo -= half;
    out.hi += half;
    return out;
}

struct SplatVertex {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) point: vec4<f32>,
}

// Corner `i` (0..4) of a quad drawn as a triangle strip: -1 or +1 per axis. Four vertex
// invocations per splat instead of six (vertex work is what a splat costs).
fn quad_corner(i: u32) -> vec2<f32> {
    return vec2<f32>(f32(i & 1u) * 2.0 - 1.0, f32(i >> 1u) * 2.0 - 1.0);
}

@vertex
fn vs_splat(@builtin(vertex_index) vertex_index: u32, @builtin(instance_index) instance: u32) -> SplatVertex {
    var out: SplatVertex;
    // Outside every clip volume: the rasterizer drops the quad.
    out.clip = vec4<f32>(2.0, 2.0, 2.0, 1.0);
    out.point = vec4<f32>(0.0);
    let s = block_splat(instance);
    if (s.point.w == 0.0) {
        return out;
    }
    let corner = quad_corner(vertex_index);
    out.clip = vec4<f32>(select(s.lo, s.hi, corner > vec2<f32>(0.0)), s.z, 1.0);
    out.point = s.point;
    return out;
}

struct SplatOut {
    @location(0) start: vec4<f32>,
}

@fragment
fn fs_splat(in: SplatVertex) -> SplatOut {
    return SplatOut(in.point);
}

#if SCATTER
// Per pixel, row by row: ~bits of the nearest splat's depth (0: none), zeroed by
// `cs_splat_clear`.
@group(0) @binding(auto) var<storage, read_write> depth: array<atomic<u32>>;
@group(0) @binding(auto) var start: texture_storage_2d<rgba32float, write>;

// Round 0, one invocation per pixel of the viewport: no splat yet (depth 0, start zero). A
// shader writes the 16-byte texels as fast as any other store, where lavapipe clears a
// 128-bit target outside a draw one texel at a time (`memcpy` per texel: 5 % of a `leap_iso`
// frame; bench/one-march-final.md, "Clears").
@compute @workgroup_size(8, 8)
fn cs_splat_clear(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    if (any(id.xy >= size)) {
        return;
    }
    atomicStore(&depth[id.y * size.x + id.x], 0u);
    textureStore(start, id.xy, vec4<f32>(0.0));
}

// The pixels [x0, x1) × [y0, y1) whose centres lie inside the splat's quad, within the
// viewport; empty for a block without a hit or a depth outside [0, 1] (the rasterizer clips it).
fn covered_pixels(s: BlockSplat) -> vec4<u32> {
    if (s.point.w == 0.0 || !(s.z >= 0.0 && s.z <= 1.0)) {
        return vec4<u32>(0u);
    }
    let size = frame.viewport.xy;
    // Pixel-space edges of the quad (y down): centre x + 0.5 inside [left, right).
    let left = (s.lo.x + 1.0) * 0.5 * size.x;
    let right = (s.hi.x + 1.0) * 0.5 * size.x;
    let top = (1.0 - s.hi.y) * 0.5 * size.y;
    let bottom = (1.0 - s.lo.y) * 0.5 * size.y;
    let lo = clamp(ceil(vec2<f32>(left, top) - 0.5), vec2<f32>(0.0), size);
    let hi = clamp(ceil(vec2<f32>(right, bottom) - 0.5), vec2<f32>(0.0), size);
    return vec4<u32>(vec2<u32>(lo), vec2<u32>(hi));
}

// The depth key of a splat: larger is nearer, never 0 for a depth in [0, 1].
fn depth_key(z: f32) -> u32 {
    return ~bitcast<u32>(z);
}

// The block this invocation draws, or none past the rectangle's last block.
fn scatter_block(id: vec3<u32>) -> BlockSplat {
    let b = max(SPLAT_BLOCK, 1u);
    let rows = (splat.rect.w + b - 1u) / b;
    if (id.x >= blocks_x() || id.y >= rows) {
        return BlockSplat(vec4<f32>(0.0), 2.0, vec2<f32>(0.0), vec2<f32>(0.0));
    }
    return block_splat(id.y * blocks_x() + id.x);
}

// One round over the pixels of this invocation's splat: round 1 (`points` false) keeps in every
// pixel the nearest splat's depth; round 2 writes the point of the splat whose depth won (splats
// at the same depth may both write: either is a start at that depth).
fn scatter_round(id: vec3<u32>, points: bool) {
    let s = scatter_block(id);
    let r = covered_pixels(s);
    let key = depth_key(s.z);
    let width = u32(frame.viewport.x);
    for (var y = r.y; y < r.w; y += 1u) {
        for (var x = r.x; x < r.z; x += 1u) {
            let i = y * width + x;
            if (!points) {
                atomicMax(&depth[i], key);
            } else if (atomicLoad(&depth[i]) == key) {
                textureStore(start, vec2<u32>(x, y), s.point);
            }
        }
    }
}

@compute @workgroup_size(8, 8)
fn cs_splat_depth(@builtin(global_invocation_id) id: vec3<u32>) {
    scatter_round(id, false);
}

@compute @workgroup_size(8, 8)
fn cs_splat_point(@builtin(global_invocation_id) id: vec3<u32>) {
    scatter_round(id, true);
}
#endif
