// Krüger & Westermann 2003 §2.3's classification ("CT": is anything in [min, max] visible after
// the transfer function?) evaluated per block on the GPU, mirroring
// `volgraph_accel::classify::OpacityClassifier`: with a LUT of N texels sampled linearly between
// texel centres (i+0.5)/N and clamped at the ends, [lo, hi] may be visible iff some texel
// i ∈ [ceil(lo·N − 1.5), floor(hi·N + 0.5)] (clamped to the LUT) has alpha > 0 (or NaN), the
// range first widened by VALUE_MARGIN. That test is one subtraction of `visible_before`, the
// count of such texels before each texel (built by the pass from the LUT it uploads), so a
// block costs the same whatever its range (a loop over the range's texels took ~10 ms of a TF
// edit on the engine's 64³ blocks under lavapipe). Rerun when the grid or the TF changes.
//
// Entry point: `cs_classify` → `empty` (R32Float 3D: 1 = empty, 0 = may be visible).

#import "common/volume.wgsl"

// The min/max grid of minmax_grid.wgsl (r = min, g = max).
@group(0) @binding(auto) var grid: texture_3d<f32>;
@group(0) @binding(auto) var empty: texture_storage_3d<r32float, write>;
// visible_before[i]: how many texels j < i of the LUT have alpha > 0 or NaN (N + 1 entries).
@group(0) @binding(auto) var<storage, read> visible_before: array<u32>;

// `volgraph_accel::classify::VALUE_MARGIN`: covers f32 rounding of interpolated values.
const VALUE_MARGIN: f32 = 1e-6;

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
    let texels = i32(textureDimensions(tf));
    let n = f32(texels);
    var first = 0;
    var last = texels - 1;
    // NaN bounds widen to the whole LUT (the conservative choice).
    if (!unknown && range.x == range.x && range.y == range.y) {
        let lo = min(range.x, range.y) - VALUE_MARGIN;
        let hi = max(range.x, range.y) + VALUE_MARGIN;
        first = clamp(i32(clamp(ceil(lo * n - 1.5), -1.0, n)), 0, texels - 1);
        last = clamp(i32(clamp(floor(hi * n + 0.5), -1.0, n)), 0, texels - 1);
    }
    let visible = visible_before[last + 1] > visible_before[first];
    textureStore(empty, vec3<i32>(id), vec4<f32>(select(1.0, 0.0, visible), 0.0, 0.0, 0.0));
}
