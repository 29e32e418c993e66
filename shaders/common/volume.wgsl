// The scalar volume and its transfer function, bound as `volume`, `linear_clamp` and `tf`.
// Conventions: docs/rendering_model.md ("Volume and world space", "Classification").

// Normalized scalar values, sampled trilinearly with clamp-to-edge: s(u) of the rendering model.
@group(0) @binding(1) var volume: texture_3d<f32>;
// Filtering sampler, clamp-to-edge on every axis (used for `volume` and `tf`).
@group(0) @binding(2) var linear_clamp: sampler;
// The transfer-function LUT as an N×1 RGBA texture (straight colour, alpha per unit step).
@group(0) @binding(3) var tf: texture_2d<f32>;

// s(u): the normalized scalar at texture-space position `u`.
fn sample_volume(u: vec3<f32>) -> f32 {
    return textureSampleLevel(volume, linear_clamp, u, 0.0).r;
}

// The LUT at scalar `s`: linear between texel centres (i+0.5)/N, clamped at the ends.
fn sample_tf(s: f32) -> vec4<f32> {
    return textureSampleLevel(tf, linear_clamp, vec2<f32>(s, 0.5), 0.0);
}
