// Frame-wide uniforms, bound as `frame` by every pass that declares it.
// Rust twin: `volgraph_core::runtime::FrameUniforms` (crates/core/src/runtime/frame.rs); keep both in step.
// Conventions: docs/rendering_model.md.

struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_clip: mat4x4<f32>,
    // The previous frame's world -> clip (this frame's on the first frame and after history
    // invalidation): Klein et al. 2005 reproject last frame's hits with it.
    prev_clip_from_world: mat4x4<f32>,
    // xyz: eye position (world); w: 1.0 when the eye is inside the volume box, else 0.0.
    eye_world: vec4<f32>,
    // xyz: half size of the volume box (world); w: unit step (world length of the smallest voxel side).
    half_extent: vec4<f32>,
    // xyz: volume dimensions in voxels; w: the transfer function's opacity unit in voxels (1 for
    // opacity per voxel, 1/unit_world for opacity per world unit).
    volume_dims: vec4<f32>,
    // x, y: viewport width and height in pixels; z, w: their reciprocals.
    viewport: vec4<f32>,
    // xyz: unit camera forward (world); w: near-plane distance.
    camera_forward: vec4<f32>,
    // xyz: the eye in texture space.
    eye_texture: vec4<f32>,
    // The texture-space pixel ray: pixel centre (x, y) looks along ray_base + x·ray_dx + y·ray_dy,
    // scaled to advance one world unit along camera_forward per unit of the ray parameter (the
    // near plane is at parameter camera_forward.w). See common/ray_box.wgsl.
    ray_base_texture: vec4<f32>,
    ray_dx_texture: vec4<f32>,
    ray_dy_texture: vec4<f32>,
    // Frames the runtime submitted before this one.
    frame_index: u32,
    // Frames since history was invalidated: 0 while history holds initial values.
    history_age: u32,
    _pad0: u32,
    _pad1: u32,
    // Sort-last windows (docs/scaling.md): the box rays are met with, whose entry anchors the
    // step grid, and the box whose samples this frame takes, both in texture space. grid_lo.w =
    // 1 when the bound volume is a window of a larger one; otherwise both boxes are [0,1]³.
    grid_lo: vec4<f32>,
    grid_hi: vec4<f32>,
    own_lo: vec4<f32>,
    own_hi: vec4<f32>,
    // A scene's crop box (read under #if CROP) and clip planes (#if CLIP: keep u with
    // dot(xyz, u) >= w; unused planes (0, 0, 0, -1)), in the bound texture's coordinates
    // (common/ray_box.wgsl `cut_segment`). crop_lo.w: which crop faces are cuts (bit a: the low
    // face of axis a, bit 3 + a: the high one), for capping.
    crop_lo: vec4<f32>,
    crop_hi: vec4<f32>,
    clip_planes: array<vec4<f32>, 6>,
    // The volume's screen footprint grown by a pixel (crates/core/src/runtime/footprint.rs): the
    // vertices of a convex polygon in pixels, two per entry (xy, zw), that vs_footprint
    // (common/footprint.wgsl) draws; footprint_vertices of them, 0 for none, 0xffffffff for the
    // whole viewport.
    footprint: array<vec4<f32>, 6>,
    footprint_vertices: u32,
    // How many of `lights` the scene has (1 to MAX_LIGHTS).
    light_count: u32,
    _pad3: u32,
    _pad4: u32,
    // The scene's lights, the key light first. w = 1: xyz the unit world direction toward a
    // directional light; w = 2: xyz a point light's world position (the bound box's own world);
    // w = 0: the headlight (each ray's own -direction). volgraph_accel::light.
    lights: array<vec4<f32>, MAX_LIGHTS>,
}

// volgraph_accel::light::MAX_LIGHTS.
const MAX_LIGHTS: u32 = 3u;

@group(0) @binding(auto) var<uniform> frame: Frame;

// True when the bound volume is a window of a larger one (sort-last rendering). The window's
// code is compiled in only where a window is set (WINDOW, a frame define like the cuts'): every
// ray's set-up pays for it otherwise, and a pass that runs per pixel and per segment (KW03's
// termination test) took 1.2× the time with it (bench/one-march-final.md).
fn is_window() -> bool {
#if WINDOW
    return frame.grid_lo.w != 0.0;
#else
    return false;
#endif
}

// World position -> texture-space position (docs/rendering_model.md "Volume and world space").
fn texture_from_world(p: vec3<f32>) -> vec3<f32> {
    return p / (2.0 * frame.half_extent.xyz) + vec3<f32>(0.5);
}

// Texture-space position -> world position.
fn world_from_texture(u: vec3<f32>) -> vec3<f32> {
    return (u - vec3<f32>(0.5)) * (2.0 * frame.half_extent.xyz);
}

// Unit world-space direction of the ray through pixel centre `pixel` (in pixels, row 0 at top).
fn pixel_ray_dir(pixel: vec2<f32>) -> vec3<f32> {
    let ndc = vec2<f32>(2.0 * pixel.x * frame.viewport.z - 1.0, 1.0 - 2.0 * pixel.y * frame.viewport.w);
    let a = frame.world_from_clip * vec4<f32>(ndc, 0.0, 1.0);
    let b = frame.world_from_clip * vec4<f32>(ndc, 1.0, 1.0);
    return normalize(b.xyz / b.w - a.xyz / a.w);
}

// True when pixel (or compute invocation) `p` lies in the viewport; compute grids are rounded up
// to whole workgroups.
fn in_viewport(p: vec2<u32>) -> bool {
    return f32(p.x) < frame.viewport.x && f32(p.y) < frame.viewport.y;
}
