// The single-pass fragment raycaster (Krüger & Westermann 2003 §2.1 "main passes" folded into
// one loop, §2.2 for the isosurface): the volume's screen footprint marches each pixel's ray
// through the shared core (common/pixel_march.wgsl, common/raymarch.wgsl;
// docs/rendering_model.md). Leaping over empty blocks, analytic rays, Klein et al. 2005's start
// estimates and leap hits, and sample counting are compiled in by the pass's settings.
//
// Pipelines: `vs_footprint` (the volume's screen footprint, common/footprint.wgsl) + `fs_dvr` →
// `color`; `fs_iso` → `color`, `hit`;
// `fs_dvr_leap` / `fs_iso_leap` (LEAP_HITS) → `color`, `leap_hit`.

#import "common/footprint.wgsl"
#import "common/pixel_march.wgsl"

struct DvrOut {
    @location(0) color: vec4<f32>,
}

@fragment
fn fs_dvr(in: FullscreenVertex) -> DvrOut {
    return DvrOut(march_pixel_dvr(vec2<u32>(in.clip.xy)).color);
}

struct IsoOut {
    @location(0) color: vec4<f32>,
    @location(1) hit: vec4<f32>,
}

@fragment
fn fs_iso(in: FullscreenVertex) -> IsoOut {
    let m = march_pixel_iso(vec2<u32>(in.clip.xy));
    return IsoOut(m.color, m.point);
}

struct LeapOut {
    @location(0) color: vec4<f32>,
    @location(1) leap_hit: vec4<f32>,
}

@fragment
fn fs_dvr_leap(in: FullscreenVertex) -> LeapOut {
    let m = march_pixel_dvr(vec2<u32>(in.clip.xy));
    return LeapOut(m.color, m.point);
}

@fragment
fn fs_iso_leap(in: FullscreenVertex) -> LeapOut {
    let m = march_pixel_iso(vec2<u32>(in.clip.xy));
    return LeapOut(m.color, m.point);
}
