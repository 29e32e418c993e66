// The fastest DVR raycaster we know how to build (issue "the fastest path"): a compute shader,
// one invocation per pixel, that
// - meets the volume box analytically (common/analytic_ray.wgsl: no entry/direction raster
//   passes, no float targets for them),
// - leaps over empty space with the distance map of `empty_distance` (LEAP = 2: out of the
//   largest cube of empty blocks around the sample; 1: out of its block; 0: no leaping),
//   looking at the map only every CHECK_EVERY samples, together for every lane (`march`),
// - classifies with the TF and the exact per-sample opacity correction (a square root when
//   HALF_STEP, else pow) or, when CORRECTED, with the pre-multiplied, opacity-corrected table of
//   opacity_lut.wgsl (one filtered lookup, no pow; approximate where the TF nears alpha 1),
// - stops at the termination threshold, and
// - counts the samples it takes (the `cs_counted` entry point, for benchmarks).
// Samples are those of common/raymarch.wgsl's loop (k + 0.5 + jitter steps from the entry), so
// the image equals `raycast` with the same step and threshold up to rounding: a leap skips only
// samples in blocks whose every sample classifies to alpha 0.

#import "common/frame.wgsl"
#import "common/raymarch.wgsl"
#import "common/analytic_ray.wgsl"

override WORKGROUP_X: u32 = 8u;
override WORKGROUP_Y: u32 = 8u;
// 0: every sample; 1: leap out of empty blocks one at a time; 2: leap over cubes of empty blocks.
override LEAP: u32 = 2u;
// Classify with the corrected table instead of the TF and pow.
override CORRECTED: bool = true;
// The correction exponent (step over opacity unit) is exactly 0.5: the exact correction is a
// square root, no pow. The node picks this pipeline per frame (the opacity unit is frame data):
// no branch on it may sit in the sample loop, which on llvmpipe slows every sample.
override HALF_STEP: bool = false;
// Samples between two looks at the distance map (see `march`).
override CHECK_EVERY: u32 = 16u;

