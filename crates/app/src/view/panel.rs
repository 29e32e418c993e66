//! The viewer's overlay: per-pass GPU milliseconds (numbers and bars, smoothed), the plan, every
//! declared parameter as a slider or field, the graph's Scalar inputs, scene feature toggles,
//! the last error, and the key help line. Edits come back as [`Action`]s the window applies
//! after the frame.

use std::collections::BTreeMap;

use volgraph_accel::cuts::{ClipPlane, CropBox, Cuts};
use volgraph_core::graph::ast::InputKind;
use volgraph_core::params::{ParamKind, ParamValue};

use super::session::LiveSession;

/// A change asked for in the panel.
#[derive(Debug)]
pub enum Action {
    /// Set a pass parameter.
    Param(String, String, ron::Value),
    /// Set a Scalar graph input.
    Scalar(String, f64),
    /// Turn a scene feature on or off.
    Feature(String, bool),
    /// Save a screenshot.
    Screenshot,
    /// Reset the camera.
    ResetCamera,
    /// A standard view of a volume in the patient frame (keys 1–6, the panel's A P L R S I).
    PatientView(volgraph_accel::camera::PatientView),
    /// Write the parameters and inputs changed here into the graph file.
    WriteBack,
    /// Set the crop box and clip planes.
    Cuts(Cuts),
    /// Render the view again at `size` pixels and save it to `path` (PNG).
    SaveImage {
        /// The PNG to write.
        path: std::path::PathBuf,
        /// Width and height in pixels.
        size: (u32, u32),
    },
    /// Save the view (camera, crop, clip, TF, effects) to a scene file.
    SaveScene(std::path::PathBuf),
    /// The TF editor's action.
    TransferFunction(super::tf_editor::TfAction),
    /// The TF editor edits this named TF input (`None`: the frame volume's).
    TfTarget(Option<String>),
    /// The scene's light.
    Lights(volgraph_accel::light::Lights),
    /// Set a value typed as `PASS.PARAM=VALUE` or `input.NAME=VALUE`.
    Assign(String),
    /// The label list's edit.
    Labels(super::label_list::LabelEdit),
    /// The label list's search text.
    LabelSearch(String),
    /// Time every pass on its own (`Runtime::set_step_profiling`) or not.
    TimeEachPass(bool),
    /// Open or close the slice panes.
    SlicePanes(bool),
    /// Draw the slice planes' outlines in the 3D view or not.
    SlicePlanesIn3d(bool),
    /// The slice panes' window (data units).
    SliceWindow(volgraph_accel::volume_meta::Window),
    /// Level of detail while moving: on or off, and the frame rate to hold.
    Lod {
        /// Render coarser while moving.
        enabled: bool,
        /// The frame rate to hold.
        target_fps: f64,
    },
}

/// Exponentially smoothed per-pass milliseconds.
#[derive(Default)]
pub struct Timings {
    per_pass: Vec<(String, f64)>,
    frame_ms: f64,
    wall_fallback: bool,
    /// The last frame's passes were submitted one by one.
    serialised: bool,
    /// Frames presented.
    pub frames: u64,
}

/// Weight of the newest frame in the smoothed figures.
const SMOOTHING: f64 = 0.1;

impl Timings {
    /// Folds in a finished frame's stats.
    pub fn add(&mut self, stats: &volgraph_core::runtime::FrameStats) {
        let blend = |old: f64, new: f64| if old == 0.0 { new } else { old + SMOOTHING * (new - old) };
        self.frame_ms = blend(self.frame_ms, stats.frame_ms);
        self.wall_fallback = stats.wall_time_fallback;
        self.serialised = stats.steps_serialised;
        let fresh = stats.per_pass_ms();
        let mut merged = Vec::with_capacity(fresh.len());
        for (pass, ms) in fresh {
            let old = self.per_pass.iter().find(|(p, _)| *p == pass).map_or(0.0, |(_, m)| *m);
            merged.push((pass, blend(old, ms)));
        }
        self.per_pass = merged;
    }
}

/// The help line.
pub const HELP: &str = "drag: rotate · wheel: zoom · shift/middle-drag: pan · R: reset camera · 1–6: patient views · M: slice panes \
     (click: crosshair, wheel: slice) · S: screenshot · F1: panel · Esc: quit";

