// The one sampling core of every raycaster — fragment (`raycast`), compute (`raycast_compute`),
// multipass segments (`raycast_segment`, `termination_test`), bricks (`raycast_bricks`) and
// `antialias`'s sub-pixel rays — implementing docs/rendering_model.md ("Samples", "Ray segment
// inside the box", "Classification and compositing", "Effects", "First-hit isosurface") exactly
// like `volgraph_accel::reference`. Krüger & Westermann 2003 §2.1 (DVR, early ray termination),
// §2.2 (first-hit isosurface), §2.3 (empty-space skipping, through `leap`).
//
// One rule for where samples lie (`Samples` in common/ray_box.wgsl, jitter here), one box exit
// (`past_box`), one compositing step (`classify_sample`), one leap over empty space
// (`leap`, common/leap_empty.wgsl), one DVR loop (`march_dvr`) and one isosurface loop
// (`march_iso`) over any range of samples [k0, end): a whole ray, a ray started late from a
// reprojected estimate (Klein et al. 2005), a segment of M samples, a run inside a brick.
//
// Effects a scene turns on are compiled in with `#if` (crates/compiler/src/shader_source.rs):
// SHADING (Blinn–Phong of every DVR sample with the gradient), PREINTEGRATION (Engel et al.
// 2001: each sample composites the segment from the previous one through a 2D table), TRICUBIC
// (common/volume.wgsl), JITTER; FUSION (several volumes per sample, common/fusion.wgsl); and the pass's choices: CORRECTED_TABLE (classify through a
// table pre-corrected for the step, opacity_lut.wgsl), LEAP (`march_dvr` leaps in rounds),
// FIRST_VISIBLE (`march_dvr` records its first visible sample for Klein's leap hits), PREFETCH
// (the compute raycaster's pipelined loop: each run fetches one sample ahead).

#import "common/frame.wgsl"
#import "common/volume.wgsl"
#import "common/raycast_params.wgsl"
#import "common/ray_box.wgsl"

// The correction exponent (step over opacity unit) is exactly 0.5: the exact correction is a
// square root, no pow. A compute raycaster picks this pipeline per frame (the opacity unit is
// frame data): no branch on it may sit in the sample loop, which on llvmpipe slows every sample.
override HALF_STEP: bool = false;
// With LEAP: samples in a run between two looks at the empty-space structure (`march_dvr`).
override CHECK_EVERY: u32 = 16u;

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
// In a sort-last window the box is the whole volume's (frame.grid_lo/hi), not [0,1]³.
fn ray_is_valid(u0: vec3<f32>, d_tex: vec3<f32>, len_tex: f32) -> bool {
    let d_len = length(d_tex);
    let lo = march_lo();
    let size = march_hi() - lo;
    if (!(len_tex > 0.0) || !(len_tex < 4.0 * max(size.x, max(size.y, size.z))) || !(d_len > 0.5) || !(d_len < 1.5)) {
        return false;
    }
    if (!all(abs((u0 - lo) / size - vec3<f32>(0.5)) < vec3<f32>(1.0))) {
        return false;
    }
    let step_tex = ray_step_tex(d_tex);
    return step_tex > 0.0 && step_tex < 1e30;
}

// The opacity-correction exponent of one step: step_voxels over the TF's opacity unit in voxels
// (frame.volume_dims.w: 1 for opacity per voxel, 1/unit_world for opacity per world unit).
#if LEVEL_STEPS
// raycast_stream.wgsl: a run through a brick of level l takes every 2^l-th sample of the grid;
// its opacity is corrected for that step.
var<private> step_multiple: f32 = 1.0;
#endif

fn step_exponent() -> f32 {
#if LEVEL_STEPS
    return step_multiple * params.step_voxels / frame.volume_dims.w;
#else
    return params.step_voxels / frame.volume_dims.w;
#endif
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
    if (HALF_STEP) {
        return 1.0 - sqrt(1.0 - a);
    }
    return 1.0 - pow(1.0 - a, step_exponent());
}

