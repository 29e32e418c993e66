// Ray segments of Krüger & Westermann 2003 §2.1 ("main passes 3 to N"): segment `i` of a ray
// covers samples k ∈ [i·M, (i+1)·M) of the same sample sequence as the single-pass raycaster
// (docs/rendering_model.md "Ray segment inside the box"), so compositing the segments front to
// back gives the single-pass integral. Shared by raycast_segment.wgsl (the segments),
// raycast_segment_counted.wgsl (the same with an invocation counter) and termination_test.wgsl
// (the intermediate pass deciding whether the next segment runs).
//
// Segments are drawn as one screen-covering triangle at depth SEGMENT_DEPTH with the segment
// index as the instance index (draw(0..3, i..i+1)), so one node records every iteration without
// per-iteration uniform buffers.

#import "common/frame.wgsl"
#import "common/raymarch.wgsl"

// (u0, 1) where the pixel's ray enters the box, (0,0,0,0) where it misses.
@group(0) @binding(auto) var entry: texture_2d<f32>;
// (d_tex, len_tex); (0,0,0,0) for no ray.
@group(0) @binding(auto) var dir: texture_2d<f32>;

// Rust twin: `SegmentParamsGpu` in crates/passes/src/raycast_segment.rs.
struct SegmentParams {
    // M: samples per segment.
    steps: u32,
    // Edge of an empty-space block in voxels (termination_test with empty-space skipping).
    block_size: u32,
    // T: the termination test stops rays whose accumulated alpha is >= T.
    threshold: f32,
    _pad0: u32,
}

@group(0) @binding(auto) var<uniform> segment: SegmentParams;

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

// One screen-covering triangle at SEGMENT_DEPTH carrying the segment index.
@vertex
fn vs_segment(@builtin(vertex_index) vertex_index: u32, @builtin(instance_index) instance: u32) -> SegmentVertex {
    let x = f32((vertex_index & 1u) << 2u) - 1.0;
    let y = f32((vertex_index & 2u) << 1u) - 1.0;
    return SegmentVertex(vec4<f32>(x, y, SEGMENT_DEPTH, 1.0), instance);
}

// A pixel's ray: entry u0, unit texture-space direction, length; `valid` false for no ray.
struct PixelRay {
    u0: vec3<f32>,
    d_tex: vec3<f32>,
    len_tex: f32,
    step_tex: f32,
    jitter: f32,
    valid: bool,
}

fn pixel_ray(pixel: vec2<u32>) -> PixelRay {
    let e = textureLoad(entry, vec2<i32>(pixel), 0);
    let d = textureLoad(dir, vec2<i32>(pixel), 0);
    var ray = PixelRay(e.xyz, d.xyz, d.w, 0.0, 0.0, false);
    if (e.w != 0.0 && ray_is_valid(e.xyz, d.xyz, d.w)) {
        ray.step_tex = ray_step_tex(d.xyz);
        ray.jitter = ray_jitter(pixel);
        ray.valid = true;
    }
    return ray;
}

// t of sample k (docs/rendering_model.md "Samples").
fn sample_t(ray: PixelRay, k: u32) -> f32 {
    return (f32(k) + 0.5 + ray.jitter) * ray.step_tex;
}

// The end (exclusive) of segment `index`'s sample range, capped by max_steps.
fn segment_end(index: u32) -> u32 {
    return min((index + 1u) * segment.steps, params.max_steps);
}

// True when segment `index` has no sample on the ray: no ray, past max_steps, or its first
// sample is beyond the exit point. The termination test uses it for "the ray left the volume".
fn segment_is_outside(ray: PixelRay, index: u32) -> bool {
    let k0 = index * segment.steps;
    return !ray.valid || k0 >= params.max_steps || !(sample_t(ray, k0) < ray.len_tex);
}

// DVR of segment `index`: samples [i·M, (i+1)·M) composited front to back into a segment
// colour (premultiplied, starting from zero) that hardware blending `dst + (1 - dst.a)·src`
// composites behind the accumulated colour. It stops early once its own alpha reaches the
// threshold (the accumulated alpha is then at least as high).
fn segment_dvr(ray: PixelRay, index: u32) -> vec4<f32> {
    var acc = vec4<f32>(0.0);
    if (!ray.valid) {
        return acc;
    }
    for (var k = index * segment.steps; k < segment_end(index); k += 1u) {
        let t = sample_t(ray, k);
        if (!(t < ray.len_tex)) {
            break;
        }
        acc = composite_sample(acc, ray.u0 + t * ray.d_tex);
        if (acc.a >= params.threshold) {
            break;
        }
    }
    return acc;
}

// First-hit isosurface within segment `index` (§2.2): the first sample k of the segment with
// s >= iso, refined against sample k-1 exactly like the single pass (sample k-1 is fetched again
// when it belongs to the previous segment), shaded, alpha 1 — so the blend keeps the closest
// hit and the termination test stops the ray. The hit is the texture-space position with w = 1
// (blended like the colour, so the closest hit stays). Zero when the segment has no hit.
fn segment_iso(ray: PixelRay, index: u32) -> IsoResult {
    if (!ray.valid) {
        return IsoResult(vec4<f32>(0.0), vec4<f32>(0.0));
    }
    let iso = params.iso_value;
    let k0 = index * segment.steps;
    var t_prev = 0.0;
    var s_prev = 0.0;
    if (k0 > 0u) {
        t_prev = sample_t(ray, k0 - 1u);
        s_prev = sample_volume(ray.u0 + t_prev * ray.d_tex);
    }
    for (var k = k0; k < segment_end(index); k += 1u) {
        let t = sample_t(ray, k);
        if (!(t < ray.len_tex)) {
            break;
        }
        let s = sample_volume(ray.u0 + t * ray.d_tex);
        if (s >= iso) {
            var t_hit = t;
            if (k > 0u) {
                t_hit = t_prev + (t - t_prev) * (iso - s_prev) / (s - s_prev);
            }
            let d_world = normalize(ray.d_tex * 2.0 * frame.half_extent.xyz);
            let u_hit = ray.u0 + t_hit * ray.d_tex;
            return IsoResult(vec4<f32>(shade_iso(u_hit, d_world), 1.0), vec4<f32>(u_hit, 1.0));
        }
        t_prev = t;
        s_prev = s;
    }
    return IsoResult(vec4<f32>(0.0), vec4<f32>(0.0));
}
