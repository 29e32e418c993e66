// Krüger & Westermann 2003 §2.1 "intermediate passes" and §2.3: between two segments, write
// the early-z buffer so the next segment's fragments are rejected for rays that are done:
//   z = 1 (MAX) if RES.a >= T, or the next segment has no sample on the ray (the ray left the
//           volume; the paper marks this with alpha 1 in RES, which would change the image's
//           alpha, so it is recomputed here from the same sample sequence instead),
//           or — with empty-space skipping — every sample of the next segment lies in an
//           empty block;
//   z = 0 otherwise (re-enabling a ray that only skipped an empty segment).
// The test runs for segment i+1 after segment i: the instance index of the draw is i+1.
//
// Empty-space test: the paper steps the coarse min/max grid at 8·D, which can step over a
// block corner; here every sample position of the next segment looks up its own block, so
// skipping is lossless (each sample's value is inside its block's conservative range).
//
// Pipelines: `vs_segment` + `fs_terminate` / `fs_terminate_empty` → `depth` (frag_depth,
// compare Always, no colour targets).

#import "common/segment.wgsl"
#import "common/empty_blocks.wgsl"

// The accumulated colour RES after the segment just drawn.
@group(0) @binding(auto) var accum: texture_2d<f32>;

struct DepthOut {
    @builtin(frag_depth) depth: f32,
}

const TERMINATED: f32 = 1.0;
const LIVE: f32 = 0.0;

// Saturated, or no sample left for segment `index`.
fn ray_is_done(pixel: vec2<u32>, s: Samples, index: u32) -> bool {
    let a = textureLoad(accum, vec2<i32>(pixel), 0).a;
    return !(a < segment.threshold) || segment_is_outside(s, index);
}

// True when every sample of segment `index` lies in an empty block: the shared leap
// (common/leap_empty.wgsl) walks the segment block by block and runs off its end, one look-up
// per block it crosses rather than one per sample.
fn segment_is_empty(s: Samples, index: u32) -> bool {
    let r = segment_range(s, index);
    return leap(r.x, s, r.y, leaping_for(s)) >= r.y;
}

// RC-a: early ray termination only. A ray never comes back once terminated, so this test can
// itself be culled by early-z: `vs_terminate_alpha` draws at depth TERMINATED with compare
// Greater, rays already at TERMINATED are rejected before the shader runs, and a live ray either
// keeps the fragment (its depth becomes TERMINATED) or is discarded (stays LIVE). No frag_depth
// is written, so the depth test stays early.
@vertex
fn vs_terminate_alpha(@builtin(vertex_index) vertex_index: u32, @builtin(instance_index) instance: u32) -> SegmentVertex {
    let p = footprint_position(vertex_index);
    return SegmentVertex(vec4<f32>(p.xy, TERMINATED, 1.0), instance);
}

@fragment
fn fs_terminate(in: SegmentVertex) {
    let pixel = vec2<u32>(in.clip.xy);
    let s = pixel_ray_samples(pixel);
    if (!ray_is_done(pixel, s, in.index)) {
        discard;
    }
}

// RC-b: early ray termination and empty-space skipping.
@fragment
fn fs_terminate_empty(in: SegmentVertex) -> DepthOut {
    let pixel = vec2<u32>(in.clip.xy);
    let s = pixel_ray_samples(pixel);
    let done = ray_is_done(pixel, s, in.index) || segment_is_empty(s, in.index);
    return DepthOut(select(LIVE, TERMINATED, done));
}
