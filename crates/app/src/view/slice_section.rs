//! The slice panes in the window: the panel's "Slices" section (open/close, window and level
//! with the CT presets, where the crosshair is) and the overlay over the panes (each pane's
//! crosshair, its name, slice and side letters) and the 3D view (the crosshair's point).

use glam::{DVec2, DVec4};
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::reslice::SliceAxis;
use volgraph_accel::volume_meta::{Window, side_label};

use super::panel::Action;
use super::slice_panes::{FourUp, SlicePanes};

/// The CT windows every viewer offers (center, width in HU), as radiology reads them.
pub const CT_WINDOWS: [(&str, f64, f64); 4] =
    [("brain", 40.0, 80.0), ("soft tissue", 40.0, 400.0), ("lung", -600.0, 1500.0), ("bone", 400.0, 1800.0)];

/// Each plane's colour, as 3D Slicer marks its views: axial red, coronal green, sagittal yellow.
pub fn plane_colour(axis: SliceAxis) -> egui::Color32 {
    match axis {
        SliceAxis::Axial => egui::Color32::from_rgb(230, 80, 70),
        SliceAxis::Coronal => egui::Color32::from_rgb(90, 200, 90),
        SliceAxis::Sagittal => egui::Color32::from_rgb(235, 200, 60),
    }
}

/// What the panel's section shows of the panes.
pub struct SliceInfo<'a> {
    /// The panes, when open.
    pub panes: Option<&'a SlicePanes>,
    /// The volume is CT in HU: the CT presets apply.
    pub hounsfield: bool,
    /// What lies at the crosshair: value, label, where (`LiveSession::crosshair_line`).
    pub crosshair: Option<String>,
}

/// The "Slices" section; returns what the user did.
pub fn section(ui: &mut egui::Ui, info: &SliceInfo<'_>) -> Vec<Action> {
    let mut actions = Vec::new();
    egui::CollapsingHeader::new("Slices").default_open(info.panes.is_some()).show(ui, |ui| {
        let mut open = info.panes.is_some();
        if ui.checkbox(&mut open, "axial, coronal, sagittal panes (M)").changed() {
            actions.push(Action::SlicePanes(open));
        }
        let Some(panes) = info.panes else {
            ui.small("the clinical four-up: click a slice to move the crosshair, the wheel steps through slices");
            return;
        };
        let mut planes = panes.planes_in_3d;
        if ui.checkbox(&mut planes, "the planes in the 3D view").changed() {
            actions.push(Action::SlicePlanesIn3d(planes));
        }
        let window = panes.view.window;
        ui.horizontal_wrapped(|ui| {
            ui.label("window:");
            if ui.button("file").on_hover_text("the file's window, else the value range").clicked() {
                actions.push(Action::SliceWindow(panes.file_window()));
            }
            if info.hounsfield {
                for (name, center, width) in CT_WINDOWS {
                    if ui.button(name).on_hover_text(format!("{center} / {width} HU")).clicked() {
                        actions.push(Action::SliceWindow(Window { center, width }));
                    }
                }
            }
        });
        let (mut center, mut width) = (window.center, window.width);
        let speed = (panes.file_window().width / 200.0).max(1e-3);
        let changed = ui
            .horizontal(|ui| {
                let c = ui.add(egui::DragValue::new(&mut center).speed(speed).prefix("level ")).changed();
                let w =
                    ui.add(egui::DragValue::new(&mut width).speed(speed).range(1e-6..=1e9).prefix("width ")).changed();
                c || w
            })
            .inner;
        if changed {
            actions.push(Action::SliceWindow(Window { center, width }));
        }
        for axis in SliceAxis::ALL {
            ui.small(format!("{}: slice {} of {}", axis.name(), panes.slice_index(axis) + 1, panes.slice_count(axis)));
        }
        if let Some(line) = &info.crosshair {
            ui.small(line);
        }
        if let Some(ms) = panes.last_update_ms {
            ui.small(format!("last slice update: {ms:.1} ms (three panes, rendered and waited for)"));
        }
    });
    actions
}