#if PREINTEGRATION
// The pre-integration table (crates/passes/src/preintegration.rs): texel (i, j) holds the
// premultiplied RGBA of a segment from scalar i/(N-1) to j/(N-1), N×N, filtered linearly.
@group(0) @binding(auto) var preintegrated: texture_2d<f32>;

fn lookup_preintegrated(s_front: f32, s_back: f32) -> vec4<f32> {
    return lookup_segment(preintegrated, s_front, s_back);
}

// The segment from `s_front` to `s_back` in a pre-integration table (several volumes'
// partners have their own, common/fusion.wgsl).
fn lookup_segment(table: texture_2d<f32>, s_front: f32, s_back: f32) -> vec4<f32> {
    let n = vec2<f32>(textureDimensions(table));
    let st = (clamp(vec2<f32>(s_front, s_back), vec2<f32>(0.0), vec2<f32>(1.0)) * (n - 1.0) + 0.5) / n;
    return textureSampleLevel(table, linear_clamp, st, 0.0);
}
#endif

#if CORRECTED_TABLE
// (rgb·α', α') per scalar, α' corrected for the step (opacity_lut.wgsl): one filtered lookup
// instead of the TF and a pow.
@group(0) @binding(auto) var corrected: texture_2d<f32>;
#endif

// Per-ray state of the effects: the unit world view direction (SHADING) and the scalar of the
// previous sample, the front of the next segment (PREINTEGRATION).
var<private> ray_view_world: vec3<f32>;
var<private> ray_prev_scalar: f32;
// The scene's lights as this ray sees them (`begin_lights`): read from the frame block once per
// ray, since on llvmpipe a uniform read inside the sample loop is repeated every sample, one
// lane at a time; the headlight resolved to this ray's direction. MAX_LIGHTS of them.
var<private> ray_light0: vec4<f32>;
var<private> ray_light1: vec4<f32>;
var<private> ray_light2: vec4<f32>;
var<private> ray_light_count: u32;

// Starts marching `s` at sample k0: the view direction, and the front value of sample k0's
// segment (the field one step before it).
fn begin_ray(s: Samples, k0: u32) {
    ray_view_world = normalize(s.delta * 2.0 * frame.half_extent.xyz);
#if SHADING
    begin_lights(ray_view_world);
#else
#if SHADOWS
    begin_lights(ray_view_world);
#endif
#endif
#if FUSION
    begin_fusion();
#endif
#if FUSION_LABEL_READS
#if SUBGROUPS
    begin_label_cubes();
#endif
#endif
    resume_ray(sample_at(s, k0) - s.delta);
}

// After skipping samples: `before` is the position of the sample just before the next one
// taken, the front of its segment.
fn resume_ray(before: vec3<f32>) {
#if PREINTEGRATION
    ray_prev_scalar = sample_volume(before);
#if FUSION_SCALAR
    resume_media(volume_position(before));
#endif
#endif
}

// The premultiplied, opacity-corrected colour the sample at texture-space `u` adds, with the
// effects compiled in.
fn classify_sample(u: vec3<f32>) -> vec4<f32> {
    return classify_value(u, sample_volume(u));
}

#if FUSION
#import "common/fusion.wgsl"
#endif
#if FUSION_LABEL_READS
#if SUBGROUPS
#import "common/label_cubes.wgsl"
#endif
#endif
#if SHADOWS
#import "common/shadows.wgsl"
#else
#if AMBIENT_OCCLUSION
#import "common/shadows.wgsl"
#endif
#endif

// `classify_sample` of the scalar `s` already fetched at `u`.
fn classify_value(u: vec3<f32>, s: f32) -> vec4<f32> {
#if FUSION
    // Several volumes: classified and combined per sample (pre-integration is of one TF).
    var p = fused_sample(u, s);
#else
#if PREINTEGRATION
    var p = lookup_preintegrated(ray_prev_scalar, s);
    ray_prev_scalar = s;
#else
#if CORRECTED_TABLE
    var p = textureSampleLevel(corrected, linear_clamp, vec2<f32>(s, 0.5), 0.0);
#else
    let c = sample_tf(s);
    let a = corrected_alpha(c.a);
    var p = vec4<f32>(c.rgb * a, a);
#endif
#endif
#endif
#if SHADING
    if (p.a > 0.0) {
        let light = lighting(u, ray_view_world);
        p = vec4<f32>(p.rgb * light.x + vec3<f32>(p.a * light.y), p.a);
    }
#else
#if SHADOWS
    p = unshaded_lit(u, p);
#else
#if AMBIENT_OCCLUSION
    p = unshaded_lit(u, p);
#endif
#endif
#endif
    return p;
}

