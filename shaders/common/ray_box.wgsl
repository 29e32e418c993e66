// A pixel's ray met analytically with the volume box, in texture space: the same segment as
// `volgraph_accel::reference::ray_segment` and docs/rendering_model.md ("Ray segment inside the
// box"). Needs only the frame, so any pass can import it — the compute raycasters through
// common/pixel_ray.wgsl, a WGSL-only pass directly (graph_kinds/mip_projection.wgsl).

#import "common/frame.wgsl"

// A pixel's ray in texture space; `len = 0` for no ray. `u0` is where it enters the box (the
// step grid's anchor); its samples lie between `begin` and `len` from there: `begin` is 0 but
// where something cuts the ray's front (`own_segment`): a sort-last window (frame.grid_lo.w),
// where the ray is met with the whole volume's box and this process takes only the samples in
// its own box, or a scene's crop box and clip planes (#if CROP, #if CLIP).
struct Ray {
    u0: vec3<f32>,
    d: vec3<f32>,
    len: f32,
    begin: f32,
    // True when the samples before `begin` are another rank's (a window's own box cut the
    // ray, not a crop or clip): a first-hit search still reads the one before.
    looks_back: bool,
}

// The part [t_in, t_out] of the line eye + t·dir (any parameter) inside the box [lo, hi]; empty
// when t_in > t_out. An axis the line runs parallel to bounds it only when the eye is outside
// that slab.
fn box_span(eye: vec3<f32>, dir: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> vec2<f32> {
    let far = vec3<f32>(3.0e38);
    let parallel = dir == vec3<f32>(0.0);
    let inv = 1.0 / select(dir, vec3<f32>(1.0), parallel);
    let ta = (lo - eye) * inv;
    let tb = (hi - eye) * inv;
    let inside = (eye >= lo) & (eye <= hi);
    let t_lo = select(min(ta, tb), select(far, -far, inside), parallel);
    let t_hi = select(max(ta, tb), select(-far, far, inside), parallel);
    return vec2<f32>(max(t_lo.x, max(t_lo.y, t_lo.z)), min(t_hi.x, min(t_hi.y, t_hi.z)));
}

// Where the ray being marched starts, uncut (for `cap_normal`); set by `own_segment`.
var<private> ray_start: vec3<f32>;

// `ray` (met with the grid box) cut to this frame's own box and to what the scene's cuts keep:
// samples from `begin` to `len`. The identity without a sort-last window or cuts. A cut ray
// keeps its entry `u0`, so every sample lies on the one step grid: each sample belongs to the
// one box that holds it, and a crop drops samples without moving the others.
fn own_segment(ray: Ray) -> Ray {
    ray_start = ray.u0;
    var begin = ray.begin;
    var end = ray.len;
    var looks_back = false;
    if (is_window() && ray.len > 0.0) {
        let span = box_span(ray.u0, ray.d, frame.own_lo.xyz, frame.own_hi.xyz);
        begin = max(span.x, 0.0);
        end = min(span.y, ray.len);
        looks_back = begin > 0.0;
    }
    let kept = cut_segment(ray.u0, ray.d, begin, end);
    // A crop face is a cap: nothing lies in front of it to look back at.
    looks_back = looks_back && kept.x <= begin;
    return Ray(ray.u0, ray.d, select(0.0, kept.y, kept.x < kept.y), kept.x, looks_back);
}

// The part [begin, end) of the ray u0 + t·d the scene's crop box (#if CROP) and clip planes
// (#if CLIP) keep; the identity when a scene uses neither (nothing of this is compiled then).
// The box and planes come in the bound texture's coordinates (FrameUniforms maps them from
// volume fractions); an unused plane is (0, 0, 0, -1), which keeps everything. The f64 twin is
// `volgraph_accel::cuts::Cuts::keeps_interval`.
fn cut_segment(u0: vec3<f32>, d: vec3<f32>, begin: f32, end: f32) -> vec2<f32> {
    var kept = vec2<f32>(begin, end);
#if CROP
    kept = crop_segment(u0, d, kept);
#endif
#if CLIP
    kept = clip_segment(u0, d, kept);
#endif
    return kept;
}

#if CROP
// `kept` cut to the crop box.
fn crop_segment(u0: vec3<f32>, d: vec3<f32>, kept: vec2<f32>) -> vec2<f32> {
    let span = box_span(u0, d, frame.crop_lo.xyz, frame.crop_hi.xyz);
    return vec2<f32>(max(kept.x, span.x), min(kept.y, span.y));
}
#endif

#if CLIP
// `kept` cut to the half-spaces of the clip planes.
fn clip_segment(u0: vec3<f32>, d: vec3<f32>, kept_in: vec2<f32>) -> vec2<f32> {
    var kept = kept_in;
    for (var i = 0u; i < 6u; i += 1u) {
        let plane = frame.clip_planes[i];
        let along = dot(plane.xyz, d);
        let at = dot(plane.xyz, u0);
        if (along > 0.0) {
            kept.x = max(kept.x, (plane.w - at) / along);
        } else if (along < 0.0) {
            kept.y = min(kept.y, (plane.w - at) / along);
        } else if (at < plane.w) {
            kept.y = -3.0e38;
        }
    }
    return kept;
}
#endif

#if CUTS
// "Capping" (docs/rendering_model.md "Cuts"; f64 twin `Cuts::cap_normal` in
// crates/base/src/cuts.rs): the shading normal `n` at `u`, on a ray starting at `ray_start`
// and running along world direction `d_world`, turned toward the world normal of every cut face
// the ray entered through within CAP_VOXELS of `u`, each by 1 - distance / CAP_VOXELS (weights scaled to sum to 1 where
// faces meet). A cut face then shows the plane it was cut along instead of the noisy gradient of
// the material just behind it. Crop faces on the volume's own boundary (the window's grid) are
// not cuts. Compiled with a cut (#if CUTS).
const CAP_VOXELS: f32 = 2.0;

// One face (texture-space half-space normal·u >= offset): its world normal on n's side, times
// its weight, and the weight; nothing unless the ray entered through it (it started on the side
// the face cuts away and runs into the kept one).
fn cap_face(normal: vec3<f32>, offset: f32, u: vec3<f32>, d_tex: vec3<f32>, n: vec3<f32>) -> vec4<f32> {
    if (dot(normal, d_tex) <= 0.0 || dot(normal, ray_start) >= offset) {
        return vec4<f32>(0.0);
    }
    let voxels = (dot(normal, u) - offset) / length(normal / frame.volume_dims.xyz);
    let w = clamp(1.0 - voxels / CAP_VOXELS, 0.0, 1.0);
    if (!(w > 0.0)) {
        return vec4<f32>(0.0);
    }
    let world = normalize(normal / frame.half_extent.xyz);
    return vec4<f32>(select(world, -world, dot(world, n) < 0.0) * w, w);
}

fn cap_normal(u: vec3<f32>, d_world: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    // Texture space runs along world / (2 · half extent).
    let d_tex = d_world / frame.half_extent.xyz;
    var acc = vec4<f32>(0.0);
#if CROP
    // Which crop faces are cuts (FrameUniforms::with_cuts): bit a low, bit 3 + a high.
    let faces = u32(frame.crop_lo.w);
    for (var a = 0u; a < 3u; a += 1u) {
        var e = vec3<f32>(0.0);
        e[a] = 1.0;
        if (((faces >> a) & 1u) != 0u) {
            acc += cap_face(e, frame.crop_lo[a], u, d_tex, n);
        }
        if (((faces >> (3u + a)) & 1u) != 0u) {
            acc += cap_face(-e, -frame.crop_hi[a], u, d_tex, n);
        }
    }
#endif
#if CLIP
    for (var i = 0u; i < 6u; i += 1u) {
        let plane = frame.clip_planes[i];
        if (any(plane.xyz != vec3<f32>(0.0))) {
            acc += cap_face(plane.xyz, plane.w, u, d_tex, n);
        }
    }
#endif
    if (!(acc.w > 0.0)) {
        return n;
    }
    let scale = select(1.0, 1.0 / acc.w, acc.w > 1.0);
    let mixed = n * (1.0 - acc.w * scale) + acc.xyz * scale;
    return select(n, normalize(mixed), length(mixed) > 1e-12);
}
#endif

// The box rays cross, in the bound texture's coordinates: the volume's [0,1]³; a sort-last
// window's whole grid; or, with several scalar volumes (FUSION_SCALAR), the union of their
// boxes (common/fusion.wgsl's `fusion.march_lo/hi`, volgraph_accel::fusion::march_box), so a
// PET reaching past its CT is drawn where it lies.
fn march_lo() -> vec3<f32> {
#if FUSION_SCALAR
    return select(fusion.march_lo.xyz, frame.grid_lo.xyz, is_window());
#else
    return select(vec3<f32>(0.0), frame.grid_lo.xyz, is_window());
#endif
}

fn march_hi() -> vec3<f32> {
#if FUSION_SCALAR
    return select(fusion.march_hi.xyz, frame.grid_hi.xyz, is_window());
#else
    return select(vec3<f32>(1.0), frame.grid_hi.xyz, is_window());
#endif
}

// The ray of pixel centre `pixel` clipped to the box and the near plane, as
// `volgraph_accel::reference::ray_segment` clips it (slab test; start at max(t_in, t_near); the
// ends clamped to [0,1]³; rays shorter than 1e-6 dropped), computed in texture space from the
// frame's per-pixel ray (FrameUniforms::ray_*_texture): the box is [0,1]³ and, the direction
// being scaled to unit forward distance, the near plane is at t = near. No loop, no early
// return: the lanes of a SIMD group stay together.
fn analytic_ray(pixel: vec2<u32>) -> Ray {
    return analytic_ray_at(vec2<f32>(pixel) + vec2<f32>(0.5));
}

// The texture-space direction of the ray through image position `at` (pixels; pixel centres at
// +0.5), scaled to unit forward distance.
fn pixel_ray_texture(at: vec2<f32>) -> vec3<f32> {
    return frame.ray_base_texture.xyz + at.x * frame.ray_dx_texture.xyz + at.y * frame.ray_dy_texture.xyz;
}

// The ray through image position `at` (any sub-pixel position), clipped like `analytic_ray`.
fn analytic_ray_at(at: vec2<f32>) -> Ray {
    return analytic_ray_along(pixel_ray_texture(at));
}

// The ray from the eye along texture-space direction `dir` (scaled to unit forward distance),
// clipped to the box and the near plane like `analytic_ray`.
fn analytic_ray_along(dir: vec3<f32>) -> Ray {
    let eye = frame.eye_texture.xyz;
    let lo = march_lo();
    let hi = march_hi();
    let span = box_span(eye, dir, lo, hi);
    let t_in = span.x;
    let t_out = span.y;
    let t0 = max(t_in, frame.camera_forward.w);
    let u0 = clamp(eye + t0 * dir, lo, hi);
    let u1 = clamp(eye + t_out * dir, lo, hi);
    let len = length(u1 - u0);
    let hit = t_in <= t_out && t0 < t_out && len >= 1e-6;
    return own_segment(Ray(u0, select(vec3<f32>(0.0, 0.0, 1.0), (u1 - u0) / len, hit), select(0.0, len, hit), 0.0, false));
}

// The texture-space length of a step of `step_voxels` voxels along unit texture-space direction
// `d_tex`: step_voxels * unit_world / |d_tex * 2*half| (`volgraph_accel::reference::step_tex`).
fn step_tex_for(step_voxels: f32, d_tex: vec3<f32>) -> f32 {
    let world_per_tex = length(d_tex * 2.0 * frame.half_extent.xyz);
    return step_voxels * frame.half_extent.w / world_per_tex;
}

// The samples of a ray, the one rule every raycaster, the probe and the f64 reference
// (`volgraph_accel::reference`, docs/rendering_model.md "Samples") share: sample k lies at
// t_k = (k + offset) · step from the entry (offset = 0.5 + jitter, in steps), that is at
// `first + k · delta` in texture space, for k < count. The hot loops keep only `first`,
// `delta`, the colour and two counters in registers.
struct Samples {
    first: vec3<f32>,
    delta: vec3<f32>,
    count: u32,
    // Texture-space length of one step.
    step: f32,
    // 0.5 + jitter (+ the samples a window's own box cut off): where sample 0 lies, in steps
    // from the entry.
    offset: f32,
    // True when the grid has samples before sample 0 that another rank takes (a sort-last
    // window cut the ray; `Ray::looks_back`): a first-hit search still knows the field one
    // step back.
    cut: bool,
}

// The samples of `ray` a step of `step_tex` apart: those of the grid k = 0.. with
// (k + 0.5 + jitter) · step_tex in [begin, len), k below `max_count`; sample 0 of the result is
// the first of them (`offset` counts the grid steps before it, so distances from the entry keep
// their meaning).
fn samples_along(ray: Ray, step_tex: f32, jitter: f32, max_count: u32) -> Samples {
    let delta = ray.d * step_tex;
    let grid_offset = 0.5 + jitter;
    let end = clamp(ceil(ray.len / step_tex - grid_offset), 0.0, f32(max_count));
    let skipped = clamp(ceil(ray.begin / step_tex - grid_offset), 0.0, end);
    let offset = grid_offset + skipped;
    return Samples(ray.u0 + offset * delta, delta, u32(end - skipped), step_tex, offset, skipped > 0.0 && ray.looks_back);
}

// Sample k's texture-space position.
fn sample_at(s: Samples, k: u32) -> vec3<f32> {
    return s.first + f32(k) * s.delta;
}

// The first sample index at or past distance `t` from the entry (capped at `count`): a ray that
// starts late (Klein et al. 2005 §4.2) keeps every sample on the grid of the full march.
fn first_sample_at(s: Samples, t: f32) -> u32 {
    return u32(clamp(ceil(t / s.step - s.offset), 0.0, f32(s.count)));
}

// The one box exit: the first sample index after sample k (at `p`) whose position lies past
// where the ray p + x·delta leaves the box [lo, hi] (any coordinates `p` and `delta` share:
// texture space for blocks and cubes of blocks, voxels for bricks and leaves); at least k + 1.
// Axes the ray runs parallel to never bound it. Every empty-space leap and every brick exit is
// this function: the samples it passes over lie in the closed box.
fn past_box(k: u32, p: vec3<f32>, delta: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> u32 {
    return past_box_by(k, p, step_exit(delta), lo, hi);
}

// A ray's step as `past_box` needs it, computed once per ray or leap rather than per box: its
// direction per axis and its reciprocal (1 on axes it runs parallel to, which never bound it).
// Three divisions less per box (a leap step on llvmpipe had nine, bench/one-march-final.md).
struct StepExit {
    positive: vec3<bool>,
    parallel: vec3<bool>,
    inverse: vec3<f32>,
}

fn step_exit(delta: vec3<f32>) -> StepExit {
    let parallel = delta == vec3<f32>(0.0);
    return StepExit(delta > vec3<f32>(0.0), parallel, vec3<f32>(1.0) / select(delta, vec3<f32>(1.0), parallel));
}

// `past_box` with the step's `StepExit`. The reciprocal moves `steps` by an ulp at most: a
// sample within rounding of a face may be leapt over, and the empty ranges' one-voxel apron
// covers it (common/block_grid.wgsl); a brick's run may end a sample early or late, which its
// slot's one-voxel border covers (raycast_bricks.wgsl).
fn past_box_by(k: u32, p: vec3<f32>, step: StepExit, lo: vec3<f32>, hi: vec3<f32>) -> u32 {
    let steps = box_exit_by(p, step, lo, hi);
    return k + max(1u, u32(clamp(floor(steps) + 1.0, 0.0, 16777216.0)));
}

// Where the line p + x·delta leaves the box [lo, hi] it is in, in steps x: its nearest far face
// (axes it runs parallel to never bound it). `past_box_by`'s samples, and the path tracer's
// distance to a block's faces (path_trace.wgsl), whose `delta` is a unit of world length.
fn box_exit_by(p: vec3<f32>, step: StepExit, lo: vec3<f32>, hi: vec3<f32>) -> f32 {
    let bound = select(lo, hi, step.positive);
    let x = select((bound - p) * step.inverse, vec3<f32>(3.0e38), step.parallel);
    return min(x.x, min(x.y, x.z));
}
