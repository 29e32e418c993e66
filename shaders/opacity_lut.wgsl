// The transfer function pre-multiplied and opacity-corrected for one step (Engel et al. 2001's
// observation that the correction depends only on the TF and the step): texel i holds
// (rgb·α', α') with α' = 1 - (1 - α)^step_voxels at the centre s_i = (i + 0.5)/N of a table N
// times denser than the LUT, so a raycaster pays one filtered lookup and no pow per sample.
// Built by the raycaster that reads it (crates/passes/src/opacity_lut.rs): as Rgba32Float where
// the device filters it (cs_table32; also ~5% faster to sample on llvmpipe), else Rgba16Float
// (cs_table16; 11 significant bits, under 0.2/255 on the composited image). Read with a linear
// sampler at s it equals the exact per-sample correction of common/raymarch.wgsl to second order
// in 1/N (with N = 4096, < 0.1/255 for the peer TFs).

#import "common/raymarch.wgsl"

@group(0) @binding(auto) var table32: texture_storage_2d<rgba32float, write>;
@group(0) @binding(auto) var table16: texture_storage_2d<rgba16float, write>;

// Texel i of an n-texel table.
fn corrected_texel(i: u32, n: u32) -> vec4<f32> {
    let s = (f32(i) + 0.5) / f32(n);
    let c = sample_tf(s);
    let a = corrected_alpha(c.a);
    return vec4<f32>(c.rgb * a, a);
}

@compute @workgroup_size(64)
fn cs_table32(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = textureDimensions(table32).x;
    if (id.x < n) {
        textureStore(table32, vec2<i32>(i32(id.x), 0), corrected_texel(id.x, n));
    }
}

@compute @workgroup_size(64)
fn cs_table16(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = textureDimensions(table16).x;
    if (id.x < n) {
        textureStore(table16, vec2<i32>(i32(id.x), 0), corrected_texel(id.x, n));
    }
}
