// The compute raycaster, one invocation per pixel — the DirectCompute thesis's
// `RAYCASTSIMPLE_CS` and, with analytic rays, leaping over cubes of empty blocks, the
// pre-corrected table and sample counting, volgraph's fastest path: the same per-pixel march as
// the fragment raycaster (common/pixel_march.wgsl), written to storage textures. Dispatch
// ceil(w / WORKGROUP_X) × ceil(h / WORKGROUP_Y); invocations outside the viewport return at
// once.
//
// Entry points: `cs_dvr` → `color`; `cs_iso` → `color`, `hit`.

#import "common/frame.wgsl"
#import "common/pixel_march.wgsl"

// Workgroup size, overridable per pipeline (the thesis found 16×12 best on its hardware).
override WORKGROUP_X: u32 = 8u;
override WORKGROUP_Y: u32 = 8u;

#import "common/color_target.wgsl"
// Texture-space hit position (w = 1), zero on a miss; only `cs_iso` writes it.
@group(0) @binding(auto) var hit: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(WORKGROUP_X, WORKGROUP_Y)
fn cs_dvr(@builtin(global_invocation_id) id: vec3<u32>) {
    if (!in_viewport(id.xy)) {
        return;
    }
    textureStore(color, vec2<i32>(id.xy), march_pixel_dvr(id.xy).color);
}

@compute @workgroup_size(WORKGROUP_X, WORKGROUP_Y)
fn cs_iso(@builtin(global_invocation_id) id: vec3<u32>) {
    if (!in_viewport(id.xy)) {
        return;
    }
    let m = march_pixel_iso(id.xy);
    textureStore(color, vec2<i32>(id.xy), m.color);
    textureStore(hit, vec2<i32>(id.xy), m.point);
}
