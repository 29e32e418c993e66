// Krüger & Westermann 2003 §2.1, pass 1 (entry point determination): the texture-space point
// where each pixel's ray enters the volume, written to the `entry` target as (u, 1); pixels
// whose ray misses keep the clear value (0,0,0,0).
//
// Two pipelines share this module:
// - `vs_box` + `fs_entry`: the box's front faces (`front_face: Ccw, cull_mode: Back`), the ray's
//   entry at t_in (docs/rendering_model.md "Ray segment inside the box").
// - `vs_fullscreen` + `fs_near_plane`: one screen-covering triangle writing the near-plane point
//   of each pixel's ray where that point is inside the box, i.e. where t_near > t_in and the front
//   face was clipped away (camera inside or touching the volume). Where it is outside the box the
//   fragment is discarded, so both pipelines can draw into the same target in either order: at a
//   pixel at most one of them writes (the front face is clipped exactly where the near-plane
//   point is inside).

#import "common/frame.wgsl"
#import "common/box_vertex.wgsl"
#import "common/fullscreen.wgsl"

struct EntryOut {
    @location(0) entry: vec4<f32>,
}

// Front faces: the entry point (u, 1).
@fragment
fn fs_entry(in: BoxVertex) -> EntryOut {
    return EntryOut(vec4<f32>(clamp(in.u, grid_box_lo(), grid_box_hi()), 1.0));
}

// The near-plane point of the ray through this pixel's centre, (u, 1), or discard when it lies
// outside [0,1]³.
@fragment
fn fs_near_plane(in: FullscreenVertex) -> EntryOut {
    // `position.xy` is the pixel centre in framebuffer coordinates (row 0 at the top).
    let ndc = vec2<f32>(2.0 * in.clip.x * frame.viewport.z - 1.0, 1.0 - 2.0 * in.clip.y * frame.viewport.w);
    let p = frame.world_from_clip * vec4<f32>(ndc, 0.0, 1.0);
    let u = texture_from_world(p.xyz / p.w);
    if (any(u < grid_box_lo()) || any(u > grid_box_hi())) {
        discard;
    }
    return EntryOut(vec4<f32>(u, 1.0));
}
