// Krüger & Westermann 2003 §2.3's classification ("CT": is anything in [min, max] visible after
// the transfer function?) evaluated per block on the GPU, mirroring
// `volgraph_accel::classify::OpacityClassifier`: [lo, hi] may be visible iff some texel it
// interpolates (common/lut_range.wgsl) has alpha > 0 (or NaN). That test is one subtraction of `visible_before`, the
// count of such texels before each texel (built by the pass from the LUT it uploads), so a
// block costs the same whatever its range (a loop over the range's texels took ~10 ms of a TF
// edit on the engine's 64³ blocks under lavapipe). Rerun when the grid or the TF changes.
//
// Entry point: `cs_classify` → `empty` (R32Float 3D: 1 = empty, 0 = may be visible).

#import "common/volume.wgsl"
#import "common/lut_range.wgsl"

// The min/max grid of minmax_grid.wgsl (r = min, g = max).
@group(0) @binding(auto) var grid: texture_3d<f32>;
@group(0) @binding(auto) var empty: texture_storage_3d<r32float, write>;
// visible_before[i]: how many texels j < i of the LUT have alpha > 0 or NaN (N + 1 entries).
@group(0) @binding(auto) var<storage, read> visible_before: array<u32>;

@compute @workgroup_size(4, 4, 4)
fn cs_classify(@builtin(global_invocation_id) id: vec3<u32>) {
    let blocks = textureDimensions(empty);
    if (any(id >= blocks)) {
        return;
    }
#if SEGMENTS
    // Pre-integrated segments run between samples in adjacent blocks: the values a segment
    // through this block can take lie in the union of its 3×3×3 neighbourhood's ranges.
    var range = vec2<f32>(3.0e38, -3.0e38);
    var unknown = false;
    let last_block = vec3<i32>(blocks) - vec3<i32>(1);
    for (var dz = -1; dz <= 1; dz += 1) {
        for (var dy = -1; dy <= 1; dy += 1) {
            for (var dx = -1; dx <= 1; dx += 1) {
                let b = clamp(vec3<i32>(id) + vec3<i32>(dx, dy, dz), vec3<i32>(0), last_block);
                let r = textureLoad(grid, b, 0).rg;
                unknown = unknown || r.x != r.x || r.y != r.y;
                range = vec2<f32>(min(range.x, r.x), max(range.y, r.y));
            }
        }
    }
#else
    let range = textureLoad(grid, vec3<i32>(id), 0).rg;
    let unknown = false;
#endif
    let texels = lut_texels_of(range, unknown, i32(textureDimensions(tf)));
    let first = texels.x;
    let last = texels.y;
    let visible = visible_before[last + 1] > visible_before[first];
    textureStore(empty, vec3<i32>(id), vec4<f32>(select(1.0, 0.0, visible), 0.0, 0.0, 0.0));
}
