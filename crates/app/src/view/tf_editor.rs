//! The viewer's transfer-function editor (issue 24 §1; what ParaView's colour-map editor,
//! Slicer's volume-rendering module and Inviwo's TF property offer): the volume's histogram on a
//! log scale in the data's units, the TF's opacity curve and control points over it. Click empty
//! space to add a point, drag a point to move it (value and opacity), right-click to delete it;
//! the selected point's colour, opacity and value are edited below (drag the numbers, or
//! double-click to type one), "shift" moves the whole function along the data axis and "width"
//! stretches it about its centre (3D Slicer's shift slider: a CT preset moved along the HU axis in
//! one motion), and the built-in presets replace the whole function. Every change comes back as a new [`TransferFunction`] for the
//! session to upload at once.

use egui::{Color32, Pos2, Rect, Sense, Stroke, Vec2};
use volgraph_accel::transfer_function::{ControlPoint, TransferFunction};

/// Height of the editing area in points.
const HEIGHT: f32 = 130.0;
/// How near (in points) the pointer must be to grab a control point.
const GRAB: f32 = 8.0;

/// What the editor asks of the session.
#[derive(Debug)]
pub enum TfAction {
    /// Use this function.
    Edit(TransferFunction),
    /// Save the TF to its file.
    Save,
    /// Turn "save on change" on or off.
    SaveOnChange(bool),
}

/// Linear → sRGB for display (the points hold linear RGB).
fn display_color(c: [f64; 3], alpha: f64) -> Color32 {
    let s = |x: f64| (volgraph_accel::srgb::encode(x) * 255.0).round() as u8;
    Color32::from_rgba_unmultiplied(s(c[0]), s(c[1]), s(c[2]), (alpha.clamp(0.0, 1.0) * 255.0) as u8)
}

