// The `shadows` effect's light volume on the GPU (crates/passes/src/shadows.rs; Behrens &
// Ratering 1998's shadow volume, computed per voxel; the f64 model is
// volgraph_accel::light::LightGrid, which the reference calls): at each voxel centre
// u0 = (i + 0.5) / m of a grid of m voxels per axis (the volume's, up to 64), the transmittance
// toward the light T = Π_{k≥1} (1 − α_tf(s(u0 + k·Δ)))^e, Δ one unit_world toward the light in
// texture space, k up to the last step inside the box, e = 1 / opacity unit, the sample at u0
// itself left out (a surface does not shadow itself); below 1/1024 the light is out. Built by the
// raycaster that reads it when the volume, TF, light or opacity unit change, into `light_out`
// (Rgba16Float, T in .r).

#import "common/raymarch.wgsl"

@group(0) @binding(auto) var light_out: texture_storage_3d<rgba16float, write>;

// volgraph_accel::light::MIN_TRANSMITTANCE.
const MIN_TRANSMITTANCE: f32 = 1.0 / 1024.0;

// Whole steps `step` from `u0` that stay inside the texture box (light::steps_to_exit).
fn steps_to_exit(u0: vec3<f32>, step: vec3<f32>) -> u32 {
    var t = 1e30;
    for (var a = 0u; a < 3u; a++) {
        if (step[a] > 0.0) {
            t = min(t, (1.0 - u0[a]) / step[a]);
        } else if (step[a] < 0.0) {
            t = min(t, -u0[a] / step[a]);
        }
    }
    return u32(clamp(floor(t), 0.0, 1e6));
}

@compute @workgroup_size(4, 4, 4)
fn cs_light_volume(@builtin(global_invocation_id) id: vec3<u32>) {
    let m = textureDimensions(light_out);
    if (any(id >= m)) {
        return;
    }
    let u0 = (vec3<f32>(id) + vec3<f32>(0.5)) / vec3<f32>(m);
    // Toward the light: a directional light's, else the eye's along the camera's forward axis.
    let toward = select(-frame.camera_forward.xyz, frame.light_world.xyz, frame.light_world.w != 0.0);
    let step = toward * frame.half_extent.w / (2.0 * frame.half_extent.xyz);
    let exponent = 1.0 / frame.volume_dims.w;
    let steps = steps_to_exit(u0, step);
    var t = 1.0;
    for (var k = 1u; k <= steps; k++) {
        let a = clamp(sample_tf(sample_volume(u0 + f32(k) * step)).a, 0.0, 1.0);
        if (a >= 1.0) {
            t = 0.0;
            break;
        }
        t *= pow(1.0 - a, exponent);
        if (t < MIN_TRANSMITTANCE) {
            t = 0.0;
            break;
        }
    }
    textureStore(light_out, id, vec4<f32>(t, 0.0, 0.0, 1.0));
}
