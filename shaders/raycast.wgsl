// The single-pass fragment raycaster (Krüger & Westermann 2003 §2.1 "main passes" folded into
// one loop, §2.2 for the isosurface): a screen-covering triangle reads each pixel's entry point
// (`entry`, pass 1) and direction/length (`dir`, pass 2) and marches the shared integral of
// common/raymarch.wgsl (docs/rendering_model.md).
//
// Pipelines: `vs_fullscreen` + `fs_dvr` → `color`; `vs_fullscreen` + `fs_iso` → `color`, `hit`.
// With ANALYTIC (`rays: "analytic"`) the entry and direction come from the frame's pixel rays
// met analytically with the box, and the `entry` / `dir` inputs are not used.

#import "common/frame.wgsl"
#import "common/fullscreen.wgsl"
#import "common/raymarch.wgsl"
#import "common/leap.wgsl"

#if ANALYTIC
#import "common/analytic_ray.wgsl"

// The pixel's entry (u0, 1; zeros for no ray) and direction (d_tex, len_tex), met analytically
// with the box (common/analytic_ray.wgsl) instead of read from the raster passes' targets.
fn pixel_entry(pixel: vec2<u32>) -> vec4<f32> {
    let r = analytic_ray(pixel);
    return select(vec4<f32>(0.0), vec4<f32>(r.u0, 1.0), r.len > 0.0);
}

fn pixel_dir(pixel: vec2<u32>) -> vec4<f32> {
    let r = analytic_ray(pixel);
    return select(vec4<f32>(0.0), vec4<f32>(r.d, r.len), r.len > 0.0);
}
#else
// (u0, 1) where the pixel's ray enters the box, (0,0,0,0) where it misses.
@group(0) @binding(auto) var entry: texture_2d<f32>;
// (d_tex, len_tex); (0,0,0,0) for no ray.
@group(0) @binding(auto) var dir: texture_2d<f32>;

fn pixel_entry(pixel: vec2<u32>) -> vec4<f32> {
    return textureLoad(entry, vec2<i32>(pixel), 0);
}

fn pixel_dir(pixel: vec2<u32>) -> vec4<f32> {
    return textureLoad(dir, vec2<i32>(pixel), 0);
}
#endif

struct RaycastOut {
    @location(0) color: vec4<f32>,
}

// Direct volume rendering: premultiplied linear RGBA over a transparent background.
@fragment
fn fs_dvr(in: FullscreenVertex) -> RaycastOut {
    let pixel = vec2<u32>(in.clip.xy);
    let e = pixel_entry(pixel);
    let d = pixel_dir(pixel);
    var color = vec4<f32>(0.0);
    if (e.w != 0.0) {
        color = march_dvr(e.xyz, d.xyz, d.w, pixel);
    }
    return RaycastOut(color);
}

struct IsoOut {
    @location(0) color: vec4<f32>,
    @location(1) hit: vec4<f32>,
}

// First-hit isosurface: shaded colour (alpha 1) and texture-space hit (w = 1), zero on a miss.
@fragment
fn fs_iso(in: FullscreenVertex) -> IsoOut {
    let pixel = vec2<u32>(in.clip.xy);
    let e = pixel_entry(pixel);
    let d = pixel_dir(pixel);
    var result = IsoResult(vec4<f32>(0.0), vec4<f32>(0.0));
    if (e.w != 0.0) {
        result = march_iso(e.xyz, d.xyz, d.w, pixel);
    }
    return IsoOut(result.color, result.hit);
}

// ---- Klein et al. 2005 §4.2: start from an estimate, report the leap hit -------------------
// `fs_dvr_leap` / `fs_iso_leap` march from the `start` target's estimate (with START; else from
// the entry) on the same step grid as fs_dvr / fs_iso, and also write `leap_hit`, where the next
// frame's ray should start (common/leap.wgsl). With COUNT they add their samples to `samples`.

#if START
// xyz: texture-space start estimate, w = 1 where there is one (reprojection_splat, hole_fill).
@group(0) @binding(auto) var start: texture_2d<f32>;
#endif

#if COUNT
// Samples taken per image row (row y adds into samples[y % 4096]).
@group(0) @binding(auto) var<storage, read_write> samples: array<atomic<u32>>;
#endif

struct LeapDvrOut {
    @location(0) color: vec4<f32>,
    @location(1) leap_hit: vec4<f32>,
}

struct LeapIsoOut {
    @location(0) color: vec4<f32>,
    @location(1) leap_hit: vec4<f32>,
}

// The first sample of this pixel's ray: from the start estimate when there is one.
fn leap_first_sample(pixel: vec2<u32>, e: vec4<f32>, d: vec4<f32>) -> u32 {
#if START
    return start_sample(textureLoad(start, vec2<i32>(pixel), 0), e.xyz, d.xyz, pixel);
#else
    return 0u;
#endif
}

fn count_samples(pixel: vec2<u32>, n: u32) {
#if COUNT
    atomicAdd(&samples[pixel.y % 4096u], n);
#endif
}

@fragment
fn fs_dvr_leap(in: FullscreenVertex) -> LeapDvrOut {
    let pixel = vec2<u32>(in.clip.xy);
    let e = pixel_entry(pixel);
    let d = pixel_dir(pixel);
    var out = LeapDvrOut(vec4<f32>(0.0), vec4<f32>(0.0));
    if (e.w != 0.0) {
        let m = leap_dvr(e.xyz, d.xyz, d.w, pixel, leap_first_sample(pixel, e, d));
        count_samples(pixel, m.samples);
        out = LeapDvrOut(m.color, leap_point(e.xyz, d.xyz, d.w, m.first_t));
    }
    return out;
}

@fragment
fn fs_iso_leap(in: FullscreenVertex) -> LeapIsoOut {
    let pixel = vec2<u32>(in.clip.xy);
    let e = pixel_entry(pixel);
    let d = pixel_dir(pixel);
    var out = LeapIsoOut(vec4<f32>(0.0), vec4<f32>(0.0));
    if (e.w != 0.0) {
        let m = leap_iso(e.xyz, d.xyz, d.w, pixel, leap_first_sample(pixel, e, d));
        count_samples(pixel, m.samples);
        out = LeapIsoOut(m.color, leap_point(e.xyz, d.xyz, d.w, m.first_t));
    }
    return out;
}
