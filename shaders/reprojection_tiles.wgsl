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
//   camera): the block's hits projected, their nearest depth raised by atomicMax into every tile their
//   projected bounding box grown by `margin` touches.

#import "common/frame.wgsl"
#import "common/ray_box.wgsl"
#import "common/reprojected_tiles.wgsl"

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
// Rust twin: `HitRectGpu` in crates/passes/src/reprojection_tiles.rs.
struct HitRect {
    // Last frame's screen rectangle of the volume: origin x, y, width, height (pixels).
    rect: vec4<u32>,
}
@group(0) @binding(auto) var<uniform> hit_rect: HitRect;
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

@compute @workgroup_size(8, 8)
fn cs_tiles_scatter(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    let base = hit_rect.rect.xy + id.xy * HIT_BLOCK;
    let end = min(hit_rect.rect.xy + hit_rect.rect.zw, size);
    if (any(base >= end)) {
        return;
    }
    // The block's hits in this frame: nearest view depth, bounding box in pixels (y down).
    var nearest = 3.0e38;
    var lo = vec2<f32>(3.0e38);
    var hi = vec2<f32>(-3.0e38);
    for (var i = 0u; i < HIT_BLOCK * HIT_BLOCK; i += 1u) {
        let pixel = base + vec2<u32>(i % HIT_BLOCK, i / HIT_BLOCK);
        if (any(pixel >= end)) {
            continue;
        }
        let hit = textureLoad(hits, vec2<i32>(pixel), 0);
        if (hit.w == 0.0) {
            continue;
        }
        let world = world_from_texture(hit.xyz);
        let clip = frame.clip_from_world * vec4<f32>(world, 1.0);
        // Behind the eye: bounds no ray of this frame (a tile it would have reached and no
        // other hit does starts at the box).
        if (!(clip.w > 0.0)) {
            continue;
        }
        let ndc = clip.xy / clip.w;
        let p = vec2<f32>((ndc.x + 1.0) * 0.5 * frame.viewport.x, (1.0 - ndc.y) * 0.5 * frame.viewport.y);
        lo = min(lo, p);
        hi = max(hi, p);
        nearest = min(nearest, view_depth(world));
    }
    if (nearest == 3.0e38) {
        return;
    }
    // The pixels whose centre (x + 0.5) lies within `margin` of the box, and their tiles; none
    // when the box is off screen.
    let margin = f32(tile_bounds.margin);
    let first = ceil(lo - vec2<f32>(margin + 0.5));
    let last = floor(hi + vec2<f32>(margin - 0.5));
    if (any(last < vec2<f32>(0.0)) || any(first > frame.viewport.xy - 1.0) || any(first > last)) {
        return;
    }
    let t0 = vec2<u32>(max(first, vec2<f32>(0.0))) / TILE;
    let t1 = vec2<u32>(min(last, frame.viewport.xy - 1.0)) / TILE;
    let key = depth_key(nearest);
    let per_row = tiles_per_row();
    for (var ty = t0.y; ty <= t1.y; ty += 1u) {
        for (var tx = t0.x; tx <= t1.x; tx += 1u) {
            atomicMax(&tiles[TILES_HEADER + ty * per_row + tx], key);
        }
    }
}
