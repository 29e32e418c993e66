// Klein et al. 2005 §4.2: marching a ray from a start estimate on the ray's own step grid, and
// reporting where the ray first met something so the next frame can start there. Used by the
// raycaster when it reads a `start` target or writes `leap_hit`, and by `antialias` for its
// sub-pixel rays. The integral is common/raymarch.wgsl's; only where marching begins differs.

#import "common/raymarch.wgsl"

// A march that may start late: the colour (DVR or shaded isosurface), the isosurface hit
// (w = 1), the ray parameter of the first sample that is not fully transparent (DVR) or of the
// isosurface hit (-1 when there is none), and the samples taken.
struct LeapMarch {
    color: vec4<f32>,
    hit: vec4<f32>,
    first_t: f32,
    samples: u32,
}

// The first sample index whose position is at or past `t_start` (texture-space distance from the
// entry): starting there keeps every sample on the grid of the full march, so a start estimate
// changes which samples are taken, never where they are.
fn first_sample_at(t_start: f32, step_tex: f32, jitter: f32) -> u32 {
    return u32(clamp(ceil(t_start / step_tex - 0.5 - jitter), 0.0, f32(params.max_steps)));
}

// Direct volume rendering from sample k0 on.
fn leap_dvr(u0: vec3<f32>, d_tex: vec3<f32>, len_tex: f32, pixel: vec2<u32>, k0: u32) -> LeapMarch {
    var out = LeapMarch(vec4<f32>(0.0), vec4<f32>(0.0), -1.0, 0u);
    if (!ray_is_valid(u0, d_tex, len_tex)) {
        return out;
    }
    let step_tex = ray_step_tex(d_tex);
    let jitter = ray_jitter(pixel);
    begin_ray(u0 + (f32(k0) + 0.5 + jitter) * step_tex * d_tex, step_tex * d_tex);
    for (var k = k0; k < params.max_steps; k += 1u) {
        let t = (f32(k) + 0.5 + jitter) * step_tex;
        if (!(t < len_tex)) {
            break;
        }
        let p = classify_sample(u0 + t * d_tex);
        out.samples += 1u;
        if (out.first_t < 0.0 && p.a > 0.0) {
            out.first_t = t;
        }
        out.color = out.color + (1.0 - out.color.a) * p;
        if (out.color.a >= params.threshold) {
            break;
        }
    }
    return out;
}

// First-hit isosurface from sample k0 on; the sample before k0 is read for the refinement (and
// a surface already behind the start is still found there).
fn leap_iso(u0: vec3<f32>, d_tex: vec3<f32>, len_tex: f32, pixel: vec2<u32>, k0: u32) -> LeapMarch {
    var out = LeapMarch(vec4<f32>(0.0), vec4<f32>(0.0), -1.0, 0u);
    if (!ray_is_valid(u0, d_tex, len_tex)) {
        return out;
    }
    let step_tex = ray_step_tex(d_tex);
    let jitter = ray_jitter(pixel);
    let iso = params.iso_value;
    var k = k0;
    var t_prev = 0.0;
    var s_prev = 0.0;
    var has_prev = false;
    if (k0 > 0u) {
        t_prev = (f32(k0) - 0.5 + jitter) * step_tex;
        s_prev = sample_volume(u0 + t_prev * d_tex);
        out.samples = 1u;
        has_prev = true;
        if (s_prev >= iso) {
            // The start was past the surface: take the sample that saw it again.
            k = k0 - 1u;
            has_prev = false;
        }
    }
    for (; k < params.max_steps; k += 1u) {
        let t = (f32(k) + 0.5 + jitter) * step_tex;
        if (!(t < len_tex)) {
            break;
        }
        let s = sample_volume(u0 + t * d_tex);
        out.samples += 1u;
        if (s >= iso) {
            var t_hit = t;
            if (has_prev) {
                t_hit = t_prev + (t - t_prev) * (iso - s_prev) / (s - s_prev);
            }
            let u = u0 + t_hit * d_tex;
            let d_world = normalize(d_tex * 2.0 * frame.half_extent.xyz);
            out.color = vec4<f32>(shade_iso(u, d_world), 1.0);
            out.hit = vec4<f32>(u, 1.0);
            out.first_t = t_hit;
            return out;
        }
        t_prev = t;
        s_prev = s;
        has_prev = true;
    }
    return out;
}

// The point the next frame starts this pixel's ray from: the first visible sample or the
// isosurface hit (w = 1); the exit point when the ray met nothing (w = 0.5: still a start for
// the next frame, but no surface for `antialias` to start sub-pixel rays at); w = 0 for a pixel
// without a ray, which the splat pass drops. The step back of Klein et al. §4.2 is taken when a
// ray starts (`start_sample`), along that ray.
fn leap_point(u0: vec3<f32>, d_tex: vec3<f32>, len_tex: f32, first_t: f32) -> vec4<f32> {
    if (!ray_is_valid(u0, d_tex, len_tex)) {
        return vec4<f32>(0.0);
    }
    if (first_t < 0.0) {
        return vec4<f32>(u0 + len_tex * d_tex, 0.5);
    }
    return vec4<f32>(u0 + max(first_t, 0.0) * d_tex, 1.0);
}

// The sample index a `start` texel (xyz: texture-space start, w > 0) gives a ray entering at u0:
// its distance along the ray, less `step_back` samples (never before the entry).
fn start_sample(start: vec4<f32>, u0: vec3<f32>, d_tex: vec3<f32>, pixel: vec2<u32>) -> u32 {
    if (start.w == 0.0) {
        return 0u;
    }
    let step_tex = ray_step_tex(d_tex);
    let t_start = max(dot(start.xyz - u0, d_tex) - params.step_back * step_tex, 0.0);
    return first_sample_at(t_start, step_tex, ray_jitter(pixel));
}
