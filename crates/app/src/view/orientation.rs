//! The orientation marker (issue 45, item 1): for a volume in the patient frame, the patient's
//! six sides — L/R, P/A, S/I — as axes from a corner of the image, turned with the camera, so a
//! view reads as the clinical tools' do (which way is the patient's left, which way is up).

use glam::DVec3;
use volgraph_accel::camera::OrbitCamera;

/// One side on screen: its letter, its axis colour and where its tip points from the marker's
/// centre (x right, y down, unit length when the axis lies in the image plane).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Side {
    /// `L`, `R`, `P`, `A`, `S` or `I`.
    pub letter: char,
    /// The tip's offset in the image, x right and y down.
    pub toward: (f64, f64),
    /// Which LPS axis (0, 1, 2).
    pub axis: usize,
}

/// The six sides as `camera` sees them (LPS: +x left, +y posterior, +z superior).
pub fn sides(camera: &OrbitCamera) -> [Side; 6] {
    let view = camera.frame(1, 1).view_from_world;
    let side = |letter, axis: usize, sign: f64| {
        let mut d = DVec3::ZERO;
        d[axis] = sign;
        let v = view.transform_vector3(d);
        Side { letter, toward: (v.x, -v.y), axis }
    };
    [
        side('L', 0, 1.0),
        side('R', 0, -1.0),
        side('P', 1, 1.0),
        side('A', 1, -1.0),
        side('S', 2, 1.0),
        side('I', 2, -1.0),
    ]
}

/// Draws the marker in the lower left of `image` (points): a line and a letter per side, the
/// sides that point away from the viewer dimmer.
pub fn draw(ctx: &egui::Context, image: egui::Rect, camera: &OrbitCamera) {
    let painter =
        ctx.layer_painter(egui::LayerId::new(egui::Order::Foreground, egui::Id::unique("orientation marker")));
    let centre = egui::pos2(image.left() + 44.0, image.bottom() - 44.0);
    let length = 30.0;
    let colours = [
        egui::Color32::from_rgb(230, 90, 90),
        egui::Color32::from_rgb(90, 200, 110),
        egui::Color32::from_rgb(110, 150, 240),
    ];
    for s in sides(camera) {
        let tip = centre + egui::vec2(s.toward.0 as f32, s.toward.1 as f32) * length;
        let colour = colours[s.axis];
        painter.line_segment([centre, tip], egui::Stroke::new(2.0, colour));
        let label = centre + egui::vec2(s.toward.0 as f32, s.toward.1 as f32) * (length + 9.0);
        painter.text(label, egui::Align2::CENTER_CENTER, s.letter, egui::FontId::proportional(13.0), colour);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use volgraph_accel::camera::PatientView;

    fn of(camera: &OrbitCamera, letter: char) -> (f64, f64) {
        sides(camera).iter().find(|s| s.letter == letter).expect("a side").toward
    }

    /// From the front the patient's left is on the image's right and superior is up; from the
    /// left, anterior is on the image's left; from above, anterior is up.
    #[test]
    fn the_marker_turns_with_the_view() {
        let anterior = PatientView::Anterior.camera(3.0);
        let (lx, ly) = of(&anterior, 'L');
        assert!(lx > 0.99 && ly.abs() < 1e-9, "L on the right: {lx}, {ly}");
        let (sx, sy) = of(&anterior, 'S');
        assert!(sy < -0.99 && sx.abs() < 1e-9, "S up: {sx}, {sy}");
        let (ax, ay) = of(&anterior, 'A');
        assert!(ax.abs() < 1e-9 && ay.abs() < 1e-9, "A points at the viewer: {ax}, {ay}");
        let left = PatientView::Left.camera(3.0);
        assert!(of(&left, 'A').0 < -0.99, "from the left, anterior on the image's left");
        let superior = PatientView::Superior.camera(3.0);
        assert!(of(&superior, 'A').1 < -0.99, "from above, anterior up");
    }
}