fn param_widget(ui: &mut egui::Ui, name: &str, kind: &ParamKind, value: &ParamValue) -> Option<ron::Value> {
    match (kind, value) {
        (ParamKind::Float { min, max, .. }, ParamValue::Float(v)) => {
            let mut x = *v;
            let logarithmic = *min > 0.0 && max / min > 100.0;
            ui.add(egui::Slider::new(&mut x, *min..=*max).text(name).logarithmic(logarithmic))
                .changed()
                .then(|| ron::Value::from(x))
        }
        (ParamKind::UInt { min, max, .. }, ParamValue::UInt(v)) => {
            let mut x = *v;
            let logarithmic = *min > 0 && max / min.max(&1) > 100;
            ui.add(egui::Slider::new(&mut x, *min..=*max).text(name).logarithmic(logarithmic))
                .changed()
                .then(|| ron::Value::from(x))
        }
        (ParamKind::Bool { .. }, ParamValue::Bool(v)) => {
            let mut x = *v;
            ui.checkbox(&mut x, name).changed().then(|| ron::Value::from(x))
        }
        (ParamKind::Choice { options, .. }, ParamValue::Choice(v)) => {
            let mut chosen = None;
            egui::ComboBox::from_label(name).selected_text(v.as_str()).show_ui(ui, |ui| {
                for o in options.iter() {
                    if ui.selectable_label(*o == v.as_str(), *o).clicked() && *o != v.as_str() {
                        chosen = Some(ron::Value::String(o.to_string()));
                    }
                }
            });
            chosen
        }
        _ => {
            ui.label(format!("{name} = {value}"));
            None
        }
    }
}

/// How the graph's history was used, for a graph that has one (Klein et al. 2005: frames that
/// ran from reprojected starts instead of the box).
pub fn history_line(stats: &volgraph_core::runtime::HistoryStats) -> String {
    format!(
        "history: {} frames from the last frame's ({} in a row now), {} restarts",
        stats.frames_from_history, stats.run, stats.restarts
    )
}

/// A progressive graph's samples per pixel (a path tracer's running mean: its noise falls as
/// 1/√spp while the view rests).
pub fn samples_line(stats: &volgraph_core::runtime::HistoryStats) -> String {
    format!(
        "{} samples per pixel (noise falls as 1/sqrt(spp); any change of view, TF, light or cuts starts over; {} restarts)",
        stats.run + 1,
        stats.restarts
    )
}

