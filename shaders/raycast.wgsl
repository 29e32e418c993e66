// The single-pass fragment raycaster (Krüger & Westermann 2003 §2.1 "main passes" folded into
// one loop, §2.2 for the isosurface): a screen-covering triangle reads each pixel's entry point
// (`entry`, pass 1) and direction/length (`dir`, pass 2) and marches the shared integral of
// common/raymarch.wgsl (docs/rendering_model.md).
//
// Pipelines: `vs_fullscreen` + `fs_dvr` → `color`; `vs_fullscreen` + `fs_iso` → `color`, `hit`.

#import "common/frame.wgsl"
#import "common/fullscreen.wgsl"
#import "common/raymarch.wgsl"

// (u0, 1) where the pixel's ray enters the box, (0,0,0,0) where it misses.
@group(0) @binding(5) var entry: texture_2d<f32>;
// (d_tex, len_tex); (0,0,0,0) for no ray.
@group(0) @binding(6) var dir: texture_2d<f32>;

struct RaycastOut {
    @location(0) color: vec4<f32>,
}

// Direct volume rendering: premultiplied linear RGBA over a transparent background.
@fragment
fn fs_dvr(in: FullscreenVertex) -> RaycastOut {
    let pixel = vec2<u32>(in.clip.xy);
    let e = textureLoad(entry, vec2<i32>(pixel), 0);
    let d = textureLoad(dir, vec2<i32>(pixel), 0);
    var color = vec4<f32>(0.0);
    if (e.w != 0.0) {
        color = march_dvr(e.xyz, d.xyz, d.w, pixel);
    }
    return RaycastOut(color);
}

struct IsoOut {
    @location(0) color: vec4<f32>,
    @location(1) hit: vec4<f32>,
}

// First-hit isosurface: shaded colour (alpha 1) and texture-space hit (w = 1), zero on a miss.
@fragment
fn fs_iso(in: FullscreenVertex) -> IsoOut {
    let pixel = vec2<u32>(in.clip.xy);
    let e = textureLoad(entry, vec2<i32>(pixel), 0);
    let d = textureLoad(dir, vec2<i32>(pixel), 0);
    var result = IsoResult(vec4<f32>(0.0), vec4<f32>(0.0));
    if (e.w != 0.0) {
        result = march_iso(e.xyz, d.xyz, d.w, pixel);
    }
    return IsoOut(result.color, result.hit);
}
