// A progressive volumetric path tracer, one path per pixel per frame, averaged into a running
// mean while the view rests (crates/passes/src/path_trace.rs; graphs/cinematic/path_traced.ron).
//
// The medium: the TF's opacity α per opacity unit L (frame.half_extent.w · frame.volume_dims.w
// world units) is an extinction coefficient σ(x) = −ln(1 − α(s(x))) / L — the continuous form of
// the raycasters' opacity correction, so the emission–absorption case (albedo 0, emission 1) is
// the DVR integral ∫ T(t) σ(t) c(t) dt that they march, estimated instead of stepped. At an
// interaction a path scatters with probability `albedo` (tinted by the TF colour) and is
// otherwise absorbed, emitting `emission` × the TF colour.
//
// - free paths by delta (Woodcock) tracking against a majorant: σ(max α of the TF), or with
//   BLOCK_MAJORANTS one per block of the min/max grid (majorant_grid.wgsl), stepping block by
//   block (Novák et al. 2014 §3: tight majorants are what make it fast);
// - light toward the directional light (or the headlight) by ratio tracking (Novák et al. 2014
//   §5.2), with Russian roulette once the transmittance is small;
// - scattering by the Henyey–Greenstein phase function, or where the field has a gradient, with
//   probability `surface` · (1 − e^(−20 |∇s|)), off a Lambertian surface whose normal is the
//   gradient (Kroes et al. 2012, "Exposure Render", §4.3's hybrid scattering);
// - paths that leave the box see the environment (the scene's map, a generated sky, or a
//   uniform one); a
//   primary ray that meets nothing is transparent, as in the raycasters (`present` draws the
//   background), and its alpha is the probability of an interaction: 1 − T of the ray,
//   estimated by ratio tracking along it (`coverage: "ratio"`: a value per path, where the
//   0-or-1 of the path's own interaction, `"interaction"`, is the noisier estimator).
//
// Accumulation: `previous` is last frame's mean (history, cleared on any change of the camera,
// TF, volume, light, cuts or this pass's parameters), frame.history_age the samples it holds;
// the new mean is written in f32 (an f16 mean stops moving once 1/(n+1) is below its ulp: after
// about 2048 samples at 1.0, far fewer for a dim pixel).

#import "common/frame.wgsl"
#import "common/volume.wgsl"
#import "common/ray_box.wgsl"

// Declared once: `PathTraceParams` (pass_params!) in crates/passes/src/path_trace.rs, which
// generates the struct imported here.
#import "params/PathTraceParams.wgsl"

@group(0) @binding(auto) var<uniform> trace: PathTraceParams;
// Last frame's running mean (premultiplied linear RGBA); zeros when history restarted.
@group(0) @binding(auto) var previous: texture_2d<f32>;
@group(0) @binding(auto) var color: texture_storage_2d<rgba32float, write>;

// α is capped below 1 so σ stays finite: a unit of length then lets 10⁻⁶ through, which no
// 8-bit image tells from opaque.
const MAX_ALPHA: f32 = 0.999999;
// No path takes more tentative collisions than this (a guard against a NaN majorant; a ray
// across the 256³ engine box at σ̄ takes a few hundred).
const MAX_TRACKING_STEPS: u32 = 65536u;

// Russian roulette spares a path whose largest throughput channel is at least this; a dimmer
// one goes on with probability (that channel / RR_LEVEL). At 1 (every path from the second
// scattering on) it added 7 % to the noise of a sample on the engine and saved no time, since
// paths end after `bounces` anyway; at 0.25 the noise is the same as without it (docs/accuracy.md).
const RR_LEVEL: f32 = 0.25;
const PI: f32 = 3.14159265358979;

// ---- random numbers: PCG (O'Neill 2014), one stream per pixel and sample --------------------

var<private> rng: u32;

