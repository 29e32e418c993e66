// Krüger & Westermann 2003 §2.3's blocks, as `volgraph_accel::minmax::MinMaxGrid` lays them out:
// block b covers u ∈ [b·B/n, min((b+1)·B, n)/n] per axis. The grids of empty flags
// (common/empty_blocks.wgsl) and of distances (common/empty_cubes.wgsl) look blocks up here.
// Each range includes a one-voxel apron, so it also bounds samples up to half a voxel beyond its
// block's faces, which absorbs the f32 rounding of look-ups and box exits (a position an ulp
// from a face may find the block on either side).

#import "common/frame.wgsl"

// The grids are read through the non-filtering sampler at texel centres (`block_texel`) rather
// than with `textureLoad`: 1.7× less time for this lookup (8.7 against 5.0 % of a `fastest`
// frame on hydrogen; bench/one-march-final.md, "llvmpipe profile").
#import "common/nearest_clamp.wgsl"

// The constants of block look-ups, read once per leap (common/leap_empty.wgsl's `LeapGrid`).
struct BlockGrid {
    // Blocks per texture-space unit (n / B) and its inverse (B / n), per axis.
    blocks_per_unit: vec3<f32>,
    units_per_block: vec3<f32>,
    // The last block's index per axis.
    last: vec3<i32>,
    // One texel of the grid's texture, in its texture coordinates.
    texel: vec3<f32>,
}

// The grid of blocks of edge `edge` voxels whose texture has `dims` texels.
fn block_grid(dims: vec3<u32>, edge: u32) -> BlockGrid {
    let n = frame.volume_dims.xyz;
    let b = f32(edge);
    return BlockGrid(n / b, b / n, vec3<i32>(dims) - vec3<i32>(1), vec3<f32>(1.0) / vec3<f32>(dims));
}

// The texture coordinates of block `b`'s texel centre: a nearest lookup there reads texel b.
fn block_texel(b: vec3<i32>, grid: BlockGrid) -> vec3<f32> {
    return (vec3<f32>(b) + vec3<f32>(0.5)) * grid.texel;
}

// The block holding texture-space position `u`: floor(u·n / B), clamped to the grid.
fn block_at(u: vec3<f32>, grid: BlockGrid) -> vec3<i32> {
    return vec3<i32>(clamp(floor(u * grid.blocks_per_unit), vec3<f32>(0.0), vec3<f32>(grid.last)));
}

// The texture-space box of blocks lo..=hi.
fn blocks_box_lo(lo: vec3<i32>, grid: BlockGrid) -> vec3<f32> {
    return vec3<f32>(lo) * grid.units_per_block;
}

fn blocks_box_hi(hi: vec3<i32>, grid: BlockGrid) -> vec3<f32> {
    return min(vec3<f32>(hi + vec3<i32>(1)) * grid.units_per_block, vec3<f32>(1.0));
}