/// Draws the panel; returns what the user changed.
pub fn show(
    root: &mut egui::Ui,
    session: &LiveSession,
    timings: &Timings,
    adapter: &str,
    under_cursor: Option<&str>,
    lod: &super::lod::Lod,
    accuracy: &str,
) -> Shown {
    let mut actions = Vec::new();
    let panel = egui::Panel::right("volgraph").default_size(320.0).show(root, |ui| {
        let Some(plan) = session.plan() else { return };
        // The buttons first, at the panel's foot: always in reach, whatever the window's height.
        egui::Panel::bottom("volgraph actions").show(ui, |ui| {
            ui.add_space(4.0);
            action_buttons(ui, &mut actions);
            ui.small(HELP);
        });
        // Everything else scrolls (the wheel over the panel), above them.
        egui::ScrollArea::vertical().id_salt("panel").auto_shrink([false, false]).show(ui, |ui| {
            ui.heading(&plan.name);
            let clock = match (timings.serialised, timings.wall_fallback) {
                (true, _) => "wall, passes one by one",
                (false, true) => "wall",
                (false, false) => "GPU",
            };
            ui.label(format!(
                "{:.2} ms/frame {clock} ({:.0} fps) · {}x{} · {adapter}",
                timings.frame_ms,
                1000.0 / timings.frame_ms.max(1e-3),
                plan.viewport.0,
                plan.viewport.1
            ));
            match session.shader_dirs() {
                [] => ui.small("shaders: built into the binary"),
                dirs => ui.small(format!(
                    "shaders: {} (watched)",
                    dirs.iter().map(|d| d.display().to_string()).collect::<Vec<_>>().join(", ")
                )),
            };
            if let Some((what, message)) = session.error() {
                ui.colored_label(
                    egui::Color32::from_rgb(255, 110, 110),
                    format!("error in {what} (keeping the last good graph):"),
                );
                egui::ScrollArea::vertical().id_salt("error").max_height(160.0).show(ui, |ui| {
                    ui.add(egui::Label::new(egui::RichText::new(message).monospace().small()).wrap());
                });
            }
            if plan.history.values().any(|h| h.while_camera_still) {
                ui.label(samples_line(&session.runtime.history_stats()));
                ui.label(
                    session.noise_line().unwrap_or_else(|| "estimated error: from the second sample on".to_string()),
                );
            } else if crate::render::accumulates(plan) {
                // A reprojecting path tracer: each pixel's count is its own after a camera move.
                let stats = session.runtime.history_stats();
                ui.label(format!(
                "{} frames since the last restart; each pixel's mean follows the view (reprojected), keeping its own \
                 count ({} restarts)",
                stats.run + 1,
                stats.restarts
            ));
                ui.label(
                    session
                        .noise_line()
                        .unwrap_or_else(|| "estimated error: from the second frame at rest on".to_string()),
                );
            } else if !plan.history.is_empty() {
                ui.label(history_line(&session.runtime.history_stats()));
            }
            // What the graph's bypasses did (Klein's reprojection left out where it cannot pay).
            for b in session.runtime.bypass_status() {
                ui.label(crate::render::bypass_line(&b));
            }
            ui.small(under_cursor.unwrap_or("under the cursor: nothing visible"));
            ui.horizontal(|ui| {
                let (mut enabled, mut fps) = (lod.enabled, 1000.0 / lod.target_ms);
                let toggled = ui.checkbox(&mut enabled, "coarser while moving, target").changed();
                let moved =
                    ui.add(egui::DragValue::new(&mut fps).range(1.0..=120.0).speed(0.5).suffix(" fps")).changed();
                if toggled || moved {
                    actions.push(Action::Lod { enabled, target_fps: fps });
                }
            });
            ui.small(lod.line());
            ui.small(accuracy);
            // What passes report about the last frame (a brick pool's uploads and occupancy).
            for line in crate::render::counter_lines(&session.runtime.pass_counters()) {
                ui.label(egui::RichText::new(line).small());
            }
            ui.separator();
            let mut each = session.runtime.step_profiling();
            let hint = "Submit and wait for every pass on its own, so each one's time is measured even where GPU \
                    timestamps miss compute work (lavapipe); frames get slower";
            if ui.checkbox(&mut each, "time each pass").on_hover_text(hint).changed() {
                actions.push(Action::TimeEachPass(each));
            }
            let max = timings.per_pass.iter().map(|(_, ms)| *ms).fold(1e-6, f64::max);
            egui::Grid::new("passes").num_columns(3).show(ui, |ui| {
                for (pass, ms) in &timings.per_pass {
                    ui.label(pass);
                    ui.add(egui::ProgressBar::new((ms / max) as f32).desired_width(120.0));
                    ui.label(format!("{ms:.2} ms"));
                    ui.end_row();
                }
            });
            ui.separator();
            {
                // Crop and clip have their own section below.
                let known: Vec<&String> =
                    plan.known_features.iter().filter(|f| !volgraph_core::cut_effects::is_cut_feature(f)).collect();
                if !known.is_empty() {
                    ui.collapsing("Features", |ui| {
                        for f in known {
                            let mut on = plan.features.contains(f);
                            if ui.checkbox(&mut on, f.as_str()).changed() {
                                actions.push(Action::Feature(f.clone(), on));
                            }
                        }
                    });
                }
                // A label map shown alone is coloured by its label list, not by the TF.
                if plan.inputs.values().any(|k| *k == InputKind::TransferFunction) && session.shows_transfer_function()
                {
                    egui::CollapsingHeader::new("Transfer function").default_open(true).show(ui, |ui| {
                        // One editor per scalar volume: which TF input it edits.
                        let targets = session.transfer_function_targets();
                        if targets.len() > 1 {
                            let current = session.workbench().tf_target.clone();
                            let label = |t: &Option<String>| {
                                targets.iter().find(|(i, _)| i == t).map_or(String::new(), |(_, l)| l.clone())
                            };
                            egui::ComboBox::from_label("edits").selected_text(label(&current)).show_ui(ui, |ui| {
                                for (input, text) in &targets {
                                    if ui.selectable_label(*input == current, text).clicked() && *input != current {
                                        actions.push(Action::TfTarget(input.clone()));
                                    }
                                }
                            });
                        }
                        let model = session.workbench().edited_tf();
                        let (histogram, range) = model.histogram();
                        let (tf, presets) = (model.transfer_function(), model.presets());
                        if let Some(a) = super::tf_editor::show(ui, tf, histogram, range, presets, model.save_on_change)
                        {
                            actions.push(Action::TransferFunction(a));
                        }
                    });
                }
                if let Some(list) = session.labels() {
                    egui::CollapsingHeader::new(format!("Labels ({})", list.rows.len())).default_open(true).show(
                        ui,
                        |ui| {
                            let mut list = list.clone();
                            let search = list.search.clone();
                            if let Some(edit) = super::label_list::show(ui, &mut list) {
                                actions.push(Action::Labels(edit));
                            }
                            if list.search != search {
                                actions.push(Action::LabelSearch(list.search));
                            }
                        },
                    );
                }
                let slice_info = super::slice_section::SliceInfo {
                    panes: session.slices(),
                    hounsfield: session.volume().meta.is_ct_hu(),
                    crosshair: session.crosshair_line(),
                };
                actions.extend(super::slice_section::section(ui, &slice_info));
                if let Some(cuts) = cuts_section(ui, session.runtime.cuts(), session.patient_box()) {
                    actions.push(Action::Cuts(cuts));
                }
                if let Some(lights) = super::light_control::lights_section(ui, session.runtime.lights()) {
                    actions.push(Action::Lights(lights));
                }
                actions.extend(super::save_section::section(ui));
                let scalars: BTreeMap<&String, f64> = plan
                    .inputs
                    .iter()
                    .filter_map(|(n, k)| match k {
                        InputKind::Scalar(default) => {
                            Some((n, session.options().scalars.get(n).copied().unwrap_or(*default)))
                        }
                        // A value in data units: the panel edits it only once the user set one.
                        InputKind::Data(_) => session.options().scalars.get(n).map(|v| (n, *v)),
                        _ => None,
                    })
                    .collect();
                if !scalars.is_empty() {
                    ui.collapsing("Scalars", |ui| {
                        for (name, value) in scalars {
                            let mut v = value;
                            let r = ui.add(
                                egui::DragValue::new(&mut v)
                                    .speed((value.abs() * 0.01).max(0.001))
                                    .prefix(format!("{name} = ")),
                            );
                            if r.drag_stopped() || (r.changed() && !r.dragged()) {
                                actions.push(Action::Scalar(name.clone(), v));
                            }
                        }
                    });
                }
                ui.collapsing("Parameters", |ui| {
                    if let Some(text) = assign_field(ui) {
                        actions.push(Action::Assign(text));
                    }
                    // The graph's own WGSL-only kinds have parameters too.
                    let registry =
                        volgraph_core::wgsl_pass::with_graph_kinds(session.workbench().graph.registry(), &plan.kinds);
                    let mut seen = Vec::new();
                    for step in &plan.steps {
                        if seen.contains(&step.pass_id) {
                            continue;
                        }
                        seen.push(step.pass_id.clone());
                        let Some(plugin) = registry.get(&step.kind) else { continue };
                        let specs = plugin.params();
                        if specs.is_empty() {
                            continue;
                        }
                        ui.collapsing(format!("{} [{}]", step.pass_id, step.kind), |ui| {
                            for spec in specs {
                                let Some((_, value)) = step.params.iter().find(|(n, _)| *n == spec.name) else {
                                    continue;
                                };
                                if let Some(v) = param_widget(ui, spec.name, &spec.kind, value) {
                                    actions.push(Action::Param(step.pass_id.clone(), spec.name.to_string(), v));
                                }
                            }
                        });
                    }
                });
                egui::CollapsingHeader::new("Graph").default_open(true).show(ui, |ui| {
                    egui::ScrollArea::both().id_salt("graph").max_height(320.0).show(ui, |ui| {
                        super::graph_picture::show(ui, plan);
                    });
                });
                ui.collapsing("Plan", |ui| {
                    ui.add(egui::Label::new(egui::RichText::new(plan.to_text()).monospace().small()).extend());
                });
            }
        });
    });
    Shown { actions, width: panel.response.rect.width() }
}

