// Maximum-intensity projection: the brightest sample along a ray, windowed by level and width.
// Shared by the stock WGSL-only kind (graph_kinds/mip_projection.wgsl) and the radiology
// example's Rust pass; `volgraph_accel::mip::mip_pixel` is its f64 reference.

#import "common/ray_box.wgsl"
#import "common/volume.wgsl"

// The largest scalar at the samples `s`.
fn brightest_sample(s: Samples) -> f32 {
    var brightest = 0.0;
    for (var k = 0u; k < s.count; k += 1u) {
        brightest = max(brightest, sample_volume(s.first + f32(k) * s.delta));
    }
    return brightest;
}

// `value` through the window centred on `level`, `width` wide, clamped to [0, 1].
fn mip_window(value: f32, level: f32, width: f32) -> f32 {
    return clamp((value - (level - 0.5 * width)) / width, 0.0, 1.0);
}
