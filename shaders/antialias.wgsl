// Klein et al. 2005 §5: selective super-sampling. A pixel whose colour differs from one of its
// four neighbours by more than `contrast` (any channel) is re-rendered from sub-pixel rays — two
// on a diagonal (2x), four on a regular grid (4x) or four on a rotated grid (rgss) — whose
// directions are interpolated from the pixel's and its neighbours' unit ray directions (linear:
// the pixel and two neighbours, as the paper's Fig. 7; bilinear: four) or the camera's own
// (exact), and which start from the nearest leap hit of the pixel and its neighbours, on their
// own step grid. Full-scene super-sampling (`full`) re-renders every pixel: the
// baseline. The other pixels keep their colour.

#import "common/frame.wgsl"
#import "common/fullscreen.wgsl"
#import "common/leap.wgsl"
// The `aa` block, declared once in Rust (`AaParams` in crates/passes/src/antialias.rs).
#import "params/AaParams.wgsl"

// The raycast colour.
@group(0) @binding(auto) var color: texture_2d<f32>;
// The raycast's leap hits (xyz texture space; w = 1 surface, 0.5 exit point, 0 no ray).
@group(0) @binding(auto) var hits: texture_2d<f32>;
@group(0) @binding(auto) var<uniform> aa: AaParams;

fn texel_clamped(t: texture_2d<f32>, p: vec2<i32>) -> vec4<f32> {
    return textureLoad(t, clamp(p, vec2<i32>(0), vec2<i32>(textureDimensions(t)) - vec2<i32>(1)), 0);
}

// Whether pixel `p` needs more rays.
fn flagged(p: vec2<i32>) -> bool {
    if (aa.full != 0u) {
        return true;
    }
    let c = texel_clamped(color, p);
    let offsets = array<vec2<i32>, 4>(vec2<i32>(1, 0), vec2<i32>(-1, 0), vec2<i32>(0, 1), vec2<i32>(0, -1));
    for (var i = 0u; i < 4u; i += 1u) {
        let d = abs(texel_clamped(color, p + offsets[i]) - c);
        if (max(max(d.x, d.y), max(d.z, d.w)) > aa.contrast) {
            return true;
        }
    }
    return false;
}

// Sub-pixel offset `i` (in pixels, from the centre) of the pattern, and the count.
fn pattern_count() -> u32 {
    return select(4u, 2u, aa.pattern == 2u);
}

fn pattern_offset(i: u32) -> vec2<f32> {
    if (aa.pattern == 2u) {
        let two = array<vec2<f32>, 2>(vec2<f32>(-0.25, -0.25), vec2<f32>(0.25, 0.25));
        return two[min(i, 1u)];
    }
    if (aa.pattern == 5u) {
        // Rotated grid: every row and column of the pixel holds exactly one sample.
        let rg = array<vec2<f32>, 4>(vec2<f32>(0.125, -0.375), vec2<f32>(0.375, 0.125), vec2<f32>(-0.125, 0.375), vec2<f32>(-0.375, -0.125));
        return rg[min(i, 3u)];
    }
    let grid = array<vec2<f32>, 4>(vec2<f32>(-0.25, -0.25), vec2<f32>(0.25, -0.25), vec2<f32>(-0.25, 0.25), vec2<f32>(0.25, 0.25));
    return grid[min(i, 3u)];
}

// The unit texture-space direction of pixel `q`'s ray (the camera's, as the raycaster's
// analytic rays).
fn pixel_direction(q: vec2<i32>) -> vec3<f32> {
    return normalize(pixel_ray_texture(vec2<f32>(q) + vec2<f32>(0.5)));
}

// The direction of the sub-pixel ray at offset `o` of pixel `p`, scaled to unit forward distance.
fn subpixel_direction(p: vec2<i32>, o: vec2<f32>) -> vec3<f32> {
    if (aa.directions == 2u) {
        return pixel_ray_texture(vec2<f32>(p) + vec2<f32>(0.5) + o);
    }
    let s = vec2<i32>(select(-1, 1, o.x >= 0.0), select(-1, 1, o.y >= 0.0));
    let w = abs(o);
    let d0 = pixel_direction(p);
    let dx = pixel_direction(p + vec2<i32>(s.x, 0));
    let dy = pixel_direction(p + vec2<i32>(0, s.y));
    var d = d0 + w.x * (dx - d0) + w.y * (dy - d0);
    if (aa.directions == 1u) {
        let dxy = pixel_direction(p + s);
        d = (1.0 - w.x) * (1.0 - w.y) * d0 + w.x * (1.0 - w.y) * dx + (1.0 - w.x) * w.y * dy + w.x * w.y * dxy;
    }
    // To unit forward distance (analytic_ray_along's convention).
    return d / max(dot(d * 2.0 * frame.half_extent.xyz, frame.camera_forward.xyz), 1e-12);
}

// Where a sub-pixel ray of pixel `p` starts: at the nearest of the points the pixel's and its
// four neighbours' rays reported (surface hits, or exit points of rays that met nothing,
// projected onto this ray), less the step back; at its entry when one of them had no ray (the
// footprint's edge runs through the pixel).
fn subray_start(p: vec2<i32>, ray: Ray, s: Samples) -> u32 {
    let offsets = array<vec2<i32>, 5>(vec2<i32>(0, 0), vec2<i32>(1, 0), vec2<i32>(-1, 0), vec2<i32>(0, 1), vec2<i32>(0, -1));
    var k0 = 0xffffffffu;
    for (var i = 0u; i < 5u; i += 1u) {
        let hit = texel_clamped(hits, p + offsets[i]);
        if (hit.w == 0.0) {
            return 0u;
        }
        k0 = min(k0, start_sample(hit, ray, s));
    }
    return k0;
}

struct AaOut {
    @location(0) color_aa: vec4<f32>,
}

fn resolve(in: FullscreenVertex, iso: bool) -> AaOut {
    let p = vec2<i32>(in.clip.xy);
    let pixel = vec2<u32>(p);
    if (!flagged(p)) {
        return AaOut(textureLoad(color, p, 0));
    }
    var sum = vec4<f32>(0.0);
    let n = pattern_count();
    for (var i = 0u; i < n; i += 1u) {
        let ray = analytic_ray_along(subpixel_direction(p, pattern_offset(i)));
        let s = pixel_samples(ray, pixel);
        let k0 = subray_start(p, ray, s);
        if (iso) {
            sum += march_iso(s, k0, s.count).color;
        } else {
            begin_ray(s, k0);
            sum += march_dvr(s, k0, s.count, vec4<f32>(0.0)).color;
        }
    }
    return AaOut(sum / f32(n));
}

@fragment
fn fs_aa_dvr(in: FullscreenVertex) -> AaOut {
    return resolve(in, false);
}

@fragment
fn fs_aa_iso(in: FullscreenVertex) -> AaOut {
    return resolve(in, true);
}
