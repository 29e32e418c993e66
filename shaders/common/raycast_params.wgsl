// Raycasting settings, bound as `params`.
// Declared once: `RaycastParamsGpu` (pass_params!, filled from the parameter blocks) in
// crates/passes/src/raycast_params.rs, whose test compares the two; it mirrors
// `volgraph_accel::reference::RaycastSettings`.

struct RaycastParams {
    // Sample distance in units of the smallest voxel side (docs/rendering_model.md "Step").
    step_voxels: f32,
    // Early ray termination: stop after the sample that makes A >= threshold.
    threshold: f32,
    // Upper bound on samples per ray.
    max_steps: u32,
    // 1: offset the first sample by the per-pixel PCG jitter; 0: no jitter.
    jitter: u32,
    // First-hit isosurface value (normalized scalar).
    iso_value: f32,
    // Blinn–Phong headlight coefficients (docs/rendering_model.md "First-hit isosurface").
    ambient: f32,
    diffuse: f32,
    specular: f32,
    shininess: f32,
    // Klein et al. 2005 §4.2: samples a leap hit is moved back along the ray.
    step_back: f32,
    _pad1: f32,
    _pad2: f32,
}

@group(0) @binding(auto) var<uniform> params: RaycastParams;