// The light reaching `u`: the share of each light that gets through (.rgb, in the scene's
// order) with SHADOWS and the ambient light's unoccluded share (.a) with AMBIENT_OCCLUSION, read
// from the illumination volume; 1 for what is not simulated.
fn illumination_at(u: vec3<f32>) -> vec4<f32> {
    var lit = vec4<f32>(1.0);
#if SHADOWS
    lit = vec4<f32>(light_transmittance(u), 1.0);
#endif
#if AMBIENT_OCCLUSION
    lit.a = ambient_occlusion(u);
#endif
    return lit;
}

// An unshaded sample `p` at `u` lit by the illumination volume: its colour scaled by the ambient
// light reaching it and the rest of the light by the share of the lights that gets through
// (volgraph_accel::reference: `ambient·AO + (1 − ambient)·mean(T)`).
fn unshaded_lit(u: vec3<f32>, p: vec4<f32>) -> vec4<f32> {
    if (!(p.a > 0.0)) {
        return p;
    }
    let lit = illumination_at(u);
    // The share of the lights that gets through: all of it without SHADOWS.
    var through = 1.0;
#if SHADOWS
    // The mean over the scene's lights (.rgb in their order).
    let count = max(ray_light_count, 1u);
    let lights = vec3<f32>(1.0, select(0.0, 1.0, count > 1u), select(0.0, 1.0, count > 2u));
    through = dot(lit.rgb, lights) / f32(count);
#endif
    let shade = params.ambient * lit.a + (1.0 - params.ambient) * through;
    return vec4<f32>(p.rgb * shade, p.a);
}

// The samples of a pixel's ray (`count` 0 when there is no ray to march): step and jitter of
// this pass.
fn pixel_samples(ray: Ray, pixel: vec2<u32>) -> Samples {
    if (!(ray.len > 0.0) || !ray_is_valid(ray.u0, ray.d, ray.len)) {
        return Samples(ray.u0, vec3<f32>(0.0), 0u, 1.0, 0.5, false);
    }
    return samples_along(ray, ray_step_tex(ray.d), ray_jitter(pixel), params.max_steps);
}

// No such sample (`Marched::first`).
const NO_SAMPLE: u32 = 0xffffffffu;

// What a DVR march did: the premultiplied colour, its first visible sample (with FIRST_VISIBLE;
// NO_SAMPLE when none), the samples it took and where it stopped.
struct Marched {
    color: vec4<f32>,
    first: u32,
    samples: u32,
    end: u32,
}

