// The Chebyshev distance map of `empty_distance` over Krüger & Westermann 2003 §2.3's blocks
// (common/block_grid.wgsl), bound as `distance`: per block, the distance in blocks to the
// nearest block that may be visible (0: this one may be), so every block within distance - 1 is
// empty too and a ray leaps out of the largest cube of empty blocks around its sample in one
// step (LEAP_CUBES; false: out of its own block). The importing shader gives the block edge as
// `fn block_edge() -> u32`.

#import "common/frame.wgsl"
#import "common/block_grid.wgsl"
#import "common/leap_empty.wgsl"

override LEAP_CUBES: bool = true;

@group(0) @binding(auto) var distance: texture_3d<f32>;

alias LeapGrid = BlockGrid;

fn leap_grid() -> LeapGrid {
    return block_grid(textureDimensions(distance), block_edge());
}

// The cube of empty blocks around `p` (or its block, which may be visible).
fn empty_region_at(p: vec3<f32>, grid: LeapGrid) -> EmptyRegion {
    let b = block_at(p, grid);
    let dist = textureSampleLevel(distance, nearest_clamp, block_texel(b, grid), 0.0).r;
    let reach = select(0, i32(dist) - 1, LEAP_CUBES && dist >= 1.0);
    let lo = max(b - vec3<i32>(reach), vec3<i32>(0));
    let hi = min(b + vec3<i32>(reach), grid.last);
    return EmptyRegion(dist >= 1.0, blocks_box_lo(lo, grid), blocks_box_hi(hi, grid));
}