// Declared once: `BlockSize` (pass_params!) in crates/passes/src/shared.rs.
struct FastParams {
    // Edge of an empty-space block in voxels (the distance map's).
    block_size: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

#if COLOR_F32
@group(0) @binding(auto) var color: texture_storage_2d<rgba32float, write>;
#else
@group(0) @binding(auto) var color: texture_storage_2d<rgba16float, write>;
#endif
@group(0) @binding(auto) var<uniform> fast: FastParams;
// Chebyshev distance in blocks to the nearest block that may be visible (0: this one may be).
@group(0) @binding(auto) var distance: texture_3d<f32>;
// (rgb·α', α') per scalar, α' corrected for the step (opacity_lut.wgsl).
@group(0) @binding(auto) var corrected: texture_2d<f32>;
// Samples taken per image row (row y adds into samples[y % SAMPLE_ROWS]; the benchmark sums them).
@group(0) @binding(auto) var<storage, read_write> samples: array<atomic<u32>>;
const SAMPLE_ROWS: u32 = 4096u;

// One front-to-back step at `u` (common/raymarch.wgsl's composite_sample when !CORRECTED).
fn composite(acc: vec4<f32>, u: vec3<f32>) -> vec4<f32> {
#if EFFECTS
    // Shading or pre-integration: the shared classification with every effect compiled in.
    return composite_sample(acc, u);
#else
    if (!CORRECTED) {
        if (HALF_STEP) {
            // The exact correction for a half-voxel step: 1 - (1 - a)^0.5, a square root.
            let c = sample_tf(sample_volume(u));
            let a = 1.0 - sqrt(1.0 - clamp(c.a, 0.0, 1.0));
            let w = (1.0 - acc.a) * a;
            return vec4<f32>(acc.rgb + w * c.rgb, acc.a + w);
        }
        return composite_sample(acc, u);
    }
    let c = textureSampleLevel(corrected, linear_clamp, vec2<f32>(sample_volume(u), 0.5), 0.0);
    let w = 1.0 - acc.a;
    return vec4<f32>(acc.rgb + w * c.rgb, acc.a + w * c.a);
#endif
}

struct Marched {
    color: vec4<f32>,
    samples: u32,
}

// The block (distance-map texel) holding texture-space `u`, clamped to the grid.
fn block_at(u: vec3<f32>) -> vec3<i32> {
    let grid = vec3<f32>(textureDimensions(distance));
    let b = floor(u * frame.volume_dims.xyz / f32(fast.block_size));
    return vec3<i32>(clamp(b, vec3<f32>(0.0), grid - vec3<f32>(1.0)));
}

// The t at which `u0 + t·d` leaves the box of blocks [lo, hi] (inclusive, block coordinates) —
// common/empty_blocks.wgsl's block_exit_t for a cube of blocks; with d one step, t is in steps.
fn cube_exit_t(lo: vec3<i32>, hi: vec3<i32>, u0: vec3<f32>, d: vec3<f32>) -> f32 {
    let n = frame.volume_dims.xyz;
    let bs = f32(fast.block_size);
    let lo_u = vec3<f32>(lo) * bs / n;
    let hi_u = min(vec3<f32>(hi + vec3<i32>(1)) * bs, n) / n;
    let bound = select(lo_u, hi_u, d > vec3<f32>(0.0));
    let t = (bound - u0) / d;
    let t_axis = select(vec3<f32>(3.0e38), t, d != vec3<f32>(0.0));
    return min(t_axis.x, min(t_axis.y, t_axis.z));
}

// The first sample index >= k outside the empty region around sample k (k itself when its
// block may be visible): out of the block (LEAP = 1) or of the largest cube of empty blocks
// around it (LEAP = 2; every block within Chebyshev distance dist - 1 is empty too).
fn leap_from(k: u32, s: Samples) -> u32 {
    let p = s.first + f32(k) * s.delta;
    let b = block_at(p);
    let dist = textureLoad(distance, b, 0).r;
    if (dist < 1.0) {
        return k;
    }
    let reach = select(0, i32(dist) - 1, LEAP == 2u);
    let grid = vec3<i32>(textureDimensions(distance)) - vec3<i32>(1);
    let lo = max(b - vec3<i32>(reach), vec3<i32>(0));
    let hi = min(b + vec3<i32>(reach), grid);
    // Steps from sample k to where the ray leaves the cube; the first sample past it.
    let steps = cube_exit_t(lo, hi, p, s.delta);
    return k + max(1u, u32(clamp(floor(steps) + 1.0, 0.0, f32(params.max_steps))));
}

// The samples of `ray` front to back, in rounds: leap while in empty space, then a run of up to
// CHECK_EVERY samples with nothing else in the loop. The lanes of a SIMD group go through the
// rounds together, so they look at the distance map at the same time and none waits while
// another does block bookkeeping. A sample taken in an empty block adds nothing (its classified
// alpha is 0), so a lane entering empty space during a run loses time, never accuracy. (On
// llvmpipe, a leap check inside the sample loop — even one never taken — makes every sample
// ~1.7× slower: bench/peer.md.)
fn march(ray: Ray, pixel: vec2<u32>) -> Marched {
    var out = Marched(vec4<f32>(0.0), 0u);
    if (!ray_is_valid(ray.u0, ray.d, ray.len)) {
        return out;
    }
    let s = ray_samples(ray, pixel);
    begin_ray(s.first, s.delta);
    var k = 0u;
    loop {
        if (LEAP != 0u) {
            // Leap over consecutive empty regions (a cube is usually left in one leap).
            let before = k;
            loop {
                if (k >= s.count) {
                    break;
                }
                let next = leap_from(k, s);
                if (next == k) {
                    break;
                }
                k = next;
            }
#if PREINTEGRATION
            if (k != before && k < s.count) {
                resume_ray(s.first + (f32(k) - 1.0) * s.delta);
            }
#endif
        }
        // A run of up to CHECK_EVERY samples with nothing else in the loop.
        let end = min(k + CHECK_EVERY, s.count);
        let run_start = k;
        var opaque = false;
        loop {
            if (k >= end) {
                break;
            }
            out.color = composite(out.color, s.first + f32(k) * s.delta);
            k += 1u;
            if (out.color.a >= params.threshold) {
                opaque = true;
                break;
            }
        }
        out.samples += k - run_start;
        if (opaque || k >= s.count) {
            break;
        }
    }
    return out;
}

fn in_viewport(p: vec2<u32>) -> bool {
    return f32(p.x) < frame.viewport.x && f32(p.y) < frame.viewport.y;
}

@compute @workgroup_size(WORKGROUP_X, WORKGROUP_Y)
fn cs_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if (!in_viewport(p)) {
        return;
    }
    // A row of pixels that misses the box skips the march altogether.
    let ray = analytic_ray(p);
    var c = vec4<f32>(0.0);
    if (ray.len > 0.0) {
        c = march(ray, p).color;
    }
    textureStore(color, vec2<i32>(p), c);
}

@compute @workgroup_size(WORKGROUP_X, WORKGROUP_Y)
fn cs_counted(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.xy;
    if (!in_viewport(p)) {
        return;
    }
    let ray = analytic_ray(p);
    var m = Marched(vec4<f32>(0.0), 0u);
    if (ray.len > 0.0) {
        m = march(ray, p);
    }
    textureStore(color, vec2<i32>(p), m.color);
    atomicAdd(&samples[p.y % SAMPLE_ROWS], m.samples);
}
