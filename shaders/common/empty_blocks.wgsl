// The per-block empty flags of Krüger & Westermann 2003 §2.3 (written by empty_space.wgsl from
// the min/max grid and the transfer function), bound as `empty`: an R32Float 3D texture with
// one texel per block, 1.0 = every trilinear sample inside the block's closed texture-space box
// is fully transparent, 0.0 = may be visible. The blocks are those of
// `volgraph_accel::minmax::MinMaxGrid`: block b covers u ∈ [b·B/n, min((b+1)·B, n)/n] per axis
// and its range includes a one-voxel apron, so it also bounds samples up to half a voxel beyond
// its faces, which absorbs f32 rounding of block look-ups and box exits. The importing shader
// gives the block edge B as `fn block_edge() -> u32`.

#import "common/frame.wgsl"
#import "common/leap_empty.wgsl"

@group(0) @binding(auto) var empty: texture_3d<f32>;

// The block holding texture-space position `u`: floor(u·n / B), clamped to the grid.
fn block_of(u: vec3<f32>) -> vec3<u32> {
    let grid = textureDimensions(empty);
    let b = floor(u * frame.volume_dims.xyz / f32(block_edge()));
    return vec3<u32>(clamp(b, vec3<f32>(0.0), vec3<f32>(grid) - vec3<f32>(1.0)));
}

// The block at `p` and its box: empty when its flag says so.
fn empty_region_at(p: vec3<f32>) -> EmptyRegion {
    let b = block_of(p);
    let n = frame.volume_dims.xyz;
    let edge = block_edge();
    let lo = vec3<f32>(b * edge) / n;
    let hi = min(vec3<f32>((b + vec3<u32>(1u)) * edge), n) / n;
    return EmptyRegion(textureLoad(empty, vec3<i32>(b), 0).r > 0.5, lo, hi);
}
