// The `shadows` scene effect (crates/passes/src/shadows.rs; Behrens & Ratering 1998's shadow
// volume; the f64 model is volgraph_accel::light::LightGrid): the light volume holds, on a grid
// of up to 64³ over the volume's box, the transmittance toward the scene's light through the
// classified volume, and each sample reads it where it lies. Compiled in only with SHADOWS.

@group(0) @binding(auto) var light_volume: texture_3d<f32>;

// The light reaching texture point `u` of the texture sampled (a brick atlas maps back to the
// volume's space: `volume_position`), trilinear between the grid's voxel centres, clamped to its
// edge as LightGrid::sample is.
fn light_transmittance(u: vec3<f32>) -> f32 {
    return textureSampleLevel(light_volume, linear_clamp, volume_position(u), 0.0).r;
}