fn pcg_next(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn seed_rng(pixel: vec2<u32>, sample_index: u32) {
    rng = pcg_next(pixel.x ^ pcg_next(pixel.y ^ pcg_next(sample_index ^ pcg_next(trace.seed))));
}

// Uniform in [0, 1): 24 random bits.
fn random() -> f32 {
    rng = rng * 747796405u + 2891336453u;
    let word = ((rng >> ((rng >> 28u) + 4u)) ^ rng) * 277803737u;
    return f32(((word >> 22u) ^ word) >> 8u) * (1.0 / 16777216.0);
}

// An exponential free path of rate `sigma`: −ln(1 − ξ) / σ, ξ < 1 so the log is finite.
fn free_path(sigma: f32) -> f32 {
    return -log(1.0 - random()) / sigma;
}

// ---- the medium ------------------------------------------------------------------------------

// World length of the TF's opacity unit.
fn opacity_unit_world() -> f32 {
    return frame.half_extent.w * frame.volume_dims.w;
}

// The frame's constants the tracking loops use, read once per path (`begin_path`): on llvmpipe
// a uniform read or a texture's size inside a loop is repeated at every step (with the block
// grids' below, 10 % of a sample's time on the engine; docs/accuracy.md).
var<private> per_opacity_unit: f32;
var<private> texture_per_world: vec3<f32>;

fn begin_path() {
    per_opacity_unit = 1.0 / opacity_unit_world();
    texture_per_world = vec3<f32>(1.0) / (2.0 * frame.half_extent.xyz);
#if BLOCK_MAJORANTS
    begin_blocks();
#endif
}

// `texture_from_world` with the path's constants.
fn path_texture(p: vec3<f32>) -> vec3<f32> {
    return p * texture_per_world + vec3<f32>(0.5);
}

fn extinction_of(alpha: f32) -> f32 {
    return -log(1.0 - clamp(alpha, 0.0, MAX_ALPHA)) * per_opacity_unit;
}

// σ and the TF colour at world point `p`.
fn medium_at(p: vec3<f32>) -> vec4<f32> {
    let u = path_texture(p);
#if FUSION
    // Several volumes: their combination at u (common/fusion.wgsl; opacity per opacity unit,
    // premultiplied: the straight colour is c / α) — for media in one place the extinctions add.
    let f = fused_sample(u, sample_volume(u));
    return vec4<f32>(select(vec3<f32>(0.0), f.rgb / f.a, f.a > 0.0), extinction_of(f.a));
#else
    let c = sample_tf(sample_volume(u));
    return vec4<f32>(c.rgb, extinction_of(c.a));
#endif
}

#if FUSION
// What common/fusion.wgsl takes from a raycaster's march: a sample's opacity is the TF's, per
// opacity unit (no step to correct for: the extinction is derived from it), and the texture
// sampled is the volume's own.
fn corrected_alpha(a_tf: f32) -> f32 {
    return clamp(a_tf, 0.0, 1.0);
}

fn volume_position(u: vec3<f32>) -> vec3<f32> {
    return u;
}

#import "common/fusion.wgsl"
#endif

// The majorant σ̄ over the path from distance `t` on, and where it stops holding (`end`).
struct MajorantSpan {
    sigma: f32,
    end: f32,
}

#if BLOCK_MAJORANTS
#import "common/block_grid.wgsl"

// The largest opacity per block of the min/max grid (majorant_grid.wgsl).
@group(0) @binding(auto) var majorants: texture_3d<f32>;

#if MAJORANT_LEAP
// The Chebyshev distance map over the same blocks (empty_distance.wgsl): an empty block's
// distance says how large a cube of empty blocks lies around it. A block is empty there exactly
// when its majorant is 0 (both: no LUT texel of its range has α > 0 or NaN).
fn block_edge() -> u32 {
    return trace.block_size;
}
#import "common/empty_cubes.wgsl"
#endif

// The block grids' constants, read once per path (`begin_path`).
var<private> majorant_grid: BlockGrid;
// A world voxel (half_extent.w), of which majorant_span looks a hundredth ahead.
var<private> majorant_ahead: f32;
#if MAJORANT_LEAP
var<private> cube_grid: LeapGrid;
#endif

fn begin_blocks() {
    majorant_grid = block_grid(textureDimensions(majorants), trace.block_size);
    majorant_ahead = frame.half_extent.w;
#if MAJORANT_LEAP
    cube_grid = leap_grid();
#endif
}

// The block the path p + t·w is in at `t` — looked up a hundredth of a voxel ahead, so a path
// on a face takes the block it enters (the grid's one-voxel apron covers the difference) — its
// majorant and where the path leaves it, capped at `limit`; at least that hundredth of a voxel
// on, so rounding at a face never stalls a path. With MAJORANT_LEAP a path in an empty block
// leaves the largest cube of empty blocks around it instead: one step where one per block took
// dozens.
fn majorant_span(p: vec3<f32>, w: vec3<f32>, t: f32, limit: f32) -> MajorantSpan {
    let grid = majorant_grid;
    let w_tex = w * texture_per_world;
    let ahead = 0.01 * majorant_ahead;
    let o = path_texture(p);
    let u = o + (t + ahead) * w_tex;
    let b = block_at(u, grid);
    var lo = blocks_box_lo(b, grid);
    var hi = blocks_box_hi(b, grid);
    let alpha = textureSampleLevel(majorants, nearest_clamp, block_texel(b, grid), 0.0).r;
#if MAJORANT_LEAP
    if (alpha == 0.0) {
        let region = empty_region_at(u, cube_grid);
        if (region.empty) {
            lo = region.lo;
            hi = region.hi;
        }
    }
#endif
    let leaves = box_exit_by(o, step_exit(w_tex), lo, hi);
    return MajorantSpan(extinction_of(alpha), min(max(leaves, t + ahead), limit));
}
#else
// One majorant for the whole volume: the TF's most opaque value's.
fn majorant_span(p: vec3<f32>, w: vec3<f32>, t: f32, limit: f32) -> MajorantSpan {
    return MajorantSpan(extinction_of(trace.max_alpha), limit);
}
#endif

// The part [t0, t1) of the world ray p + t·w inside the box and kept by the scene's cuts. The
// box is the one primary rays cross (`march_lo/hi`, common/ray_box.wgsl): the volume's, or with
// several scalar volumes the union of their boxes, so a PET reaching past its CT scatters light
// where it lies.
fn world_segment(p: vec3<f32>, w: vec3<f32>) -> vec2<f32> {
    let half = frame.half_extent.xyz;
    let span = box_span(p, w, world_from_texture(march_lo()), world_from_texture(march_hi()));
    let kept = cut_segment(texture_from_world(p), w / (2.0 * half), max(span.x, 0.0), span.y);
    return select(vec2<f32>(0.0, 0.0), kept, kept.x < kept.y);
}

// The next tentative collision after `t` on p + t·w before `limit`: free paths at the rate of
// the majorant `m` holds; a path that reaches a majorant's end restarts there at the next one's
// rate (the exponential has no memory), and one of rate 0 (an empty block) is crossed at once.
// `limit` when the path leaves; `m` is left holding the result's majorant.
fn next_tentative(p: vec3<f32>, w: vec3<f32>, t0: f32, m: ptr<function, MajorantSpan>, limit: f32) -> f32 {
    var t = t0;
    for (var i = 0u; i < MAX_TRACKING_STEPS; i += 1u) {
        if (t >= limit) {
            return limit;
        }
        if ((*m).sigma > 0.0) {
            let next = t + free_path((*m).sigma);
            if (next < (*m).end) {
                return next;
            }
        }
        t = (*m).end;
        *m = majorant_span(p, w, t, limit);
    }
    return limit;
}

// Delta tracking: the distance to the first real interaction in [t0, t1), or −1 when the path
// leaves: a tentative collision is real with probability σ/σ̄.
fn delta_track(p: vec3<f32>, w: vec3<f32>, span: vec2<f32>) -> f32 {
    var t = span.x;
    var m = majorant_span(p, w, t, span.y);
    for (var i = 0u; i < MAX_TRACKING_STEPS; i += 1u) {
        t = next_tentative(p, w, t, &m, span.y);
        if (t >= span.y) {
            return -1.0;
        }
        if (random() * m.sigma < medium_at(p + t * w).a) {
            return t;
        }
    }
    return -1.0;
}

// Ratio tracking: an unbiased estimate of the transmittance along [t0, t1), the product of
// (1 − σ/σ̄) over the tentative collisions.
fn ratio_track(p: vec3<f32>, w: vec3<f32>, span: vec2<f32>) -> f32 {
    var t = span.x;
    var m = majorant_span(p, w, t, span.y);
    var transmittance = 1.0;
    for (var i = 0u; i < MAX_TRACKING_STEPS; i += 1u) {
        t = next_tentative(p, w, t, &m, span.y);
        if (t >= span.y) {
            return transmittance;
        }
        transmittance *= max(1.0 - medium_at(p + t * w).a / m.sigma, 0.0);
        // Russian roulette: a small estimate survives with probability ½, doubled.
        if (transmittance < 0.1) {
            if (random() < 0.5) {
                return 0.0;
            }
            transmittance *= 2.0;
        }
    }
    return 0.0;
}

// Delta tracking of a primary ray (`delta_track`'s first interaction, −1 when it leaves: x)
// that also estimates its transmittance by ratio tracking (`ratio_track`: y) over the same
// tentative collisions, continued past the first real one to the ray's end: whatever is
// accepted, the tentative collisions are one Poisson process of rate σ̄ along the whole ray, so
// the product over all of them is ratio tracking's estimate — without tracking the ray twice.
fn primary_track(p: vec3<f32>, w: vec3<f32>, span: vec2<f32>) -> vec2<f32> {
    var t = span.x;
    var m = majorant_span(p, w, t, span.y);
    var hit = -1.0;
    var transmittance = 1.0;
    for (var i = 0u; i < MAX_TRACKING_STEPS; i += 1u) {
        t = next_tentative(p, w, t, &m, span.y);
        if (t >= span.y) {
            break;
        }
        let sigma = medium_at(p + t * w).a;
        if (hit < 0.0 && random() * m.sigma < sigma) {
            hit = t;
        }
        if (transmittance > 0.0) {
            transmittance *= max(1.0 - sigma / m.sigma, 0.0);
            // Russian roulette as ratio_track's: a small estimate survives with probability ½.
            if (transmittance < 0.1) {
                transmittance = select(0.0, 2.0 * transmittance, random() < 0.5);
            }
        }
        if (hit >= 0.0 && transmittance == 0.0) {
            break;
        }
    }
    return vec2<f32>(hit, transmittance);
}

// The transmittance from `p` toward the light: ratio tracking's estimate, or delta tracking's
// 0 or 1 (`shadow_rays: "delta"`, the cheaper, noisier estimator bench cinematic compares).
fn light_transmittance(p: vec3<f32>, l: vec3<f32>, distance: f32) -> f32 {
    let whole = world_segment(p, l);
    // Material beyond a point light casts no shadow.
    let span = vec2<f32>(whole.x, min(whole.y, distance));
    if (trace.shadow_rays == 1u) {
        return select(0.0, 1.0, delta_track(p, l, span) < 0.0);
    }
    return ratio_track(p, l, span);
}

// ---- light -----------------------------------------------------------------------------------

// The unit world direction toward the scene's light `i` from world point `p` (xyz) and the
// distance to it (w; 3e38 for a distant light): a directional light (w = 1), a point light
// (w = 2), else the headlight (from the eye, along the camera's forward axis).
// volgraph_accel::light::Toward.
fn toward_light(p: vec3<f32>, i: u32) -> vec4<f32> {
    let light = frame.lights[i];
    if (light.w == 2.0) {
        let d = light.xyz - p;
        let r = length(d);
        return vec4<f32>(select(vec3<f32>(0.0, 1.0, 0.0), d / r, r > 1e-12), r);
    }
    if (light.w == 1.0) {
        return vec4<f32>(light.xyz, 3.0e38);
    }
    return vec4<f32>(-frame.camera_forward.xyz, 3.0e38);
}

// The scene's environment map (volgraph_accel::environment): equirectangular, row 0 up, the
// column at u = atan2(x, −z) / 2π + ½; 1×1 black when the scene has none.
@group(0) @binding(auto) var environment_map: texture_2d<f32>;

// The map's radiance along unit `w`, nearest texel (EnvironmentMap::radiance).
fn environment_radiance(w: vec3<f32>) -> vec3<f32> {
    let size = vec2<i32>(textureDimensions(environment_map));
    let u = atan2(w.x, -w.z) / (2.0 * PI) + 0.5;
    let v = acos(clamp(w.y, -1.0, 1.0)) / PI;
    let x = ((i32(floor(u * f32(size.x))) % size.x) + size.x) % size.x;
    let y = clamp(i32(floor(v * f32(size.y))), 0, size.y - 1);
    return textureLoad(environment_map, vec2<i32>(x, y), 0).rgb;
}

// What a path leaving along `w` sees: world +y is up (the orbit camera's up).
fn environment(w: vec3<f32>) -> vec3<f32> {
    if (trace.environment == 1u) {
        return vec3<f32>(trace.environment_intensity);
    }
    if (trace.environment_map == 1u) {
        return environment_radiance(w) * trace.environment_intensity;
    }
    let ground = vec3<f32>(0.32, 0.30, 0.28);
    let horizon = vec3<f32>(0.85, 0.85, 0.82);
    let zenith = vec3<f32>(0.35, 0.55, 0.95);
    let up = w.y;
    let sky = select(mix(horizon, ground, smoothstep(0.0, 0.3, -up)), mix(horizon, zenith, smoothstep(0.0, 0.6, up)), up >= 0.0);
    return sky * trace.environment_intensity;
}

// ---- scattering ------------------------------------------------------------------------------

// Henyey–Greenstein for the cosine between the path's direction and the outgoing one.
fn henyey_greenstein(cos_theta: f32, g: f32) -> f32 {
    let d = 1.0 + g * g - 2.0 * g * cos_theta;
    return (1.0 - g * g) / (4.0 * PI * d * sqrt(max(d, 1e-12)));
}

// Any unit vector perpendicular to unit `n`, and the third of a frame (Duff et al. 2017).
fn basis(n: vec3<f32>) -> mat3x3<f32> {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    let t = vec3<f32>(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    let u = vec3<f32>(b, s + n.y * n.y * a, -n.y);
    return mat3x3<f32>(t, u, n);
}

// A direction from the HG lobe around `w`; `xi`: two uniform numbers in [0, 1).
fn sample_henyey_greenstein(w: vec3<f32>, g: f32, xi: vec2<f32>) -> vec3<f32> {
    var cos_theta = 1.0 - 2.0 * xi.x;
    if (abs(g) > 1e-3) {
        let q = (1.0 - g * g) / (1.0 - g + 2.0 * g * xi.x);
        cos_theta = clamp((1.0 + g * g - q * q) / (2.0 * g), -1.0, 1.0);
    }
    let sin_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta));
    let phi = 2.0 * PI * xi.y;
    return normalize(basis(w) * vec3<f32>(sin_theta * cos(phi), sin_theta * sin(phi), cos_theta));
}

