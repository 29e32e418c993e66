//! An independent f64 path tracer of the medium `path_trace` renders on the GPU
//! (`shaders/path_trace.wgsl`; issue "light that scatters", item 4): the same light transport —
//! extinction σ = −ln(1 − α) / L from the TF, scattering with probability `albedo` tinted by the
//! TF colour, absorption emitting `emission` × colour, Henyey–Greenstein or Lambertian-surface
//! scattering (Kroes et al. 2012 §4.3), the scene's lights (directional, point, the headlight),
//! a sky or uniform environment — estimated another way: f64 throughout, its own random streams
//! (SplitMix64), one global majorant, the light's transmittance by delta tracking (a 0-or-1
//! visibility) instead of the GPU's ratio tracking, and the plain estimators the GPU improves on
//! (absorption ends a path at random, the light scattered by the one lobe drawn, alpha 1 when the
//! path interacted). Both are unbiased, so their means agree within their
//! confidence intervals (crates/passes/tests/path_trace.rs); [`PixelEstimate`] carries the
//! sample variance that interval needs.

use glam::DVec3;
use rayon::prelude::*;

use crate::camera::OrbitCamera;
use crate::light::{Light, Lights};
use crate::reference::{intersect_box, lut_sample};
use crate::volume::Volume;

/// What a path leaving the volume sees (`path_trace`'s `environment`).
#[derive(Clone, Debug, PartialEq)]
pub enum Environment {
    /// The generated sky along world +y.
    Sky,
    /// The same radiance everywhere.
    Uniform,
    /// The scene's map (`Runtime::set_environment`), scaled by `environment_intensity`.
    Map(std::sync::Arc<crate::environment::EnvironmentMap>),
}

/// The medium's and the light's parameters, as `path_trace`'s (its `PathTraceParams`).
#[derive(Clone, Debug, PartialEq)]
pub struct PathTraceSettings {
    /// Probability that an interaction scatters.
    pub albedo: f64,
    /// Radiance an absorbing interaction emits, times the TF colour.
    pub emission: f64,
    /// Henyey–Greenstein g.
    pub anisotropy: f64,
    /// Weight of the gradient-surface term.
    pub surface: f64,
    /// Scattering events a path may take.
    pub bounces: u32,
    /// Irradiance of each light.
    pub light_intensity: f64,
    /// What paths leaving the volume see.
    pub environment: Environment,
    /// Radiance scale of the environment.
    pub environment_intensity: f64,
    /// The scene's lights: each one's direct light is estimated at every scattering event.
    pub lights: Lights,
    /// The TF's opacity is per this many voxels (1: per voxel).
    pub opacity_unit_voxels: f64,
    /// The scene's crop box and clip planes: paths, primary and scattered, and the light's
    /// visibility see only the region they keep (`cut_segment` of ray_box.wgsl).
    pub cuts: crate::cuts::Cuts,
}

impl Default for PathTraceSettings {
    /// `path_trace`'s defaults.
    fn default() -> Self {
        Self {
            albedo: 0.9,
            emission: 0.0,
            anisotropy: 0.0,
            surface: 0.5,
            bounces: 4,
            light_intensity: 2.0,
            environment: Environment::Sky,
            environment_intensity: 0.6,
            lights: Lights::one(Light::Headlight),
            opacity_unit_voxels: 1.0,
            cuts: crate::cuts::Cuts::default(),
        }
    }
}

/// α is capped below 1 as on the GPU (`MAX_ALPHA` of path_trace.wgsl).
pub const MAX_ALPHA: f64 = 0.999999;

/// One pixel's estimate over its samples: mean and unbiased sample variance of premultiplied
/// RGBA.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelEstimate {
    /// The mean over the samples.
    pub mean: [f64; 4],
    /// Their unbiased sample variance (0 for one sample).
    pub variance: [f64; 4],
}

/// SplitMix64 (Steele et al. 2014): a small, well-mixed generator; uniform in [0, 1) from its
/// top 53 bits.
pub(crate) struct SplitMix64(pub(crate) u64);

impl SplitMix64 {
    pub(crate) fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The scene a path moves through.
struct Medium<'a> {
    volume: &'a Volume,
    lut: &'a [[f32; 4]],
    settings: PathTraceSettings,
    half: DVec3,
    /// The box paths cross, in world units (centre, half size): the volume's, or with several
    /// scalar volumes the union of their boxes (`Fusion::march_box`), as the GPU's `march_lo/hi`.
    bounds: (DVec3, DVec3),
    unit_world: f64,
    majorant: f64,
    toward_lights: Vec<crate::light::Toward>,
    /// Several volumes: the medium is their combination (`Fusion::classify` without the
    /// step's correction: opacity per opacity unit).
    fusion: Option<crate::fusion::Fusion<'a>>,
}

