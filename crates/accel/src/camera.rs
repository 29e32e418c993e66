//! The orbit camera shared by the GPU passes and the CPU reference
//! (`docs/rendering_model.md`, "Camera").

use glam::{DMat4, DVec3, DVec4};
use serde::{Deserialize, Serialize};

/// Which way an orbit camera keeps up (`docs/rendering_model.md`, "Camera").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum CameraUp {
    /// World +y up; azimuth 0 looks from +z (the default, and every volume outside the patient
    /// frame).
    #[default]
    Y,
    /// The patient's: world +z (superior, in LPS) up; azimuth 0 looks from the patient's front
    /// (anterior, world −y) and azimuth 90 from the patient's left (+x), as the clinical tools'
    /// views do.
    Patient,
}

impl CameraUp {
    /// A direction of the orbit's own space (y up, azimuth 0 along +z) in the world.
    pub fn to_world(self, v: DVec3) -> DVec3 {
        match self {
            CameraUp::Y => v,
            // Orbit x → world x (left), orbit y (up) → world z (superior), orbit z → world −y
            // (anterior): a rotation (its columns x, z, −y have determinant 1).
            CameraUp::Patient => DVec3::new(v.x, -v.z, v.y),
        }
    }
}

/// The standard views of a volume in the patient frame (`--view`): where the eye stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PatientView {
    /// From the front.
    Anterior,
    /// From behind.
    Posterior,
    /// From the patient's left.
    Left,
    /// From the patient's right.
    Right,
    /// From above the head (anterior at the top of the image).
    Superior,
    /// From below the feet (anterior at the top of the image).
    Inferior,
}

impl PatientView {
    /// Every view with its name, in the order the viewer's keys 1–6 take them.
    pub const ALL: [(&'static str, PatientView); 6] = [
        ("anterior", PatientView::Anterior),
        ("posterior", PatientView::Posterior),
        ("left", PatientView::Left),
        ("right", PatientView::Right),
        ("superior", PatientView::Superior),
        ("inferior", PatientView::Inferior),
    ];

    /// The view a name gives (`anterior`, …; case-insensitive).
    pub fn from_name(name: &str) -> Option<PatientView> {
        Self::ALL.iter().find(|(n, _)| n.eq_ignore_ascii_case(name.trim())).map(|(_, v)| *v)
    }

    /// The names, for messages.
    pub fn names() -> String {
        Self::ALL.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
    }

    /// The orbit camera of this view at `distance`, superior up.
    pub fn camera(self, distance: f64) -> OrbitCamera {
        let (azimuth_deg, elevation_deg) = match self {
            PatientView::Anterior => (0.0, 0.0),
            PatientView::Posterior => (180.0, 0.0),
            PatientView::Left => (90.0, 0.0),
            PatientView::Right => (-90.0, 0.0),
            PatientView::Superior => (0.0, 90.0),
            PatientView::Inferior => (0.0, -90.0),
        };
        OrbitCamera { azimuth_deg, elevation_deg, distance, up: CameraUp::Patient, ..OrbitCamera::default() }
    }
}

/// An orbit camera looking at the origin, where the volume box is centred.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OrbitCamera {
    /// Rotation about the up axis, degrees; 0 looks from +z (from the front with
    /// [`CameraUp::Patient`]).
    pub azimuth_deg: f64,
    /// Angle above the plane across the up axis, degrees.
    pub elevation_deg: f64,
    /// Distance of the eye from the origin, world units (the volume's longest side is 1).
    pub distance: f64,
    /// Vertical field of view, degrees.
    pub fov_y_deg: f64,
    /// Near plane distance.
    pub near: f64,
    /// The point looked at (world); the orbit turns about it. The origin (the volume's centre)
    /// unless panned.
    pub target: [f64; 3],
    /// Far plane distance; [`OrbitCamera::frame`] moves it out to `distance + 1` when that is
    /// farther, so the volume (longest side 1, inside a sphere of radius √3/2 about the origin)
    /// is never clipped however far away the camera is.
    pub far: f64,
    /// Which way is up: world +y, or the patient's superior.
    pub up: CameraUp,
}

impl Default for OrbitCamera {
    fn default() -> Self {
        Self {
            azimuth_deg: 30.0,
            elevation_deg: 20.0,
            distance: 3.2,
            fov_y_deg: 30.0,
            near: 0.01,
            far: 100.0,
            target: [0.0; 3],
            up: CameraUp::Y,
        }
    }
}

