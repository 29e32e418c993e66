//! A scene's camera: one orbit (turning 1° per frame over `frames`) or a path of keyframes,
//! checked as the command line's `--camera` is checked, and the orbit camera of each frame.

use serde::Deserialize;
use volgraph_accel::camera::{CameraUp, OrbitCamera};

use super::MAX_FRAMES;

/// One keyframe of a camera path.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Keyframe {
    /// The frame it holds at.
    pub frame: u32,
    /// Degrees about +y.
    pub azimuth: f64,
    /// Degrees above the xz plane.
    pub elevation: f64,
    /// Distance from the volume's centre, world units.
    pub distance: f64,
}

/// The camera of a scene.
#[derive(Clone, Debug, Deserialize, PartialEq)]
pub enum CameraSpec {
    /// One orbit camera; with `frames` > 1 it turns 1° about y per frame (as `render --frames`).
    Orbit {
        /// Degrees about +y.
        azimuth: f64,
        /// Degrees above the xz plane.
        elevation: f64,
        /// Distance, world units.
        distance: f64,
        /// The point it orbits (world units; default the volume's centre): a viewer's pan.
        #[serde(default)]
        target: Option<(f64, f64, f64)>,
        /// Which way is up: `Y` (default), or `Patient` — superior up, azimuth 0 from the front
        /// (`--view`; a volume in the patient frame).
        #[serde(default)]
        up: CameraUp,
    },
    /// Keyframes, interpolated linearly in azimuth, elevation and distance.
    Path {
        /// At least one, in increasing frame order.
        keyframes: Vec<Keyframe>,
    },
}

/// The orbit values the CLI's `--camera` accepts: finite degrees, an elevation within ±90°
/// (beyond it the orbit flips over the pole) and a positive distance at which a ray can still
/// be set up (at 1e-300 world units the eye is inside the volume at a point, and the
/// projection divides by it).
fn check_orbit(azimuth: f64, elevation: f64, distance: f64) -> Result<(), String> {
    if !(azimuth.is_finite() && elevation.is_finite() && distance.is_finite()) {
        return Err("azimuth, elevation and distance must be finite numbers".into());
    }
    // 1e-300 as written, not as three hundred zeros.
    let number = |x: f64| if x != 0.0 && !(1e-4..1e7).contains(&x.abs()) { format!("{x:e}") } else { format!("{x}") };
    if elevation.abs() > 90.0 {
        return Err(format!("elevation {} must be within -90..=90 degrees", number(elevation)));
    }
    if !(MIN_DISTANCE..=MAX_DISTANCE).contains(&distance) {
        return Err(format!(
            "distance {} must be within {MIN_DISTANCE}..={MAX_DISTANCE} world units (the volume's longest side is 1)",
            number(distance)
        ));
    }
    Ok(())
}

/// The nearest eye distance from the volume's centre (inside the volume is fine, the centre is
/// not a camera).
pub const MIN_DISTANCE: f64 = 1e-3;
/// The farthest (beyond it the volume is under a pixel at any sensible field of view).
pub const MAX_DISTANCE: f64 = 1e6;

pub(super) fn check_camera(camera: &CameraSpec) -> Result<(), String> {
    match camera {
        CameraSpec::Orbit { azimuth, elevation, distance, target, .. } => {
            check_orbit(*azimuth, *elevation, *distance)?;
            if target.is_some_and(|(x, y, z)| !(x.is_finite() && y.is_finite() && z.is_finite())) {
                return Err("target must be three finite numbers (world units)".into());
            }
        }
        CameraSpec::Path { keyframes } => {
            if keyframes.is_empty() {
                return Err("a Path needs at least one keyframe".into());
            }
            for (i, k) in keyframes.iter().enumerate() {
                check_orbit(k.azimuth, k.elevation, k.distance).map_err(|m| format!("keyframe {i}: {m}"))?;
                if k.frame >= MAX_FRAMES {
                    return Err(format!(
                        "keyframe {i}: frame {} is beyond the last frame a scene renders ({}); a path holds at most \
                         {MAX_FRAMES} frames",
                        k.frame,
                        MAX_FRAMES - 1
                    ));
                }
                if i > 0 && k.frame <= keyframes[i - 1].frame {
                    return Err(format!(
                        "keyframe {i}: frame {} does not come after {}",
                        k.frame,
                        keyframes[i - 1].frame
                    ));
                }
            }
        }
    }
    Ok(())
}

impl CameraSpec {
    /// The orbit camera of frame `index`: an orbit turns 1° about y per frame (as `render
    /// --frames`); a path interpolates its keyframes linearly and holds the ends.
    pub fn at(&self, index: u32) -> OrbitCamera {
        match self {
            CameraSpec::Orbit { azimuth, elevation, distance, target, up } => OrbitCamera {
                azimuth_deg: azimuth + index as f64,
                elevation_deg: *elevation,
                distance: *distance,
                target: target.map_or([0.0; 3], |(x, y, z)| [x, y, z]),
                up: *up,
                ..OrbitCamera::default()
            },
            CameraSpec::Path { keyframes } => {
                let orbit = |k: &Keyframe| (k.azimuth, k.elevation, k.distance);
                let (a, e, d) = match keyframes.iter().position(|k| k.frame >= index) {
                    None => keyframes.last().map_or((30.0, 20.0, 3.2), orbit),
                    Some(0) => orbit(&keyframes[0]),
                    Some(i) => {
                        let (k0, k1) = (&keyframes[i - 1], &keyframes[i]);
                        let t = (index - k0.frame) as f64 / (k1.frame - k0.frame) as f64;
                        let lerp = |x: f64, y: f64| x + (y - x) * t;
                        (lerp(k0.azimuth, k1.azimuth), lerp(k0.elevation, k1.elevation), lerp(k0.distance, k1.distance))
                    }
                };
                OrbitCamera { azimuth_deg: a, elevation_deg: e, distance: d, ..OrbitCamera::default() }
            }
        }
    }
}
