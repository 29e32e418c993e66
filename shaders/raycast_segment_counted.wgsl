// raycast_segment.wgsl with a debug counter: every fragment invocation adds 1 to `invocations`,
// so a test can show that fragments rejected by the early depth test (Krüger & Westermann 2003
// §2.1) never run the segment shader. A shader with side effects only keeps its depth test
// early when forced (`@early_depth_test(force)`, wgpu's SHADER_EARLY_DEPTH_TEST, Vulkan), which
// is why this lives in its own module: devices without the feature never compile it.
//
// Pipelines: `vs_segment` + `fs_dvr_counted` / `fs_iso_counted` → `accum`.

#import "common/segment.wgsl"

// Fragment invocations since the counter was last cleared (the node clears it every frame).
@group(0) @binding(auto) var<storage, read_write> invocations: atomic<u32>;

struct SegmentOut {
    @location(0) accum: vec4<f32>,
}

@fragment
@early_depth_test(force)
fn fs_dvr_counted(in: SegmentVertex) -> SegmentOut {
    atomicAdd(&invocations, 1u);
    return SegmentOut(segment_dvr(pixel_ray_samples(vec2<u32>(in.clip.xy)), in.index));
}

struct SegmentIsoOut {
    @location(0) accum: vec4<f32>,
    @location(1) hit: vec4<f32>,
}

@fragment
@early_depth_test(force)
fn fs_iso_counted(in: SegmentVertex) -> SegmentIsoOut {
    atomicAdd(&invocations, 1u);
    let r = segment_iso(pixel_ray_samples(vec2<u32>(in.clip.xy)), in.index);
    return SegmentIsoOut(r.color, r.hit);
}