// A cosine-weighted direction about unit `n`; `xi`: two uniform numbers in [0, 1).
fn sample_cosine(n: vec3<f32>, xi: vec2<f32>) -> vec3<f32> {
    let r = sqrt(xi.x);
    let phi = 2.0 * PI * xi.y;
    return normalize(basis(n) * vec3<f32>(r * cos(phi), r * sin(phi), sqrt(max(0.0, 1.0 - r * r))));
}

// The field's world gradient at `p` by central differences one voxel apart (scalar per voxel).
fn voxel_gradient(p: vec3<f32>) -> vec3<f32> {
    let u = texture_from_world(p);
    let h = 1.0 / frame.volume_dims.xyz;
    let dx = sample_volume(u + vec3<f32>(h.x, 0.0, 0.0)) - sample_volume(u - vec3<f32>(h.x, 0.0, 0.0));
    let dy = sample_volume(u + vec3<f32>(0.0, h.y, 0.0)) - sample_volume(u - vec3<f32>(0.0, h.y, 0.0));
    let dz = sample_volume(u + vec3<f32>(0.0, 0.0, h.z)) - sample_volume(u - vec3<f32>(0.0, 0.0, h.z));
    // Per voxel along each axis; world directions scale by the voxel's world size per axis.
    let voxel_world = 2.0 * frame.half_extent.xyz / frame.volume_dims.xyz;
    return 0.5 * vec3<f32>(dx, dy, dz) * (frame.half_extent.w / voxel_world);
}