/// What [`show`] drew: what the user changed, and the panel's width in points (the image is
/// drawn beside it, never under it).
pub struct Shown {
    /// What the user changed.
    pub actions: Vec<Action>,
    /// The panel's width, points.
    pub width: f32,
}

/// The panel's buttons: screenshot, reset camera, write to graph file, save view (wrapping onto
/// more rows in a narrow panel).
fn action_buttons(ui: &mut egui::Ui, actions: &mut Vec<Action>) {
    ui.horizontal_wrapped(|ui| {
        if ui.button("screenshot").clicked() {
            actions.push(Action::Screenshot);
        }
        if ui.button("reset camera").clicked() {
            actions.push(Action::ResetCamera);
        }
        // The patient views, superior up (keys 1–6).
        for (name, view) in volgraph_accel::camera::PatientView::ALL {
            let letter = name[..1].to_uppercase();
            if ui.button(&letter).on_hover_text(format!("the {name} view, superior up")).clicked() {
                actions.push(Action::PatientView(view));
            }
        }
        if ui.button("write to graph file").on_hover_text("the values changed here, written at their place").clicked() {
            actions.push(Action::WriteBack);
        }
        if ui
            .button("save view")
            .on_hover_text(format!(
                "graph, volume, camera, crop, clip, TF and effects to {SAVED_SCENE} (an edited TF beside it): render \
                 --scene draws it again"
            ))
            .clicked()
        {
            actions.push(Action::SaveScene(SAVED_SCENE.into()));
        }
    });
}

