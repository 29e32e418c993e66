// The compute raycaster, one invocation per pixel — the DirectCompute thesis's
// `RAYCASTSIMPLE_CS` and, with analytic rays, leaping over cubes of empty blocks, the
// pre-corrected table and sample counting, volgraph's fastest path: the same per-pixel march as
// the fragment raycaster (common/pixel_march.wgsl), written to storage textures. Dispatch
// ceil(w / WORKGROUP_X) × ceil(h / WORKGROUP_Y); invocations outside the viewport return at
// once, after the workgroup has copied the TF into its memory (TF_WORKGROUP, with PREFETCH the
// pipelined sample loop of `sample_loop: "pipelined"`).
//
// Entry points: `cs_dvr` → `color`; `cs_iso` → `color`, `hit`.

#import "common/frame.wgsl"
#import "common/pixel_march.wgsl"

#import "common/workgroup_pixel.wgsl"
#import "common/color_target.wgsl"
// Texture-space hit position (w = 1), zero on a miss; only `cs_iso` writes it.
@group(0) @binding(auto) var hit: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(WORKGROUP_X, WORKGROUP_Y)
fn cs_dvr(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let pixel = begin_invocation(group, local);
    if (!in_viewport(pixel)) {
        return;
    }
    textureStore(color, vec2<i32>(pixel), march_pixel_dvr(pixel).color);
}

@compute @workgroup_size(WORKGROUP_X, WORKGROUP_Y)
fn cs_iso(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let pixel = begin_invocation(group, local);
    if (!in_viewport(pixel)) {
        return;
    }
    let m = march_pixel_iso(pixel);
    textureStore(color, vec2<i32>(pixel), m.color);
    textureStore(hit, vec2<i32>(pixel), m.point);
}
