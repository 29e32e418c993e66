// The illumination volume of the `shadows` and `ambient_occlusion` effects on the GPU
// (crates/passes/src/shadows.rs; the f64 model is volgraph_accel::light::LightGrid, which the
// reference calls). At each voxel centre u0 = (i + 0.5) / m of a grid of m voxels per axis (the
// volume's, up to 64):
// - SHADOWS (Behrens & Ratering 1998's shadow volume, per voxel): the transmittance toward each
//   of the scene's lights T = Π_{k≥1} (1 − α_tf(s(u0 + k·Δ)))^e, Δ one unit_world toward the light in texture
//   space, k up to the last step inside the box, e = 1 / opacity unit, the sample at u0 itself
//   left out (a surface does not shadow itself); below 1/1024 the light is out;
// - AMBIENT_OCCLUSION (Hernell et al. 2010, cones reduced to rays): the mean transmittance along
//   14 directions (the axes and the diagonals) over 8 steps each (fewer where the box ends).
// Built by the raycaster that reads it when the volume, TF, light or opacity unit change, into
// `light_out` (Rgba16Float: each light's T in .rgb in the scene's order, AO in .a; 1 for an
// effect that is off and a light the scene does not have).

#import "common/raymarch.wgsl"

@group(0) @binding(auto) var light_out: texture_storage_3d<rgba16float, write>;

// volgraph_accel::light::MIN_TRANSMITTANCE.
const MIN_TRANSMITTANCE: f32 = 1.0 / 1024.0;

// volgraph_accel::light::OCCLUSION_STEPS.
const OCCLUSION_STEPS: u32 = 8u;

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

// The transmittance from `u0` along `step` over at most `max_steps` steps (light::LightGrid's
// `along`); what the scene's crop and clip planes cut away casts no shadow (samples k in the
// kept [begin, end) of common/ray_box.wgsl's cut_segment, the identity without cuts).
fn transmittance_along(u0: vec3<f32>, step: vec3<f32>, max_steps: u32, exponent: f32) -> f32 {
    let steps = min(steps_to_exit(u0, step), max_steps);
    let kept = cut_segment(u0, step, 0.0, 3.0e38);
    var t = 1.0;
    for (var k = 1u; k <= steps; k++) {
        if (!(f32(k) >= kept.x && f32(k) < kept.y)) {
            continue;
        }
        let p = u0 + f32(k) * step;
#if FUSION
        // Several volumes: their combined opacity (common/fusion.wgsl).
        let a = clamp(fused_alpha(p, sample_volume(p)), 0.0, 1.0);
#else
        let a = clamp(sample_tf(sample_volume(p)).a, 0.0, 1.0);
#endif
        if (a >= 1.0) {
            return 0.0;
        }
        t *= pow(1.0 - a, exponent);
        if (t < MIN_TRANSMITTANCE) {
            return 0.0;
        }
    }
    return t;
}

// Whole steps of unit_world toward a point light `distance` away (light::steps_to_light).
fn steps_to_light(distance: f32) -> u32 {
    return u32(clamp(floor(distance / frame.half_extent.w), 0.0, 1e6));
}

// One unit_world along the unit world direction `d`, in texture space (light::light_step_tex).
fn unit_step_toward(d: vec3<f32>) -> vec3<f32> {
    return d * frame.half_extent.w / (2.0 * frame.half_extent.xyz);
}

// The transmittance toward each of the scene's lights from `u0` (.rgb in the scene's order, 1
// for a light it lacks): toward a directional light its direction, toward the headlight the
// eye's along the camera's forward axis; toward a point light (w = 2) this voxel's own
// direction, up to the light (light::Toward).
fn transmittances_toward_lights(u0: vec3<f32>, exponent: f32) -> vec4<f32> {
    var t = vec4<f32>(1.0);
    for (var i = 0u; i < frame.light_count; i++) {
        let light = frame.lights[i];
        var toward = select(-frame.camera_forward.xyz, light.xyz, light.w == 1.0);
        var steps = 0xffffffffu;
        if (light.w == 2.0) {
            let d = light.xyz - world_from_texture(u0);
            let r = length(d);
            toward = select(vec3<f32>(0.0, 1.0, 0.0), d / r, r > 1e-12);
            steps = steps_to_light(r);
        }
        t[i] = transmittance_along(u0, unit_step_toward(toward), steps, exponent);
    }
    return t;
}

// The unoccluded share of the neighbourhood of `u0`: the mean transmittance along the 6 axes,
// then the 8 diagonals (light::OCCLUSION_DIRECTIONS, in that order), OCCLUSION_STEPS each.
fn occlusion_at(u0: vec3<f32>, exponent: f32) -> f32 {
    var sum = 0.0;
    for (var j = 0u; j < 14u; j++) {
        var d: vec3<f32>;
        if (j < 6u) {
            d = vec3<f32>(0.0);
            d[j / 2u] = select(1.0, -1.0, (j & 1u) == 1u);
        } else {
            let c = j - 6u;
            d = normalize(vec3<f32>(select(1.0, -1.0, c >= 4u), select(1.0, -1.0, (c & 2u) != 0u), select(1.0, -1.0, (c & 1u) != 0u)));
        }
        sum += transmittance_along(u0, unit_step_toward(d), OCCLUSION_STEPS, exponent);
    }
    return sum / 14.0;
}

@compute @workgroup_size(4, 4, 4)
fn cs_light_volume(@builtin(global_invocation_id) id: vec3<u32>) {
    let m = textureDimensions(light_out);
    if (any(id >= m)) {
        return;
    }
    let u0 = (vec3<f32>(id) + vec3<f32>(0.5)) / vec3<f32>(m);
    let exponent = 1.0 / frame.volume_dims.w;
#if FUSION
    begin_fusion();
#endif
    var t = vec4<f32>(1.0);
#if SHADOWS
    t = transmittances_toward_lights(u0, exponent);
#endif
    var ao = 1.0;
#if AMBIENT_OCCLUSION
    ao = occlusion_at(u0, exponent);
#endif
    textureStore(light_out, id, vec4<f32>(t.rgb, ao));
}