// A scattering point's lobes and the light reaching it: the probability of scattering off the
// gradient's surface rather than by the phase function (none where the field is flat), that
// surface's normal (facing the incoming path), and the light of the scene's lights scattered
// toward the path by the mixture of the two lobes.
struct Scattering {
    surface: f32,
    normal: vec3<f32>,
    direct: vec3<f32>,
}

fn scattering_at(p: vec3<f32>, w: vec3<f32>) -> Scattering {
    let g = voxel_gradient(p);
    let strength = length(g);
    let surface = select(0.0, trace.surface * (1.0 - exp(-20.0 * strength)), strength > 1e-6);
    var n = -g / max(strength, 1e-30);
    if (dot(n, w) > 0.0) {
        n = -n;
    }
    // Next-event estimation toward every light: its direction (xyz) and the irradiance that
    // reaches here (w). A point light's irradiance falls as 1/r² (light_intensity at one world
    // unit). The light scattered toward the eye is weighted by the mixture of the two lobes, each
    // by its probability — off a Lambertian surface light × cos / π, by the phase function
    // light × p — rather than by the one lobe drawn (the same mean, without the noise of the
    // draw: the lobes differ by 4× at a lit surface).
    var direct = vec3<f32>(0.0);
    for (var i = 0u; i < frame.light_count; i++) {
        let light = toward_light(p, i);
        let falloff = select(1.0, 1.0 / max(light.w * light.w, 1e-12), light.w < 1.0e38);
        let irradiance = light_transmittance(p, light.xyz, light.w) * trace.light_intensity * falloff;
        let lobes = surface * max(dot(n, light.xyz), 0.0) / PI + (1.0 - surface) * henyey_greenstein(dot(w, light.xyz), trace.anisotropy);
        direct += vec3<f32>(irradiance * lobes);
    }
    return Scattering(surface, n, direct);
}

