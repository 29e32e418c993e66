// Klein et al. 2005 §4.3–4.4 with per-tile depth bounds instead of per-pixel splats. Last
// frame's leap hits are reprojected with this frame's camera, and every screen tile of
// TILE×TILE pixels keeps the nearest view depth of the hits that land on it or within `margin`
// pixels of it; the raycaster starts each ray of the tile at that depth on its own ray
// (common/reprojected_tiles.wgsl). A tile bound is at least as near as any per-pixel splat of
// half size `margin` would have been — the conservative side — and costs one atomic per tile a
// block of hits touches instead of a write per pixel, with no hole-filling pass after it: a
// tile no hit reached, or one within `silhouette_band` pixels of the volume's silhouette (where
// rays newly in view enter the box in front of every old hit), starts at the box.
//
// Two rounds:
// - `cs_tiles_clear`, one invocation per tile: the header (tile edge, tiles per row) and each
//   tile's key — "none yet" (0), or "from the box" (all ones, which no depth outbids) for a tile
//   near the silhouette;
// - `cs_tiles_scatter`, one invocation per HIT_BLOCK × HIT_BLOCK block of last frame's screen
//   rectangle of the volume (where its hits can be; the node computes it from last frame's
//   camera): the block's hits projected, and each tile within `margin` of one of them raised by
//   atomicMax to the nearest depth among the hits near it — one atomic per tile the block
//   touches.

#import "common/frame.wgsl"
#import "common/ray_box.wgsl"
#import "common/reprojected_tiles.wgsl"
#import "common/reprojected_hit.wgsl"

// Declared once: `TileBoundsParams` (pass_params!) in crates/passes/src/reprojection_tiles.rs,
// which generates the struct imported here.
#import "params/TileBoundsParams.wgsl"

// Tile edge in pixels, and last frame's pixels per invocation side: pipeline constants (a loop
// bounded by a uniform made lavapipe recompile at every dispatch; see reprojection_splat.wgsl).
override TILE: u32 = 4u;
override HIT_BLOCK: u32 = 4u;

// Last frame's leap hits: xyz texture space, w = 1 (surface) or 0.5 (exit point); w = 0 where
// there was no ray.
@group(0) @binding(auto) var hits: texture_2d<f32>;
@group(0) @binding(auto) var<uniform> tile_bounds: TileBoundsParams;
// TILES_HEADER words, then one key per tile, row by row (common/reprojected_tiles.wgsl).
@group(0) @binding(auto) var<storage, read_write> tiles: array<atomic<u32>>;

fn tiles_per_row() -> u32 {
    return (u32(frame.viewport.x) + TILE - 1u) / TILE;
}

fn tile_rows() -> u32 {
    return (u32(frame.viewport.y) + TILE - 1u) / TILE;
}

// Whether the ray of pixel `p` (clamped to the viewport) meets the box.
fn meets_box(p: vec2<i32>) -> bool {
    let size = vec2<i32>(frame.viewport.xy);
    return analytic_ray(vec2<u32>(clamp(p, vec2<i32>(0), size - vec2<i32>(1)))).len > 0.0;
}

// True when every pixel within `silhouette_band` of tile `t` has a ray: the footprint — the
// pixels whose rays meet the box — is the projection of a convex body, so the tile's square
// grown by the band lies inside it when its four corners do.
fn inside_footprint(t: vec2<u32>) -> bool {
    let band = i32(tile_bounds.silhouette_band);
    let lo = vec2<i32>(t * TILE) - vec2<i32>(band);
    let hi = vec2<i32>((t + vec2<u32>(1u)) * TILE) - vec2<i32>(1) + vec2<i32>(band);
    return meets_box(lo) && meets_box(vec2<i32>(hi.x, lo.y)) && meets_box(vec2<i32>(lo.x, hi.y)) && meets_box(hi);
}

@compute @workgroup_size(8, 8)
fn cs_tiles_clear(@builtin(global_invocation_id) id: vec3<u32>) {
    if (all(id.xy == vec2<u32>(0u))) {
        atomicStore(&tiles[0], TILE);
        atomicStore(&tiles[1], tiles_per_row());
    }
    if (id.x >= tiles_per_row() || id.y >= tile_rows()) {
        return;
    }
    let key = select(FROM_THE_BOX, NO_BOUND_YET, inside_footprint(id.xy));
    atomicStore(&tiles[TILES_HEADER + id.y * tiles_per_row() + id.x], key);
}