/// Where the panel's "save view" writes (the current folder).
pub const SAVED_SCENE: &str = "view.scene.ron";

/// The crop box (a checkbox and a low/high slider per axis) and the first clip plane (normal and
/// offset); planes after the first (from `--clip`) are kept and listed. Returns new cuts when a
/// control changed them.
/// A field for a value typed as `PASS.PARAM=VALUE` or `input.NAME=VALUE` (what `volgraph set`
/// takes); Enter submits it. Sliders clamp to a parameter's declared range, so this is where a
/// value outside it or a misspelt name can be typed — and is refused with its message
/// (`LiveSession::assign`). The text stays, to be corrected.
pub fn assign_field(ui: &mut egui::Ui) -> Option<String> {
    let id = ui.make_persistent_id("assign");
    let mut text: String = ui.data_mut(|d| d.get_temp(id)).unwrap_or_default();
    let response = ui
        .horizontal(|ui| {
            let label = ui.label("set");
            ui.add(
                egui::TextEdit::singleline(&mut text)
                    .hint_text("march.step_voxels=0.7 or input.NAME=1.5")
                    .desired_width(220.0),
            )
            .labelled_by(label.id)
        })
        .inner;
    let submitted = response.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
    ui.data_mut(|d| d.insert_temp(id, text.clone()));
    (submitted && !text.trim().is_empty()).then_some(text)
}

///
/// With `patient` (the volume's LPS corner and extent in mm, `VolumeMeta::patient_box`) each crop
/// slider also says where it cuts in the patient, by side: `x from · R 30.0 mm`.
/// The patient sides a clip plane can keep: letter, LPS axis, the normal's sign along it.
const CLIP_SIDES: [(&str, usize, f64); 6] =
    [("R", 0, -1.0), ("L", 0, 1.0), ("A", 1, -1.0), ("P", 1, 1.0), ("I", 2, -1.0), ("S", 2, 1.0)];

/// Where clip plane `p` lies in the patient frame of a box at `corner` with `extent` (mm): along
/// one axis, the side it keeps and its position (`d · keeps L of L 20.0 mm`); oblique, its
/// normal by sides and its distance from the origin.
fn clip_plane_text(p: &ClipPlane, corner: glam::DVec3, extent: glam::DVec3) -> String {
    use volgraph_accel::volume_meta::{direction_label, patient_plane, side_label};
    let Some((n, d)) = patient_plane(p.normal, p.offset, corner, extent) else { return "d".to_string() };
    let keeps = direction_label(n);
    match (0..3).find(|&a| n[a].abs() > 1.0 - 1e-9) {
        // n = ±eₐ: the plane is pₐ = d · nₐ.
        Some(a) => format!("d · keeps {keeps} of {} mm", side_label(a, d * n[a])),
        None => format!("d · keeps {keeps}, {d:.1} mm from the origin"),
    }
}

