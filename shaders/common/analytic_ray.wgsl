// The pixel's ray met analytically with the volume box — no entry/exit raster passes, no
// float targets for them — and its samples as `first + k · delta`, for compute raycasters
// (`raycast_fast`) and the fetch-ceiling probe (`fetch_probe`). The same segment as
// `volgraph_accel::reference::ray_segment` and docs/rendering_model.md ("Ray segment inside the
// box"); the same samples as common/raymarch.wgsl's loops.

#import "common/ray_box.wgsl"
#import "common/raymarch.wgsl"

// Sample k of a ray lies at `first + k · delta` (texture space): `first` the first sample,
// `delta` one step. The hot loop keeps only these, the colour and two counters in registers.
struct Samples {
    first: vec3<f32>,
    delta: vec3<f32>,
    count: u32,
}

// The samples of `ray` for pixel `pixel`: k = 0.. with (k + 0.5 + jitter) · step_tex < len
// (at most max_steps), step and jitter from common/raymarch.wgsl. Call only for a valid ray
// (`ray_is_valid`).
fn ray_samples(ray: Ray, pixel: vec2<u32>) -> Samples {
    let step_tex = ray_step_tex(ray.d);
    let jitter = ray_jitter(pixel);
    let delta = ray.d * step_tex;
    let count = u32(clamp(ceil(ray.len / step_tex - 0.5 - jitter), 0.0, f32(params.max_steps)));
    return Samples(ray.u0 + (0.5 + jitter) * delta, delta, count);
}