impl Medium<'_> {
    fn extinction_of(&self, alpha: f64) -> f64 {
        -(1.0 - alpha.clamp(0.0, MAX_ALPHA)).ln() / (self.unit_world * self.settings.opacity_unit_voxels)
    }

    fn texture(&self, p: DVec3) -> DVec3 {
        p / (2.0 * self.half) + 0.5
    }

    /// TF colour and σ at world point `p`.
    fn at(&self, p: DVec3) -> ([f64; 3], f64) {
        let u = self.texture(p);
        let s = self.volume.sample_trilinear(u);
        let Some(fusion) = &self.fusion else {
            let c = lut_sample(self.lut, s);
            return ([c[0], c[1], c[2]], self.extinction_of(c[3]));
        };
        // Premultiplied by the combination's opacity: the straight colour is c / α.
        let c = fusion.classify(self.volume, self.lut, u, s, 1.0);
        let a = c[3];
        let colour = if a > 0.0 { [c[0] / a, c[1] / a, c[2] / a] } else { [0.0; 3] };
        (colour, self.extinction_of(a))
    }

    /// Where along p + t·w the box begins and ends (from t ≥ 0), cut to what the scene's cuts
    /// keep.
    fn span(&self, p: DVec3, w: DVec3) -> Option<(f64, f64)> {
        let (t0, t1) = intersect_box(p - self.bounds.0, w, self.bounds.1)?;
        self.kept(p, w, (t0.max(0.0), t1))
    }

    /// The part of [t0, t1) on p + t·w the cuts keep (they are in texture coordinates, where the
    /// ray is texture(p) + t · w / (2 · half)), if any.
    fn kept(&self, p: DVec3, w: DVec3, (t0, t1): (f64, f64)) -> Option<(f64, f64)> {
        let (t0, t1) = self.settings.cuts.keeps_interval(self.texture(p), w / (2.0 * self.half), t0, t1);
        (t1 > t0).then_some((t0, t1))
    }

    /// Delta tracking: the first real interaction in [t0, t1), if any.
    fn delta_track(&self, p: DVec3, w: DVec3, (t0, t1): (f64, f64), rng: &mut SplitMix64) -> Option<f64> {
        if self.majorant.is_nan() || self.majorant <= 0.0 {
            return None;
        }
        let mut t = t0;
        loop {
            t -= (1.0 - rng.uniform()).ln() / self.majorant;
            if t >= t1 {
                return None;
            }
            if rng.uniform() * self.majorant < self.at(p + t * w).1 {
                return Some(t);
            }
        }
    }

    fn environment(&self, w: DVec3) -> DVec3 {
        let k = self.settings.environment_intensity;
        match &self.settings.environment {
            Environment::Uniform => return DVec3::splat(k),
            Environment::Map(map) => return map.radiance(w) * k,
            Environment::Sky => {}
        }
        let ground = DVec3::new(0.32, 0.30, 0.28);
        let horizon = DVec3::new(0.85, 0.85, 0.82);
        let zenith = DVec3::new(0.35, 0.55, 0.95);
        let smooth = |e0: f64, e1: f64, x: f64| {
            let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
            t * t * (3.0 - 2.0 * t)
        };
        let sky = if w.y >= 0.0 {
            horizon.lerp(zenith, smooth(0.0, 0.6, w.y))
        } else {
            horizon.lerp(ground, smooth(0.0, 0.3, -w.y))
        };
        sky * k
    }

    /// The field's gradient at `p`, per voxel, as path_trace.wgsl's `voxel_gradient`.
    fn gradient(&self, p: DVec3) -> DVec3 {
        let u = self.texture(p);
        let dims = self.volume.dims.as_dvec3();
        let h = 1.0 / dims;
        let s = |v: DVec3| self.volume.sample_trilinear(v);
        let d = DVec3::new(
            s(u + DVec3::X * h.x) - s(u - DVec3::X * h.x),
            s(u + DVec3::Y * h.y) - s(u - DVec3::Y * h.y),
            s(u + DVec3::Z * h.z) - s(u - DVec3::Z * h.z),
        );
        0.5 * d * (self.unit_world / (2.0 * self.half / dims))
    }

    /// One path from `p` along `w` over `span` (a pixel's ray in the box).
    fn trace(&self, mut p: DVec3, mut w: DVec3, mut span: (f64, f64), rng: &mut SplitMix64) -> [f64; 4] {
        let s = &self.settings;
        let mut radiance = DVec3::ZERO;
        let mut throughput = DVec3::ONE;
        let mut alpha = 0.0;
        for bounce in 0..=s.bounces {
            let Some(t) = self.delta_track(p, w, span, rng) else {
                if bounce > 0 {
                    radiance += throughput * self.environment(w);
                }
                break;
            };
            if bounce == 0 {
                alpha = 1.0;
            }
            p += t * w;
            let colour = DVec3::from_array(self.at(p).0);
            if rng.uniform() >= s.albedo {
                radiance += throughput * s.emission * colour;
                break;
            }
            throughput *= colour;
            if bounce == s.bounces {
                break;
            }
            let g = self.gradient(p);
            let strength = g.length();
            let surface = s.surface * (1.0 - (-20.0 * strength).exp());
            // Toward each light (a point light's direction from here, its irradiance falling as
            // 1/r²); its visibility by delta tracking up to it: reached (1) or not (0).
            let to_lights: Vec<(DVec3, f64)> = self
                .toward_lights
                .iter()
                .map(|toward| {
                    let (l, r) = toward.from(p);
                    let lit = match self.span(p, l) {
                        Some((t0, t1)) => t0 >= t1.min(r) || self.delta_track(p, l, (t0, t1.min(r)), rng).is_none(),
                        None => true,
                    };
                    let irradiance =
                        if r.is_finite() { s.light_intensity / (r * r).max(1e-12) } else { s.light_intensity };
                    (l, if lit { irradiance } else { 0.0 })
                })
                .collect();
            if strength > 1e-6 && rng.uniform() < surface {
                let mut n = -g / strength;
                if n.dot(w) > 0.0 {
                    n = -n;
                }
                for &(l, to_light) in &to_lights {
                    radiance += throughput * to_light * n.dot(l).max(0.0) / std::f64::consts::PI;
                }
                w = sample_cosine(n, rng);
            } else {
                for &(l, to_light) in &to_lights {
                    radiance += throughput * to_light * henyey_greenstein(w.dot(l), s.anisotropy);
                }
                w = sample_henyey_greenstein(w, s.anisotropy, rng);
            }
            match self.span(p, w) {
                Some(next) => span = next,
                None => {
                    // On the box's face heading out: the path leaves at once.
                    radiance += throughput * self.environment(w);
                    break;
                }
            }
        }
        [radiance.x, radiance.y, radiance.z, alpha]
    }
}