/// Draws each pane's crosshair, name, slice and side letters over the panes, and the crosshair's
/// point over the 3D view seen by `camera`. `layout` is in physical pixels; `ppp` pixels per point.
pub fn draw_overlay(
    ctx: &egui::Context,
    layout: &FourUp,
    ppp: f32,
    panes: &SlicePanes,
    camera: &OrbitCamera,
    patient: bool,
) {
    let painter = ctx.layer_painter(egui::LayerId::new(egui::Order::Background, egui::Id::unique("slice overlay")));
    let to_points = |x: f64, y: f64| egui::pos2(x as f32 / ppp, y as f32 / ppp);
    let pane = layout.pane();
    let yellow = egui::Color32::from_rgb(240, 200, 40);
    for (axis, [x, y, w, h]) in SliceAxis::ALL.into_iter().zip(layout.panes) {
        let (x0, y0) = (f64::from(x), f64::from(y));
        let rect = egui::Rect::from_min_max(to_points(x0, y0), to_points(x0 + f64::from(w), y0 + f64::from(h)));
        let c = panes.crosshair_in(axis, pane) + DVec2::new(x0, y0);
        let stroke = egui::Stroke::new(1.0, yellow.gamma_multiply(0.8));
        painter.line_segment(
            [egui::pos2(rect.left(), c.y as f32 / ppp), egui::pos2(rect.right(), c.y as f32 / ppp)],
            stroke,
        );
        painter.line_segment(
            [egui::pos2(c.x as f32 / ppp, rect.top()), egui::pos2(c.x as f32 / ppp, rect.bottom())],
            stroke,
        );
        painter.rect_stroke(rect, 0.0, egui::Stroke::new(1.5, plane_colour(axis)), egui::StrokeKind::Inside);
        let font = egui::FontId::proportional(12.0);
        let name = format!("{} {}/{}", axis.name(), panes.slice_index(axis) + 1, panes.slice_count(axis));
        painter.text(
            rect.left_top() + egui::vec2(4.0, 2.0),
            egui::Align2::LEFT_TOP,
            name,
            font.clone(),
            egui::Color32::WHITE,
        );
        // The sides at the pane's edges (the patient frame's letters; index axes otherwise).
        let [(c_axis, c_back), (r_axis, r_back)] = axis.pane_axes();
        let letter = |a: usize, toward_plus: bool| edge_letter(a, toward_plus, patient);
        let edges = [
            (rect.left_center() + egui::vec2(3.0, 0.0), egui::Align2::LEFT_CENTER, letter(c_axis, c_back)),
            (rect.right_center() - egui::vec2(3.0, 0.0), egui::Align2::RIGHT_CENTER, letter(c_axis, !c_back)),
            (rect.center_top() + egui::vec2(0.0, 16.0), egui::Align2::CENTER_TOP, letter(r_axis, r_back)),
            (rect.center_bottom() - egui::vec2(0.0, 3.0), egui::Align2::CENTER_BOTTOM, letter(r_axis, !r_back)),
        ];
        for (at, align, text) in edges {
            painter.text(at, align, text, font.clone(), yellow);
        }
    }
    // The crosshair in the 3D view, where the three planes meet, and the planes' outlines,
    // projected by the camera.
    let [x, y, w, h] = layout.view;
    let frame = camera.frame(w, h);
    let project = |world: glam::DVec3| {
        let clip = frame.clip_from_world * DVec4::from((world, 1.0));
        (clip.w > 0.0).then(|| {
            let ndc = clip.truncate() / clip.w;
            to_points(
                f64::from(x) + (ndc.x + 1.0) * 0.5 * f64::from(w),
                f64::from(y) + (1.0 - ndc.y) * 0.5 * f64::from(h),
            )
        })
    };
    let view_rect =
        egui::Rect::from_min_max(to_points(f64::from(x), f64::from(y)), to_points(f64::from(x + w), f64::from(y + h)));
    let painter = painter.with_clip_rect(view_rect);
    if panes.planes_in_3d {
        for axis in SliceAxis::ALL {
            let corners: Option<Vec<egui::Pos2>> = panes.plane_corners_world(axis).into_iter().map(project).collect();
            if let Some(mut outline) = corners {
                outline.push(outline[0]);
                painter.add(egui::Shape::line(outline, egui::Stroke::new(1.5, plane_colour(axis))));
            }
        }
    }
    if let Some(at) = project(panes.crosshair_world()) {
        painter.circle_stroke(at, 5.0, egui::Stroke::new(1.5, yellow));
        painter.circle_filled(at, 1.5, yellow);
    }
}

/// The letter of the pane edge that axis `a`'s values grow toward (`toward_plus`) or away from:
/// L/R, P/A, S/I in the patient frame (LPS), else +x/−x and so on.
fn edge_letter(a: usize, toward_plus: bool, patient: bool) -> String {
    if patient {
        // side_label of a positive or negative distance names the side; keep its letter.
        side_label(a, if toward_plus { 1.0 } else { -1.0 }).chars().next().unwrap_or('?').to_string()
    } else {
        format!("{}{}", if toward_plus { "+" } else { "−" }, ["x", "y", "z"][a])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pane_edges_carry_the_patient_sides_the_clinical_tools_show() {
        // Axial: the patient's right on the left edge, left on the right, anterior at the top.
        let [(c, c_back), (r, r_back)] = SliceAxis::Axial.pane_axes();
        assert_eq!(edge_letter(c, c_back, true), "R");
        assert_eq!(edge_letter(c, !c_back, true), "L");
        assert_eq!(edge_letter(r, r_back, true), "A");
        // Sagittal: anterior on the left, superior at the top.
        let [(c, c_back), (r, r_back)] = SliceAxis::Sagittal.pane_axes();
        assert_eq!(edge_letter(c, c_back, true), "A");
        assert_eq!(edge_letter(r, r_back, true), "S");
        assert_eq!(edge_letter(2, true, false), "+z");
    }
}
