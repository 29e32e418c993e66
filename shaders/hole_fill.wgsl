// Klein et al. 2005 §4.4's two hole-filling steps. First, extended splats: a pixel no splat
// reached takes the start nearest the eye among the splats within `extend` pixels — a larger
// splat drawn only into holes. Then every pixel still without a start begins at the volume
// box's front face — met analytically here (common/ray_box.wgsl), the raycaster's
// `rays: "analytic"` entry. One more rule keeps the image exact while the volume turns: a pixel
// within `band` pixels of the footprint's silhouette also starts at the box — a splat can carry
// a neighbour's hit across the silhouette into a pixel whose ray, newly in view, meets the box
// in front of that hit.

#import "common/frame.wgsl"
#import "common/footprint.wgsl"
#import "common/ray_box.wgsl"

// Declared once: `HoleParams` (pass_params!) in crates/passes/src/hole_fill.rs,
// which generates the struct imported here.
#import "params/HoleParams.wgsl"

// The reprojected starts (w = 1 where a splat landed).
@group(0) @binding(auto) var splats: texture_2d<f32>;
@group(0) @binding(auto) var<uniform> holes: HoleParams;
// Per image row, the range [x0, x1] of the pixel centres lying inside the footprint (the pixels
// whose ray meets the box) by a margin; x0 > x1 for none. The node computes it each frame from
// the footprint's polygon (crates/core/src/runtime/footprint.rs).
@group(0) @binding(auto) var<storage, read> footprint_rows: array<vec2<f32>>;

// (u0, 1) where pixel `p`'s ray enters the box, (0,0,0,0) where it misses.
fn entry_of(p: vec2<i32>) -> vec4<f32> {
    let r = analytic_ray(vec2<u32>(max(p, vec2<i32>(0))));
    return select(vec4<f32>(0.0), vec4<f32>(r.u0, 1.0), r.len > 0.0);
}

// True when some pixel within `band` of `pixel` may have no ray (the footprint's edge is near).
// The footprint — the pixels whose rays meet the box past the near plane — is the projection of
// a convex body, so it is convex: the square around `pixel` (clamped to the viewport) lies
// inside it when its four corners do, that is when its first and last rows' spans hold both its
// ends. Two reads where four corner rays met the box took 2 of a 4.6 ms pass on llvmpipe
// (bench/one-march-final.md, "Hole fill's footprint").
fn near_silhouette(pixel: vec2<i32>) -> bool {
    let size = vec2<i32>(frame.viewport.xy);
    let b = holes.silhouette_band;
    let lo = clamp(pixel - vec2<i32>(b), vec2<i32>(0), size - vec2<i32>(1));
    let hi = clamp(pixel + vec2<i32>(b), vec2<i32>(0), size - vec2<i32>(1));
    let first = footprint_rows[lo.y];
    let last = footprint_rows[hi.y];
    let x = vec2<f32>(vec2<i32>(lo.x, hi.x)) + vec2<f32>(0.5);
    return !(x.x >= max(first.x, last.x) && x.y <= min(first.y, last.y));
}

// The splat within `extend` pixels of `pixel` nearest the eye; w = 0 when there is none.
fn nearest_splat(pixel: vec2<i32>) -> vec4<f32> {
    let size = vec2<i32>(frame.viewport.xy);
    var best = vec4<f32>(0.0);
    var best_distance = 3.0e38;
    for (var dy = -holes.extend; dy <= holes.extend; dy += 1) {
        for (var dx = -holes.extend; dx <= holes.extend; dx += 1) {
            let q = clamp(pixel + vec2<i32>(dx, dy), vec2<i32>(0), size - vec2<i32>(1));
            let s = textureLoad(splats, q, 0);
            let distance = length(world_from_texture(s.xyz) - frame.eye_world.xyz);
            if (s.w > 0.0 && distance < best_distance) {
                best = s;
                best_distance = distance;
            }
        }
    }
    return best;
}

struct HoleOut {
    @location(0) start: vec4<f32>,
}

@fragment
fn fs_hole(in: FullscreenVertex) -> HoleOut {
    let pixel = vec2<i32>(in.clip.xy);
    let e = entry_of(pixel);
    var s = textureLoad(splats, pixel, 0);
    if (e.w == 0.0 || near_silhouette(pixel)) {
        return HoleOut(e);
    }
    if (s.w == 0.0) {
        s = nearest_splat(pixel);
    }
    return HoleOut(select(s, e, s.w == 0.0));
}