// Direct volume rendering of samples [k0, end) of `s` behind the premultiplied `start`, front to
// back (docs/rendering_model.md), stopping after the sample that makes A >= threshold. Call
// `begin_ray` (or `resume_ray`) first. With LEAP it goes in rounds: leap while the sample lies
// in empty space (`leap`), then a run of up to CHECK_EVERY samples with nothing else in the
// loop. The lanes of a SIMD group go through the rounds together, so they look at the
// empty-space structure at the same time; a sample taken in an empty block adds nothing (its
// classified alpha is 0), so a lane entering empty space during a run loses time, never
// accuracy. (On llvmpipe, a leap check inside the sample loop — even one never taken — makes
// every sample ~1.7× slower: bench/peer.md.)
fn march_dvr(s: Samples, k0: u32, end: u32, start: vec4<f32>) -> Marched {
    var out = Marched(start, NO_SAMPLE, 0u, k0);
    var k = k0;
    // Read once: on llvmpipe a uniform read inside a loop that calls a texture function is
    // repeated every sample, one lane at a time (bench/one-march-final.md, "llvmpipe profile").
    let threshold = params.threshold;
#if LEAP
    let leaping = leaping_for(s);
#endif
    // Termination is tested after a sample, never before the first (T = 0 takes one sample, as
    // the reference does).
    loop {
        if (k >= end) {
            break;
        }
#if LEAP
        let before = k;
        k = leap(k, s, end, leaping);
        if (k >= end) {
            break;
        }
        if (k != before) {
            resume_ray(sample_at(s, k) - s.delta);
        }
        let run_end = min(k + CHECK_EVERY, end);
#else
#if FUSION_LABEL_READS
#if SUBGROUPS
        // Runs, so that each finds its stretch inside one label (common/label_cubes.wgsl).
        let run_end = min(k + CHECK_EVERY, end);
#else
        let run_end = end;
#endif
#else
        let run_end = end;
#endif
#endif
        // k < run_end here, so the run tests its two ends once per sample, after it, with `|`
        // (no short circuit: one branch, not two — 3 % fewer instructions on llvmpipe).
        let run_start = k;
#if FUSION_LABEL_READS
#if SUBGROUPS
        // The run's first stretch inside one label (common/label_cubes.wgsl): its samples take
        // the label found for the stretch, so they read no label map. A loop of its own, left by
        // the whole subgroup at once when one lane's stretch ends (`subgroupAll`): the lanes of a
        // subgroup run a loop's body together until the last leaves it (llvmpipe runs both
        // sides of a branch), so a lane inside its stretch beside one outside would otherwise
        // pay for both; the rest of the run reads as before.
        let known_end = min(begin_label_run(s, k), run_end);
        label_known = true;
        loop {
            if (!subgroupAll((k < known_end) & (out.color.a < threshold))) {
                break;
            }
            let p = classify_sample(sample_at(s, k));
#if FIRST_VISIBLE
            out.first = select(out.first, k, out.first == NO_SAMPLE && p.a > 0.0);
#endif
            out.color = out.color + (1.0 - out.color.a) * p;
            k += 1u;
        }
        label_known = false;
        if ((k >= run_end) | (out.color.a >= threshold)) {
            out.samples += k - run_start;
            if (out.color.a >= threshold) {
                break;
            }
            continue;
        }
#endif
#endif
#if PREFETCH
        // The pipelined loop: the next sample's fetch is issued before this one is classified,
        // so the lookup's latency hides behind a fetch (one extra fetch per run, a loss where
        // the volume fetch is a function call, as on llvmpipe).
        var next = sample_volume(sample_at(s, k));
#endif
        loop {
#if PREFETCH
            let value = next;
            next = sample_volume(sample_at(s, k + 1u));
            let p = classify_value(sample_at(s, k), value);
#else
            let p = classify_sample(sample_at(s, k));
#endif
#if FIRST_VISIBLE
            out.first = select(out.first, k, out.first == NO_SAMPLE && p.a > 0.0);
#endif
            out.color = out.color + (1.0 - out.color.a) * p;
            k += 1u;
            if ((k >= run_end) | (out.color.a >= threshold)) {
                break;
            }
        }
        out.samples += k - run_start;
        if (out.color.a >= threshold) {
            break;
        }
    }
    out.end = k;
    return out;
}


// Where the point `u` of the texture sampled lies in the volume's texture space: `u` itself,
// but where a march samples a brick atlas, whose run of samples in one slot maps back by
// `u · sampled_scale + sampled_offset` (raycast_bricks.wgsl sets both per run). The cut faces a
// shading normal turns toward are in the volume's space.
var<private> sampled_scale: vec3<f32> = vec3<f32>(1.0);
var<private> sampled_offset: vec3<f32> = vec3<f32>(0.0);

fn volume_position(u: vec3<f32>) -> vec3<f32> {
    return u * sampled_scale + sampled_offset;
}

