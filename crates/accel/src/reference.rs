//! The f64 CPU reference raycaster: `docs/rendering_model.md` implemented once, slowly and
//! exactly, so that every GPU image (fragment or compute, DVR or isosurface) can be compared
//! with it pixel by pixel. The GPU twin of the marching code is `shaders/common/raymarch.wgsl`;
//! the two follow the same steps in the same order.
//!
//! Techniques: Krüger & Westermann 2003 §2.1 (front-to-back compositing along per-pixel rays with
//! early ray termination) and §2.2 (first-hit isosurface with gradient shading).

use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::camera::{CameraFrame, OrbitCamera};
use crate::cuts::Cuts;
use crate::fusion::Fusion;
use crate::volume::Volume;

/// Blinn–Phong headlight coefficients for the isosurface (`docs/rendering_model.md`,
/// "First-hit isosurface"); WGSL twin: the shading fields of `RaycastParams`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Phong {
    /// Ambient term, multiplies the base colour (default 0.15).
    pub ambient: f64,
    /// Diffuse term, multiplies the base colour and `|n·l|` (default 0.75).
    pub diffuse: f64,
    /// Specular term, white, multiplies `|n·h|^shininess` (default 0.25).
    pub specular: f64,
    /// Specular exponent (default 32).
    pub shininess: f64,
}

impl Default for Phong {
    fn default() -> Self {
        Self { ambient: 0.15, diffuse: 0.75, specular: 0.25, shininess: 32.0 }
    }
}

/// What a ray computes (`docs/rendering_model.md`, "Classification and compositing" and
/// "First-hit isosurface").
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum RenderMode {
    /// Direct volume rendering: emission–absorption through the transfer function
    /// (Krüger & Westermann 2003 §2.1).
    #[default]
    Dvr,
    /// First-hit isosurface, shaded with a headlight (Krüger & Westermann 2003 §2.2).
    Isosurface {
        /// The iso value, a normalized scalar in \[0,1\].
        iso: f64,
        /// Shading coefficients.
        #[serde(default)]
        shading: Phong,
    },
}

/// Scene effects of the DVR integral (`docs/rendering_model.md`, "Effects"): each one the GPU
/// compiles only when a scene asks for it, computed here in f64 so every GPU image is compared
/// with the exact answer of the same model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Effects {
    /// Blinn–Phong headlight shading of every DVR sample with the gradient of the reconstructed
    /// field (central differences one voxel apart, world space, anisotropic spacing respected).
    pub shading: bool,
    /// Pre-integrated classification (Engel et al. 2001): each sample composites the segment
    /// from the previous sample with the scalar linear in between, integrated exactly.
    pub preintegration: bool,
    /// Tricubic B-spline reconstruction ([`Volume::sample_tricubic`]) instead of trilinear.
    pub tricubic: bool,
    /// Shadows (Behrens & Ratering 1998): the light reaching a sample through the volume, from
    /// the light grid ([`crate::light::LightGrid`]), scales its lit terms — with shading the
    /// diffuse and specular ones, without it the colour by `ambient·AO + (1 − ambient)·T`.
    #[serde(default)]
    pub shadows: bool,
    /// Ambient occlusion (Hernell et al. 2010): the unoccluded share `AO` of a sample's
    /// neighbourhood, from the light grid, scales its ambient term.
    #[serde(default)]
    pub ambient_occlusion: bool,
}

