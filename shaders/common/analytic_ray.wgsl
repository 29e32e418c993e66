// The pixel's ray met analytically with the volume box — no entry/exit raster passes, no
// float targets for them — and its samples as `first + k · delta`, for compute raycasters
// (`raycast_fast`) and the fetch-ceiling probe (`fetch_probe`). The same segment as
// `volgraph_accel::reference::ray_segment` and docs/rendering_model.md ("Ray segment inside the
// box"); the same samples as common/raymarch.wgsl's loops.

#import "common/ray_box.wgsl"
#import "common/raymarch.wgsl"

// The samples of `ray` for pixel `pixel`: k = 0.. with (k + 0.5 + jitter) · step_tex < len
// (at most max_steps), step and jitter from common/raymarch.wgsl. Call only for a valid ray
// (`ray_is_valid`).
fn ray_samples(ray: Ray, pixel: vec2<u32>) -> Samples {
    return samples_along(ray, ray_step_tex(ray.d), ray_jitter(pixel), params.max_steps);
}

