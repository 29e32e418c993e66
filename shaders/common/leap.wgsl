// Klein et al. 2005 §4.2: a ray may start from an estimate on its own step grid, and reports
// where it first met something so the next frame can start there. Used by the raycasters with
// a `start` input or a `leap_hit` output (common/pixel_march.wgsl) and by `antialias` for its
// sub-pixel rays. The integral is common/raymarch.wgsl's; only where marching begins differs.

#import "common/raymarch.wgsl"

// The point the next frame starts this pixel's ray from: `found` (xyz, w = 1: the first
// visible sample or the isosurface hit) when there is one; the exit point when the ray met
// nothing (w = 0.5: still a start for the next frame, but no surface for `antialias` to start
// sub-pixel rays at); w = 0 for a pixel without a ray, which the splat pass drops. The step back
// of Klein et al. §4.2 is taken when a ray starts (`start_sample`), along that ray.
fn leap_point(ray: Ray, s: Samples, found: vec4<f32>) -> vec4<f32> {
    if (s.count == 0u) {
        return vec4<f32>(0.0);
    }
    if (found.w == 0.0) {
        return vec4<f32>(ray.u0 + ray.len * ray.d, 0.5);
    }
    return found;
}

// The first sample a `start` texel (xyz: texture-space start, w > 0) gives the ray of samples
// `s` entering at `ray.u0`: its distance along the ray, less `step_back` samples (never before
// the entry), on the ray's own step grid.
fn start_sample(start: vec4<f32>, ray: Ray, s: Samples) -> u32 {
    if (start.w == 0.0) {
        return 0u;
    }
    let t_start = max(dot(start.xyz - ray.u0, ray.d) - params.step_back * s.step, 0.0);
    return first_sample_at(s, t_start);
}
