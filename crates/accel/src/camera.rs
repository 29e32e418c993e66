//! The orbit camera shared by the GPU passes and the CPU reference
//! (`docs/rendering_model.md`, "Camera").

use glam::{DMat4, DVec3, DVec4};
use serde::{Deserialize, Serialize};

/// An orbit camera looking at the origin, where the volume box is centred.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OrbitCamera {
    /// Rotation about +y, degrees; 0 looks from +z.
    pub azimuth_deg: f64,
    /// Angle above the xz plane, degrees.
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
        DVec3::from_array(self.target) + self.distance * DVec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos())
    }

    /// Matrices for a `width × height` viewport.
    pub fn frame(&self, width: u32, height: u32) -> CameraFrame {
        let eye = self.eye();
        let up = if self.elevation_deg.to_radians().cos().abs() < 1e-6 { DVec3::Z } else { DVec3::Y };
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
