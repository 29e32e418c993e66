// Maximum-intensity projection as a WGSL-only pass kind, declared in the graph that uses it
// (graphs/basic/mip.ron) with no Rust: the brightest sample along each pixel's ray, windowed by
// level and width — the view radiologists read angiography in. The rays are volgraph's own
// (common/ray_box.wgsl: the box met analytically) and the samples sit where every raycaster's
// do, (k + 0.5) steps from the entry, so `volgraph_accel::mip::mip_pixel` is its f64 reference.
//
// The kind declares inputs {"volume": Volume}, outputs {"color": Rgba16Float} and the
// parameters below; volgraph fills `params` from that list, one f32 each, in order.

#import "common/ray_box.wgsl"
#import "common/mip.wgsl"

struct Params {
    level: f32,
    width: f32,
    step_voxels: f32,
}

@group(0) @binding(auto) var<uniform> params: Params;
@group(0) @binding(auto) var color: texture_storage_2d<rgba16float, write>;

// At most this many samples per ray (a 4096³ volume's diagonal at step 0.25 is ~28k).
const MAX_SAMPLES: u32 = 65536u;

@compute @workgroup_size(8, 8)
fn cs_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if (f32(p.x) >= frame.viewport.x || f32(p.y) >= frame.viewport.y) {
        return;
    }
    let ray = analytic_ray(p);
    var out = vec4<f32>(0.0);
    if (ray.len > 0.0) {
        let s = samples_along(ray, step_tex_for(params.step_voxels, ray.d), 0.0, MAX_SAMPLES);
        let g = mip_window(brightest_sample(s), params.level, params.width);
        out = vec4<f32>(g, g, g, 1.0);
    }
    textureStore(color, vec2<i32>(p), out);
}