// The hits one invocation keeps to bound each tile by the hits near it alone, and the most
// tiles per side such a block may touch; a block beyond either (a silhouette with depths far
// apart) bounds every tile it touches by its nearest hit, which is nearer still.
const LOCAL_HITS: u32 = 64u;
const LOCAL_TILES: u32 = 5u;
const FAR: f32 = 3.0e38;

// The tiles (first x, y, last x, y) holding a pixel centre (x + 0.5) within `margin` of the
// pixel-space box [lo, hi]; first > last when none (off screen).
fn tiles_near(lo: vec2<f32>, hi: vec2<f32>) -> vec4<i32> {
    let margin = f32(tile_bounds.margin);
    let first = max(ceil(lo - vec2<f32>(margin + 0.5)), vec2<f32>(0.0));
    let last = min(floor(hi + vec2<f32>(margin - 0.5)), frame.viewport.xy - 1.0);
    if (any(first > last)) {
        return vec4<i32>(1, 1, 0, 0);
    }
    return vec4<i32>(vec2<i32>(first) / i32(TILE), vec2<i32>(last) / i32(TILE));
}

@compute @workgroup_size(8, 8)
fn cs_tiles_scatter(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    let origin = vec2<u32>(tile_bounds.rect_x, tile_bounds.rect_y);
    let base = origin + id.xy * HIT_BLOCK;
    let end = min(origin + vec2<u32>(tile_bounds.rect_w, tile_bounds.rect_h), size);
    if (any(base >= end)) {
        return;
    }
    // The block's hits in this frame: where each lands (pixels, y down) and its view depth;
    // their nearest depth and bounding box.
    var points: array<vec3<f32>, LOCAL_HITS>;
    var count = 0u;
    var nearest = FAR;
    var lo = vec2<f32>(FAR);
    var hi = vec2<f32>(-FAR);
    for (var i = 0u; i < HIT_BLOCK * HIT_BLOCK; i += 1u) {
        let pixel = base + vec2<u32>(i % HIT_BLOCK, i / HIT_BLOCK);
        if (any(pixel >= end)) {
            continue;
        }
        // No hit, or behind the eye: bounds no ray of this frame (a tile it would have reached
        // and no other hit does starts at the box).
        let hit = reprojected_hit(pixel);
        if (!hit.valid) {
            continue;
        }
        let p = pixel_from_ndc(hit.ndc.xy);
        let depth = view_depth(hit.world);
        if (count < LOCAL_HITS) {
            points[count] = vec3<f32>(p, depth);
        }
        count += 1u;
        lo = min(lo, p);
        hi = max(hi, p);
        nearest = min(nearest, depth);
    }
    let range = tiles_near(lo, hi);
    if (count == 0u || any(range.xy > range.zw)) {
        return;
    }
    let per_row = tiles_per_row();
    let n = vec2<u32>(range.zw - range.xy) + vec2<u32>(1u);
    if (count <= LOCAL_HITS && all(n <= vec2<u32>(LOCAL_TILES))) {
        // Each tile by the hits within `margin` of it: as tight as splatting every hit alone,
        // one atomic per tile touched.
        var mins: array<f32, 25>;
        for (var t = 0u; t < LOCAL_TILES * LOCAL_TILES; t += 1u) {
            mins[t] = FAR;
        }
        for (var i = 0u; i < count; i += 1u) {
            let q = points[i];
            let r = tiles_near(q.xy, q.xy) - vec4<i32>(range.xy, range.xy);
            for (var ty = r.y; ty <= r.w; ty += 1) {
                for (var tx = r.x; tx <= r.z; tx += 1) {
                    let t = u32(ty) * LOCAL_TILES + u32(tx);
                    mins[t] = min(mins[t], q.z);
                }
            }
        }
        for (var ty = 0u; ty < n.y; ty += 1u) {
            for (var tx = 0u; tx < n.x; tx += 1u) {
                let z = mins[ty * LOCAL_TILES + tx];
                if (z < FAR) {
                    let tile = vec2<u32>(range.xy) + vec2<u32>(tx, ty);
                    atomicMax(&tiles[TILES_HEADER + tile.y * per_row + tile.x], depth_key(z));
                }
            }
        }
        return;
    }
    let key = depth_key(nearest);
    for (var ty = u32(range.y); ty <= u32(range.w); ty += 1u) {
        for (var tx = u32(range.x); tx <= u32(range.z); tx += 1u) {
            atomicMax(&tiles[TILES_HEADER + ty * per_row + tx], key);
        }
    }
}
