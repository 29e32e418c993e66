// The compute raycaster of the DirectCompute thesis (one thread per pixel, `RAYCASTSIMPLE_CS`):
// each invocation reads its pixel's entry point (`entry`) and direction/length (`dir`), marches
// the shared integral of common/raymarch.wgsl (docs/rendering_model.md) and writes storage
// textures. Dispatch ceil(w / WORKGROUP_X) × ceil(h / WORKGROUP_Y); invocations outside the
// viewport return at once.
//
// Entry points: `cs_dvr` → `color`; `cs_iso` → `color`, `hit`.

#import "common/frame.wgsl"
#import "common/raymarch.wgsl"

// Workgroup size, overridable per pipeline (the thesis found 16×12 best on its hardware).
override WORKGROUP_X: u32 = 8u;
override WORKGROUP_Y: u32 = 8u;

// (u0, 1) where the pixel's ray enters the box, (0,0,0,0) where it misses.
@group(0) @binding(auto) var entry: texture_2d<f32>;
// (d_tex, len_tex); (0,0,0,0) for no ray.
@group(0) @binding(auto) var dir: texture_2d<f32>;
// Premultiplied linear RGBA (Rgba32Float when the scene asks for f32 precision).
#if COLOR_F32
@group(0) @binding(auto) var color: texture_storage_2d<rgba32float, write>;
#else
@group(0) @binding(auto) var color: texture_storage_2d<rgba16float, write>;
#endif
// Texture-space hit position (w = 1), zero on a miss; only `cs_iso` writes it.
@group(0) @binding(auto) var hit: texture_storage_2d<rgba32float, write>;

// True when invocation `id` is a pixel of the viewport (the grid is rounded up).
fn pixel_in_viewport(id: vec3<u32>) -> bool {
    return f32(id.x) < frame.viewport.x && f32(id.y) < frame.viewport.y;
}

// Direct volume rendering of one pixel.
@compute @workgroup_size(WORKGROUP_X, WORKGROUP_Y)
fn cs_dvr(@builtin(global_invocation_id) id: vec3<u32>) {
    if (!pixel_in_viewport(id)) {
        return;
    }
    let pixel = id.xy;
    let e = textureLoad(entry, vec2<i32>(pixel), 0);
    let d = textureLoad(dir, vec2<i32>(pixel), 0);
    var result = vec4<f32>(0.0);
    if (e.w != 0.0) {
        result = march_dvr(e.xyz, d.xyz, d.w, pixel);
    }
    textureStore(color, vec2<i32>(pixel), result);
}

// First-hit isosurface of one pixel.
@compute @workgroup_size(WORKGROUP_X, WORKGROUP_Y)
fn cs_iso(@builtin(global_invocation_id) id: vec3<u32>) {
    if (!pixel_in_viewport(id)) {
        return;
    }
    let pixel = id.xy;
    let e = textureLoad(entry, vec2<i32>(pixel), 0);
    let d = textureLoad(dir, vec2<i32>(pixel), 0);
    var result = IsoResult(vec4<f32>(0.0), vec4<f32>(0.0));
    if (e.w != 0.0) {
        result = march_iso(e.xyz, d.xyz, d.w, pixel);
    }
    textureStore(color, vec2<i32>(pixel), result.color);
    textureStore(hit, vec2<i32>(pixel), result.hit);
}
