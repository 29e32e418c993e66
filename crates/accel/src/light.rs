//! The scene's lights (issue "light that scatters", item 1): one to three ([`Lights`]), each the
//! headlight — from the eye, the default — a directional light fixed in the world, placed by
//! azimuth and elevation as an orbit camera is ([`crate::camera::OrbitCamera::eye`]: `--light
//! 35,25` shines from where a camera at azimuth 35°, elevation 25° would look from), or a point
//! light. Blinn–Phong shading (the GPU's `lighting` in `shaders/common/raymarch.wgsl`, the
//! reference's `lighting`) sums over them: diffuse `|n·l|`, specular `|n·h|^shininess` with `h`
//! halfway between the light and the eye (with the headlight `h = l`, the shading of every
//! earlier image).

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Where the light comes from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Light {
    /// From the eye, along every view ray.
    #[default]
    Headlight,
    /// A distant light fixed in the world, from azimuth and elevation in degrees (the orbit
    /// camera's angles: azimuth about +y from +z, elevation toward +y).
    Directional {
        /// Degrees about +y, from +z toward +x.
        azimuth_deg: f64,
        /// Degrees above the xz plane, toward +y (−90..90).
        elevation_deg: f64,
    },
    /// A point light at a world position (the volume's box is centred on the origin, its
    /// longest side 2 world units): the direction toward it changes from sample to sample.
    /// Blinn–Phong takes its direction only (no fall-off, as a directional light's irradiance is
    /// constant); the path tracer's `light_intensity` is its irradiance one world unit away,
    /// falling as 1/r².
    Point {
        /// World x.
        x: f64,
        /// World y (up).
        y: f64,
        /// World z.
        z: f64,
    },
}

/// How far from the origin a point light may be, per coordinate, in world units (the volume's
/// box is 2 across): its squared distance stays far inside f32.
pub const MAX_POINT_DISTANCE: f64 = 1e6;

/// Where light reaches a point from: one direction for every point, or a position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Toward {
    /// The unit world direction toward a distant light (the headlight's resolved).
    Direction(DVec3),
    /// A point light's world position.
    Point(DVec3),
}

impl Toward {
    /// The unit direction toward the light from world point `p`, and the distance to it
    /// (infinite for a distant light; 0 at the light itself, whose direction is then +y).
    pub fn from(&self, p: DVec3) -> (DVec3, f64) {
        match *self {
            Toward::Direction(d) => (d, f64::INFINITY),
            Toward::Point(at) => {
                let d = at - p;
                let r = d.length();
                if r > 1e-12 { (d / r, r) } else { (DVec3::Y, 0.0) }
            }
        }
    }
}