// ---- one path --------------------------------------------------------------------------------

// Where this frame's path first interacted along the pixel's ray (world), and whether it did:
// the point a REPROJECT pass finds the pixel's last-frame mean by.
var<private> first_point: vec3<f32>;
var<private> first_hit: bool;

// One path's estimate for the pixel's ray: premultiplied RGB and alpha (1 when the primary ray
// interacted).
fn trace_pixel(pixel: vec2<u32>) -> vec4<f32> {
#if FUSION
    begin_fusion();
#endif
    begin_path();
    let ray = analytic_ray(pixel);
    if (!(ray.len > ray.begin)) {
        return vec4<f32>(0.0);
    }
    let world_per_tex = length(ray.d * 2.0 * frame.half_extent.xyz);
    var p = world_from_texture(ray.u0);
    var w = normalize(ray.d * 2.0 * frame.half_extent.xyz);
    var span = vec2<f32>(ray.begin, ray.len) * world_per_tex;
    var radiance = vec3<f32>(0.0);
    var throughput = vec3<f32>(1.0);
    var alpha = 0.0;
    let ratio_coverage = trace.coverage == 0u;
    for (var bounce = 0u; bounce <= trace.bounces; bounce += 1u) {
        var t: f32;
        if (bounce == 0u && ratio_coverage) {
            let tracked = primary_track(p, w, span);
            t = tracked.x;
            alpha = 1.0 - tracked.y;
        } else {
            t = delta_track(p, w, span);
        }
        if (t < 0.0) {
            if (bounce > 0u) {
                radiance += throughput * environment(w);
            }
            break;
        }
        p = p + t * w;
        if (bounce == 0u) {
            alpha = select(1.0, alpha, ratio_coverage);
            first_point = p;
            first_hit = true;
        }
        let medium = medium_at(p);
        // Absorbed with probability 1 − albedo, emitting, else scattered: both in expectation
        // (the path carries the albedo in its throughput instead of ending at random, which
        // left a tenth of the paths black at albedo 0.9; Russian roulette below ends dim ones).
        radiance += throughput * (1.0 - trace.albedo) * trace.emission * medium.rgb;
        throughput *= trace.albedo * medium.rgb;
        if (bounce == trace.bounces || !(trace.albedo > 0.0)) {
            break;
        }
        let here = scattering_at(p, w);
        let surface = here.surface;
        let n = here.normal;
        radiance += throughput * here.direct;
        // The next direction from the mixture: each lobe importance-sampled (f·cos/pdf and
        // p/pdf are 1, so the mixture's weight is 1 too).
        if (surface > 0.0 && random() < surface) {
            w = sample_cosine(n, vec2<f32>(random(), random()));
        } else {
            w = sample_henyey_greenstein(w, trace.anisotropy, vec2<f32>(random(), random()));
        }
        // Russian roulette from the second scattering on (unbiased): the path goes on with
        // probability q, its largest throughput channel over RR_LEVEL (between 1/20 and 1), and
        // its throughput is divided by q — dim paths end early, and a divided throughput stays
        // below RR_LEVEL, so no channel exceeds 1 and the furnace and energy bounds hold sample
        // by sample.
        if (bounce >= 1u && trace.russian_roulette == 1u) {
            let q = clamp(max(throughput.r, max(throughput.g, throughput.b)) / RR_LEVEL, 0.05, 1.0);
            if (random() >= q) {
                break;
            }
            throughput /= q;
        }
        span = world_segment(p, w);
    }
    return vec4<f32>(radiance, alpha);
}

