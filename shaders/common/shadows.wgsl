// The `shadows` and `ambient_occlusion` scene effects (crates/passes/src/shadows.rs; the f64
// model is volgraph_accel::light::LightGrid): the illumination volume holds, on a grid of up to
// 64³ over the volume's box, the transmittance toward each of the scene's lights through the
// classified volume (.rgb in the scene's order, Behrens & Ratering 1998) and the unoccluded
// share of each point's neighbourhood (.a, Hernell et al. 2010), and each sample reads them
// where it lies (`illumination_at` in common/raymarch.wgsl). Compiled in only with SHADOWS or
// AMBIENT_OCCLUSION.

@group(0) @binding(auto) var light_volume: texture_3d<f32>;

// The illumination at texture point `u` of the texture sampled (a brick atlas maps back to the
// volume's space: `volume_position`), trilinear between the grid's voxel centres, clamped to its
// edge as LightGrid::sample is.
fn illumination(u: vec3<f32>) -> vec4<f32> {
    return textureSampleLevel(light_volume, linear_clamp, volume_position(u), 0.0);
}

// The light reaching `u` from each of the scene's lights (.rgb in the scene's order).
fn light_transmittance(u: vec3<f32>) -> vec3<f32> {
    return illumination(u).rgb;
}

// The share of the ambient light reaching `u`.
fn ambient_occlusion(u: vec3<f32>) -> f32 {
    return illumination(u).a;
}