/// Raycasting settings shared by the reference and the GPU raycasters (WGSL twin:
/// `RaycastParams` in `shaders/common/raycast_params.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RaycastSettings {
    /// Sample distance in units of the smallest voxel side (`unit_world`).
    pub step_voxels: f64,
    /// Early ray termination: stop after the sample that makes `A >= threshold` (1.0 is lossless).
    pub threshold: f64,
    /// Upper bound on samples per ray.
    pub max_steps: u32,
    /// Offset each ray's first sample by the per-pixel PCG jitter (`docs/rendering_model.md`,
    /// "Samples").
    pub jitter: bool,
    /// DVR or isosurface.
    pub mode: RenderMode,
    /// Effects of the DVR integral.
    pub effects: Effects,
    /// Shading coefficients of DVR samples (`effects.shading`).
    pub dvr_shading: Phong,
    /// The TF's opacity is per this many voxel units of distance: 1 for "per voxel" (the
    /// default), `1 / unit_world` for "per world unit" (a scene's opacity reference length).
    /// The correction exponent is `step_voxels / opacity_unit_voxels`.
    pub opacity_unit_voxels: f64,
    /// Crop box and clip planes: samples outside what they keep are dropped, the step grid
    /// stays the uncut ray's ([`crate::cuts`], `docs/rendering_model.md` "Cuts").
    #[serde(skip)]
    pub cuts: Cuts,
    /// The scene's lights: the headlight by default, directional and point lights
    /// ([`crate::light`]).
    #[serde(default)]
    pub lights: crate::light::Lights,
}

impl Default for RaycastSettings {
    fn default() -> Self {
        Self {
            step_voxels: 0.5,
            threshold: 1.0,
            max_steps: 4096,
            jitter: false,
            mode: RenderMode::Dvr,
            effects: Effects::default(),
            dvr_shading: Phong::default(),
            opacity_unit_voxels: 1.0,
            cuts: Cuts::NONE,
            lights: crate::light::Lights::one(crate::light::Light::Headlight),
        }
    }
}

impl RaycastSettings {
    /// The opacity-correction exponent of one step.
    pub fn step_exponent(&self) -> f64 {
        self.step_voxels / self.opacity_unit_voxels
    }
}

/// A reference image: premultiplied linear RGBA and, for isosurfaces, the hit positions.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Premultiplied linear RGBA, row 0 at the top, `width * height` entries.
    pub color: Vec<[f64; 4]>,
    /// Isosurface mode: texture-space hit position in xyz and 1 in w; zeros on a miss and in DVR.
    pub hit: Vec<[f64; 4]>,
    /// Total number of volume samples taken along all rays (gradient samples not counted).
    pub samples: u64,
}

impl ReferenceImage {
    /// Index of pixel `(x, y)` in `color` and `hit`.
    pub fn index(&self, x: u32, y: u32) -> usize {
        x as usize + self.width as usize * y as usize
    }
}

/// One pixel's ray inside the box, in texture space (`docs/rendering_model.md`, "Ray segment
/// inside the box"); what passes 1 and 2 of Krüger & Westermann 2003 §2.1 store per pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RaySegment {
    /// Texture-space start `u(eye + t0·d)`, `t0 = max(t_in, t_near)`.
    pub u0: DVec3,
    /// Unit texture-space direction `normalize(u1 - u0)`.
    pub d_tex: DVec3,
    /// Texture-space length `|u1 - u0|`.
    pub len_tex: f64,
    /// Unit world-space direction of the ray (the headlight comes from `-dir_world`).
    pub dir_world: DVec3,
}

/// Segments shorter than this in texture space are no ray. Same constant as
/// `MIN_RAY_LENGTH_TEX` in `shaders/ray_directions.wgsl` (`docs/rendering_model.md`).
pub const MIN_RAY_LENGTH_TEX: f64 = 1e-6;

/// Slab intersection of the ray `origin + t·dir` with the box `[-half, half]`: `(t_in, t_out)`,
/// or `None` when the ray misses or has a non-finite input. A zero direction component is
/// handled explicitly (the ray is inside that slab for every `t` or for none), so axis-aligned
/// and face-grazing rays never produce NaN; the box is closed, so a ray lying in a face hits.
pub fn intersect_box(origin: DVec3, dir: DVec3, half: DVec3) -> Option<(f64, f64)> {
    if !origin.is_finite() || !dir.is_finite() || !half.is_finite() {
        return None;
    }
    let (mut t_in, mut t_out) = (f64::NEG_INFINITY, f64::INFINITY);
    for axis in 0..3 {
        let (o, d, h) = (origin[axis], dir[axis], half[axis]);
        if d == 0.0 {
            if o < -h || o > h {
                return None;
            }
            continue;
        }
        let (a, b) = ((-h - o) / d, (h - o) / d);
        t_in = t_in.max(a.min(b));
        t_out = t_out.min(a.max(b));
    }
    (t_in <= t_out && t_in.is_finite() && t_out.is_finite()).then_some((t_in, t_out))
}

