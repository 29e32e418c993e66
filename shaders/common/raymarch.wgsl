// The volume-rendering integral shared by every raycaster (fragment and compute), implementing
// docs/rendering_model.md ("Ray segment inside the box" from `u0` on, "Classification and
// compositing", "Effects", "First-hit isosurface") exactly like `volgraph_accel::reference`.
// Krüger & Westermann 2003 §2.1 (DVR, early ray termination) and §2.2 (first-hit isosurface).
//
// Effects a scene turns on are compiled in with `#if` (crates/core/src/shader_source.rs):
// SHADING (Blinn–Phong of every DVR sample with the gradient), PREINTEGRATION (Engel et al.
// 2001: each sample composites the segment from the previous one through a 2D table), TRICUBIC
// (common/volume.wgsl). A loop that uses them calls `begin_ray` before its first sample and
// `resume_ray` after skipping samples.

#import "common/frame.wgsl"
#import "common/volume.wgsl"
#import "common/raycast_params.wgsl"
#import "common/ray_box.wgsl"

// O'Neill's PCG hash (state = v*747796405 + 2891336453, then the RXS-M-XS output permutation).
fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// The per-pixel offset of the first sample, in steps, in [-0.5, 0.5); compiled in only with
// JITTER (the `jitter` effect), else 0. Stable across frames, unless JITTER_PER_FRAME
// (`jitter_per_frame`) moves it every frame (the hash of pixel + frame · pixels; frame 0 equals
// the stable offsets) so that accumulating frames averages the noise away.
fn ray_jitter(pixel: vec2<u32>) -> f32 {
#if JITTER
    let width = u32(frame.viewport.x);
    var key = pixel.x + pixel.y * width;
#if JITTER_PER_FRAME
    key = key + frame.frame_index * width * u32(frame.viewport.y);
#endif
    return f32(pcg_hash(key)) / 4294967296.0 - 0.5;
#else
    return 0.0;
#endif
}

// The step of this pass's `step_voxels` along unit texture-space direction `d_tex`.
fn ray_step_tex(d_tex: vec3<f32>) -> f32 {
    return step_tex_for(params.step_voxels, d_tex);
}

// True when the ray (u0, d_tex, len_tex) can be marched: positive finite length, a unit
// direction, a positive finite step. Written with `>`/`<` so NaN fails every test.
fn ray_is_valid(u0: vec3<f32>, d_tex: vec3<f32>, len_tex: f32) -> bool {
    let d_len = length(d_tex);
    if (!(len_tex > 0.0) || !(len_tex < 4.0) || !(d_len > 0.5) || !(d_len < 1.5)) {
        return false;
    }
    if (!all(abs(u0 - vec3<f32>(0.5)) < vec3<f32>(1.0))) {
        return false;
    }
    let step_tex = ray_step_tex(d_tex);
    return step_tex > 0.0 && step_tex < 1e30;
}

// The opacity-correction exponent of one step: step_voxels over the TF's opacity unit in voxels
// (frame.volume_dims.w: 1 for opacity per voxel, 1/unit_world for opacity per world unit).
fn step_exponent() -> f32 {
    return params.step_voxels / frame.volume_dims.w;
}

// Opacity correction from the LUT's per-unit alpha to this step: 1 - (1 - a)^step_exponent.
// The ends are handled explicitly because pow(0, y) is undefined in WGSL.
fn corrected_alpha(a_tf: f32) -> f32 {
    let a = clamp(a_tf, 0.0, 1.0);
    if (a >= 1.0) {
        return 1.0;
    }
    if (a <= 0.0) {
        return 0.0;
    }
    return 1.0 - pow(1.0 - a, step_exponent());
}

#if PREINTEGRATION
// The pre-integration table (crates/passes/src/preintegration.rs): texel (i, j) holds the
// premultiplied RGBA of a segment from scalar i/(N-1) to j/(N-1), N×N, filtered linearly.
@group(0) @binding(auto) var preintegrated: texture_2d<f32>;

fn lookup_preintegrated(s_front: f32, s_back: f32) -> vec4<f32> {
    let n = vec2<f32>(textureDimensions(preintegrated));
    let st = (clamp(vec2<f32>(s_front, s_back), vec2<f32>(0.0), vec2<f32>(1.0)) * (n - 1.0) + 0.5) / n;
    return textureSampleLevel(preintegrated, linear_clamp, st, 0.0);
}
#endif

// Per-ray state of the effects: the unit world view direction (SHADING) and the scalar of the
// previous sample, the front of the next segment (PREINTEGRATION).
var<private> ray_view_world: vec3<f32>;
var<private> ray_prev_scalar: f32;

// Starts a ray whose sample k lies at first + k·delta: the view direction, and the front value
// of sample 0's segment (the field one step before it).
fn begin_ray(first: vec3<f32>, delta: vec3<f32>) {
    ray_view_world = normalize(delta * 2.0 * frame.half_extent.xyz);
#if PREINTEGRATION
    ray_prev_scalar = sample_volume(first - delta);
#endif
}

// After skipping samples: `before` is the position of the sample just before the next one
// taken, the front of its segment.
fn resume_ray(before: vec3<f32>) {
#if PREINTEGRATION
    ray_prev_scalar = sample_volume(before);
#endif
}

