// The fetch ceiling (`volgraph bench fetch`): every sample a raycaster with this step would take
// along the pixel's ray through the box — common/ray_box.wgsl's rays and samples, no
// leaping, no termination — and nothing else: no classification, no compositing. What it
// writes (the mean scalar along the ray, an average-intensity projection) only keeps the
// samples from being optimised away. Its samples per second bound those of any raycaster on this
// device, volume and texture format.

#import "common/frame.wgsl"
#import "common/raymarch.wgsl"

override WORKGROUP_X: u32 = 8u;
override WORKGROUP_Y: u32 = 8u;

@group(0) @binding(auto) var color: texture_storage_2d<rgba16float, write>;
// Samples taken per image row (as common/pixel_march.wgsl's).
@group(0) @binding(auto) var<storage, read_write> samples: array<atomic<u32>>;
const SAMPLE_ROWS: u32 = 4096u;

struct Fetched {
    mean: f32,
    samples: u32,
}

fn fetch_ray(p: vec2<u32>) -> Fetched {
    let s = pixel_samples(analytic_ray(p), p);
    var sum = 0.0;
    for (var k = 0u; k < s.count; k += 1u) {
        sum += sample_volume(sample_at(s, k));
    }
    return Fetched(sum / f32(max(s.count, 1u)), s.count);
}

@compute @workgroup_size(WORKGROUP_X, WORKGROUP_Y)
fn cs_main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (!in_viewport(id.xy)) {
        return;
    }
    let f = fetch_ray(id.xy);
    textureStore(color, vec2<i32>(id.xy), vec4<f32>(vec3<f32>(f.mean), 1.0));
}

@compute @workgroup_size(WORKGROUP_X, WORKGROUP_Y)
fn cs_counted(@builtin(global_invocation_id) id: vec3<u32>) {
    if (!in_viewport(id.xy)) {
        return;
    }
    let f = fetch_ray(id.xy);
    textureStore(color, vec2<i32>(id.xy), vec4<f32>(vec3<f32>(f.mean), 1.0));
    atomicAdd(&samples[id.y % SAMPLE_ROWS], f.samples);
}
