// Ray segments of Krüger & Westermann 2003 §2.1 ("main passes 3 to N"): segment `i` of a ray
// covers samples k ∈ [i·M, (i+1)·M) of the same sample sequence as the single-pass raycaster
// (docs/rendering_model.md "Ray segment inside the box"), so compositing the segments front to
// back gives the single-pass integral. Shared by raycast_segment.wgsl (the segments),
// raycast_segment_counted.wgsl (the same with an invocation counter) and termination_test.wgsl
// (the intermediate pass deciding whether the next segment runs).
//
// Segments are drawn over the volume's screen footprint (common/footprint.wgsl: a fan of
// triangles, the pixels outside it have no ray and keep RES at zero) at depth SEGMENT_DEPTH with
// the segment index as the instance index (draw(0..30, i..i+1)), so one node records every
// iteration without per-iteration uniform buffers.

#import "common/frame.wgsl"
#import "common/footprint.wgsl"
#import "common/raymarch.wgsl"
#import "common/pixel_ray.wgsl"

// Declared once in Rust (`SegmentParams` in crates/passes/src/raycast_segment.rs).
#import "params/SegmentParams.wgsl"

@group(0) @binding(auto) var<uniform> segment: SegmentParams;

// The block edge of common/empty_blocks.wgsl.
fn block_edge() -> u32 {
    return segment.block_size;
}

// The depth segments are drawn at. The early-z buffer holds 0 for live rays and 1 for
// terminated ones; with depth compare Greater (the paper's GREATER) a segment fragment passes
// exactly where the stored depth is 0.
const SEGMENT_DEPTH: f32 = 0.5;

struct SegmentVertex {
    // In the fragment stage `clip.xy` is the pixel centre (row 0 at the top).
    @builtin(position) clip: vec4<f32>,
    // The segment index i (the instance index of the draw).
    @location(0) @interpolate(flat) index: u32,
}

// The footprint's fan at SEGMENT_DEPTH carrying the segment index.
@vertex
fn vs_segment(@builtin(vertex_index) vertex_index: u32, @builtin(instance_index) instance: u32) -> SegmentVertex {
    let p = footprint_position(vertex_index);
    return SegmentVertex(vec4<f32>(p.xy, SEGMENT_DEPTH, 1.0), instance);
}

// The samples of a pixel's ray (the single-pass raycaster's).
fn pixel_ray_samples(pixel: vec2<u32>) -> Samples {
    return pixel_samples(pixel_ray(pixel), pixel);
}

// Segment `index`'s sample range [k0, end) of `s`.
fn segment_range(s: Samples, index: u32) -> vec2<u32> {
    let k0 = index * segment.steps;
    return vec2<u32>(k0, min(k0 + segment.steps, s.count));
}

// True when segment `index` has no sample on the ray: no ray, past max_steps, or its first
// sample is beyond the exit point. The termination test uses it for "the ray left the volume".
fn segment_is_outside(s: Samples, index: u32) -> bool {
    return index * segment.steps >= s.count;
}

// DVR of segment `index`: its samples composited front to back into a segment colour
// (premultiplied, starting from zero) that hardware blending `dst + (1 - dst.a)·src` composites
// behind the accumulated colour. It stops early once its own alpha reaches the threshold (the
// accumulated alpha is then at least as high). With LEAP it leaps over empty blocks inside the
// segment (§2.3's skipping, lossless).
fn segment_dvr(s: Samples, index: u32) -> vec4<f32> {
    let r = segment_range(s, index);
    if (r.x >= r.y) {
        return vec4<f32>(0.0);
    }
    begin_ray(s, r.x);
    return march_dvr(s, r.x, r.y, vec4<f32>(0.0)).color;
}

// First-hit isosurface within segment `index` (§2.2): refined against the sample before the
// segment exactly like the single pass, shaded, alpha 1 — so the blend keeps the closest hit
// and the termination test stops the ray. Zero when the segment has no hit.
fn segment_iso(s: Samples, index: u32) -> IsoMarch {
    let r = segment_range(s, index);
    if (r.x >= r.y) {
        return IsoMarch(vec4<f32>(0.0), vec4<f32>(0.0), 0u, 0u);
    }
    return march_iso(s, r.x, r.y);
}