/// The texture-space segment of pixel `(x, y)`'s ray: through the pixel centre
/// ([`CameraFrame::pixel_ray`]), from `max(t_in, t_near)` to `t_out`; `None` when there is no
/// ray (it misses, `t_out <= t0`, or the segment is shorter than [`MIN_RAY_LENGTH_TEX`]).
pub fn ray_segment(volume: &Volume, camera: &OrbitCamera, frame: &CameraFrame, x: u32, y: u32) -> Option<RaySegment> {
    ray_segment_in(volume, camera, frame, (x, y), (DVec3::ZERO, DVec3::ONE))
}

/// [`ray_segment`] through the texture-space box `[lo, hi]` instead of the volume's `[0,1]³`
/// (several scalar volumes: the union of their boxes, [`crate::fusion::Fusion::march_box`]).
pub fn ray_segment_in(
    volume: &Volume,
    camera: &OrbitCamera,
    frame: &CameraFrame,
    (x, y): (u32, u32),
    (lo, hi): (DVec3, DVec3),
) -> Option<RaySegment> {
    let half = volume.half_extent_world();
    let (eye, dir) = frame.pixel_ray(x, y);
    // The box in world space, about its centre (0 and `half` for the volume's own).
    let (wlo, whi) = ((lo - 0.5) * 2.0 * half, (hi - 0.5) * 2.0 * half);
    let centre = (wlo + whi) * 0.5;
    let (t_in, t_out) = intersect_box(eye - centre, dir, (whi - wlo) * 0.5)?;
    let t0 = t_in.max(frame.near_t(camera.near, dir));
    if t0.is_nan() || t_out <= t0 {
        return None;
    }
    // Clamped like the GPU's entry/exit targets, which clamp interpolation overshoot.
    let texture = |t: f64| ((eye + t * dir) / (2.0 * half) + 0.5).clamp(lo, hi);
    let (u0, u1) = (texture(t0), texture(t_out));
    let len_tex = (u1 - u0).length();
    if len_tex.is_nan() || len_tex < MIN_RAY_LENGTH_TEX {
        return None;
    }
    Some(RaySegment { u0, d_tex: (u1 - u0) / len_tex, len_tex, dir_world: dir })
}

/// The transfer function at scalar `s` as a 1D linear sampler with clamp-to-edge reads it:
/// linear between texel centres `(i+0.5)/N`, constant beyond the end centres
/// (`docs/rendering_model.md`, "Classification"). An empty LUT reads as zero; NaN reads as 0.
pub fn lut_sample(lut: &[[f32; 4]], s: f64) -> [f64; 4] {
    let n = lut.len();
    if n == 0 {
        return [0.0; 4];
    }
    let s = if s.is_nan() { 0.0 } else { s };
    let p = s * n as f64 - 0.5;
    let base = p.floor();
    let f = p - base;
    let last = (n - 1) as f64;
    let i0 = base.clamp(0.0, last) as usize;
    let i1 = (base + 1.0).clamp(0.0, last) as usize;
    std::array::from_fn(|c| lut[i0][c] as f64 * (1.0 - f) + lut[i1][c] as f64 * f)
}

/// O'Neill's PCG hash as in `shaders/common/raymarch.wgsl` (wrapping u32 arithmetic).
pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// The per-pixel first-sample offset in steps, `pcg_hash(x + y·w) / 2³² − 0.5`
/// (`docs/rendering_model.md`, "Samples").
pub fn pixel_jitter(x: u32, y: u32, width: u32) -> f64 {
    pcg_hash(x.wrapping_add(y.wrapping_mul(width))) as f64 / 4_294_967_296.0 - 0.5
}