fn cuts_section(ui: &mut egui::Ui, cuts: Cuts, patient: Option<(glam::DVec3, glam::DVec3)>) -> Option<Cuts> {
    let mut crop = cuts.crop();
    let mut planes: Vec<ClipPlane> = cuts.planes().copied().collect();
    let mut changed = false;
    ui.collapsing("Crop and clip", |ui| {
        let mut on = crop.is_some();
        if ui.checkbox(&mut on, "crop box (volume fractions)").changed() {
            crop = on.then_some(CropBox::WHOLE);
            changed = true;
        }
        if let Some(c) = crop.as_mut() {
            for (axis, name) in ["x", "y", "z"].into_iter().enumerate() {
                let (mut lo, mut hi) = (c.lo[axis], c.hi[axis]);
                // Where a fraction cuts in the patient: by side, in mm.
                let at = |f: f64| {
                    patient.map_or(String::new(), |(corner, extent)| {
                        format!(
                            " · {} mm",
                            volgraph_accel::volume_meta::side_label(axis, corner[axis] + f * extent[axis])
                        )
                    })
                };
                let (lo_text, hi_text) = (format!("{name} from{}", at(lo)), format!("{name} to{}", at(hi)));
                changed |= ui.add(egui::Slider::new(&mut lo, 0.0..=0.99).text(lo_text)).changed();
                changed |= ui.add(egui::Slider::new(&mut hi, 0.01..=1.0).text(hi_text)).changed();
                // The box stays a box: the high end at least a hundredth past the low one.
                c.lo[axis] = lo.min(0.99);
                c.hi[axis] = hi.max(c.lo[axis] + 0.01).min(1.0);
            }
        }
        let mut on = !planes.is_empty();
        if ui.checkbox(&mut on, "clip plane (keeps n·f >= d)").changed() {
            planes = if on { vec![ClipPlane { normal: glam::DVec3::X, offset: 0.5 }] } else { Vec::new() };
            changed = true;
        }
        if let Some(p) = planes.first_mut() {
            // In the patient frame: a plane through the box's centre keeping one side, and where
            // the plane lies in mm.
            if patient.is_some() {
                ui.horizontal(|ui| {
                    ui.label("keep toward");
                    for (letter, axis, sign) in CLIP_SIDES {
                        let hint = format!("a plane through the centre keeping the patient's {letter} half");
                        if ui.small_button(letter).on_hover_text(hint).clicked() {
                            let mut n = glam::DVec3::ZERO;
                            n[axis] = sign;
                            *p = ClipPlane { normal: n, offset: 0.5 * sign };
                            changed = true;
                        }
                    }
                });
            }
            let mut n = p.normal;
            for (axis, name) in ["n.x", "n.y", "n.z"].into_iter().enumerate() {
                changed |= ui.add(egui::Slider::new(&mut n[axis], -1.0..=1.0).text(name)).changed();
            }
            let where_text =
                patient.map_or_else(|| "d".to_string(), |(corner, extent)| clip_plane_text(p, corner, extent));
            changed |= ui.add(egui::Slider::new(&mut p.offset, -3.0..=3.0).text(where_text)).changed();
            // A zero normal keeps nothing meaningful: the slider cannot leave one.
            if n != glam::DVec3::ZERO {
                p.normal = n;
            }
        }
        for p in planes.iter().skip(1) {
            ui.small(format!("plane ({:.2}, {:.2}, {:.2}) · f >= {:.2}", p.normal.x, p.normal.y, p.normal.z, p.offset));
        }
    });
    if !changed {
        return None;
    }
    Cuts::new(crop, &planes).ok()
}

/// The "Crop and clip" section driven with egui's test harness: the crop checkbox and a slider
/// moved through AccessKit, as assistive technology (or a user) would.
#[cfg(test)]
mod tests {
    use super::*;
    use egui_kittest::Harness;
    use egui_kittest::kittest::Queryable as _;