/// The matrices and eye position of a camera for one viewport.
#[derive(Clone, Copy, Debug)]
pub struct CameraFrame {
    /// Eye position, world space.
    pub eye: DVec3,
    /// `view` transform (world → eye), right-handed.
    pub view_from_world: DMat4,
    /// Projection (eye → clip), WebGPU depth range \[0,1\].
    pub clip_from_view: DMat4,
    /// `clip_from_view * view_from_world`.
    pub clip_from_world: DMat4,
    /// Inverse of `clip_from_world`.
    pub world_from_clip: DMat4,
    /// Unit forward direction of the camera, world space.
    pub forward: DVec3,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl OrbitCamera {
    /// The eye position in world space.
    pub fn eye(&self) -> DVec3 {
        let (az, el) = (self.azimuth_deg.to_radians(), self.elevation_deg.to_radians());
        let orbit = DVec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos());
        DVec3::from_array(self.target) + self.distance * self.up.to_world(orbit)
    }

    /// The world direction kept up on screen (looking straight along it, the azimuth-0 side is
    /// up instead).
    pub fn up_vector(&self) -> DVec3 {
        let straight = self.elevation_deg.to_radians().cos().abs() < 1e-6;
        self.up.to_world(if straight { DVec3::Z } else { DVec3::Y })
    }

    /// Matrices for a `width × height` viewport.
    pub fn frame(&self, width: u32, height: u32) -> CameraFrame {
        let eye = self.eye();
        let up = self.up_vector();
        let target = DVec3::from_array(self.target);
        let view_from_world = glam::dcamera::rh::view::look_at_mat4(eye, target, up);
        let aspect = width.max(1) as f64 / height.max(1) as f64;
        let clip_from_view = glam::dcamera::rh::proj::directx::perspective(
            self.fov_y_deg.to_radians(),
            aspect,
            self.near,
            self.far.max(self.distance + DVec3::from_array(self.target).length() + 1.0),
        );
        let clip_from_world = clip_from_view * view_from_world;
        CameraFrame {
            eye,
            view_from_world,
            clip_from_view,
            clip_from_world,
            world_from_clip: clip_from_world.inverse(),
            forward: (target - eye).normalize_or(DVec3::NEG_Z),
            width,
            height,
        }
    }
}

impl CameraFrame {
    /// The world-space ray through the centre of pixel `(x, y)` (row 0 at the top):
    /// origin at the eye, unit direction.
    pub fn pixel_ray(&self, x: u32, y: u32) -> (DVec3, DVec3) {
        let ndc_x = 2.0 * (x as f64 + 0.5) / self.width as f64 - 1.0;
        let ndc_y = 1.0 - 2.0 * (y as f64 + 0.5) / self.height as f64;
        let unproject = |z: f64| {
            let p = self.world_from_clip * DVec4::new(ndc_x, ndc_y, z, 1.0);
            p.truncate() / p.w
        };
        let dir = (unproject(1.0) - unproject(0.0)).normalize();
        (self.eye, dir)
    }

    /// Distance along a unit ray `dir` from the eye to the near plane.
    pub fn near_t(&self, near: f64, dir: DVec3) -> f64 {
        near / dir.dot(self.forward).max(1e-12)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The patient views stand where their names say in LPS (+x left, +y posterior, +z
    /// superior), superior up on screen (anterior up looking along the body axis).
    #[test]
    fn patient_views_stand_where_their_names_say() {
        let d = 3.0;
        let eye = |v: PatientView| v.camera(d).eye();
        let close = |a: DVec3, b: DVec3| (a - b).length() < 1e-9;
        assert!(close(eye(PatientView::Anterior), DVec3::new(0.0, -d, 0.0)));
        assert!(close(eye(PatientView::Posterior), DVec3::new(0.0, d, 0.0)));
        assert!(close(eye(PatientView::Left), DVec3::new(d, 0.0, 0.0)));
        assert!(close(eye(PatientView::Right), DVec3::new(-d, 0.0, 0.0)));
        assert!(close(eye(PatientView::Superior), DVec3::new(0.0, 0.0, d)));
        assert!(close(eye(PatientView::Inferior), DVec3::new(0.0, 0.0, -d)));
        assert_eq!(PatientView::Anterior.camera(d).up_vector(), DVec3::Z, "superior up");
        assert!(close(PatientView::Superior.camera(d).up_vector(), DVec3::new(0.0, -1.0, 0.0)), "anterior up");
        // From the front the patient's left (+x) is on the image's right, as in Slicer's
        // anterior view.
        let f = PatientView::Anterior.camera(d).frame(64, 64);
        let right = (f.clip_from_world * DVec4::new(1.0, 0.0, 0.0, 1.0)).x;
        assert!(right > 0.0, "the patient's left on the image's right");
        assert_eq!(PatientView::from_name("Left"), Some(PatientView::Left));
        assert_eq!(PatientView::from_name("lateral"), None);
        // The default camera is unchanged: y up.
        assert_eq!(OrbitCamera::default().up_vector(), DVec3::Y);
    }
}