impl Light {
    /// The unit world direction toward a distant light; `None` for the headlight (it is each
    /// ray's own `-direction`) and for a point light (see [`Light::toward_with`]).
    pub fn toward(&self) -> Option<DVec3> {
        match *self {
            Light::Headlight | Light::Point { .. } => None,
            Light::Directional { azimuth_deg, elevation_deg } => {
                let (az, el) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
                Some(DVec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos()))
            }
        }
    }

    /// Where the light comes from, with `headlight` (a unit world direction toward the eye) for
    /// the headlight.
    pub fn toward_with(&self, headlight: DVec3) -> Toward {
        match *self {
            Light::Point { x, y, z } => Toward::Point(DVec3::new(x, y, z)),
            _ => Toward::Direction(self.toward().unwrap_or(headlight)),
        }
    }

    /// Reads `--light`: `headlight`, `AZ,EL` in degrees (finite; elevation within −90..90), or
    /// `point:X,Y,Z` in world units (finite).
    pub fn parse(text: &str) -> Result<Self, String> {
        let text = text.trim();
        if text.eq_ignore_ascii_case("headlight") {
            return Ok(Light::Headlight);
        }
        if let Some(at) = text.strip_prefix("point:").or_else(|| text.strip_prefix("POINT:")) {
            let bad = || {
                format!(
                    "\"{text}\" is no point light: write point:X,Y,Z in world units (the volume's box is centred on \
                     the origin, its longest side 2), e.g. point:0,2,1"
                )
            };
            let values: Vec<f64> =
                at.split(',').map(|v| v.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|_| bad())?;
            let [x, y, z] = values[..] else { return Err(bad()) };
            let light = Light::Point { x, y, z };
            light.check().map_err(|e| format!("\"{text}\": {e}"))?;
            return Ok(light);
        }
        let bad = || {
            format!(
                "\"{text}\" is no light: write AZ,EL in degrees (azimuth about the vertical axis, elevation -90..90, \
                 e.g. 35,25), point:X,Y,Z or headlight"
            )
        };
        let (az, el) = text.split_once(',').ok_or_else(bad)?;
        let (azimuth_deg, elevation_deg): (f64, f64) =
            (az.trim().parse().map_err(|_| bad())?, el.trim().parse().map_err(|_| bad())?);
        let light = Light::Directional { azimuth_deg, elevation_deg };
        light.check().map_err(|e| format!("\"{text}\": {e}"))?;
        Ok(light)
    }

    /// Fails for angles that are not finite or an elevation beyond ±90°.
    pub fn check(&self) -> Result<(), String> {
        match *self {
            Light::Headlight => Ok(()),
            Light::Point { x, y, z } => {
                if !([x, y, z].iter().all(|v| v.is_finite())) {
                    return Err(format!("a point light's position must be finite world units, not ({x}, {y}, {z})"));
                }
                // The GPU holds it in f32 and squares its distance: far beyond the box a point
                // light is a directional one, which is what to write.
                if [x, y, z].iter().any(|v| v.abs() > MAX_POINT_DISTANCE) {
                    return Err(format!(
                        "a point light's position is within ±{MAX_POINT_DISTANCE:e} world units (the box is 2 across), \
                         not ({x:e}, {y:e}, {z:e}); for a light that far write its direction as AZ,EL"
                    ));
                }
                Ok(())
            }
            Light::Directional { azimuth_deg, elevation_deg } => {
                if !(azimuth_deg.is_finite() && elevation_deg.is_finite()) {
                    return Err(format!(
                        "a light's azimuth and elevation must be finite degrees, not {azimuth_deg} and {elevation_deg}"
                    ));
                }
                if !(-90.0..=90.0).contains(&elevation_deg) {
                    // Short, where a header-sized number would print 40 digits (1e39).
                    let shown = if elevation_deg.abs() < 1e6 {
                        format!("{elevation_deg}")
                    } else {
                        format!("{elevation_deg:e}")
                    };
                    return Err(format!("a light's elevation is -90..90 degrees, not {shown}"));
                }
                Ok(())
            }
        }
    }
}

/// The most lights a scene holds: the light volume keeps one shadow channel per light beside
/// ambient occlusion's (`Rgba16Float`: `.rgb` the lights', `.a` occlusion's), and a key, a
/// fill and a back light are the three a studio or VTK's light kit sets.
pub const MAX_LIGHTS: usize = 3;

/// The scene's lights, one to [`MAX_LIGHTS`] (the headlight by default), each checked. Every
/// light shades every sample (Blinn–Phong's diffuse and specular terms are summed over them,
/// each scaled by its own shadow), and the path tracer estimates each one's direct light. The
/// first is the key light: the one `--light` and the viewer's light control move.
#[derive(Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(into = "Vec<Light>", try_from = "Vec<Light>")]
pub struct Lights {
    list: [Light; MAX_LIGHTS],
    count: usize,
}

impl std::fmt::Debug for Lights {
    /// The lights the scene has, as a list (the unused slots are not shown).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.as_slice()).finish()
    }
}

impl Default for Lights {
    fn default() -> Self {
        Self::one(Light::Headlight)
    }
}

impl From<Light> for Lights {
    fn from(light: Light) -> Self {
        Self::one(light)
    }
}

