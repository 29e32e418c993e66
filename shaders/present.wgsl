// `present`: linear premultiplied RGBA → 8-bit sRGB over a grey background.
// Pipeline: `vs_fullscreen` + `fs_present` → `display` (Rgba8Unorm holding sRGB-encoded values).

#import "common/fullscreen.wgsl"

// Rust twin: `PresentParamsGpu` in crates/passes/src/present.rs.
struct PresentParams {
    // Linear grey level behind the volume.
    background: f32,
    _pad0: f32,
    _pad1: f32,
    _pad2: f32,
}

@group(0) @binding(0) var color: texture_2d<f32>;
@group(0) @binding(1) var<uniform> params: PresentParams;

struct PresentOut {
    @location(0) display: vec4<f32>,
}

// The sRGB transfer function (IEC 61966-2-1).
fn srgb_encode(linear: vec3<f32>) -> vec3<f32> {
    let c = clamp(linear, vec3<f32>(0.0), vec3<f32>(1.0));
    let low = c * 12.92;
    let high = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(high, low, c <= vec3<f32>(0.0031308));
}

@fragment
fn fs_present(in: FullscreenVertex) -> PresentOut {
    let c = textureLoad(color, vec2<i32>(in.clip.xy), 0);
    let over = c.rgb + (1.0 - c.a) * vec3<f32>(params.background);
    return PresentOut(vec4<f32>(srgb_encode(over), 1.0));
}