/// Opacity correction of the LUT's per-unit-step alpha to a step of `step_voxels`:
/// `1 - (1 - a)^step_voxels`, with `a` clamped to \[0,1\].
pub fn corrected_alpha(a_tf: f64, step_voxels: f64) -> f64 {
    let a = a_tf.clamp(0.0, 1.0);
    if a >= 1.0 {
        1.0
    } else if a <= 0.0 {
        0.0
    } else {
        1.0 - (1.0 - a).powf(step_voxels)
    }
}

/// A ray's marching parameters, derived once per pixel.
struct March<'a> {
    volume: &'a Volume,
    lut: &'a [[f32; 4]],
    /// Several volumes: a second volume and how samples combine (`crate::fusion`).
    fusion: Option<&'a Fusion<'a>>,
    settings: &'a RaycastSettings,
    seg: RaySegment,
    step_tex: f64,
    jitter: f64,
    /// The first sample the cuts keep (0 without cuts): the grid is the uncut ray's.
    k0: u32,
    /// Where the cuts end the ray (texture-space distance from `seg.u0`; `seg.len_tex` uncut).
    end_tex: f64,
    /// The light grid of the `shadows` effect.
    light_grid: Option<&'a crate::light::LightGrid>,
}

impl<'a> March<'a> {
    /// The march of `seg`, cut to what `settings.cuts` keep (`crate::cuts`): samples stay on
    /// the uncut grid `(k + 0.5 + jitter)·step` and only those in the kept interval are taken,
    /// as `samples_along` in `shaders/common/ray_box.wgsl` takes them.
    fn new(
        volume: &'a Volume,
        lut: &'a [[f32; 4]],
        fusion: Option<&'a Fusion<'a>>,
        settings: &'a RaycastSettings,
        seg: RaySegment,
        step_tex: f64,
        jitter: f64,
    ) -> Self {
        let (begin, end) = settings.cuts.keeps_interval(seg.u0, seg.d_tex, 0.0, seg.len_tex);
        let offset = 0.5 + jitter;
        let k0 = if begin < end { ((begin / step_tex - offset).ceil()).clamp(0.0, u32::MAX as f64) as u32 } else { 0 };
        let end_tex = if begin < end { end } else { 0.0 };
        Self { volume, lut, fusion, settings, seg, step_tex, jitter, k0, end_tex, light_grid: None }
    }

    fn t(&self, k: u32) -> f64 {
        (k as f64 + 0.5 + self.jitter) * self.step_tex
    }

    /// The reconstructed field at texture-space `u`: trilinear, or the tricubic B-spline.
    fn field(&self, u: DVec3) -> f64 {
        if self.settings.effects.tricubic { self.volume.sample_tricubic(u) } else { self.volume.sample_trilinear(u) }
    }

    fn sample(&self, t: f64) -> f64 {
        self.field(self.seg.u0 + t * self.seg.d_tex)
    }

    /// The premultiplied, opacity-corrected colour sample `t` adds (front value `s_prev` for
    /// pre-integration), shaded when asked.
    fn classify(&self, t: f64, s: f64, s_prev: f64) -> [f64; 4] {
        let exponent = self.settings.step_exponent();
        let mut p = if let Some(fusion) = self.fusion {
            // Several volumes: classified and combined per sample; with pre-integration the
            // scan's segment is tinted or masked by the label (`tint`, `inside`), or each
            // medium's segment combined (`fuse`, `add`; label maps alone are refused).
            let segment = self.settings.effects.preintegration.then(|| crate::fusion::Segment {
                scan: preintegrate(self.lut, s_prev, s, exponent),
                front: self.seg.u0 + (t - self.step_tex) * self.seg.d_tex,
            });
            fusion.classify_scan(self.volume, self.lut, self.seg.u0 + t * self.seg.d_tex, s, exponent, segment)
        } else if self.settings.effects.preintegration {
            preintegrate(self.lut, s_prev, s, exponent)
        } else {
            let c = lut_sample(self.lut, s);
            let a = corrected_alpha(c[3], exponent);
            [c[0] * a, c[1] * a, c[2] * a, a]
        };
        if self.settings.effects.shading && p[3] > 0.0 {
            let u = self.seg.u0 + t * self.seg.d_tex;
            let (diffuse, specular) = self.lighting(u, &self.settings.dvr_shading);
            for c in p.iter_mut().take(3) {
                *c *= diffuse;
            }
            for i in 0..3 {
                p[i] += p[3] * specular;
            }
        }
        let lit_by_grid = self.settings.effects.shadows || self.settings.effects.ambient_occlusion;
        if lit_by_grid && !self.settings.effects.shading && p[3] > 0.0 {
            // Unshaded: the light reaching the sample (and its share of the ambient light)
            // scales its colour.
            let ambient = self.settings.dvr_shading.ambient;
            // With several lights the share of them that gets through (their mean).
            let (light, ao) = self.illumination(self.seg.u0 + t * self.seg.d_tex);
            let lights = self.settings.lights.as_slice().len();
            let through = light[..lights].iter().sum::<f64>() / lights as f64;
            let lit = ambient * ao + (1.0 - ambient) * through;
            for c in p.iter_mut().take(3) {
                *c *= lit;
            }
        }
        p
    }