    #[test]
    fn a_clip_plane_says_where_it_cuts_the_patient() {
        let (corner, extent) = (glam::DVec3::new(-100.0, -50.0, -20.0), glam::DVec3::new(200.0, 100.0, 40.0));
        let right_half = ClipPlane { normal: -glam::DVec3::X, offset: -0.5 };
        assert_eq!(clip_plane_text(&right_half, corner, extent), "d · keeps R of L 0.0 mm");
        let above = ClipPlane { normal: glam::DVec3::Z, offset: 0.75 };
        assert_eq!(clip_plane_text(&above, corner, extent), "d · keeps S of S 10.0 mm");
        let oblique = ClipPlane { normal: glam::DVec3::new(1.0, 0.0, 1.0), offset: 1.0 };
        assert!(clip_plane_text(&oblique, corner, extent).starts_with("d · keeps S 0.98 · L 0.20, "));
    }

    /// The panel's A P L R S I buttons ask for the patient views (as keys 1–6 do).
    #[test]
    fn the_view_buttons_ask_for_the_patient_views() {
        use volgraph_accel::camera::PatientView;
        let mut h = Harness::builder().with_size(egui::Vec2::new(480.0, 120.0)).build_ui_state(
            |ui, asked: &mut Vec<PatientView>| {
                let mut actions = Vec::new();
                action_buttons(ui, &mut actions);
                asked.extend(actions.into_iter().filter_map(|a| match a {
                    Action::PatientView(v) => Some(v),
                    _ => None,
                }));
            },
            Vec::new(),
        );
        h.run();
        for letter in ["L", "S"] {
            h.get_by_label(letter).click();
            h.run();
        }
        assert_eq!(h.state().as_slice(), [PatientView::Left, PatientView::Superior]);
    }

    /// In the patient frame each crop slider says where it cuts, by side, in mm.
    #[test]
    fn crop_sliders_say_where_they_cut_in_the_patient() {
        let patient = Some((glam::DVec3::new(-100.0, -50.0, 10.0), glam::DVec3::new(200.0, 100.0, 50.0)));
        let crop = CropBox::new(glam::DVec3::ZERO, glam::DVec3::new(0.5, 1.0, 1.0)).expect("box");
        let mut h = Harness::builder().with_size(egui::Vec2::new(360.0, 420.0)).build_ui_state(
            |ui, cuts: &mut Cuts| {
                if let Some(next) = cuts_section(ui, *cuts, patient) {
                    *cuts = next;
                }
            },
            Cuts::new(Some(crop), &[]).expect("cuts"),
        );
        h.run();
        h.get_by_label("Crop and clip").click();
        h.run();
        for label in ["x from · R 100.0 mm", "x to · L 0.0 mm", "y from · A 50.0 mm", "z to · S 60.0 mm"] {
            assert!(h.query_all_by_label(label).next().is_some(), "no slider \"{label}\"");
        }
    }

    #[test]
    fn the_crop_checkbox_and_sliders_set_the_cuts() {
        let mut h = Harness::builder().with_size(egui::Vec2::new(360.0, 420.0)).build_ui_state(
            |ui, cuts: &mut Cuts| {
                if let Some(next) = cuts_section(ui, *cuts, None) {
                    *cuts = next;
                }
            },
            Cuts::NONE,
        );
        h.run();
        h.get_by_label("Crop and clip").click();
        h.run();
        h.get_by_label("crop box (volume fractions)").click();
        h.run();
        assert_eq!(h.state().crop(), Some(CropBox::WHOLE), "the box starts as the whole volume");
        h.get_by_role_and_label(egui::accesskit::Role::Slider, "x to").set_value_accesskit(0.4);
        h.run();
        let crop = h.state().crop().expect("a crop");
        assert!((crop.hi.x - 0.4).abs() < 1e-9 && crop.lo.x == 0.0, "{crop:?}");
        // The high end cannot pass below the low one: the box stays a box.
        h.get_by_role_and_label(egui::accesskit::Role::Slider, "x from").set_value_accesskit(0.6);
        h.run();
        let crop = h.state().crop().expect("a crop");
        assert!(crop.hi.x > crop.lo.x, "{crop:?}");
        h.get_by_label("clip plane (keeps n·f >= d)").click();
        h.run();
        assert_eq!(h.state().planes().count(), 1);
    }
}
