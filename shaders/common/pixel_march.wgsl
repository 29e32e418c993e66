// One pixel's march for the single-pass raycasters, fragment (raycast.wgsl) and compute
// (raycast_compute.wgsl) alike: its ray (common/pixel_ray.wgsl), its samples and the shared
// loops of common/raymarch.wgsl, with the pass's choices compiled in:
// - LEAP with LEAP_BLOCKS (`empty` flags) or LEAP_CUBES (`distance` map): empty-space leaping
//   (Krüger & Westermann 2003 §2.3 in one pass); `blocks` holds the block edge;
// - START: begin each ray at the `start` estimate (Klein et al. 2005 §4.2);
// - START_TILES: begin each ray at its tile's depth bound (`start_tiles`, reprojection_tiles);
// - LEAP_HITS: report where the next frame's ray should start (`leap_hit`);
// - COUNT: add the samples taken to `samples` (benchmarks).
// - COUNT_LEAPABLE (with LEAP_HITS): add to `leapable` the samples a perfect start estimate
//   would let the ray leap over — those before its leap point less the step back — whatever
//   its start was: the measure a graph's bypass weighs reprojection's fixed cost against.

#import "common/frame.wgsl"
#import "common/raymarch.wgsl"
#import "common/pixel_ray.wgsl"
#import "common/leap.wgsl"

#if LEAP
// Declared once: `BlockSize` (pass_params!) in crates/passes/src/shared.rs,
// which generates the struct imported here.
#import "params/BlockSize.wgsl"

@group(0) @binding(auto) var<uniform> blocks: BlockSize;

fn block_edge() -> u32 {
    return blocks.block_size;
}
#endif
#if LEAP_BLOCKS
#import "common/empty_blocks.wgsl"
#endif
#if LEAP_CUBES
#import "common/empty_cubes.wgsl"
#endif

#if START
// xyz: texture-space start estimate, w = 1 where there is one (reprojection_splat, hole_fill).
@group(0) @binding(auto) var start: texture_2d<f32>;
#endif

#if START_TILES
#import "common/reprojected_tiles.wgsl"
// Per-tile view-depth bounds (common/reprojected_tiles.wgsl's layout).
@group(0) @binding(auto) var<storage, read> start_tiles: array<u32>;
#endif

// Words of the counting buffers: image row y adds into word y % SAMPLE_ROWS.
const SAMPLE_ROWS: u32 = 4096u;

#if COUNT
// Samples taken per image row (benchmarks sum them).
@group(0) @binding(auto) var<storage, read_write> samples: array<atomic<u32>>;
#endif

#if COUNT_LEAPABLE
// Samples a perfect start estimate would leap over, per image row (a bypass sums them).
@group(0) @binding(auto) var<storage, read_write> leapable: array<atomic<u32>>;
#endif

// A pixel's colour and point: the isosurface hit (w = 1, zero on a miss) or, with LEAP_HITS,
// the next frame's start (common/leap.wgsl's `leap_point`).
struct PixelMarch {
    color: vec4<f32>,
    point: vec4<f32>,
}

// The first sample of this pixel's ray: from the start estimate when there is one.
fn first_sample(pixel: vec2<u32>, ray: Ray, s: Samples) -> u32 {
#if START
    return start_sample(textureLoad(start, vec2<i32>(pixel), 0), ray, s);
#else
#if START_TILES
    return tile_start_sample(pixel, ray, s);
#else
    return 0u;
#endif
#endif
}

#if START_TILES
// The first sample of this pixel's ray from its tile's depth bound, less `step_back` samples
// (common/leap.wgsl's rule for a point estimate).
fn tile_start_sample(pixel: vec2<u32>, ray: Ray, s: Samples) -> u32 {
    let edge = start_tiles[0];
    if (edge == 0u) {
        return 0u;
    }
    let key = start_tiles[TILES_HEADER + (pixel.y / edge) * start_tiles[1] + pixel.x / edge];
    let t = tile_bound_t(key, ray.u0, ray.d);
    return first_sample_at(s, max(t - params.step_back * s.step, 0.0));
}
#endif

fn count_samples(pixel: vec2<u32>, n: u32) {
#if COUNT
    atomicAdd(&samples[pixel.y % SAMPLE_ROWS], n);
#endif
}

// `reach`: the sample the ray's leap point lies at (`s.count` when it met nothing); the next
// frame's ray would start `step_back` samples before it.
fn count_leapable(pixel: vec2<u32>, s: Samples, reach: u32) {
#if COUNT_LEAPABLE
    // One pixel in 16 (a 4×4 lattice) counts for its 16: a mean over the image needs no more,
    // and an atomic per pixel costs as much as a sample where lanes run atomics one by one.
    if (s.count > 0u && (pixel.x & 3u) == 0u && (pixel.y & 3u) == 0u) {
        let back = u32(params.step_back);
        atomicAdd(&leapable[pixel.y % SAMPLE_ROWS], 16u * (reach - min(reach, back)));
    }
#endif
}

// Direct volume rendering of one pixel: premultiplied linear RGBA over a transparent background.
fn march_pixel_dvr(pixel: vec2<u32>) -> PixelMarch {
    let ray = pixel_ray(pixel);
    let s = pixel_samples(ray, pixel);
    let k0 = first_sample(pixel, ray, s);
    begin_ray(s, k0);
    let m = march_dvr(s, k0, s.count, vec4<f32>(0.0));
    count_samples(pixel, m.samples);
    var point = vec4<f32>(0.0);
#if LEAP_HITS
    point = leap_point(ray, s, select(vec4<f32>(0.0), vec4<f32>(sample_at(s, m.first), 1.0), m.first != NO_SAMPLE));
    count_leapable(pixel, s, select(s.count, m.first, m.first != NO_SAMPLE));
#endif
    return PixelMarch(m.color, point);
}

// First-hit isosurface of one pixel: shaded colour (alpha 1) and hit.
fn march_pixel_iso(pixel: vec2<u32>) -> PixelMarch {
    let ray = pixel_ray(pixel);
    let s = pixel_samples(ray, pixel);
    let m = march_iso(s, first_sample(pixel, ray, s), s.count);
    count_samples(pixel, m.samples);
#if LEAP_HITS
    count_leapable(pixel, s, m.at);
    return PixelMarch(m.color, leap_point(ray, s, m.hit));
#else
    return PixelMarch(m.color, m.hit);
#endif
}
