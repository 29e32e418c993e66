// Before the segment loop of Krüger & Westermann 2003 §2.1: the accumulation target RES cleared
// to (0,0,0,0) and the early-z buffer cleared to 0 (every ray live). The clears are the render
// pass's load operations; the pipeline draws nothing and exists so the pass has its targets,
// label and timing like every other pass.
//
// Pipeline: `vs_fullscreen` + `fs_init` → `accum`, depth `depth`.

#import "common/fullscreen.wgsl"

struct InitOut {
    @location(0) accum: vec4<f32>,
}

@fragment
fn fs_init(in: FullscreenVertex) -> InitOut {
    return InitOut(vec4<f32>(0.0));
}

struct InitHitOut {
    @location(0) accum: vec4<f32>,
    @location(1) hit: vec4<f32>,
}

// With a hit target (isosurface segments): both cleared to (0,0,0,0), "no hit yet".
@fragment
fn fs_init_hit(in: FullscreenVertex) -> InitHitOut {
    return InitHitOut(vec4<f32>(0.0), vec4<f32>(0.0));
}
