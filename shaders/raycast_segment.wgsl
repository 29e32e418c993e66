// Krüger & Westermann 2003 §2.1 "main passes 3 to N": one ray segment of M samples per pass,
// blended front to back into the accumulation target RES by the fixed-function blender
// (src factor OneMinusDstAlpha, dst factor One: RES += (1 - RES.a)·segment). Drawn at
// SEGMENT_DEPTH with the depth test GREATER against the early-z buffer the termination test
// writes, so fragments of terminated rays are rejected before this shader runs (it writes no
// depth and has no side effects, which keeps early-z on). §2.2's isosurface variant keeps the
// closest hit of the segment, shaded, with alpha 1.
//
// Pipelines: `vs_segment` + `fs_dvr` / `fs_iso` → `accum` (Modify port, blended).

#import "common/segment.wgsl"
#import "common/empty_blocks.wgsl"

struct SegmentOut {
    @location(0) accum: vec4<f32>,
}

// DVR segment `in.index` of this pixel's ray.
@fragment
fn fs_dvr(in: SegmentVertex) -> SegmentOut {
    return SegmentOut(segment_dvr(pixel_ray(vec2<u32>(in.clip.xy)), in.index));
}

// Isosurface segment `in.index` of this pixel's ray.
struct SegmentIsoOut {
    @location(0) accum: vec4<f32>,
    @location(1) hit: vec4<f32>,
}

@fragment
fn fs_iso(in: SegmentVertex) -> SegmentIsoOut {
    let r = segment_iso(pixel_ray(vec2<u32>(in.clip.xy)), in.index);
    return SegmentIsoOut(r.color, r.hit);
}

// DVR of segment `index` leaping over empty blocks (§2.3's skipping inside the segment): a
// sample in an empty block contributes exactly nothing, so the segment jumps to its first sample
// past that block's exit — the same leap rule as raycast_ess.wgsl, so the image is unchanged.
fn segment_dvr_leap(ray: PixelRay, index: u32) -> vec4<f32> {
    var acc = vec4<f32>(0.0);
    if (!ray.valid) {
        return acc;
    }
    let end = segment_end(index);
    var k = index * segment.steps;
    var known_block = vec3<u32>(0xffffffffu);
    var known_empty = false;
    loop {
        if (k >= end) {
            break;
        }
        let t = sample_t(ray, k);
        if (!(t < ray.len_tex)) {
            break;
        }
        let u = ray.u0 + t * ray.d_tex;
        let b = block_of(u, segment.block_size);
        // One flag look-up per block entered, not per sample.
        if (any(b != known_block)) {
            known_block = b;
            known_empty = block_is_empty(b);
        }
        if (known_empty) {
            let next = first_sample_past_block(b, segment.block_size, ray.u0, ray.d_tex, ray.step_tex, ray.jitter);
            k = max(k + 1u, u32(clamp(next, 0.0, f32(end))));
            continue;
        }
        acc = composite_sample(acc, u);
        if (acc.a >= params.threshold) {
            break;
        }
        k += 1u;
    }
    return acc;
}

@fragment
fn fs_dvr_leap(in: SegmentVertex) -> SegmentOut {
    return SegmentOut(segment_dvr_leap(pixel_ray(vec2<u32>(in.clip.xy)), in.index));
}
