// Raycasting settings, bound as `params`.
// Declared once: `RaycastParamsGpu` (pass_params!, filled from the parameter blocks) in
// crates/passes/src/raycast_params.rs, which generates the struct imported here (its members
// documented there); it mirrors `volgraph_accel::reference::RaycastSettings`.

#import "params/RaycastParamsGpu.wgsl"

@group(0) @binding(auto) var<uniform> params: RaycastParamsGpu;