// The scene's lights for a ray along the unit world direction `d_world` (`ray_light0..2`): each
// directional light's direction (w = 1), each point light's position (w = 2), the headlight as
// the directional light toward the eye, -d_world (volgraph_accel::light::Toward).
fn begin_lights(d_world: vec3<f32>) {
    ray_light_count = frame.light_count;
    let headlight = vec4<f32>(-d_world, 1.0);
    ray_light0 = select(headlight, frame.lights[0], frame.lights[0].w != 0.0);
    ray_light1 = select(headlight, frame.lights[1], frame.lights[1].w != 0.0);
    ray_light2 = select(headlight, frame.lights[2], frame.lights[2].w != 0.0);
}

// The unit world direction toward the ray's light `i` (`ray_light0..2`) from texture point `u` (of
// the texture sampled: `volume_position` maps a brick atlas back): a directional light's, a
// point light's from u's world point. Uniform branches.
fn light_at(u: vec3<f32>, i: u32) -> vec3<f32> {
    var light = ray_light0;
    if (i == 1u) {
        light = ray_light1;
    } else if (i == 2u) {
        light = ray_light2;
    }
    if (light.w == 2.0) {
        let d = light.xyz - world_from_texture(volume_position(u));
        let r = length(d);
        return select(vec3<f32>(0.0, 1.0, 0.0), d / r, r > 1e-12);
    }
    return light.xyz;
}

// Blinn–Phong at texture-space point `u` seen along the unit world direction `d_world`, lit by
// each of the scene's lights from its unit world direction `l` (`light_at`;
// docs/rendering_model.md "First-hit isosurface", "Effects"): (ambient + Σ diffuse·|n·l|, the
// white specular term Σ |n·h|^shininess), n from the central-difference gradient of the
// reconstructed field, facing the light where the gradient vanishes (constant regions: no NaN);
// h = normalize(l + v), exactly l for the headlight (l = v), no highlight where light and eye
// are opposite (volgraph_accel::light::blinn_phong_terms).
fn lighting(u: vec3<f32>, d_world: vec3<f32>) -> vec2<f32> {
    // One voxel of the texture sampled: the volume, or a brick atlas (raycast_bricks.wgsl),
    // whose slots hold the brick's neighbours on every side.
    let off = 1.0 / vec3<f32>(textureDimensions(volume));
    let g = vec3<f32>(
        sample_volume(u + vec3<f32>(off.x, 0.0, 0.0)) - sample_volume(u - vec3<f32>(off.x, 0.0, 0.0)),
        sample_volume(u + vec3<f32>(0.0, off.y, 0.0)) - sample_volume(u - vec3<f32>(0.0, off.y, 0.0)),
        sample_volume(u + vec3<f32>(0.0, 0.0, off.z)) - sample_volume(u - vec3<f32>(0.0, 0.0, off.z)),
    );
    let has_gradient = length(g) >= 1e-6;
    // g spans two voxels per axis: the world gradient is g / (2 · voxel_world) with
    // voxel_world = 2·half / dims, so its direction is that of g · dims / half.
    let gradient_n = -normalize(select(vec3<f32>(1.0), g, has_gradient) * frame.volume_dims.xyz / frame.half_extent.xyz);
    // Shadows: only the light that gets through reaches the diffuse and specular terms;
    // ambient occlusion: only the unoccluded share of the ambient light.
    let lit = illumination_at(u);
    // The lights one after another, not a loop: on llvmpipe a loop over them (a trip count
    // unknown at compile time, a private array indexed at run time) made one light's shading
    // 15 % slower; a light the scene lacks is a uniform branch not taken.
    var light = vec2<f32>(params.ambient * lit.a, 0.0) + lit.r * blinn_phong(u, d_world, gradient_n, has_gradient, 0u);
    if (ray_light_count > 1u) {
        light += lit.g * blinn_phong(u, d_world, gradient_n, has_gradient, 1u);
    }
    if (ray_light_count > 2u) {
        light += lit.b * blinn_phong(u, d_world, gradient_n, has_gradient, 2u);
    }
    return light;
}

