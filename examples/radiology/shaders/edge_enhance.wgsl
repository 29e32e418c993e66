// A WGSL-only pass (no Rust): unsharp masking, the edge enhancement radiology viewers apply to
// make vessel borders crisp. Declared in the graph that uses it (graphs/mip_enhanced.ron):
//   inputs {"color": Target}, outputs {"enhanced": Rgba16Float}, params [strength, radius].
// The parameter block is laid out by volgraph from that list, one f32 each, in order.

struct Params {
    strength: f32,
    radius: f32,
}

@group(0) @binding(auto) var<uniform> params: Params;
@group(0) @binding(auto) var color: texture_2d<f32>;
@group(0) @binding(auto) var enhanced: texture_storage_2d<rgba16float, write>;

// The pixel at `p`, clamped to the image.
fn at(p: vec2<i32>) -> vec4<f32> {
    let size = vec2<i32>(textureDimensions(color));
    return textureLoad(color, clamp(p, vec2<i32>(0), size - vec2<i32>(1)), 0);
}

@compute @workgroup_size(8, 8)
fn cs_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(color);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let p = vec2<i32>(id.xy);
    let r = i32(params.radius);
    // The mean of the 4 neighbours `radius` pixels away: the blurred image of the mask.
    let blur = 0.25 * (at(p + vec2<i32>(r, 0)) + at(p - vec2<i32>(r, 0)) + at(p + vec2<i32>(0, r)) + at(p - vec2<i32>(0, r)));
    let c = at(p);
    let sharp = clamp(c + params.strength * (c - blur), vec4<f32>(0.0), vec4<f32>(1.0));
    textureStore(enhanced, p, vec4<f32>(sharp.rgb, c.a));
}