    /// Front-to-back emission–absorption; returns the colour and the number of samples.
    fn dvr(&self) -> ([f64; 4], u64) {
        let mut acc = [0.0f64; 4];
        let mut k = self.k0;
        // Pre-integration: the front value of the first sample's segment is the field one step
        // before it.
        let mut s_prev =
            if self.settings.effects.preintegration { self.sample(self.t(k) - self.step_tex) } else { 0.0 };
        while k < self.settings.max_steps {
            let t = self.t(k);
            if t >= self.end_tex {
                break;
            }
            let s = self.sample(t);
            let p = self.classify(t, s, s_prev);
            s_prev = s;
            k += 1;
            let w = 1.0 - acc[3];
            for i in 0..4 {
                acc[i] += w * p[i];
            }
            if acc[3] >= self.settings.threshold {
                break;
            }
        }
        (acc, (k - self.k0.min(k)) as u64)
    }

    /// The light's factors at `u`: `ambient + diffuse·|n·l|` and the white specular term
    /// `|n·h|^shininess`, `n` from the gradient (facing the light where the gradient vanishes);
    /// `l` toward each of the scene's lights ([`crate::light::Lights`]; the headlight's `l = v`
    /// by default), their diffuse and specular terms summed.
    fn lighting(&self, u: DVec3, p: &Phong) -> (f64, f64) {
        let dims = self.volume.dims.as_dvec3();
        let off = 1.0 / dims;
        let s = |v: DVec3| self.field(v);
        let g = DVec3::new(
            s(u + DVec3::new(off.x, 0.0, 0.0)) - s(u - DVec3::new(off.x, 0.0, 0.0)),
            s(u + DVec3::new(0.0, off.y, 0.0)) - s(u - DVec3::new(0.0, off.y, 0.0)),
            s(u + DVec3::new(0.0, 0.0, off.z)) - s(u - DVec3::new(0.0, 0.0, off.z)),
        );
        let v = -self.seg.dir_world;
        let half = self.volume.half_extent_world();
        // Shadows: only the light that gets through reaches the diffuse and specular terms;
        // ambient occlusion: only the unoccluded share of the ambient light.
        let (through, ao) = self.illumination(u);
        let (mut diffuse, mut specular) = (p.ambient * ao, 0.0);
        for (light, t) in self.settings.lights.as_slice().iter().zip(through) {
            // A point light's direction from this sample's world point (the volume's own space).
            let l = light.toward_with(v).from((u - 0.5) * 2.0 * half).0;
            let mut n = if g.length() >= ZERO_GRADIENT { -(g * dims / half).normalize() } else { l };
            if !self.settings.cuts.is_none() {
                // A cut face shows the plane it was cut along ("capping", crate::cuts).
                n = self.settings.cuts.cap_normal(u, self.seg.u0, self.seg.d_tex, n, dims, half);
            }
            let (n_dot_l, n_dot_h) = crate::light::blinn_phong_terms(n, l, v);
            let spec = if n_dot_l > 0.0 { p.specular * n_dot_h.powf(p.shininess) } else { 0.0 };
            diffuse += t * p.diffuse * n_dot_l;
            specular += t * spec;
        }
        (diffuse, specular)
    }

