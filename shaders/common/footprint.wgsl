// The volume's screen footprint as a draw: a fan of triangles over the polygon the frame block
// carries (`frame.footprint`, crates/core/src/runtime/footprint.rs), the pixels whose ray meets
// the box grown by a pixel. A fragment pass that writes zeros where a pixel has no ray draws it
// instead of the fullscreen triangle (`RecordContext::draw_footprint`, draw 0..30, its targets
// cleared to zeros first): no fragment outside the footprint runs. llvmpipe runs every line of a
// fragment shader for every pixel it draws, branches and all, so the ray set-up, the shading
// after the loop and the writes of the pixels around the volume were most of a raycast's fixed
// cost (bench/one-march-final.md, "Footprint draws").

#import "common/frame.wgsl"
#import "common/fullscreen.wgsl"

// The polygon's most vertices (`FAN_VERTICES` in Rust); a footprint with more covers the
// viewport.
const FOOTPRINT_FAN_VERTICES: u32 = 12u;

fn footprint_vertex(k: u32) -> vec2<f32> {
    let pair = frame.footprint[k / 2u];
    return select(pair.xy, pair.zw, (k & 1u) == 1u);
}

// Clip position (depth 0) of vertex `vertex_index` (0..30) of the fan: triangle
// t = vertex_index / 3 is (0, t + 1, t + 2); triangles past the polygon collapse to a point,
// which the rasterizer drops. A footprint wider than the fan draws the fullscreen triangle as
// triangle 0. Passes that draw at a depth of their own (KW03's segments and termination test)
// take the position from here.
fn footprint_position(vertex_index: u32) -> vec4<f32> {
    var n = frame.footprint_vertices;
#if FUSION_SCALAR
    // With several scalar volumes rays cross the union of their boxes (common/ray_box.wgsl
    // march_lo/hi), which the footprint — the frame volume's box — does not cover: the whole
    // viewport, its pixels without a ray writing zeros.
    n = FOOTPRINT_FAN_VERTICES + 1u;
#endif
    let t = vertex_index / 3u;
    let corner = vertex_index % 3u;
    let collapsed = vec4<f32>(-2.0, -2.0, 0.0, 1.0);
    if (n > FOOTPRINT_FAN_VERTICES) {
        return select(collapsed, fullscreen_position(corner), t == 0u);
    }
    if (t + 2u >= n) {
        return collapsed;
    }
    let p = footprint_vertex(select(t + corner, 0u, corner == 0u));
    let ndc = vec2<f32>(2.0 * p.x * frame.viewport.z - 1.0, 1.0 - 2.0 * p.y * frame.viewport.w);
    return vec4<f32>(ndc, 0.0, 1.0);
}

@vertex
fn vs_footprint(@builtin(vertex_index) vertex_index: u32) -> FullscreenVertex {
    return FullscreenVertex(footprint_position(vertex_index));
}