// The diffuse and specular terms of the ray's light `i` at `u` seen along `d_world`
// (`lighting`), with the gradient's normal where the field has one, else facing the light.
fn blinn_phong(u: vec3<f32>, d_world: vec3<f32>, gradient_n: vec3<f32>, has_gradient: bool, i: u32) -> vec2<f32> {
    let v = -d_world;
    let l = light_at(u, i);
    var n = select(l, gradient_n, has_gradient);
    // A cut face shows the plane it was cut along (common/ray_box.wgsl).
#if CUTS
    n = cap_normal(volume_position(u), d_world, n);
#endif
    let n_dot_l = abs(dot(n, l));
    let lv = l + v;
    var n_dot_h = 0.0;
    if (all(l == v)) {
        n_dot_h = n_dot_l;
    } else if (length(lv) > 1e-6) {
        n_dot_h = abs(dot(n, lv / length(lv)));
    }
    var spec = 0.0;
    if (n_dot_l > 0.0) {
        spec = params.specular * pow(n_dot_h, params.shininess);
    }
    return vec2<f32>(params.diffuse * n_dot_l, spec);
}

// The shaded colour of the isosurface at `u`.
fn shade_iso(u: vec3<f32>, d_world: vec3<f32>) -> vec3<f32> {
    begin_lights(d_world);
    let light = lighting(u, d_world);
    let base = sample_tf(params.iso_value).rgb;
    return clamp(base * light.x + vec3<f32>(light.y), vec3<f32>(0.0), vec3<f32>(1.0));
}

// What an isosurface march found: shaded colour (alpha 1) and texture-space hit (w = 1), zero
// on a miss; the samples it took; the sample it stopped at (the hit's, or `end` on a miss).
struct IsoMarch {
    color: vec4<f32>,
    hit: vec4<f32>,
    samples: u32,
    at: u32,
}

// First-hit isosurface over samples [k0, end) of `s`: the first sample k with value >= iso,
// refined linearly against sample k - 1 (read again when k0 > 0, so a segment or a late start
// refines like the whole ray; a start already past the surface reports the sample before it,
// unrefined), shaded with the headlight. The loop only finds k — one fetch and one compare per
// sample, like the DVR run's body — and the refinement and shading (six more fetches) run once
// after it: inside the loop, every lane of a SIMD group would wait through the shading of each
// other lane's hit.
fn march_iso(s: Samples, k0: u32, end: u32) -> IsoMarch {
    var out = IsoMarch(vec4<f32>(0.0), vec4<f32>(0.0), 0u, end);
    let iso = params.iso_value;
    var k = k0;
    var prev = 0.0;
    var has_prev = false;
    if (k0 > 0u && k0 <= s.count) {
        prev = sample_volume(sample_at(s, k0 - 1u));
        out.samples = 1u;
        has_prev = true;
        if (prev >= iso) {
            // The start was past the surface: take the sample that saw it again.
            k = k0 - 1u;
            has_prev = false;
        }
    } else if (s.cut && k0 == 0u && s.count > 0u) {
        // A sort-last window cut the ray: the sample before is another rank's. Where it already
        // saw the surface, the hit is that rank's; otherwise it brackets a hit here.
        prev = sample_volume(s.first - s.delta);
        out.samples = 1u;
        if (prev >= iso) {
            out.at = 0u;
            return out;
        }
        has_prev = true;
    }
    let first = k;
    var v = 0.0;
    loop {
        if (k >= end) {
            break;
        }
        v = sample_volume(sample_at(s, k));
        if (v >= iso) {
            break;
        }
        prev = v;
        k += 1u;
    }
    if (k >= end) {
        out.samples += k - first;
        return out;
    }
    out.samples += k - first + 1u;
    out.at = k;
    var x = f32(k);
    if (has_prev || k > first) {
        x = x - 1.0 + (iso - prev) / (v - prev);
    }
    let u = s.first + x * s.delta;
    let d_world = normalize(s.delta * 2.0 * frame.half_extent.xyz);
    out.color = vec4<f32>(shade_iso(u, d_world), 1.0);
    out.hit = vec4<f32>(u, 1.0);
    return out;
}
