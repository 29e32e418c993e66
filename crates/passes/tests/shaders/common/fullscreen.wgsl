// One triangle covering the whole viewport: draw(0..3, 0..1), no vertex buffer.

// Clip-space position of vertex `vertex_index` (0..3): (-1,-1), (3,-1), (-1,3), at depth 0.
// Counter-clockwise in NDC, so it survives `front_face: Ccw, cull_mode: Back`.
fn fullscreen_position(vertex_index: u32) -> vec4<f32> {
    let x = f32((vertex_index & 1u) << 2u) - 1.0;
    let y = f32((vertex_index & 2u) << 1u) - 1.0;
    return vec4<f32>(x, y, 0.0, 1.0);
}

struct FullscreenVertex {
    // In the fragment stage `clip.xy` is the pixel centre in framebuffer coordinates (row 0 at
    // the top): `vec2<u32>(clip.xy)` is the pixel.
    @builtin(position) clip: vec4<f32>,
}

// One triangle covering the viewport (draw 0..3, no vertex buffer).
@vertex
fn vs_fullscreen(@builtin(vertex_index) vertex_index: u32) -> FullscreenVertex {
    return FullscreenVertex(fullscreen_position(vertex_index));
}