/// The editor. `histogram` counts normalized values; `range` is the data values its ends stand
/// for. Returns at most one action per frame.
pub fn show(
    ui: &mut egui::Ui,
    tf: &TransferFunction,
    histogram: &[u64],
    range: (f64, f64),
    presets: &[(&'static str, TransferFunction)],
    save_on_change: bool,
) -> Option<TfAction> {
    let mut action = None;
    // The data's range (a constant volume has none: the TF's domain, or a unit span, instead).
    let (lo, hi) = [range, tf.domain]
        .into_iter()
        .find(|(a, b)| a.is_finite() && b.is_finite() && b > a)
        .unwrap_or((range.0.min(0.0), range.0.max(0.0) + 1.0));
    let selected_id = ui.make_persistent_id("tf_selected");
    let mut selected: Option<usize> = ui.data(|d| d.get_temp(selected_id)).filter(|&i| i < tf.points.len());
    let (response, painter) = ui.allocate_painter(Vec2::new(ui.available_width(), HEIGHT), Sense::click_and_drag());
    let rect = response.rect;
    let to_screen = |value: f64, alpha: f64| {
        let x = ((value - lo) / (hi - lo)).clamp(0.0, 1.0) as f32;
        Pos2::new(rect.left() + x * rect.width(), rect.bottom() - alpha.clamp(0.0, 1.0) as f32 * rect.height())
    };
    let from_screen = |p: Pos2| {
        let x = ((p.x - rect.left()) / rect.width()).clamp(0.0, 1.0) as f64;
        let a = ((rect.bottom() - p.y) / rect.height()).clamp(0.0, 1.0) as f64;
        (lo + x * (hi - lo), a)
    };
    painter.rect_filled(rect, 2.0, Color32::from_gray(24));
    // The histogram, log scale: air or a scanner's noise floor would flatten everything else.
    let peak = histogram.iter().copied().max().unwrap_or(0).max(1) as f64;
    let bar = rect.width() / histogram.len().max(1) as f32;
    for (i, &count) in histogram.iter().enumerate() {
        if count == 0 {
            continue;
        }
        let h = ((1.0 + count as f64).ln() / (1.0 + peak).ln()) as f32 * rect.height();
        let x = rect.left() + i as f32 * bar;
        painter.rect_filled(
            Rect::from_min_max(Pos2::new(x, rect.bottom() - h), Pos2::new(x + bar.max(1.0), rect.bottom())),
            0.0,
            Color32::from_gray(70),
        );
    }
    // The opacity curve, each segment in its colour.
    let n = 96;
    for k in 0..n {
        let (v0, v1) = (lo + (hi - lo) * k as f64 / n as f64, lo + (hi - lo) * (k + 1) as f64 / n as f64);
        let (c0, c1) = (tf.eval(v0), tf.eval(v1));
        painter.line_segment(
            [to_screen(v0, c0[3]), to_screen(v1, c1[3])],
            Stroke::new(2.0, display_color([c0[0], c0[1], c0[2]], 1.0)),
        );
    }
    for (i, p) in tf.points.iter().enumerate() {
        let at = to_screen(p.value, p.alpha);
        painter.circle_filled(at, 5.0, display_color(p.color, 1.0));
        let ring = if selected == Some(i) { Color32::WHITE } else { Color32::from_gray(140) };
        painter.circle_stroke(at, 5.0, Stroke::new(1.5, ring));
    }
    let nearest = |pos: Pos2| {
        tf.points
            .iter()
            .enumerate()
            .map(|(i, p)| (i, to_screen(p.value, p.alpha).distance(pos)))
            .filter(|(_, d)| *d <= GRAB)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    };
    let dragging_id = ui.make_persistent_id("tf_dragging");
    // Grab what was under the pointer when the button went down: a drag starts only once the
    // pointer has moved a few points, by when a fast hand is already off the point.
    if response.drag_started()
        && let Some(pos) = ui.input(|i| i.pointer.press_origin()).or(response.interact_pointer_pos())
    {
        let grabbed = nearest(pos);
        ui.data_mut(|d| d.insert_temp(dragging_id, grabbed));
        selected = grabbed.or(selected);
    }
    let dragging: Option<usize> = ui.data(|d| d.get_temp::<Option<usize>>(dragging_id)).flatten();
    if response.dragged()
        && let (Some(i), Some(pos)) = (dragging, response.interact_pointer_pos())
        && i < tf.points.len()
    {
        let (value, alpha) = from_screen(pos);
        let mut next = tf.clone();
        next.points[i].value = value;
        next.points[i].alpha = alpha;
        // Keep the order (and the selection on the dragged point).
        let moved = next.points[i].clone();
        next.points.sort_by(|a, b| a.value.total_cmp(&b.value));
        let new_index = next.points.iter().position(|p| *p == moved).unwrap_or(i);
        ui.data_mut(|d| d.insert_temp(dragging_id, Some(new_index)));
        selected = Some(new_index);
        action = Some(TfAction::Edit(widen(next)));
    }
    if response.drag_stopped() {
        ui.data_mut(|d| d.insert_temp::<Option<usize>>(dragging_id, None));
    }
    if response.clicked()
        && let Some(pos) = response.interact_pointer_pos()
    {
        match nearest(pos) {
            Some(i) => selected = Some(i),
            None => {
                let (value, alpha) = from_screen(pos);
                let [r, g, b, _] = tf.eval(value);
                let next = with_point(tf, ControlPoint { value, color: [r, g, b], alpha });
                selected = next.points.iter().position(|p| p.value == value);
                action = Some(TfAction::Edit(next));
            }
        }
    }
    if response.secondary_clicked()
        && let Some(pos) = response.interact_pointer_pos()
        && let Some(i) = nearest(pos)
        && tf.points.len() > 1
    {
        let mut next = tf.clone();
        next.points.remove(i);
        selected = None;
        action = Some(TfAction::Edit(next));
    }
    ui.horizontal(|ui| {
        ui.small(format!("{lo:.4}"));
        ui.small("data values (histogram: log scale)");
        ui.small(format!("{hi:.4}"));
    });
    ui.small("click: add a point · drag: move · right-click: delete");
    if let Some(i) = selected.filter(|&i| i < tf.points.len()) {
        let p = &tf.points[i];
        let (mut value, mut alpha) = (p.value, p.alpha);
        let mut color = p.color.map(|c| c as f32);
        let mut changed = false;
        ui.horizontal(|ui| {
            ui.label(format!("point {}", i + 1));
            changed |= ui.color_edit_button_rgb(&mut color).changed();
            changed |= ui.add(egui::DragValue::new(&mut value).speed((hi - lo) / 500.0).prefix("value ")).changed();
            changed |= ui.add(egui::DragValue::new(&mut alpha).speed(0.005).range(0.0..=1.0).prefix("α ")).changed();
        });
        if changed && action.is_none() {
            let mut next = tf.clone();
            next.points[i] = ControlPoint { value, color: color.map(f64::from), alpha };
            next.points.sort_by(|a, b| a.value.total_cmp(&b.value));
            action = Some(TfAction::Edit(widen(next)));
        }
    }
    // The whole function: each frame's drag (or a typed amount) applied once, from 0 and ×1.
    ui.horizontal(|ui| {
        let (mut shift, mut width) = (0.0, 1.0);
        let label = ui.label("shift");
        let moved = ui.add(egui::DragValue::new(&mut shift).speed((hi - lo) / 500.0)).labelled_by(label.id);
        let label = ui.label("width ×");
        let stretched = ui.add(egui::DragValue::new(&mut width).speed(0.005).range(0.01..=100.0)).labelled_by(label.id);
        if moved.changed() && shift != 0.0 && action.is_none() {
            action = Some(TfAction::Edit(shifted(tf, shift)));
        } else if stretched.changed() && width != 1.0 && action.is_none() {
            action = Some(TfAction::Edit(stretched_by(tf, width)));
        }
    });
    ui.horizontal(|ui| {
        egui::ComboBox::from_label("preset").selected_text("replace with…").show_ui(ui, |ui| {
            for (name, preset) in presets {
                if ui.selectable_label(false, *name).clicked() {
                    action = Some(TfAction::Edit(preset.clone()));
                }
            }
        });
        if ui.button("save TF").on_hover_text("to its file, RON or ParaView JSON as it came; a preset's or a fitted TF to NAME.tf.ron or view.tf.ron in the current folder").clicked() {
            action = Some(TfAction::Save);
        }
        let mut on = save_on_change;
        if ui.checkbox(&mut on, "save on change").changed() {
            action = Some(TfAction::SaveOnChange(on));
        }
    });
    ui.data_mut(|d| d.insert_temp(selected_id, selected));
    action
}

/// `tf` with `point` added in value order (replacing a point at the same value), the domain
/// stretched over it: the editor's click and the script's `tf-point`.
pub fn with_point(tf: &TransferFunction, point: ControlPoint) -> TransferFunction {
    let mut next = tf.clone();
    next.points.retain(|p| p.value != point.value);
    let at = next.points.partition_point(|p| p.value <= point.value);
    next.points.insert(at, point);
    widen(next)
}

/// `tf` moved by `delta` data units along the value axis, its domain with it: every point keeps
/// its colour and opacity.
pub fn shifted(tf: &TransferFunction, delta: f64) -> TransferFunction {
    let mut next = tf.clone();
    next.points.iter_mut().for_each(|p| p.value += delta);
    next.domain = (tf.domain.0 + delta, tf.domain.1 + delta);
    next
}

/// `tf` stretched by `factor` about the centre of its points' values (the domain widened over
/// them): a ramp made `factor` times as wide, where it was.
pub fn stretched_by(tf: &TransferFunction, factor: f64) -> TransferFunction {
    let (first, last) = match (tf.points.first(), tf.points.last()) {
        (Some(a), Some(b)) => (a.value, b.value),
        _ => return tf.clone(),
    };
    let centre = 0.5 * (first + last);
    let mut next = tf.clone();
    next.points.iter_mut().for_each(|p| p.value = centre + (p.value - centre) * factor);
    widen(next)
}

/// The domain stretched over every point (a point dragged past an end takes the domain along).
fn widen(mut tf: TransferFunction) -> TransferFunction {
    for p in &tf.points {
        tf.domain = (tf.domain.0.min(p.value), tf.domain.1.max(p.value));
    }
    tf
}

/// The editor driven with egui's own test harness (`egui_kittest`): synthetic pointer events on
/// the canvas, the function the editor hands back checked.
#[cfg(test)]
mod tests {
    use super::*;
    use egui_kittest::Harness;

    struct State {
        tf: TransferFunction,
        /// The canvas: top-left corner and width, read where the editor is placed.
        origin: Pos2,
        width: f32,
        edits: usize,
        last: Option<TfAction>,
    }

    fn start() -> TransferFunction {
        let point = |value, color, alpha| ControlPoint { value, color, alpha };
        TransferFunction {
            domain: (0.0, 100.0),
            points: vec![point(0.0, [0.0; 3], 0.0), point(50.0, [1.0, 0.0, 0.0], 0.5), point(100.0, [1.0; 3], 1.0)],
        }
    }

    fn harness() -> Harness<'static, State> {
        let state = State { tf: start(), origin: Pos2::ZERO, width: 0.0, edits: 0, last: None };
        let mut h = Harness::builder().with_size(Vec2::new(420.0, 320.0)).build_ui_state(
            |ui, s: &mut State| {
                s.origin = ui.cursor().min;
                s.width = ui.available_width();
                if let Some(action) = show(ui, &s.tf, &[5, 50, 500, 50, 5], (0.0, 100.0), &[], false) {
                    if let TfAction::Edit(tf) = &action {
                        s.tf = tf.clone();
                        s.edits += 1;
                    }
                    s.last = Some(action);
                }
            },
            state,
        );
        h.run();
        h
    }

    /// Where data value `v` at opacity `a` is on the canvas.
    fn at(h: &Harness<'_, State>, v: f64, a: f64) -> Pos2 {
        let s = h.state();
        Pos2::new(s.origin.x + (v / 100.0) as f32 * s.width, s.origin.y + HEIGHT - a as f32 * HEIGHT)
    }

    /// A constant volume (no value range) and a degenerate TF domain still draw and edit.
    #[test]
    fn a_constant_volume_still_draws() {
        let mut tf = start();
        tf.domain = (5.0, 5.0);
        let mut h = Harness::builder().with_size(Vec2::new(420.0, 320.0)).build_ui_state(
            |ui, tf: &mut TransferFunction| {
                if let Some(TfAction::Edit(next)) = show(ui, tf, &[7], (5.0, 5.0), &[], false) {
                    *tf = next;
                }
            },
            tf,
        );
        h.run();
        let at = Pos2::new(200.0, 60.0);
        h.hover_at(at);
        h.step();
        h.drag_at(at);
        h.step();
        h.drop_at(at);
        h.run();
        assert!(h.state().points.iter().all(|p| p.value.is_finite() && p.alpha.is_finite()), "{:?}", h.state());
    }

    #[test]
    fn dragging_a_point_moves_its_value_and_opacity() {
        let mut h = harness();
        let (from, to) = (at(&h, 50.0, 0.5), at(&h, 30.0, 0.8));
        h.hover_at(from);
        h.step();
        h.drag_at(from);
        h.step();
        for k in 1..=6 {
            h.hover_at(from + (to - from) * (k as f32 / 6.0));
            h.step();
        }
        h.drop_at(to);
        h.step();
        let p = &h.state().tf.points[1];
        // One screen point is 100/404 ≈ 0.25 data units across and 1/130 ≈ 0.008 opacity up;
        // the pointer lands on a point's position rounded by egui: within 1 unit and 0.02.
        assert!((p.value - 30.0).abs() < 1.0 && (p.alpha - 0.8).abs() < 0.02, "moved to {p:?}");
        assert_eq!(p.color, [1.0, 0.0, 0.0], "the colour stays with the point");
        assert!(h.state().edits >= 1);
    }

    /// "shift" moves every point by the amount typed (or dragged), "width ×" stretches them about
    /// their centre; colours and opacities stay.
    #[test]
    fn shift_and_width_move_and_stretch_the_whole_function() {
        use egui_kittest::kittest::Queryable as _;
        let mut h = harness();
        h.get_by_label("shift").set_value_accesskit(20.0);
        h.run();
        let values: Vec<f64> = h.state().tf.points.iter().map(|p| p.value).collect();
        assert_eq!(values, [20.0, 70.0, 120.0], "shifted by 20");
        assert_eq!(h.state().tf.domain, (20.0, 120.0));
        let alphas: Vec<f64> = h.state().tf.points.iter().map(|p| p.alpha).collect();
        assert_eq!(alphas, [0.0, 0.5, 1.0], "opacities stay");
        h.get_by_label("width ×").set_value_accesskit(0.5);
        h.run();
        let values: Vec<f64> = h.state().tf.points.iter().map(|p| p.value).collect();
        assert_eq!(values, [45.0, 70.0, 95.0], "half as wide about 70");
        assert_eq!(h.state().tf.points[1].color, [1.0, 0.0, 0.0], "colours stay");
    }

    #[test]
    fn a_click_adds_a_point_and_a_right_click_deletes_it() {
        let mut h = harness();
        let empty = at(&h, 75.0, 0.1);
        h.hover_at(empty);
        h.step();
        h.drag_at(empty);
        h.step();
        h.drop_at(empty);
        h.run();
        let points = &h.state().tf.points;
        assert_eq!(points.len(), 4, "{points:?}");
        let added = &points[2];
        assert!((added.value - 75.0).abs() < 1.0 && (added.alpha - 0.1).abs() < 0.02, "{added:?}");
        // Its colour is the function's there: between red and white.
        assert!(added.color[0] == 1.0 && added.color[1] > 0.0 && added.color[1] < 1.0, "{added:?}");
        let on_it = at(&h, added.value, added.alpha);
        h.hover_at(on_it);
        h.step();
        for pressed in [true, false] {
            h.event(egui::Event::PointerButton {
                pos: on_it,
                button: egui::PointerButton::Secondary,
                pressed,
                modifiers: egui::Modifiers::NONE,
            });
            h.step();
        }
        h.run();
        assert_eq!(h.state().tf.points, start().points, "deleted again");
    }
}
