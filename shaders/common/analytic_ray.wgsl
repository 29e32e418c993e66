// The pixel's ray met analytically with the volume box — no entry/exit raster passes, no
// float targets for them — and its samples as `first + k · delta`, for compute raycasters
// (`raycast_fast`) and the fetch-ceiling probe (`fetch_probe`). The same segment as
// `volgraph_accel::reference::ray_segment` and docs/rendering_model.md ("Ray segment inside the
// box"); the same samples as common/raymarch.wgsl's loops.

#import "common/frame.wgsl"
#import "common/raymarch.wgsl"

// A pixel's ray in texture space; `len = 0` for no ray.
struct Ray {
    u0: vec3<f32>,
    d: vec3<f32>,
    len: f32,
}

// The ray of pixel centre `pixel` clipped to the box and the near plane, exactly like
// `volgraph_accel::reference::ray_segment` (slab test; start at max(t_in, t_near); the ends
// clamped to [0,1]³; rays shorter than 1e-6 dropped).
fn analytic_ray(pixel: vec2<u32>) -> Ray {
    var ray = Ray(vec3<f32>(0.0), vec3<f32>(0.0, 0.0, 1.0), 0.0);
    let dir = pixel_ray_dir(vec2<f32>(pixel) + vec2<f32>(0.5));
    let eye = frame.eye_world.xyz;
    let half = frame.half_extent.xyz;
    var t_in = -3.0e38;
    var t_out = 3.0e38;
    for (var axis = 0u; axis < 3u; axis += 1u) {
        let o = eye[axis];
        let d = dir[axis];
        let h = half[axis];
        if (d == 0.0) {
            if (o < -h || o > h) {
                return ray;
            }
            continue;
        }
        let a = (-h - o) / d;
        let b = (h - o) / d;
        t_in = max(t_in, min(a, b));
        t_out = min(t_out, max(a, b));
    }
    let t_near = frame.camera_forward.w / max(dot(dir, frame.camera_forward.xyz), 1e-12);
    let t0 = max(t_in, t_near);
    if (!(t_in <= t_out) || !(t0 < t_out)) {
        return ray;
    }
    let u0 = clamp(texture_from_world(eye + t0 * dir), vec3<f32>(0.0), vec3<f32>(1.0));
    let u1 = clamp(texture_from_world(eye + t_out * dir), vec3<f32>(0.0), vec3<f32>(1.0));
    let len = length(u1 - u0);
    if (!(len >= 1e-6)) {
        return ray;
    }
    ray.u0 = u0;
    ray.d = (u1 - u0) / len;
    ray.len = len;
    return ray;
}

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

