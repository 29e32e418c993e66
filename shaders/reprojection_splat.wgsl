// Klein et al. 2005 §4.3–4.4: last frame's leap hits reprojected with this frame's camera as
// k×k-pixel splats (instanced quads pulling their point from the `hits` texture: WebGPU has no
// point size), depth-tested so the splat nearest the eye wins. Each fragment writes its point's
// texture-space position as this pixel's ray start (w = 1); pixels no splat covers keep
// (0,0,0,0) for hole_fill. Only the pixels of last frame's screen rectangle of the volume are
// drawn (the rectangle comes from the node, in `splat`). With `block` b > 1 one splat carries
// the nearest of a b×b block of hits over the block's projected bounding box grown by k/2: b²
// times fewer quads, each start at most as far as the hit it stands for.

#import "common/frame.wgsl"

// Rust twin: `SplatParamsGpu` in crates/passes/src/reprojection_splat.rs.
struct SplatParams {
    // Last frame's screen rectangle of the volume: origin x, y, width, height (pixels).
    rect: vec4<u32>,
    // Splat edge in pixels (k).
    size: f32,
    // Hits per splat side (b).
    block: u32,
    _pad1: f32,
    _pad2: f32,
}

// Last frame's leap hits: xyz texture space, w = 1 (surface) or 0.5 (exit point); w = 0 where
// there was no ray.
@group(0) @binding(auto) var hits: texture_2d<f32>;
@group(0) @binding(auto) var<uniform> splat: SplatParams;

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
    let b = max(splat.block, 1u);
    let blocks_x = max((splat.rect.z + b - 1u) / b, 1u);
    let base = splat.rect.xy + vec2<u32>(instance % blocks_x, instance / blocks_x) * b;
    let end = splat.rect.xy + splat.rect.zw;
    // The nearest hit of the block (NDC depth), and the NDC bounding box of all its hits.
    var nearest = vec4<f32>(0.0);
    var nearest_z = 2.0;
    var lo = vec2<f32>(3.0e38);
    var hi = vec2<f32>(-3.0e38);
    for (var i = 0u; i < b * b; i += 1u) {
        let pixel = base + vec2<u32>(i % b, i / b);
        if (any(pixel >= end)) {
            continue;
        }
        let hit = textureLoad(hits, vec2<i32>(pixel), 0);
        if (hit.w == 0.0) {
            continue;
        }
        let clip = frame.clip_from_world * vec4<f32>(world_from_texture(hit.xyz), 1.0);
        if (!(clip.w > 0.0)) {
            continue;
        }
        let ndc = clip.xyz / clip.w;
        lo = min(lo, ndc.xy);
        hi = max(hi, ndc.xy);
        if (ndc.z < nearest_z) {
            nearest_z = ndc.z;
            nearest = vec4<f32>(hit.xyz, 1.0);
        }
    }
    if (nearest.w == 0.0) {
        return out;
    }
    // Half the splat edge in NDC units (y up).
    let half = splat.size * vec2<f32>(frame.viewport.z, frame.viewport.w);
    let corner = quad_corner(vertex_index);
    let xy = select(lo, hi, corner > vec2<f32>(0.0)) + corner * half;
    out.clip = vec4<f32>(xy, nearest_z, 1.0);
    out.point = nearest;
    return out;
}

struct SplatOut {
    @location(0) start: vec4<f32>,
}

@fragment
fn fs_splat(in: SplatVertex) -> SplatOut {
    return SplatOut(in.point);
}