    /// The light reaching texture point `u` from each light and the ambient light's unoccluded
    /// share there (all 1 without a light grid).
    fn illumination(&self, u: DVec3) -> ([f64; crate::light::MAX_LIGHTS], f64) {
        self.light_grid.map_or(([1.0; crate::light::MAX_LIGHTS], 1.0), |g| g.sample(u))
    }

    /// First hit of `s >= iso`, refined linearly; returns colour, hit and samples taken.
    fn iso(&self, iso: f64, shading: &Phong) -> ([f64; 4], [f64; 4], u64) {
        let (mut t_prev, mut s_prev) = (0.0, 0.0);
        // A cut face is a cap: the first kept sample at or over the iso value is the hit, not
        // refined against the cut-away field (zeroed voxels there would be below it).
        let mut k = self.k0;
        while k < self.settings.max_steps {
            let t = self.t(k);
            if t >= self.end_tex {
                break;
            }
            let s = self.sample(t);
            if s >= iso {
                let t_hit = if k > self.k0 { t_prev + (t - t_prev) * (iso - s_prev) / (s - s_prev) } else { t };
                let u = self.seg.u0 + t_hit * self.seg.d_tex;
                let rgb = self.shade(u, iso, shading);
                return ([rgb.x, rgb.y, rgb.z, 1.0], [u.x, u.y, u.z, 1.0], (k - self.k0) as u64 + 1);
            }
            t_prev = t;
            s_prev = s;
            k += 1;
        }
        ([0.0; 4], [0.0; 4], (k - self.k0.min(k)) as u64)
    }

    /// Headlight Blinn–Phong at texture-space `u` (`docs/rendering_model.md`): the gradient
    /// spans two voxels per axis, so the world gradient is g / (2·voxel_world) with voxel_world
    /// = 2·half / dims and its direction that of g·dims/half; with a headlight l = v, so
    /// h = normalize(l + v) = l and n·h = n·l.
    fn shade(&self, u: DVec3, iso: f64, p: &Phong) -> DVec3 {
        let (diffuse, spec) = self.lighting(u, p);
        let base = lut_sample(self.lut, iso);
        let base = DVec3::new(base[0], base[1], base[2]);
        (base * diffuse + DVec3::splat(spec)).clamp(DVec3::ZERO, DVec3::ONE)
    }
}

/// Pre-integrated classification of a segment of `exponent` opacity units (Engel et al. 2001):
/// the scalar runs linearly from `s_front` to `s_back`; extinction `τ(s) = −ln(1 − α_tf(s))` per
/// unit, emission the LUT colour; integrated front to back in f64 with sub-steps fine enough to
/// resolve every LUT texel the segment crosses (at least 4 per texel, at least 64). Returns
/// premultiplied RGBA. For `s_front = s_back` it is the point-sampled correction
/// `1 − (1 − α)^exponent`. The GPU's pre-integration table holds this function on a 256² grid.
pub fn preintegrate(lut: &[[f32; 4]], s_front: f64, s_back: f64, exponent: f64) -> [f64; 4] {
    let texels = lut.len().max(1) as f64;
    let crossed = ((s_back - s_front).abs() * texels).ceil();
    let n = ((4.0 * crossed) as usize).clamp(64, 1 << 16);
    let dx = exponent / n as f64;
    let mut acc = [0.0f64; 4];
    for i in 0..n {
        let s = s_front + (s_back - s_front) * (i as f64 + 0.5) / n as f64;
        let c = lut_sample(lut, s);
        let a = corrected_alpha(c[3], dx);
        let w = (1.0 - acc[3]) * a;
        for k in 0..3 {
            acc[k] += w * c[k];
        }
        acc[3] += w;
    }
    acc
}

