// Test shader for the runtime's resource kinds: a point list written to a small target, drawn
// as instanced 2x2-pixel quads with vertex pulling (WebGPU has no point size), and a compute
// pass counting lit pixels into a storage buffer with an atomic.
#import "common/fullscreen.wgsl"
#import "common/frame.wgsl"

// --- point_list: texel i of an N×1 target holds point i's NDC position.
struct PointsOut {
    @location(0) points: vec4<f32>,
}

@fragment
fn fs_points(in: FullscreenVertex) -> PointsOut {
    let i = floor(in.clip.x);
    // Pixel centres of a 4-wide grid of points, 8 pixels apart, row 5 of the viewport.
    let px = vec2<f32>(4.0 + 8.0 * i, 5.0);
    let ndc = vec2<f32>(2.0 * px.x * frame.viewport.z - 1.0, 1.0 - 2.0 * px.y * frame.viewport.w);
    return PointsOut(vec4<f32>(ndc, 0.0, 1.0));
}

// --- splat: one instance per point, six vertices per quad.
@group(0) @binding(1) var points: texture_2d<f32>;

@vertex
fn vs_splat(@builtin(vertex_index) v: u32, @builtin(instance_index) i: u32) -> @builtin(position) vec4<f32> {
    let size = textureDimensions(points);
    let p = textureLoad(points, vec2<i32>(i32(i % size.x), i32(i / size.x)), 0).xy;
    let corners = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(-1.0, 1.0),
    );
    // A quad one pixel from the centre each way: 2x2 pixels around a pixel corner... shifted by
    // half a pixel so it covers exactly the 2x2 pixels whose corner is the point's pixel centre.
    let half_pixel = frame.viewport.zw;
    let c = corners[v] * half_pixel * 2.0 * 0.999;
    return vec4<f32>(p + c, 0.0, 1.0);
}

struct SplatOut {
    @location(0) image: vec4<f32>,
}

@fragment
fn fs_splat() -> SplatOut {
    return SplatOut(vec4<f32>(1.0, 0.0, 0.0, 1.0));
}

// --- count_lit: counts[0] += 1 for every pixel with red > 0.5.
@group(0) @binding(2) var image: texture_2d<f32>;
@group(0) @binding(3) var<storage, read_write> counts: array<atomic<u32>>;

@compute @workgroup_size(8, 8)
fn cs_count(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(image);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    if (textureLoad(image, vec2<i32>(id.xy), 0).r > 0.5) {
        atomicAdd(&counts[0], 1u);
    }
    // counts[1]: the frame index the frame contract gave this frame.
    if (id.x == 0u && id.y == 0u) {
        atomicStore(&counts[1], frame.frame_index);
    }
}
