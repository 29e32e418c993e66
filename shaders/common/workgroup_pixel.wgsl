// The compute raycasters' workgroups (raycast_compute.wgsl, raycast_bricks.wgsl): their size,
// overridable per pipeline (the `workgroup_x`/`workgroup_y` parameters; the DirectCompute thesis
// found 16×12 best on its hardware), and which pixel each invocation marches.

#import "common/volume.wgsl"

override WORKGROUP_X: u32 = 8u;
override WORKGROUP_Y: u32 = 8u;

// The pixel of invocation `local` of workgroup `group`. Consecutive invocations — the lanes of
// one SIMD vector, 8 on llvmpipe — cover a 4×2 tile of the workgroup's rectangle instead of a
// row of 8, so a vector's rays start closer together and take more alike paths: 2 % fewer
// instructions in the march on hydrogen (bench/one-march.md); in the brick raycaster the lanes
// cross brick faces closer together, so fewer wait for the others' runs (bench/one-march-final.md,
// "Brick runs"). A GPU's 32-lane warp covers the same 8×4 (or 16×2) pixels either way.
// Workgroups whose sides are not multiples of 4 and 2 keep rows.
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

// What every invocation of a compute raycaster does first: with TF_WORKGROUP (the pipelined
// sample loop, common/volume.wgsl) its share of copying the LUT into workgroup memory, which
// ends with a barrier, so it comes before any invocation returns; then the pixel it marches.
fn begin_invocation(group: vec3<u32>, local: u32) -> vec2<u32> {
#if TF_WORKGROUP
    load_tf_workgroup(local, WORKGROUP_X * WORKGROUP_Y);
#endif
    return invocation_pixel(group, local);
}