impl From<Lights> for Vec<Light> {
    fn from(lights: Lights) -> Self {
        lights.as_slice().to_vec()
    }
}

impl TryFrom<Vec<Light>> for Lights {
    type Error = String;
    fn try_from(lights: Vec<Light>) -> Result<Self, String> {
        Self::new(&lights)
    }
}

impl Lights {
    /// One light.
    pub const fn one(light: Light) -> Self {
        Self { list: [light; MAX_LIGHTS], count: 1 }
    }

    /// `lights` in order: one to [`MAX_LIGHTS`], each passing [`Light::check`] (the error
    /// names the light by its place, from 1).
    pub fn new(lights: &[Light]) -> Result<Self, String> {
        if lights.is_empty() || lights.len() > MAX_LIGHTS {
            return Err(format!(
                "{} lights: a scene has 1 to {MAX_LIGHTS} (a key, a fill and a back light; the light volume keeps one \
                 shadow per light)",
                lights.len()
            ));
        }
        let mut list = [lights[0]; MAX_LIGHTS];
        for (i, light) in lights.iter().enumerate() {
            light.check().map_err(|e| if lights.len() > 1 { format!("light {}: {e}", i + 1) } else { e })?;
            list[i] = *light;
        }
        Ok(Self { list, count: lights.len() })
    }

    /// The lights, the key light first.
    pub fn as_slice(&self) -> &[Light] {
        &self.list[..self.count]
    }

    /// The key light (the first).
    pub fn key(&self) -> Light {
        self.list[0]
    }

    /// These lights with the key light replaced (the others kept).
    pub fn with_key(mut self, key: Light) -> Self {
        self.list[0] = key;
        self
    }

    /// Where each light comes from, with `headlight` for the headlight ([`Light::toward_with`]).
    pub fn toward_with(&self, headlight: DVec3) -> Vec<Toward> {
        self.as_slice().iter().map(|l| l.toward_with(headlight)).collect()
    }
}

/// Blinn–Phong's two factors for the gradient normal `n` (unit, or the light's direction where
/// the gradient vanishes), the unit direction `l` toward the light and `v` toward the eye:
/// `|n·l|` and `|n·h|` with `h = normalize(l + v)` — `h = l` exactly for the headlight
/// (`l = v`), 0 where light and eye are opposite (`h` undefined; the lit side is then the one
/// the eye cannot see). The GPU's `headlight` computes the same.
pub fn blinn_phong_terms(n: DVec3, l: DVec3, v: DVec3) -> (f64, f64) {
    let n_dot_l = n.dot(l).abs();
    let h = l + v;
    let n_dot_h = if l == v {
        n_dot_l
    } else if h.length() > 1e-6 {
        n.dot(h / h.length()).abs()
    } else {
        0.0
    };
    (n_dot_l, n_dot_h)
}

/// Whole steps of `unit_world` a light ray may take toward a light `distance` away (all of them
/// toward a distant light): the GPU's `steps_to_light` (light_volume.wgsl).
pub fn steps_to_light(distance: f64, unit_world: f64) -> u32 {
    if distance.is_finite() { (distance / unit_world).floor().clamp(0.0, 1e6) as u32 } else { u32::MAX }
}

/// Light-grid voxels per axis at most: transmittance toward the light varies slowly (it is an
/// integral along the light's rays), so the grid is the volume's up to this many voxels per
/// axis, coarser beyond (Ropinski et al. 2008 keep illumination volumes coarse too).
pub const LIGHT_GRID_MAX: u32 = 64;

/// The light grid's voxels per axis for a volume of `dims`.
pub fn light_grid_dims(dims: glam::UVec3) -> glam::UVec3 {
    dims.min(glam::UVec3::splat(LIGHT_GRID_MAX)).max(glam::UVec3::ONE)
}