// The premultiplied, opacity-corrected colour the sample at texture-space `u` adds, with the
// effects compiled in.
fn classify_sample(u: vec3<f32>) -> vec4<f32> {
    let s = sample_volume(u);
#if PREINTEGRATION
    var p = lookup_preintegrated(ray_prev_scalar, s);
    ray_prev_scalar = s;
#else
    let c = sample_tf(s);
    let a = corrected_alpha(c.a);
    var p = vec4<f32>(c.rgb * a, a);
#endif
#if SHADING
    if (p.a > 0.0) {
        let light = headlight(u, ray_view_world);
        p = vec4<f32>(p.rgb * light.x + vec3<f32>(p.a * light.y), p.a);
    }
#endif
    return p;
}

// One front-to-back compositing step (docs/rendering_model.md): the sample at texture-space
// `u` classified, added behind the premultiplied `acc`. Every DVR loop (single pass, segments,
// empty-space leaping) composites through this function.
fn composite_sample(acc: vec4<f32>, u: vec3<f32>) -> vec4<f32> {
    return acc + (1.0 - acc.a) * classify_sample(u);
}

// Direct volume rendering along u0 + t·d_tex, t in [0, len_tex): premultiplied linear RGBA,
// front to back, stopping after the sample that makes A >= threshold or after max_steps samples.
fn march_dvr(u0: vec3<f32>, d_tex: vec3<f32>, len_tex: f32, pixel: vec2<u32>) -> vec4<f32> {
    var acc = vec4<f32>(0.0);
    if (!ray_is_valid(u0, d_tex, len_tex)) {
        return acc;
    }
    let step_tex = ray_step_tex(d_tex);
    let jitter = ray_jitter(pixel);
    begin_ray(u0 + (0.5 + jitter) * step_tex * d_tex, step_tex * d_tex);
    for (var k = 0u; k < params.max_steps; k += 1u) {
        let t = (f32(k) + 0.5 + jitter) * step_tex;
        if (!(t < len_tex)) {
            break;
        }
        acc = composite_sample(acc, u0 + t * d_tex);
        if (acc.a >= params.threshold) {
            break;
        }
    }
    return acc;
}

// First-hit isosurface result: shaded premultiplied colour (alpha 1) and texture-space hit
// position (w = 1); both (0,0,0,0) when the ray misses.
struct IsoResult {
    color: vec4<f32>,
    hit: vec4<f32>,
}

// Blinn–Phong headlight at texture-space point `u` seen along the unit world direction `d_world`
// (docs/rendering_model.md "First-hit isosurface", "Effects"): (ambient + diffuse·|n·l|, the
// white specular term), n from the central-difference gradient of the reconstructed field, the
// light facing the eye where the gradient vanishes (constant regions: no NaN).
fn headlight(u: vec3<f32>, d_world: vec3<f32>) -> vec2<f32> {
    let off = 1.0 / frame.volume_dims.xyz;
    let g = vec3<f32>(
        sample_volume(u + vec3<f32>(off.x, 0.0, 0.0)) - sample_volume(u - vec3<f32>(off.x, 0.0, 0.0)),
        sample_volume(u + vec3<f32>(0.0, off.y, 0.0)) - sample_volume(u - vec3<f32>(0.0, off.y, 0.0)),
        sample_volume(u + vec3<f32>(0.0, 0.0, off.z)) - sample_volume(u - vec3<f32>(0.0, 0.0, off.z)),
    );
    let l = -d_world;
    var n = l;
    if (length(g) >= 1e-6) {
        // g spans two voxels per axis: the world gradient is g / (2 · voxel_world) with
        // voxel_world = 2·half / dims, so its direction is that of g · dims / half.
        n = -normalize(g * frame.volume_dims.xyz / frame.half_extent.xyz);
    }
    // Headlight: l = v = -d, so h = normalize(l + v) = l.
    let n_dot_l = abs(dot(n, l));
    var spec = 0.0;
    if (n_dot_l > 0.0) {
        spec = params.specular * pow(n_dot_l, params.shininess);
    }
    return vec2<f32>(params.ambient + params.diffuse * n_dot_l, spec);
}

// The shaded colour of the isosurface at `u`.
fn shade_iso(u: vec3<f32>, d_world: vec3<f32>) -> vec3<f32> {
    let light = headlight(u, d_world);
    let base = sample_tf(params.iso_value).rgb;
    return clamp(base * light.x + vec3<f32>(light.y), vec3<f32>(0.0), vec3<f32>(1.0));
}

// First-hit isosurface along u0 + t·d_tex: the first sample k with s >= iso, refined linearly
// between samples k-1 and k (t_0 itself when k = 0), shaded with the headlight.
fn march_iso(u0: vec3<f32>, d_tex: vec3<f32>, len_tex: f32, pixel: vec2<u32>) -> IsoResult {
    var result = IsoResult(vec4<f32>(0.0), vec4<f32>(0.0));
    if (!ray_is_valid(u0, d_tex, len_tex)) {
        return result;
    }
    let step_tex = ray_step_tex(d_tex);
    let jitter = ray_jitter(pixel);
    let iso = params.iso_value;
    var t_prev = 0.0;
    var s_prev = 0.0;
    for (var k = 0u; k < params.max_steps; k += 1u) {
        let t = (f32(k) + 0.5 + jitter) * step_tex;
        if (!(t < len_tex)) {
            break;
        }
        let s = sample_volume(u0 + t * d_tex);
        if (s >= iso) {
            var t_hit = t;
            if (k > 0u) {
                t_hit = t_prev + (t - t_prev) * (iso - s_prev) / (s - s_prev);
            }
            let u = u0 + t_hit * d_tex;
            let d_world = normalize(d_tex * 2.0 * frame.half_extent.xyz);
            result.color = vec4<f32>(shade_iso(u, d_world), 1.0);
            result.hit = vec4<f32>(u, 1.0);
            return result;
        }
        t_prev = t;
        s_prev = s;
    }
    return result;
}
