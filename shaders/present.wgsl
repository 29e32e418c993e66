// `present`: linear premultiplied RGBA → 8-bit sRGB over a grey background, one compute
// invocation per pixel into `display` (Rgba8Unorm holding sRGB-encoded values). A compute pass:
// on llvmpipe it costs a third of the fullscreen-triangle draw it replaced, and on data-centre
// GPUs compute is the fast path.

// Declared once: `PresentParams` (pass_params!) in crates/passes/src/present.rs,
// which generates the struct imported here.
#import "params/PresentParams.wgsl"

@group(0) @binding(auto) var color: texture_2d<f32>;
@group(0) @binding(auto) var<uniform> params: PresentParams;
@group(0) @binding(auto) var display: texture_storage_2d<rgba8unorm, write>;

// The sRGB transfer function (IEC 61966-2-1), its power segment 1.055·c^(1/2.4) − 0.055 fitted
// with three nested square roots (c^(1/2), c^(1/4), c^(1/8) and c; Taylor's fit): within
// 0.25/255 of the exact curve over [0.0031308, 1], so an 8-bit code differs by one for ~1.6 %
// of inputs and never by more (crates/passes/tests/present.rs). On llvmpipe a pow costs a
// logarithm and an exponential per channel, and the pass took 4 % of a `fastest` frame.
fn srgb_encode(linear: vec3<f32>) -> vec3<f32> {
    let c = clamp(linear, vec3<f32>(0.0), vec3<f32>(1.0));
    let low = c * 12.92;
    let s1 = sqrt(c);
    let s2 = sqrt(s1);
    let s3 = sqrt(s2);
    let high = 0.662002687 * s1 + 0.684122060 * s2 - 0.323583601 * s3 - 0.0225411470 * c;
    return select(high, low, c <= vec3<f32>(0.0031308));
}

@compute @workgroup_size(8, 8)
fn cs_present(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(display);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let c = textureLoad(color, vec2<i32>(id.xy), 0);
    let over = c.rgb + (1.0 - c.a) * vec3<f32>(params.background);
    textureStore(display, vec2<i32>(id.xy), vec4<f32>(srgb_encode(over), 1.0));
}
