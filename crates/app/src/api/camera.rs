//! The camera as the library takes it: an orbit, a patient view by name, or the command line's
//! default for the volume (and the scene's camera, where a scene gives one).

use anyhow::anyhow;
use volgraph_accel::camera::{OrbitCamera, PatientView};
use volgraph_accel::volume::Volume;

use super::ApiError;

/// A camera: an orbit, a patient view by name, or the command line's default for the volume.
#[derive(Clone, Debug, PartialEq)]
pub enum Camera {
    /// `--camera AZ,EL,DIST`: degrees about +y, degrees up, distance in world units.
    Orbit(f64, f64, f64),
    /// `--view NAME` (anterior, posterior, left, right, superior, inferior).
    View(String),
    /// Neither: the scene's first camera where a scene gives one, else the anterior view for a
    /// volume in the patient frame, else 30°, 20°, 3.2.
    Default,
}

impl Camera {
    /// The orbit camera this names for `volume` (`scene`: the scene's first camera, which a
    /// default camera takes).
    pub fn orbit(&self, volume: &Volume, scene: Option<OrbitCamera>) -> Result<OrbitCamera, ApiError> {
        match self {
            Camera::Orbit(azimuth_deg, elevation_deg, distance) => {
                let finite = [azimuth_deg, elevation_deg, distance].iter().all(|v| v.is_finite());
                if !finite || *distance <= 0.0 {
                    return Err(ApiError::Input(anyhow!(
                        "camera ({azimuth_deg}, {elevation_deg}, {distance}): azimuth, elevation and a distance > 0, \
                         all finite"
                    )));
                }
                Ok(OrbitCamera {
                    azimuth_deg: *azimuth_deg,
                    elevation_deg: *elevation_deg,
                    distance: *distance,
                    ..OrbitCamera::default()
                })
            }
            Camera::View(name) => {
                crate::scene_args::check_view_frame(Some(name), volume)?;
                let view = PatientView::from_name(name)
                    .ok_or_else(|| anyhow!("view \"{name}\": not a view; the views are {}", PatientView::names()))?;
                Ok(view.camera(3.2))
            }
            Camera::Default if scene.is_some() => Ok(scene.unwrap_or_default()),
            Camera::Default if volume.meta.frame == volgraph_accel::volume_meta::WorldFrame::Lps => {
                Ok(PatientView::Anterior.camera(3.2))
            }
            Camera::Default => Ok(OrbitCamera::default()),
        }
    }
}