/// The illumination grid of the `shadows` and `ambient_occlusion` effects, on a grid of the
/// volume's voxels up to [`LIGHT_GRID_MAX`] per axis, at each grid voxel's centre `u0`:
/// - shadows (Behrens & Ratering 1998's shadow volume, computed per voxel by marching toward the
///   light): the transmittance toward the light `T = Π_{k≥1} (1 − α_tf(s(u0 + k·Δ)))^e`, `Δ` one
///   `unit_world` toward the light in texture space, up to the box's face — the light reaching
///   `u0` through everything between it and the light (its own sample excluded, so a surface
///   does not shadow itself); `e = 1 / opacity_unit_voxels`;
/// - ambient occlusion (Hernell et al. 2010's local ambient occlusion, with cone samples reduced
///   to rays): the mean over [`OCCLUSION_DIRECTIONS`] of the transmittance along each over
///   [`OCCLUSION_STEPS`] steps of one `unit_world` (fewer where the box ends: outside is empty).
#[derive(Clone, Debug, PartialEq)]
pub struct LightGrid {
    /// Voxels per axis.
    pub dims: glam::UVec3,
    /// Transmittance toward each light per voxel, x fastest (no lights without shadows).
    pub transmittance: Vec<Vec<f64>>,
    /// Ambient occlusion (the unoccluded share, 1 in the open) per voxel (empty without it).
    pub occlusion: Vec<f64>,
}

/// Steps of one `unit_world` each ambient-occlusion ray takes: the neighbourhood whose material
/// darkens a point (Hernell et al. 2010 use a few voxels' radius too).
pub const OCCLUSION_STEPS: u32 = 8;

