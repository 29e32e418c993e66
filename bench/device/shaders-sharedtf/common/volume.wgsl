// The scalar volume and its transfer function, bound as `volume`, `linear_clamp` and `tf`.
// Conventions: docs/rendering_model.md ("Volume and world space", "Classification").

// Normalized scalar values, sampled trilinearly with clamp-to-edge: s(u) of the rendering model.
@group(0) @binding(auto) var volume: texture_3d<f32>;
// Filtering sampler, clamp-to-edge on every axis (used for `volume` and `tf`).
@group(0) @binding(auto) var linear_clamp: sampler;
// The transfer-function LUT as a 1D RGBA texture of N texels (straight colour, alpha per unit
// step).
@group(0) @binding(auto) var tf: texture_1d<f32>;

// s(u): the normalized scalar at texture-space position `u`, trilinear.
fn sample_trilinear(u: vec3<f32>) -> f32 {
    return textureSampleLevel(volume, linear_clamp, u, 0.0).r;
}

#if TRICUBIC
// s(u) reconstructed with the tricubic B-spline from 8 trilinear fetches (Sigg & Hadwiger 2005,
// GPU Gems 2 ch. 20): per axis the four B-spline weights fold into two linear fetches at offsets
// h0, h1 with weights g0, g1. Clamp-to-edge sampling makes it the B-spline over clamped indices,
// like `Volume::sample_tricubic`.
fn sample_tricubic(u: vec3<f32>) -> f32 {
    let n = vec3<f32>(textureDimensions(volume));
    let p = u * n - vec3<f32>(0.5);
    let i = floor(p);
    let f = p - i;
    let f2 = f * f;
    let f3 = f2 * f;
    let w0 = (vec3<f32>(1.0) - 3.0 * f + 3.0 * f2 - f3) / 6.0;
    let w1 = (3.0 * f3 - 6.0 * f2 + vec3<f32>(4.0)) / 6.0;
    let w2 = (-3.0 * f3 + 3.0 * f2 + 3.0 * f + vec3<f32>(1.0)) / 6.0;
    let w3 = f3 / 6.0;
    let g0 = w0 + w1;
    let g1 = w2 + w3;
    // Fetch positions in voxel-index space, then texture space (voxel centres at (i+0.5)/n).
    let h0 = (i - vec3<f32>(1.0) + w1 / g0 + vec3<f32>(0.5)) / n;
    let h1 = (i + vec3<f32>(1.0) + w3 / g1 + vec3<f32>(0.5)) / n;
    let s000 = sample_trilinear(vec3<f32>(h0.x, h0.y, h0.z));
    let s100 = sample_trilinear(vec3<f32>(h1.x, h0.y, h0.z));
    let s010 = sample_trilinear(vec3<f32>(h0.x, h1.y, h0.z));
    let s110 = sample_trilinear(vec3<f32>(h1.x, h1.y, h0.z));
    let s001 = sample_trilinear(vec3<f32>(h0.x, h0.y, h1.z));
    let s101 = sample_trilinear(vec3<f32>(h1.x, h0.y, h1.z));
    let s011 = sample_trilinear(vec3<f32>(h0.x, h1.y, h1.z));
    let s111 = sample_trilinear(vec3<f32>(h1.x, h1.y, h1.z));
    let x00 = g0.x * s000 + g1.x * s100;
    let x10 = g0.x * s010 + g1.x * s110;
    let x01 = g0.x * s001 + g1.x * s101;
    let x11 = g0.x * s011 + g1.x * s111;
    let y0 = g0.y * x00 + g1.y * x10;
    let y1 = g0.y * x01 + g1.y * x11;
    return g0.z * y0 + g1.z * y1;
}

// s(u): the tricubic B-spline reconstruction.
fn sample_volume(u: vec3<f32>) -> f32 {
    return sample_tricubic(u);
}
#else
// s(u): the normalized scalar at texture-space position `u`, trilinear.
fn sample_volume(u: vec3<f32>) -> f32 {
    return sample_trilinear(u);
}
#endif

// Experiment (bench/device/README.md): the LUT copied into workgroup memory by the compute
// raycaster's entry points (`load_tf_shared`), interpolated by hand: no texture op per sample.
const TF_SHARED_MAX: u32 = 256u;
var<workgroup> tf_shared: array<vec4<f32>, 256>;

// The LUT at scalar `s`: linear between texel centres (i+0.5)/N, clamped at the ends.
fn sample_tf(s: f32) -> vec4<f32> {
    let n = min(textureDimensions(tf), TF_SHARED_MAX);
    let x = clamp(s, 0.0, 1.0) * f32(n) - 0.5;
    let i = clamp(floor(x), 0.0, f32(n - 1u));
    let f = clamp(x - i, 0.0, 1.0);
    let i0 = u32(i);
    let i1 = min(i0 + 1u, n - 1u);
    return mix(tf_shared[i0], tf_shared[i1], f);
}