/// Gradients shorter than this (in normalized scalar units over two voxels) count as zero and the
/// normal faces the eye: below one u16 step (1.5e-5), above the f32 rounding of GPU samples
/// (~1e-7). Same constant in `shaders/common/raymarch.wgsl`.
pub const ZERO_GRADIENT: f64 = 1e-6;

/// Texture-space step of a ray with unit texture direction `d_tex`:
/// `step_voxels · unit_world / |d_tex · 2·half|`.
pub fn step_tex(volume: &Volume, d_tex: DVec3, step_voxels: f64) -> f64 {
    step_voxels * volume.unit_step_world() / (d_tex * 2.0 * volume.half_extent_world()).length()
}

/// Renders `volume` through `lut` from `camera` into a `width × height` image following
/// `docs/rendering_model.md` in f64, one rayon task per row. Bad input (an empty or
/// inconsistent volume, a zero-sized image, a non-positive step) gives a transparent image,
/// never a panic.
pub fn render_reference(
    volume: &Volume,
    lut: &[[f32; 4]],
    camera: &OrbitCamera,
    width: u32,
    height: u32,
    settings: &RaycastSettings,
) -> ReferenceImage {
    render_fused_reference(volume, lut, None, camera, width, height, settings)
}

/// [`render_reference`] of several volumes in one march (`crate::fusion`): `volume` is the
/// frame volume (its box is the one rays meet), `fusion` the second volume and how each sample
/// combines them.
pub fn render_fused_reference(
    volume: &Volume,
    lut: &[[f32; 4]],
    fusion: Option<&Fusion<'_>>,
    camera: &OrbitCamera,
    width: u32,
    height: u32,
    settings: &RaycastSettings,
) -> ReferenceImage {
    let pixels = width as usize * height as usize;
    let mut color = vec![[0.0; 4]; pixels];
    let mut hit = vec![[0.0; 4]; pixels];
    let usable =
        volume.voxel_count() > 0 && volume.data.len() == volume.voxel_count() && volume.extent().min_element() > 0.0;
    if !usable || pixels == 0 {
        return ReferenceImage { width, height, color, hit, samples: 0 };
    }
    let frame = camera.frame(width, height);
    let grid = shadow_grid(volume, lut, fusion, &frame, settings);
    let row_len = width as usize;
    let samples = color
        .par_chunks_mut(row_len)
        .zip(hit.par_chunks_mut(row_len))
        .enumerate()
        .map(|(y, (color_row, hit_row))| {
            let mut row_samples = 0;
            for x in 0..width {
                let (c, h, n) =
                    fused_pixel_lit(volume, lut, (fusion, grid.as_ref()), camera, &frame, (x, y as u32), settings);
                color_row[x as usize] = c;
                hit_row[x as usize] = h;
                row_samples += n;
            }
            row_samples
        })
        .sum();
    ReferenceImage { width, height, color, hit, samples }
}

/// One pixel of [`render_reference`]: premultiplied colour, the isosurface hit (zero for DVR or
/// no hit) and the samples taken. `frame` is `camera.frame(width, height)`; the volume must be
/// usable (as `render_reference` checks). For sparse checks (the viewer's live error).
pub fn reference_pixel(
    volume: &Volume,
    lut: &[[f32; 4]],
    camera: &OrbitCamera,
    frame: &CameraFrame,
    (x, y): (u32, u32),
    settings: &RaycastSettings,
) -> ([f64; 4], [f64; 4], u64) {
    fused_pixel(volume, lut, None, camera, frame, (x, y), settings)
}

/// [`reference_pixel`] of several volumes (`crate::fusion`). With the `shadows` effect it
/// computes the light grid for this one pixel: for many, compute it once ([`shadow_grid`]) and
/// call [`fused_pixel_lit`].
pub fn fused_pixel(
    volume: &Volume,
    lut: &[[f32; 4]],
    fusion: Option<&Fusion<'_>>,
    camera: &OrbitCamera,
    frame: &CameraFrame,
    (x, y): (u32, u32),
    settings: &RaycastSettings,
) -> ([f64; 4], [f64; 4], u64) {
    let grid = shadow_grid(volume, lut, fusion, frame, settings);
    fused_pixel_lit(volume, lut, (fusion, grid.as_ref()), camera, frame, (x, y), settings)
}

