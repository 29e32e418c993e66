// Presenting a graph output on a window surface, sRGB-correct: the output is either linear
// colour (a raycaster's float `image`) or already sRGB-encoded 8-bit (`present`'s `display`);
// the surface either encodes in hardware (an *Srgb format) or expects encoded values.
// The output is scaled to its region of the surface (the whole surface, or the viewer's image
// beside its panel; the pass's viewport) with nearest sampling (equal sizes in steady state).

struct BlitParams {
    // 1: the source holds sRGB-encoded values.
    source_encoded: u32,
    // 1: the surface format is not sRGB, so the shader must write encoded values.
    surface_wants_encoded: u32,
    // The region's corner and size on the surface, pixels.
    region_origin: vec2<f32>,
    region_size: vec2<f32>,
}

@group(0) @binding(0) var source: texture_2d<f32>;
@group(0) @binding(1) var<uniform> params: BlitParams;

@vertex
fn vs_blit(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    return select(pow((c + vec3<f32>(0.055)) / 1.055, vec3<f32>(2.4)), c / 12.92, c <= vec3<f32>(0.04045));
}

fn linear_to_srgb(c: vec3<f32>) -> vec3<f32> {
    let x = clamp(c, vec3<f32>(0.0), vec3<f32>(1.0));
    return select(1.055 * pow(x, vec3<f32>(1.0 / 2.4)) - 0.055, x * 12.92, x <= vec3<f32>(0.0031308));
}

@fragment
fn fs_blit(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let size = vec2<f32>(textureDimensions(source));
    let texel = vec2<i32>(clamp(floor((p.xy - params.region_origin) / params.region_size * size), vec2<f32>(0.0), size - 1.0));
    var rgb = textureLoad(source, texel, 0).rgb;
    if (params.source_encoded == 1u && params.surface_wants_encoded == 0u) {
        rgb = srgb_to_linear(rgb);
    } else if (params.source_encoded == 0u && params.surface_wants_encoded == 1u) {
        rgb = linear_to_srgb(rgb);
    }
    return vec4<f32>(rgb, 1.0);
}