#if REPROJECT
// Martschinke et al. 2019's idea for path-traced volumes (and Klein et al. 2005's for hits):
// when the camera moves, a pixel keeps the mean of where its surface was last frame. `aux` is
// per pixel: x = the samples its mean holds, yzw = the mean world point of its paths' first
// interactions. A pixel's surface point this frame is its path's first interaction (else its
// last-frame mean point's depth along this frame's ray); projected with last frame's camera it
// lands on the pixel whose mean it continues, when that pixel's mean point lies within
// `reproject_tolerance` voxels of it (else the pixel starts over: a disocclusion). After a move
// a pixel keeps at most `reproject_keep` samples, so light of the old view fades.
@group(0) @binding(auto) var previous_aux: texture_2d<f32>;
@group(0) @binding(auto) var aux: texture_storage_2d<rgba32float, write>;

// Whether the camera moved since last frame (history restarts set last frame's camera to this
// frame's).
fn camera_moved() -> bool {
    let a = frame.clip_from_world;
    let b = frame.prev_clip_from_world;
    return any(a[0] != b[0]) || any(a[1] != b[1]) || any(a[2] != b[2]) || any(a[3] != b[3]);
}

// The mean point of a pixel none of whose paths has interacted: far from every surface.
const NO_POINT: f32 = 1.0e30;