/// The ambient-occlusion rays: the 6 axes and the 8 diagonals, each normalized in world space.
pub const OCCLUSION_DIRECTIONS: [[f64; 3]; 14] = [
    [1.0, 0.0, 0.0],
    [-1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, -1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.0, 0.0, -1.0],
    [1.0, 1.0, 1.0],
    [1.0, 1.0, -1.0],
    [1.0, -1.0, 1.0],
    [1.0, -1.0, -1.0],
    [-1.0, 1.0, 1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [-1.0, -1.0, -1.0],
];

impl LightGrid {
    /// The grid over `volume` of the opacity `alpha` gives at a texture point (per
    /// `opacity_unit_voxels`, before the step's correction: the TF's at the reconstructed field,
    /// or several volumes' combined, `fusion::Fusion::alpha`): transmittance toward the unit
    /// world direction toward each light of `towards` (shadows; none without), ambient
    /// occlusion where `occlusion`.
    pub fn compute(
        volume: &crate::volume::Volume,
        (towards, occlusion): (&[Toward], bool),
        (opacity_unit_voxels, cuts): (f64, &crate::cuts::Cuts),
        alpha: &(dyn Fn(DVec3) -> f64 + Sync),
    ) -> Self {
        use rayon::prelude::*;
        let dims = light_grid_dims(volume.dims);
        let exponent = 1.0 / opacity_unit_voxels;
        let m = dims.as_dvec3();
        let centre = |i: usize| {
            let i = i as u32;
            (glam::UVec3::new(i % dims.x, (i / dims.x) % dims.y, i / (dims.x * dims.y)).as_dvec3() + 0.5) / m
        };
        // The transmittance from `u0` along `step` over at most `max` steps; what the scene's
        // crop and clip planes cut away casts no shadow (samples k in the kept [begin, end)).
        let along = |u0: DVec3, step: DVec3, max: u32| {
            let (begin, end) = cuts.keeps_interval(u0, step, 0.0, f64::MAX);
            // Optical depth in opacity units: T = exp(exponent · Σ ln(1 − α)).
            let mut depth = 0.0;
            for k in 1..=steps_to_exit(u0, step).min(max) {
                if !((k as f64) >= begin && (k as f64) < end) {
                    continue;
                }
                let a = alpha(u0 + k as f64 * step).clamp(0.0, 1.0);
                depth += (1.0 - a).ln();
                if exponent * depth < MIN_TRANSMITTANCE.ln() {
                    return 0.0;
                }
            }
            (exponent * depth).exp()
        };
        let count = (dims.x * dims.y * dims.z) as usize;
        let toward_one = |toward: &Toward| -> Vec<f64> {
            match *toward {
                Toward::Direction(toward) => {
                    let step = light_step_tex(volume, toward);
                    (0..count).into_par_iter().map(|i| along(centre(i), step, u32::MAX)).collect()
                }
                point @ Toward::Point(_) => {
                    // Toward a point light: each voxel's own direction, up to the light (material
                    // beyond it casts no shadow); whole steps of one unit_world, as the GPU takes.
                    let half = volume.half_extent_world();
                    let unit = volume.unit_step_world();
                    (0..count)
                        .into_par_iter()
                        .map(|i| {
                            let u0 = centre(i);
                            let (d, r) = point.from((u0 - 0.5) * 2.0 * half);
                            along(u0, light_step_tex(volume, d), steps_to_light(r, unit))
                        })
                        .collect()
                }
            }
        };
        let transmittance = towards.iter().map(toward_one).collect();
        let occlusion = if occlusion {
            let steps: Vec<DVec3> = OCCLUSION_DIRECTIONS
                .iter()
                .map(|d| light_step_tex(volume, DVec3::from_array(*d).normalize()))
                .collect();
            (0..count)
                .into_par_iter()
                .map(|i| {
                    let u0 = centre(i);
                    steps.iter().map(|&step| along(u0, step, OCCLUSION_STEPS)).sum::<f64>() / steps.len() as f64
                })
                .collect()
        } else {
            Vec::new()
        };
        Self { dims, transmittance, occlusion }
    }

    /// The transmittance toward each light (in the scene's order) and the ambient occlusion at
    /// texture point `u`, each trilinear between the grid's voxel centres, clamped to the edge
    /// (as the GPU samples the light volume); 1 for a channel the grid does not hold.
    pub fn sample(&self, u: DVec3) -> ([f64; MAX_LIGHTS], f64) {
        let mut lights = [1.0; MAX_LIGHTS];
        for (t, values) in lights.iter_mut().zip(&self.transmittance) {
            *t = self.sample_channel(values, u);
        }
        (lights, self.sample_channel(&self.occlusion, u))
    }

    fn sample_channel(&self, values: &[f64], u: DVec3) -> f64 {
        if values.is_empty() {
            return 1.0;
        }
        let n = self.dims.as_dvec3();
        let p = (u * n - 0.5).clamp(DVec3::ZERO, n - 1.0);
        let i = p.floor();
        let f = p - i;
        let top = self.dims.as_ivec3() - 1;
        let at = |dx: i32, dy: i32, dz: i32| {
            let c = (i.as_ivec3() + glam::IVec3::new(dx, dy, dz)).min(top);
            values[(c.x + self.dims.x as i32 * (c.y + self.dims.y as i32 * c.z)) as usize]
        };
        let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
        let x00 = lerp(at(0, 0, 0), at(1, 0, 0), f.x);
        let x10 = lerp(at(0, 1, 0), at(1, 1, 0), f.x);
        let x01 = lerp(at(0, 0, 1), at(1, 0, 1), f.x);
        let x11 = lerp(at(0, 1, 1), at(1, 1, 1), f.x);
        lerp(lerp(x00, x10, f.y), lerp(x01, x11, f.y), f.z)
    }
}

/// Below this the light is out: the march toward it stops (the GPU's `MIN_TRANSMITTANCE`).
pub const MIN_TRANSMITTANCE: f64 = 1.0 / 1024.0;

/// One `unit_world` (the smallest voxel side) toward the light `toward`, in texture space.
pub fn light_step_tex(volume: &crate::volume::Volume, toward: DVec3) -> DVec3 {
    toward * volume.unit_step_world() / (2.0 * volume.half_extent_world())
}

/// Whole steps `step` from `u0` that stay inside the texture box `[0, 1]³`.
pub fn steps_to_exit(u0: DVec3, step: DVec3) -> u32 {
    let mut t = f64::INFINITY;
    for a in 0..3 {
        if step[a] > 0.0 {
            t = t.min((1.0 - u0[a]) / step[a]);
        } else if step[a] < 0.0 {
            t = t.min(-u0[a] / step[a]);
        }
    }
    if t.is_finite() { t.floor().clamp(0.0, 1e6) as u32 } else { 0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_light_sits_where_an_orbit_camera_of_its_angles_would() {
        let camera = crate::camera::OrbitCamera { azimuth_deg: 35.0, elevation_deg: 25.0, ..Default::default() };
        let light = Light::parse("35, 25").expect("parses");
        let toward = light.toward().expect("directional");
        let eye = camera.eye() - DVec3::from_array(camera.target);
        assert!((toward - eye.normalize()).length() < 1e-12, "{toward} vs {eye}");
        assert_eq!(Light::parse("HEADLIGHT"), Ok(Light::Headlight));
    }

    /// `point:X,Y,Z` is a point light in world units; its direction and distance from a point
    /// come from where it is; bad positions say what to write.
    #[test]
    fn a_point_light_is_where_it_is_put() {
        let light = Light::parse("point: 0, 2,1").expect("parses");
        assert_eq!(light, Light::Point { x: 0.0, y: 2.0, z: 1.0 });
        let (d, r) = light.toward_with(DVec3::Z).from(DVec3::new(0.0, 0.0, 1.0));
        assert_eq!((d, r), (DVec3::Y, 2.0));
        assert_eq!(light.toward(), None);
        for text in ["point:1,2", "point:a,b,c", "point:inf,0,0", "point:1,2,3,4"] {
            let e = Light::parse(text).expect_err(text);
            assert!(e.contains(&format!("\"{text}\"")), "{text}: {e}");
        }
        assert!(Light::parse("point:nan,0,0").expect_err("NaN").contains("finite"));
        // 1e39 is finite in f64 but infinite on the GPU (it drew a black image): refused.
        assert!(Light::parse("point:1e39,0,0").expect_err("1e39").contains("AZ,EL"));
        assert!(Light::parse("point:-1,0,-1e6").is_ok());
    }

    #[test]
    fn bad_lights_say_what_to_write() {
        assert!(Light::parse("0,1e39").expect_err("1e39").ends_with("not 1e39"));
        for text in ["", "35", "a,b", "NaN,0", "0,inf", "0,91", "1,2,3"] {
            let e = Light::parse(text).expect_err(text);
            assert!(e.contains(&format!("\"{}\"", text.trim())), "{text}: {e}");
        }
    }

    /// A slab of opaque material between the light and a grid voxel shadows it fully; a voxel
    /// on the light's side of the slab is lit; the grid samples between voxel centres.
    #[test]
    fn an_opaque_slab_shadows_what_lies_behind_it() {
        use crate::volume::{Volume, VoxelData};
        let n = 16u32;
        // Value 1 in the slab z in 6..10, else 0.
        let data: Vec<u8> = (0..n * n * n).map(|i| if (6..10).contains(&(i / (n * n))) { 255 } else { 0 }).collect();
        let volume = Volume::new("slab", glam::UVec3::splat(n), DVec3::ONE, VoxelData::U8(data));
        // Opaque above 0.5, clear below.
        let lut: Vec<[f32; 4]> = (0..256).map(|i| if i >= 128 { [1.0; 4] } else { [0.0; 4] }).collect();
        let toward = DVec3::Z; // light at +z
        let alpha = |u: DVec3| crate::reference::lut_sample(&lut, volume.sample_trilinear(u))[3];
        // A second light from -z: each light has its own shadow.
        let towards = [Toward::Direction(toward), Toward::Direction(-toward)];
        let grid = LightGrid::compute(&volume, (&towards, true), (1.0, &crate::cuts::Cuts::NONE), &alpha);
        assert_eq!(grid.dims, glam::UVec3::splat(n));
        let at = |z: u32| grid.transmittance[0][(8 + n * (8 + n * z)) as usize];
        assert_eq!(at(2), 0.0, "behind the slab");
        assert_eq!(at(12), 1.0, "on the light's side");
        assert_eq!(at(15), 1.0, "the last voxel toward the light");
        let from_below = |z: u32| grid.transmittance[1][(8 + n * (8 + n * z)) as usize];
        assert_eq!((from_below(2), from_below(12)), (1.0, 0.0), "the second light's side is the other");
        let (mid, _) = grid.sample(DVec3::new(0.5, 0.5, 12.5 / 16.0));
        assert_eq!(mid, [1.0, 0.0, 1.0], "lit from +z, shadowed from -z, 1 for the light not there");
        // Ambient occlusion: one voxel above the slab (z = 10) 5 of the 14 rays (−z and the four
        // diagonals with −z) run into it within their 8 steps; six voxels above (z = 15) only
        // −z reaches it, the diagonals end 10.4 voxels up.
        let ao = |z: u32| grid.occlusion[(8 + n * (8 + n * z)) as usize];
        assert!((ao(10) - 9.0 / 14.0).abs() < 1e-12, "beside the slab: {}", ao(10));
        assert!((ao(15) - 13.0 / 14.0).abs() < 1e-12, "six voxels above: {}", ao(15));
        assert_eq!(steps_to_exit(DVec3::splat(0.5), DVec3::new(0.0, 0.0, 0.1)), 5);
        // A clip plane keeping z < 0.3 removes the slab: nothing shadows the voxel behind it.
        let keep_low = crate::cuts::ClipPlane::new(DVec3::new(0.0, 0.0, -1.0), -0.3).expect("plane");
        let cuts = crate::cuts::Cuts::new(None, &[keep_low]).expect("cuts");
        let cut = LightGrid::compute(&volume, (&towards[..1], false), (1.0, &cuts), &alpha);
        assert_eq!(cut.transmittance[0][(8 + n * (8 + n * 2)) as usize], 1.0, "the cut-away slab casts no shadow");
        assert_eq!(steps_to_exit(DVec3::splat(0.5), DVec3::ZERO), 0);
    }

    /// One to three lights, each checked and named by its place; the key light is the first.
    #[test]
    fn a_scene_has_one_to_three_lights() {
        let key = Light::Directional { azimuth_deg: 30.0, elevation_deg: 20.0 };
        let fill = Light::Point { x: 0.0, y: 2.0, z: 1.0 };
        let lights = Lights::new(&[key, fill]).expect("two");
        assert_eq!(lights.as_slice(), &[key, fill]);
        assert_eq!(lights.with_key(Light::Headlight).as_slice(), &[Light::Headlight, fill]);
        assert_eq!(Lights::default().as_slice(), &[Light::Headlight]);
        assert!(Lights::new(&[]).expect_err("none").starts_with("0 lights"));
        assert!(Lights::new(&[key; 4]).expect_err("four").starts_with("4 lights: a scene has 1 to 3"));
        let bad = Light::Directional { azimuth_deg: 0.0, elevation_deg: 95.0 };
        assert_eq!(
            Lights::new(&[key, bad]).expect_err("bad"),
            "light 2: a light's elevation is -90..90 degrees, not 95"
        );
        assert_eq!(Lights::new(&[bad]).expect_err("bad"), "a light's elevation is -90..90 degrees, not 95");
    }

    #[test]
    fn with_the_headlight_the_half_vector_is_the_light() {
        let n = DVec3::new(0.3, 0.4, 0.866).normalize();
        let l = DVec3::new(0.0, 0.0, 1.0);
        let (nl, nh) = blinn_phong_terms(n, l, l);
        assert!((nl - nh).abs() < 1e-15);
        assert_eq!(blinn_phong_terms(n, l, -l).1, 0.0, "light facing the eye: no highlight");
    }
}