/// Henyey–Greenstein for the cosine between the path's direction and the outgoing one.
pub fn henyey_greenstein(cos_theta: f64, g: f64) -> f64 {
    let d = 1.0 + g * g - 2.0 * g * cos_theta;
    (1.0 - g * g) / (4.0 * std::f64::consts::PI * d * d.max(1e-24).sqrt())
}

/// Two unit vectors completing unit `n` to an orthonormal frame.
fn perpendiculars(n: DVec3) -> (DVec3, DVec3) {
    let t = n.any_orthonormal_vector();
    (t, n.cross(t))
}

fn sample_henyey_greenstein(w: DVec3, g: f64, rng: &mut SplitMix64) -> DVec3 {
    let xi = rng.uniform();
    let cos_theta = if g.abs() > 1e-3 {
        let q = (1.0 - g * g) / (1.0 - g + 2.0 * g * xi);
        ((1.0 + g * g - q * q) / (2.0 * g)).clamp(-1.0, 1.0)
    } else {
        1.0 - 2.0 * xi
    };
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let phi = 2.0 * std::f64::consts::PI * rng.uniform();
    let (a, b) = perpendiculars(w);
    (a * sin_theta * phi.cos() + b * sin_theta * phi.sin() + w * cos_theta).normalize()
}

fn sample_cosine(n: DVec3, rng: &mut SplitMix64) -> DVec3 {
    let r = rng.uniform().sqrt();
    let phi = 2.0 * std::f64::consts::PI * rng.uniform();
    let (a, b) = perpendiculars(n);
    (a * r * phi.cos() + b * r * phi.sin() + n * (1.0 - r * r).max(0.0).sqrt()).normalize()
}

/// `spp` paths per pixel of a `width`×`height` image from `camera` (pixel centres, as the
/// GPU's rays), in parallel over rows; `seed` picks the random streams.
pub fn render_path_traced(
    volume: &Volume,
    lut: &[[f32; 4]],
    camera: &OrbitCamera,
    size: (u32, u32),
    settings: &PathTraceSettings,
    samples: (u32, u64),
) -> Vec<PixelEstimate> {
    render_path_traced_fused(volume, lut, None, camera, size, settings, samples)
}

