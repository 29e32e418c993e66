// The bounding-box vertex stage shared by Krüger & Westermann 2003 §2.1 passes 1 and 2
// (entry_points.wgsl, ray_directions.wgsl): draw(0..36, 0..1), no vertex buffer.

#import "common/frame.wgsl"
#import "common/box.wgsl"

struct BoxVertex {
    @builtin(position) clip: vec4<f32>,
    // Texture-space position of the box surface point. Interpolated perspective-correctly, so
    // at a pixel centre it is the exact intersection of that pixel's ray with the box face.
    @location(0) u: vec3<f32>,
}

// Box vertex `vertex_index` (0..36): clip position and texture-space position.
@vertex
fn vs_box(@builtin(vertex_index) vertex_index: u32) -> BoxVertex {
    let corner = box_corner(vertex_index);
    var out: BoxVertex;
    if (is_window()) {
        // A sort-last window draws the whole volume's box: its faces anchor the step grid.
        out.u = mix(frame.grid_lo.xyz, frame.grid_hi.xyz, corner * 0.5 + vec3<f32>(0.5));
        out.clip = frame.clip_from_world * vec4<f32>(world_from_texture(out.u), 1.0);
        return out;
    }
    out.clip = frame.clip_from_world * vec4<f32>(corner * frame.half_extent.xyz, 1.0);
    out.u = corner * 0.5 + vec3<f32>(0.5);
    return out;
}

// The box the rays are met with in texture space: [0,1]³, or the whole volume's box in a
// sort-last window.
fn grid_box_lo() -> vec3<f32> {
    return select(vec3<f32>(0.0), frame.grid_lo.xyz, is_window());
}

fn grid_box_hi() -> vec3<f32> {
    return select(vec3<f32>(1.0), frame.grid_hi.xyz, is_window());
}
