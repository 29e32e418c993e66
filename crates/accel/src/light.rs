//! The scene's light (issue "light that scatters", item 1): the headlight — from the eye, the
//! default — or a directional light fixed in the world, placed by azimuth and elevation as an
//! orbit camera is ([`crate::camera::OrbitCamera::eye`]: `--light 35,25` shines from where a
//! camera at azimuth 35°, elevation 25° would look from). Blinn–Phong shading (the GPU's
//! `headlight` in `shaders/common/raymarch.wgsl`, the reference's `lighting`) reads it:
//! diffuse `|n·l|`, specular `|n·h|^shininess` with `h` halfway between the light and the eye
//! (with the headlight `h = l`, the shading of every earlier image).

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
}

impl Light {
    /// The unit world direction toward the light; `None` for the headlight (it is each ray's
    /// own `-direction`).
    pub fn toward(&self) -> Option<DVec3> {
        match *self {
            Light::Headlight => None,
            Light::Directional { azimuth_deg, elevation_deg } => {
                let (az, el) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
                Some(DVec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos()))
            }
        }
    }

    /// Reads `--light`: `headlight`, or `AZ,EL` in degrees (finite; elevation within −90..90).
    pub fn parse(text: &str) -> Result<Self, String> {
        let text = text.trim();
        if text.eq_ignore_ascii_case("headlight") {
            return Ok(Light::Headlight);
        }
        let bad = || {
            format!(
                "\"{text}\" is no light: write AZ,EL in degrees (azimuth about the vertical axis, elevation -90..90, \
                 e.g. 35,25) or headlight"
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
            Light::Directional { azimuth_deg, elevation_deg } => {
                if !(azimuth_deg.is_finite() && elevation_deg.is_finite()) {
                    return Err(format!(
                        "a light's azimuth and elevation must be finite degrees, not {azimuth_deg} and {elevation_deg}"
                    ));
                }
                if !(-90.0..=90.0).contains(&elevation_deg) {
                    return Err(format!("a light's elevation is -90..90 degrees, not {elevation_deg}"));
                }
                Ok(())
            }
        }
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

    #[test]
    fn bad_lights_say_what_to_write() {
        for text in ["", "35", "a,b", "NaN,0", "0,inf", "0,91", "1,2,3"] {
            let e = Light::parse(text).expect_err(text);
            assert!(e.contains(&format!("\"{}\"", text.trim())), "{text}: {e}");
        }
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