struct Continued {
    mean: vec4<f32>,
    aux: vec4<f32>,
}

// The last-frame mean and aux this pixel continues: its own while the camera rests; where its
// surface point was seen last frame after a move; nothing (zeros) where that does not hold.
fn continued(pixel: vec2<u32>) -> Continued {
    let none = Continued(vec4<f32>(0.0), vec4<f32>(0.0));
    let here = vec2<i32>(pixel);
    if (!camera_moved()) {
        return Continued(textureLoad(previous, here, 0), textureLoad(previous_aux, here, 0));
    }
    var point = first_point;
    if (!first_hit) {
        // No interaction this sample: the depth of last frame's mean point at this pixel, along
        // this frame's ray.
        let own = textureLoad(previous_aux, here, 0);
        if (!(own.x > 0.0) || own.y == NO_POINT) {
            return none;
        }
        let dir = pixel_ray_dir(vec2<f32>(pixel) + vec2<f32>(0.5));
        point = frame.eye_world.xyz + dir * length(own.yzw - frame.eye_world.xyz);
    }
    let clip = frame.prev_clip_from_world * vec4<f32>(point, 1.0);
    if (!(clip.w > 0.0)) {
        return none;
    }
    let ndc = clip.xy / clip.w;
    let at = vec2<f32>((ndc.x + 1.0) * 0.5 * frame.viewport.x, (1.0 - ndc.y) * 0.5 * frame.viewport.y);
    if (any(at < vec2<f32>(0.0)) || any(at >= frame.viewport.xy)) {
        return none;
    }
    // (Lengths of differences: with MAJORANT_LEAP `distance` names the distance map.)
    // The pixel the point lands in, where its mean point is near enough; else, of the 2×2 pixels
    // whose centres surround the point, the one whose mean point lies nearest (at an edge the
    // pixel it lands in may hold the mean of a neighbouring, farther surface).
    let size = vec2<i32>(frame.viewport.xy);
    let tolerance = trace.reproject_tolerance * frame.half_extent.w;
    var best = vec2<i32>(floor(at));
    let own = textureLoad(previous_aux, best, 0);
    if (!(own.x > 0.0 && length(own.yzw - point) <= tolerance)) {
        best = vec2<i32>(-1);
        var best_distance = tolerance;
        let corner = vec2<i32>(floor(at - vec2<f32>(0.5)));
        for (var i = 0; i < 4; i += 1) {
            let q = clamp(corner + vec2<i32>(i & 1, i >> 1u), vec2<i32>(0), size - vec2<i32>(1));
            let was = textureLoad(previous_aux, q, 0);
            let d = length(was.yzw - point);
            if (was.x > 0.0 && d <= best_distance) {
                best = q;
                best_distance = d;
            }
        }
        if (best.x < 0) {
            return none;
        }
    }
    let was = textureLoad(previous_aux, best, 0);
    let kept = min(was.x, f32(trace.reproject_keep));
    return Continued(textureLoad(previous, best, 0), vec4<f32>(kept, was.yzw));
}
#endif