/// The light grid the `shadows` and `ambient_occlusion` effects read (`None` without them): a
/// transmittance per scene light — the headlight's from the eye along the camera's forward axis
/// (one direction for the whole grid) — as the GPU computes it; with several volumes from their
/// combined opacity (`Fusion::alpha`).
pub fn shadow_grid(
    volume: &Volume,
    lut: &[[f32; 4]],
    fusion: Option<&Fusion<'_>>,
    frame: &CameraFrame,
    settings: &RaycastSettings,
) -> Option<crate::light::LightGrid> {
    if !(settings.effects.shadows || settings.effects.ambient_occlusion) {
        return None;
    }
    let towards = if settings.effects.shadows { settings.lights.toward_with(-frame.forward) } else { Vec::new() };
    let tricubic = settings.effects.tricubic;
    let field = |u: DVec3| if tricubic { volume.sample_tricubic(u) } else { volume.sample_trilinear(u) };
    let alpha = |u: DVec3| match fusion {
        Some(f) => f.alpha(volume, lut, u, field(u)),
        None => lut_sample(lut, field(u))[3],
    };
    let occlusion = settings.effects.ambient_occlusion;
    let unit = (settings.opacity_unit_voxels, &settings.cuts);
    Some(crate::light::LightGrid::compute(volume, (&towards, occlusion), unit, &alpha))
}

/// [`fused_pixel`] with the light grid of the `shadows` effect given ([`shadow_grid`]).
pub fn fused_pixel_lit(
    volume: &Volume,
    lut: &[[f32; 4]],
    (fusion, light_grid): (Option<&Fusion<'_>>, Option<&crate::light::LightGrid>),
    camera: &OrbitCamera,
    frame: &CameraFrame,
    (x, y): (u32, u32),
    settings: &RaycastSettings,
) -> ([f64; 4], [f64; 4], u64) {
    let bounds = fusion.map_or((DVec3::ZERO, DVec3::ONE), |f| f.march_box());
    let Some(seg) = ray_segment_in(volume, camera, frame, (x, y), bounds) else {
        return ([0.0; 4], [0.0; 4], 0);
    };
    let step_tex = step_tex(volume, seg.d_tex, settings.step_voxels);
    if !(step_tex > 0.0 && step_tex < 1e30) {
        return ([0.0; 4], [0.0; 4], 0);
    }
    let jitter = if settings.jitter { pixel_jitter(x, y, frame.width) } else { 0.0 };
    let march = March { light_grid, ..March::new(volume, lut, fusion, settings, seg, step_tex, jitter) };
    match settings.mode {
        RenderMode::Dvr => {
            let (c, n) = march.dvr();
            (c, [0.0; 4], n)
        }
        RenderMode::Isosurface { iso, shading } => march.iso(iso, &shading),
    }
}

/// The `width × height` image with `n × n` rays per pixel on a regular sub-pixel grid, averaged:
/// the anti-aliased answer super-sampling approaches (Klein et al. 2005 §5's study compares
/// against `n = 4`, 16 rays per pixel). Rendered by [`render_reference`] at `n` times the
/// resolution, then box-filtered; premultiplied colour per pixel, row-major.
pub fn render_supersampled(
    volume: &Volume,
    lut: &[[f32; 4]],
    camera: &OrbitCamera,
    width: u32,
    height: u32,
    n: u32,
    settings: &RaycastSettings,
) -> Vec<[f64; 4]> {
    let n = n.max(1);
    let fine = render_reference(volume, lut, camera, width * n, height * n, settings);
    let mut out = vec![[0.0; 4]; width as usize * height as usize];
    let weight = 1.0 / (n * n) as f64;
    for (i, c) in fine.color.iter().enumerate() {
        let (x, y) = (i as u32 % (width * n) / n, i as u32 / (width * n) / n);
        let pixel = &mut out[(y * width + x) as usize];
        for k in 0..4 {
            pixel[k] += weight * c[k];
        }
    }
    out
}
