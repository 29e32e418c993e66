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

// The pixel of invocation `local` of workgroup `group`. Consecutive invocations — the lanes of
// one SIMD vector, 8 on llvmpipe — cover a 4×2 tile of the workgroup's rectangle instead of a
// row of 8, so a vector's rays start closer together and take more alike paths
// (bench/one-march.md: 2 % fewer instructions in the march on hydrogen). A GPU's 32-lane warp
// covers the same 8×4 (or 16×2) pixels either way. Workgroups whose sides are not multiples of 4
// and 2 keep rows.
fn invocation_pixel(group: vec3<u32>, local: u32) -> vec2<u32> {
    var offset = vec2<u32>(local % WORKGROUP_X, local / WORKGROUP_X);
    if (WORKGROUP_X % 4u == 0u && WORKGROUP_Y % 2u == 0u) {
        let tile = local / 8u;
        let lane = local % 8u;
        // At least 1: the constants are folded even where the branch is not taken, and a
        // workgroup narrower than 4 would divide by zero (the pipeline fails to build).
        let tiles_per_row = max(WORKGROUP_X / 4u, 1u);
        offset = vec2<u32>((tile % tiles_per_row) * 4u + lane % 4u, (tile / tiles_per_row) * 2u + lane / 4u);
    }
    return group.xy * vec2<u32>(WORKGROUP_X, WORKGROUP_Y) + offset;
}

// Every invocation of the group copies its share of the LUT, before any returns.
fn load_tf_shared(local: u32) {
    let n = min(textureDimensions(tf), TF_SHARED_MAX);
    for (var i = local; i < n; i = i + WORKGROUP_X * WORKGROUP_Y) {
        tf_shared[i] = textureLoad(tf, i32(i), 0);
    }
    workgroupBarrier();
}

@compute @workgroup_size(WORKGROUP_X, WORKGROUP_Y)
fn cs_dvr(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    load_tf_shared(local);
    let pixel = invocation_pixel(group, local);
    if (!in_viewport(pixel)) {
        return;
    }
    textureStore(color, vec2<i32>(pixel), march_pixel_dvr(pixel).color);
}

@compute @workgroup_size(WORKGROUP_X, WORKGROUP_Y)
fn cs_iso(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    load_tf_shared(local);
    let pixel = invocation_pixel(group, local);
    if (!in_viewport(pixel)) {
        return;
    }
    let m = march_pixel_iso(pixel);
    textureStore(color, vec2<i32>(pixel), m.color);
    textureStore(hit, vec2<i32>(pixel), m.point);
}
