// One pixel's march for the single-pass raycasters, fragment (raycast.wgsl) and compute
// (raycast_compute.wgsl) alike: its ray (common/pixel_ray.wgsl), its samples and the shared
// loops of common/raymarch.wgsl, with the pass's choices compiled in:
// - LEAP with LEAP_BLOCKS (`empty` flags) or LEAP_CUBES (`distance` map): empty-space leaping
//   (Krüger & Westermann 2003 §2.3 in one pass); `blocks` holds the block edge;
// - START: begin each ray at the `start` estimate (Klein et al. 2005 §4.2);
// - LEAP_HITS: report where the next frame's ray should start (`leap_hit`);
// - COUNT: add the samples taken to `samples` (benchmarks).

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

#if COUNT
// Samples taken per image row (row y adds into samples[y % SAMPLE_ROWS]; benchmarks sum them).
@group(0) @binding(auto) var<storage, read_write> samples: array<atomic<u32>>;
const SAMPLE_ROWS: u32 = 4096u;
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
    return 0u;
#endif
}

fn count_samples(pixel: vec2<u32>, n: u32) {
#if COUNT
    atomicAdd(&samples[pixel.y % SAMPLE_ROWS], n);
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
    return PixelMarch(m.color, leap_point(ray, s, m.hit));
#else
    return PixelMarch(m.color, m.hit);
#endif
}
