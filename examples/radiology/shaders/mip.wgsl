// Maximum-intensity projection (examples/radiology/src/mip.rs): the brightest sample along each
// pixel's ray, windowed by level and width. The ray and its samples are volgraph's own
// (common/ray_box.wgsl: the box met analytically, k + 0.5 steps from the entry), so the
// result can be checked against a CPU MIP over volgraph_accel's reference rays.

#import "common/frame.wgsl"
#import "common/raymarch.wgsl"
#import "common/mip.wgsl"

// Declared once: `MipParams` (pass_params!) in examples/radiology/src/mip.rs,
// which generates the struct imported here.
#import "params/MipParams.wgsl"

@group(0) @binding(auto) var<uniform> mip: MipParams;
@group(0) @binding(auto) var color: texture_storage_2d<rgba16float, write>;

@compute @workgroup_size(8, 8)
fn cs_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if (!in_viewport(p)) {
        return;
    }
    let ray = analytic_ray(p);
    var out = vec4<f32>(0.0);
    if (ray.len > 0.0 && ray_is_valid(ray.u0, ray.d, ray.len)) {
        let s = pixel_samples(ray, p);
        let g = mip_window(brightest_sample(s), mip.level, mip.width);
        out = vec4<f32>(g, g, g, 1.0);
    }
    textureStore(color, vec2<i32>(p), out);
}