@compute @workgroup_size(8, 8)
fn cs_path_trace(@builtin(global_invocation_id) id: vec3<u32>) {
    let pixel = id.xy;
    if (!in_viewport(pixel)) {
        return;
    }
    seed_rng(pixel, frame.history_age);
    first_hit = false;
    let sample = trace_pixel(pixel);
#if REPROJECT
    let from_last = continued(pixel);
    let before = from_last.mean;
    let n = from_last.aux.x;
    // The mean first-interaction point over the samples that had one (a running mean weighted
    // like the colour's: exact while every sample interacts, a fair depth otherwise).
    // A pixel none of whose paths has interacted yet keeps a point no surface is near (1e30).
    var point = select(vec3<f32>(NO_POINT), from_last.aux.yzw, n > 0.0);
    if (first_hit) {
        point = select(first_point, point + (first_point - point) / (n + 1.0), n > 0.0 && point.x != NO_POINT);
    }
    textureStore(aux, vec2<i32>(pixel), vec4<f32>(n + 1.0, point));
#else
    let n = f32(frame.history_age);
    let before = textureLoad(previous, vec2<i32>(pixel), 0);
#endif
    // The running mean over n + 1 samples; a NaN sample (none should occur) is dropped rather
    // than poisoning the mean for good.
    let safe = select(vec4<f32>(before), sample, all(sample == sample));
    textureStore(color, vec2<i32>(pixel), before + (safe - before) / (n + 1.0));
}