/// [`render_path_traced`] of several volumes: the medium at each point is their combination
/// `fusion` makes (`Fusion::classify`, opacity per opacity unit), inside the frame volume's box.
pub fn render_path_traced_fused(
    volume: &Volume,
    lut: &[[f32; 4]],
    fusion: Option<crate::fusion::Fusion<'_>>,
    camera: &OrbitCamera,
    (width, height): (u32, u32),
    settings: &PathTraceSettings,
    (spp, seed): (u32, u64),
) -> Vec<PixelEstimate> {
    let frame = camera.frame(width, height);
    // The texture-space box rays cross ([`Fusion::march_box`]: the union of several scalar
    // volumes' boxes; the volume's [0,1]³ otherwise).
    let box_tex = fusion.as_ref().map_or((DVec3::ZERO, DVec3::ONE), |f| f.march_box());
    let table_max = |lut: &[[f32; 4]]| {
        lut.iter().map(|t| if t[3].is_nan() { 1.0 } else { f64::from(t[3]).clamp(0.0, 1.0) }).fold(0.0, f64::max)
    };
    let max_alpha = match &fusion {
        None => table_max(lut),
        Some(f) => {
            let first =
                if f.combine == crate::fusion::Combine::Labels { table_max(f.label_lut) } else { table_max(lut) };
            let partners = f.second.iter().map(|(_, l, _)| *l).chain(f.more.iter().map(|(_, l, _)| *l));
            let maxima: Vec<f64> = std::iter::once(first).chain(partners.map(table_max)).collect();
            crate::fusion::max_alpha(f.combine, &maxima)
        }
    };
    let mut medium = Medium {
        volume,
        lut,
        settings: settings.clone(),
        half: volume.half_extent_world(),
        bounds: {
            let half = volume.half_extent_world();
            let (lo, hi) = box_tex;
            (((lo + hi) * 0.5 - 0.5) * 2.0 * half, (hi - lo) * half)
        },
        unit_world: volume.unit_step_world(),
        majorant: 0.0,
        toward_lights: settings.lights.toward_with(-frame.forward),
        fusion,
    };
    medium.majorant = medium.extinction_of(max_alpha);
    (0..height)
        .into_par_iter()
        .flat_map_iter(|y| {
            let medium = &medium;
            let frame = &frame;
            (0..width).map(move |x| {
                let Some(ray) = crate::reference::ray_segment_in(volume, camera, frame, (x, y), box_tex) else {
                    return PixelEstimate::default();
                };
                let p0 = (ray.u0 - 0.5) * 2.0 * medium.half;
                let p1 = (ray.u0 + ray.d_tex * ray.len_tex - 0.5) * 2.0 * medium.half;
                let length = (p1 - p0).length();
                let w = (p1 - p0) / length;
                let Some(span) = medium.kept(p0, w, (0.0, length)) else {
                    return PixelEstimate::default();
                };
                let mut rng =
                    SplitMix64(seed ^ (u64::from(y) << 32 | u64::from(x)).wrapping_mul(0x2545_f491_4f6c_dd1d));
                let (mut sum, mut squares) = ([0.0; 4], [0.0; 4]);
                for _ in 0..spp {
                    let sample = medium.trace(p0, w, span, &mut rng);
                    for c in 0..4 {
                        sum[c] += sample[c];
                        squares[c] += sample[c] * sample[c];
                    }
                }
                let n = f64::from(spp.max(1));
                let mean = sum.map(|s| s / n);
                let variance = std::array::from_fn(|c| {
                    if spp > 1 { ((squares[c] - n * mean[c] * mean[c]) / (n - 1.0)).max(0.0) } else { 0.0 }
                });
                PixelEstimate { mean, variance }
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The phase function integrates to 1 over the sphere (a midpoint sum over cos θ).
    #[test]
    fn henyey_greenstein_is_normalised() {
        for g in [-0.8, 0.0, 0.3, 0.9] {
            let n = 200_000;
            let sum: f64 = (0..n)
                .map(|i| {
                    let c = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
                    henyey_greenstein(c, g) * 2.0 * std::f64::consts::PI * 2.0 / n as f64
                })
                .sum();
            assert!((sum - 1.0).abs() < 1e-3, "g = {g}: ∫p = {sum}");
        }
    }

    /// A transparent TF: nothing interacts, every pixel is zero with zero variance.
    #[test]
    fn an_empty_medium_renders_nothing() {
        let volume = crate::generate::marschner_lobb_f32(16);
        let lut = vec![[1.0, 1.0, 1.0, 0.0]; 16];
        let image =
            render_path_traced(&volume, &lut, &OrbitCamera::default(), (8, 8), &PathTraceSettings::default(), (16, 1));
        assert!(image.iter().all(|p| *p == PixelEstimate::default()));
    }
}
