// The pre-integration table (Engel et al. 2001) of the transfer function for one step: texel
// (i, j) of an N×N table holds the premultiplied RGBA of a segment of `step_exponent()` opacity
// units along which the scalar runs linearly from s_f = i/(N-1) to s_b = j/(N-1), integrated
// front to back with sub-steps fine enough to resolve every LUT texel the segment crosses (at
// least 4 per texel, at least 64) — `volgraph_accel::reference::preintegrate`, which the CPU
// reference evaluates exactly at every sample. Built by the raycaster that reads it
// (crates/passes/src/preintegration.rs) when the TF or the step changes, as Rgba32Float where
// the device filters it (cs_table32), else Rgba16Float (cs_table16).

#import "common/raymarch.wgsl"

@group(0) @binding(auto) var table32: texture_storage_2d<rgba32float, write>;
@group(0) @binding(auto) var table16: texture_storage_2d<rgba16float, write>;

fn segment(s_front: f32, s_back: f32) -> vec4<f32> {
    let texels = f32(textureDimensions(tf));
    let crossed = ceil(abs(s_back - s_front) * texels);
    let n = u32(clamp(4.0 * crossed, 64.0, 65536.0));
    let dx = step_exponent() / f32(n);
    var acc = vec4<f32>(0.0);
    for (var i = 0u; i < n; i += 1u) {
        let s = s_front + (s_back - s_front) * (f32(i) + 0.5) / f32(n);
        let c = sample_tf(s);
        let ac = clamp(c.a, 0.0, 1.0);
        var a = 1.0;
        if (ac < 1.0) {
            a = 1.0 - pow(1.0 - ac, dx);
        }
        let w = (1.0 - acc.a) * a;
        acc = vec4<f32>(acc.rgb + w * c.rgb, acc.a + w);
    }
    return acc;
}

fn texel(id: vec2<u32>, n: u32) -> vec4<f32> {
    let s = vec2<f32>(id) / f32(n - 1u);
    return segment(s.x, s.y);
}

@compute @workgroup_size(8, 8)
fn cs_table32(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = textureDimensions(table32).x;
    if (id.x < n && id.y < n) {
        textureStore(table32, vec2<i32>(id.xy), texel(id.xy, n));
    }
}

@compute @workgroup_size(8, 8)
fn cs_table16(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = textureDimensions(table16).x;
    if (id.x < n && id.y < n) {
        textureStore(table16, vec2<i32>(id.xy), texel(id.xy, n));
    }
}
