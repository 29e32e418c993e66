// The per-block empty flags of Krüger & Westermann 2003 §2.3 (written by empty_space.wgsl from
// the min/max grid and the transfer function), bound as `empty`: an R32Float 3D texture with
// one texel per block (common/block_grid.wgsl), 1.0 = every trilinear sample inside the block's
// closed texture-space box is fully transparent, 0.0 = may be visible. The importing shader
// gives the block edge B as `fn block_edge() -> u32`.

#import "common/frame.wgsl"
#import "common/block_grid.wgsl"
#import "common/leap_empty.wgsl"

@group(0) @binding(auto) var empty: texture_3d<f32>;

alias LeapGrid = BlockGrid;

fn leap_grid() -> LeapGrid {
    return block_grid(textureDimensions(empty), block_edge());
}

// The block at `p` and its box: empty when its flag says so.
fn empty_region_at(p: vec3<f32>, grid: LeapGrid) -> EmptyRegion {
    let b = block_at(p, grid);
    let flag = textureSampleLevel(empty, nearest_clamp, block_texel(b, grid), 0.0).r;
    return EmptyRegion(flag > 0.5, blocks_box_lo(b, grid), blocks_box_hi(b, grid));
}
