// The per-block empty flags of Krüger & Westermann 2003 §2.3 (written by empty_space.wgsl from
// the min/max grid and the transfer function), bound as `empty`: an R32Float 3D texture with
// one texel per block, 1.0 = every trilinear sample inside the block's closed texture-space box
// is fully transparent, 0.0 = may be visible. The blocks are those of
// `volgraph_accel::minmax::MinMaxGrid`: block b covers u ∈ [b·B/n, min((b+1)·B, n)/n] per axis
// and its range includes a one-voxel apron, so it also bounds samples up to half a voxel beyond
// its faces, which absorbs f32 rounding of block look-ups and box exits.

#import "common/frame.wgsl"

@group(0) @binding(auto) var empty: texture_3d<f32>;

// The block holding texture-space position `u`: floor(u·n / B), clamped to the grid.
fn block_of(u: vec3<f32>, block_size: u32) -> vec3<u32> {
    let grid = textureDimensions(empty);
    let b = floor(u * frame.volume_dims.xyz / f32(block_size));
    return vec3<u32>(clamp(b, vec3<f32>(0.0), vec3<f32>(grid) - vec3<f32>(1.0)));
}

// Whether block `b` is empty under the current transfer function.
fn block_is_empty(b: vec3<u32>) -> bool {
    return textureLoad(empty, vec3<i32>(b), 0).r > 0.5;
}

// The t at which the ray u0 + t·d leaves block b's closed texture-space box (the smallest exit
// over the three slabs; axes the ray runs parallel to never bound it).
fn block_exit_t(b: vec3<u32>, block_size: u32, u0: vec3<f32>, d: vec3<f32>) -> f32 {
    let n = frame.volume_dims.xyz;
    let lo = vec3<f32>(b * block_size) / n;
    let hi = min(vec3<f32>((b + vec3<u32>(1u)) * block_size), n) / n;
    let bound = select(lo, hi, d > vec3<f32>(0.0));
    let t = (bound - u0) / d;
    let t_axis = select(vec3<f32>(3.0e38), t, d != vec3<f32>(0.0));
    return min(t_axis.x, min(t_axis.y, t_axis.z));
}

// The leap rule every empty-space skip uses: the index of the first sample whose t lies past
// block b's exit (t_k = (k + 0.5 + jitter)·step_tex > t_exit), as a float to clamp by the caller.
// The samples leapt over lie inside b's closed box, which its conservative range covers, so a
// skip over an empty block is lossless.
fn first_sample_past_block(b: vec3<u32>, block_size: u32, u0: vec3<f32>, d: vec3<f32>, step_tex: f32, jitter: f32) -> f32 {
    let t_exit = block_exit_t(b, block_size, u0, d);
    return floor(t_exit / step_tex - 0.5 - jitter) + 1.0;
}
