//! Mouse and keyboard control of the orbit camera: drag to rotate, wheel to zoom, shift-drag or
//! middle-drag to pan, R to reset.

use glam::DVec3;
use volgraph_accel::camera::OrbitCamera;

/// Degrees of rotation per pixel dragged.
const DEGREES_PER_PIXEL: f64 = 0.4;
/// Zoom factor per wheel line.
const ZOOM_PER_LINE: f64 = 0.9;

/// The camera and the drag in progress.
pub struct Orbit {
    /// The camera.
    pub camera: OrbitCamera,
    start: OrbitCamera,
    rotating: bool,
    panning: bool,
    last: Option<(f64, f64)>,
}

impl Orbit {
    /// Whether a button is held (the camera is turning or panning).
    pub fn is_dragging(&self) -> bool {
        self.rotating || self.panning
    }

    /// Control of `camera`; R returns to it.
    pub fn new(camera: OrbitCamera) -> Self {
        Self { camera, start: camera, rotating: false, panning: false, last: None }
    }

    /// Back to the start camera.
    pub fn reset(&mut self) {
        self.camera = self.start;
    }

    /// A button went down or up: `pan` for the middle button or shift held.
    pub fn button(&mut self, pressed: bool, pan: bool) {
        if pressed {
            self.rotating = !pan;
            self.panning = pan;
        } else {
            self.rotating = false;
            self.panning = false;
            self.last = None;
        }
    }

    /// The cursor moved to `(x, y)` in a window `height` pixels tall.
    pub fn moved(&mut self, x: f64, y: f64, height: f64) {
        if let Some((lx, ly)) = self.last {
            let (dx, dy) = (x - lx, y - ly);
            if self.rotating {
                self.camera.azimuth_deg -= dx * DEGREES_PER_PIXEL;
                self.camera.elevation_deg = (self.camera.elevation_deg + dy * DEGREES_PER_PIXEL).clamp(-89.0, 89.0);
            } else if self.panning {
                let frame = self.camera.frame(1, 1);
                let forward = frame.forward;
                let right = forward.cross(self.camera.up_vector()).normalize_or(DVec3::X);
                let up = right.cross(forward);
                // One window height of drag moves the target by the visible height at its distance.
                let scale =
                    2.0 * self.camera.distance * (self.camera.fov_y_deg.to_radians() / 2.0).tan() / height.max(1.0);
                let t = DVec3::from_array(self.camera.target) - right * dx * scale + up * dy * scale;
                self.camera.target = t.to_array();
            }
        }
        self.last = Some((x, y));
    }

    /// The wheel turned `lines` (positive: away from the user, zoom in).
    pub fn wheel(&mut self, lines: f64) {
        self.camera.distance = (self.camera.distance * ZOOM_PER_LINE.powf(lines)).clamp(0.05, 1000.0);
    }

    /// Turns the camera `degrees` about the target (scripted rotation).
    pub fn turn(&mut self, degrees: f64) {
        self.camera.azimuth_deg += degrees;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drag_rotates_wheel_zooms_shift_drag_pans_and_reset_restores() {
        let mut o = Orbit::new(OrbitCamera::default());
        o.button(true, false);
        o.moved(100.0, 100.0, 500.0);
        o.moved(110.0, 105.0, 500.0);
        assert_eq!(o.camera.azimuth_deg, 30.0 - 4.0);
        assert_eq!(o.camera.elevation_deg, 20.0 + 2.0);
        o.button(false, false);
        o.wheel(1.0);
        assert!((o.camera.distance - 3.2 * 0.9).abs() < 1e-12);
        o.button(true, true);
        o.moved(0.0, 0.0, 500.0);
        o.moved(50.0, 0.0, 500.0);
        assert!(DVec3::from_array(o.camera.target).length() > 0.0, "panned");
        o.reset();
        assert_eq!(o.camera, OrbitCamera::default());
    }
}
