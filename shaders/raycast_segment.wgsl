// Krüger & Westermann 2003 §2.1 "main passes 3 to N": one ray segment of M samples per pass,
// blended front to back into the accumulation target RES by the fixed-function blender
// (src factor OneMinusDstAlpha, dst factor One: RES += (1 - RES.a)·segment). Drawn at
// SEGMENT_DEPTH with the depth test GREATER against the early-z buffer the termination test
// writes, so fragments of terminated rays are rejected before this shader runs (it writes no
// depth and has no side effects, which keeps early-z on). §2.2's isosurface variant keeps the
// closest hit of the segment, shaded, with alpha 1. With LEAP (and LEAP_BLOCKS) the DVR segment
// leaps over empty blocks inside itself (§2.3).
//
// Pipelines: `vs_segment` + `fs_dvr` / `fs_iso` → `accum` (Modify port, blended).

#import "common/segment.wgsl"
#if LEAP_BLOCKS
#import "common/empty_blocks.wgsl"
#endif

struct SegmentOut {
    @location(0) accum: vec4<f32>,
}

// DVR segment `in.index` of this pixel's ray.
@fragment
fn fs_dvr(in: SegmentVertex) -> SegmentOut {
    return SegmentOut(segment_dvr(pixel_ray_samples(vec2<u32>(in.clip.xy)), in.index));
}

// Isosurface segment `in.index` of this pixel's ray.
struct SegmentIsoOut {
    @location(0) accum: vec4<f32>,
    @location(1) hit: vec4<f32>,
}

@fragment
fn fs_iso(in: SegmentVertex) -> SegmentIsoOut {
    let r = segment_iso(pixel_ray_samples(vec2<u32>(in.clip.xy)), in.index);
    return SegmentIsoOut(r.color, r.hit);
}
