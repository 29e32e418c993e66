// Stretches of a ray inside one label (volgraph_accel::labels::cubes, the label-map analogue of
// the empty-space distance map of Krüger & Westermann 2003 §2.3): per block of the label map
// (`fusion.label_block` voxels a side), its label where the block and a one-voxel apron hold one
// label, and the Chebyshev distance in blocks to the nearest block that does not hold that label
// alone. Every sample in the cube of blocks within distance − 1, or up to half a voxel past it,
// has all 8 corners (and its nearest voxel) of that label, so a march reads the label map
// nowhere along the stretch of the ray inside that cube: at the start of each run `march_dvr`
// (common/raymarch.wgsl) finds the stretch (`begin_label_run`) and classifies its samples with
// `label_known` set, which makes common/fusion.wgsl take the stretch's table entry
// (`label_run_entry`) instead of reading.
//
// Imported by common/raymarch.wgsl with FUSION_LABEL_READS on a device with SUBGROUPS, whose
// march leaves a stretch when any lane of the subgroup does (`subgroupAll`): without it, lanes
// in and out of their stretches would run both loops (measured on llvmpipe with a map of 117
// regions: 20 % slower than reading every sample). Elsewhere, and in marches without runs (the
// path tracer, the light volume), every sample reads (`label_known` stays false).

#import "common/ray_box.wgsl"

@group(0) @binding(auto) var label_cubes: texture_3d<u32>;

// The label map's blocks per texture unit (n / edge), their inverse, and its last block.
var<private> label_blocks_per_unit: vec3<f32>;
var<private> label_units_per_block: vec3<f32>;
var<private> label_last_block: vec3<i32>;
// Where the label map lies: its texture point is volume_position(u) · scale + offset.
var<private> label_point_scale: vec3<f32>;
var<private> label_point_offset: vec3<f32>;

// The constants, once per ray (`begin_ray`, after `begin_fusion`): the map's blocks and where it
// lies.
fn begin_label_cubes() {
    let blocks = textureDimensions(label_cubes);
    let edge = f32(fusion.label_block);
    label_units_per_block = vec3<f32>(edge) / label_n;
    label_blocks_per_unit = label_n / edge;
    label_last_block = vec3<i32>(blocks) - vec3<i32>(1);
    label_point_scale = label_map_scale();
    label_point_offset = label_map_offset();
}

// The sampled texture's point of the label map's texture point `at` (the inverse of the map's
// placement and of `volume_position`).
fn sampled_from_label(at: vec3<f32>) -> vec3<f32> {
    return ((at - label_point_offset) / label_point_scale - sampled_offset) / sampled_scale;
}

// At the start of a run at sample k of `s`: the end of the stretch of samples from k inside the
// cube of one label around sample k (k itself where sample k's block is not of one label, or lies
// outside the map), and that label's table entry in `label_run_entry`.
fn begin_label_run(s: Samples, k: u32) -> u32 {
    let u = sample_at(s, k);
    let at = volume_position(u) * label_point_scale + label_point_offset;
    let b = vec3<i32>(clamp(floor(at * label_blocks_per_unit), vec3<f32>(0.0), vec3<f32>(label_last_block)));
    let texel = textureLoad(label_cubes, b, 0).xy;
    let reach = i32(texel.y) - 1;
    let lo_block = max(b - vec3<i32>(reach), vec3<i32>(0));
    let hi_block = min(b + vec3<i32>(reach), label_last_block);
    // The cube's box in the label map's texture space, then in the sampled texture's (a flipped
    // placement swaps its faces). The blocks' one-voxel apron covers the rounding of both maps
    // and of the box exit, as the empty cubes' does (common/block_grid.wgsl).
    let a = sampled_from_label(vec3<f32>(lo_block) * label_units_per_block);
    let c = sampled_from_label(min(vec3<f32>(hi_block + vec3<i32>(1)) * label_units_per_block, vec3<f32>(1.0)));
    let lo = min(a, c);
    let hi = max(a, c);
    label_run_entry = label_entry(texel.x);
    if (texel.y >= 1u && in_box(at) && all(u >= lo) && all(u <= hi)) {
        return past_box_by(k, u, step_exit(s.delta), lo, hi);
    }
    return k;
}
