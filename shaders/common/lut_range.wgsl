// The LUT texels a value range can reach, shared by the classifiers of the min/max grid
// (empty_space.wgsl: is any of them visible? majorant_grid.wgsl: how opaque is the most opaque?),
// mirroring `volgraph_accel::classify::OpacityClassifier`: with a LUT of N texels sampled
// linearly between texel centres (i+0.5)/N and clamped at the ends, a value in [lo, hi]
// interpolates texels i ∈ [ceil(lo·N − 1.5), floor(hi·N + 0.5)] (clamped to the LUT), the range
// first widened by VALUE_MARGIN.

// `volgraph_accel::classify::VALUE_MARGIN`: covers f32 rounding of interpolated values.
const VALUE_MARGIN: f32 = 1e-6;

// The first and last texel (inclusive) of a LUT of `texels` texels that values in `range`
// (x = min, y = max) interpolate; the whole LUT when a bound is NaN or `unknown` (the
// conservative choice).
fn lut_texels_of(range: vec2<f32>, unknown: bool, texels: i32) -> vec2<i32> {
    let n = f32(texels);
    var first = 0;
    var last = texels - 1;
    if (!unknown && range.x == range.x && range.y == range.y) {
        let lo = min(range.x, range.y) - VALUE_MARGIN;
        let hi = max(range.x, range.y) + VALUE_MARGIN;
        first = clamp(i32(clamp(ceil(lo * n - 1.5), -1.0, n)), 0, texels - 1);
        last = clamp(i32(clamp(floor(hi * n + 0.5), -1.0, n)), 0, texels - 1);
    }
    return vec2<i32>(first, last);
}
