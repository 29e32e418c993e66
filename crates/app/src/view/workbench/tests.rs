//! The workbench without a device: graph edits compiled and written back, the step widened and
//! restored, the transfer function edited and saved, and the frame policy driven with a stand-in
//! for the session.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use volgraph_accel::transfer_function::{ControlPoint, Preset, TransferFunction};
use volgraph_accel::volume::Volume;
use volgraph_core::{CompileOptions, Plan};

use super::*;
use crate::view::session::Event;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A scratch folder removed when dropped.
struct Scratch(PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn scratch(name: &str) -> Scratch {
    let dir = std::env::temp_dir().join(format!("volgraph-workbench-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    Scratch(dir)
}

fn volume() -> Volume {
    volgraph_accel::generate::marschner_lobb(16)
}

/// `graph` (from the source tree) copied into `dir`, as the workbench of a 32×32 view.
fn graph_in(dir: &Path, graph: &str) -> GraphEdits {
    let path = dir.join("graph.ron");
    std::fs::copy(root().join(graph), &path).expect("graph copy");
    let source = std::fs::read_to_string(&path).expect("readable");
    GraphEdits::new(&path, source, CompileOptions::new(32, 32), crate::program::registry(), &volume())
}

fn plan(graph: &GraphEdits) -> Plan {
    graph.plan_for(graph.source(), graph.options()).expect("compiles")
}

/// What a session does with a change: compile the options, and take them once they do.
fn set_param(graph: &mut GraphEdits, pass: &str, param: &str, value: ron::Value) {
    let options = graph.with_param(pass, param, &value);
    graph.plan_for(graph.source(), &options).expect("the edit compiles");
    graph.param_set(pass, param, &value, options);
}

fn widen(graph: &mut GraphEdits, factor: f64) {
    let plan = plan(graph);
    match graph.step_request(factor, Some(&plan)) {
        StepRequest::Apply(change) => {
            graph.plan_for(graph.source(), &change.options).expect("the wider step compiles");
            graph.step_applied(change);
        }
        other => panic!("×{factor}: {other:?}"),
    }
}

fn number(options: &CompileOptions, key: &str) -> Option<f64> {
    match options.param_overrides.get(key) {
        Some(ron::Value::Number(n)) => Some(n.into_f64()),
        _ => None,
    }
}

#[test]
fn a_parameter_edit_written_back_is_the_graph_text_with_that_value() {
    let dir = scratch("write_back");
    let mut graph = graph_in(&dir.0, "graphs/basic/fragment_raycast.ron");
    let original = graph.source().to_string();
    set_param(&mut graph, "march", "step_voxels", ron::Value::from(1.5));
    assert_eq!(graph.source(), original, "an edit is an override until it is written");
    let inputs = plan(&graph).inputs;
    assert_eq!(graph.write_back_assignments(&inputs).expect("assignments"), vec!["march.step_voxels=1.5"]);
    let lines = graph.write_back(&inputs).expect("written");
    assert!(lines.len() == 1 && lines[0].contains("march.step_voxels = 1.5 (was 0.5)"), "{lines:?}");
    let expected = original.replacen("\"step_voxels\": 0.5,", "\"step_voxels\": 1.5,", 1);
    assert_ne!(expected, original);
    assert_eq!(std::fs::read_to_string(graph.path()).expect("readable"), expected);
    assert_eq!(graph.source(), expected, "it runs from the file now");
    assert!(graph.options().param_overrides.is_empty(), "the file says what the override said");
    assert!(!graph.needs_reload(&[graph.path().to_path_buf()], false), "its own write is no reload");
    assert!(graph.needs_reload(&[graph.path().to_path_buf()], true), "after a failure the same text recovers");
    assert!(graph.write_back(&inputs).expect("nothing left").is_empty());
}

#[test]
fn only_the_graphs_own_inputs_are_written_back() {
    let dir = scratch("write_back_inputs");
    let mut graph = graph_in(&dir.0, "graphs/kruger_westermann_2003/rc_b.ron");
    let options = graph.with_scalar("threshold", 0.9);
    graph.scalar_set("threshold", 0.9, options);
    let inputs = plan(&graph).inputs;
    // A scalar the graph has no input for (the plan would refuse it; here only the model).
    let options = graph.with_scalar("not_an_input", 2.0);
    graph.set_options(options);
    assert_eq!(graph.write_back_assignments(&inputs).expect("assignments"), vec!["input.threshold=0.9"]);
    graph.write_back(&inputs).expect("written");
    assert!(graph.source().contains("\"threshold\": Scalar(0.9)"), "{}", graph.source());
    assert_eq!(graph.options().scalars.keys().collect::<Vec<_>>(), ["not_an_input"], "what is no input stays");
}

#[test]
fn a_typed_assignment_must_compile_in_the_graph_text() {
    let dir = scratch("assign");
    let graph = graph_in(&dir.0, "graphs/basic/fragment_raycast.ron");
    let (target, value) = graph.check_assignment("march.step_voxels = 0.75").expect("a good value");
    assert_eq!(target.to_string(), "march.step_voxels");
    assert!(matches!(value, ron::Value::Number(n) if n.into_f64() == 0.75), "{value:?}");
    let refused = graph.check_assignment("march.step_voxels=-1").expect_err("out of range");
    assert!(refused.contains("step_voxels") && refused.contains("-1"), "{refused}");
    let refused = graph.check_assignment("march.step_voxle=1").expect_err("misspelt");
    assert!(refused.contains("did you mean") && refused.contains("step_voxels"), "{refused}");
    assert!(graph.check_assignment("march.step_voxels").is_err(), "no '='");
}

#[test]
fn features_cuts_and_the_viewport_are_options_the_model_takes_once_they_run() {
    let dir = scratch("options");
    let mut graph = graph_in(&dir.0, "graphs/basic/fragment_raycast.ron");
    let shading = graph.with_feature("shading", true);
    assert!(shading.features.contains("shading") && !graph.options().features.contains("shading"));
    graph.set_options(shading);
    assert!(graph.with_feature("shading", false).features.is_empty());
    let crop = volgraph_accel::cuts::CropBox::parse("0,0,0,0.5,1,1").expect("a crop box");
    let cut = volgraph_accel::cuts::Cuts::new(Some(crop), &[]).expect("cuts");
    let cropped = graph.with_cuts(&cut);
    assert!(cropped.features.len() > 1 && cropped.features.contains("shading"), "{:?}", cropped.features);
    assert_eq!(graph.with_cuts(&Default::default()).features, graph.options().features);
    assert_eq!(graph.with_viewport((64, 40)).viewport, (64, 40));
}

#[test]
fn the_step_widens_the_graphs_own_spacing_and_comes_back_with_the_edits_made_meanwhile() {
    let dir = scratch("step");
    let mut graph = graph_in(&dir.0, "graphs/kruger_westermann_2003/sbvr.ron");
    assert!(matches!(graph.step_request(1.0, None), StepRequest::Unchanged));
    assert!(matches!(graph.step_request(2.0, None), StepRequest::NoPlan), "no plan, no spacings to widen");
    widen(&mut graph, 2.0);
    assert_eq!(graph.step_factor(), 2.0);
    assert_eq!(number(graph.options(), "slices.slice_voxels"), Some(1.0));
    // ×2 → ×4 widens the graph's spacing, not ×2's.
    widen(&mut graph, 4.0);
    assert_eq!(number(graph.options(), "slices.slice_voxels"), Some(2.0));
    // A spacing the user sets while coarse is the new own one.
    set_param(&mut graph, "slices", "slice_voxels", ron::Value::from(0.25));
    widen(&mut graph, 2.0);
    assert_eq!(number(graph.options(), "slices.slice_voxels"), Some(0.5));
    widen(&mut graph, 1.0);
    assert_eq!(graph.step_factor(), 1.0);
    assert_eq!(number(graph.options(), "slices.slice_voxels"), Some(0.25), "the user's value");
}

#[test]
fn a_step_fed_by_graph_inputs_widens_the_inputs_and_keeps_scalars_set_meanwhile() {
    let dir = scratch("step_inputs");
    let mut graph = graph_in(&dir.0, "graphs/kruger_westermann_2003/rc_b.ron");
    let (inputs, passes) = step_inputs(graph.source());
    assert!(inputs.contains("step_voxels") && inputs.contains("segment_steps"), "{inputs:?}");
    assert!(passes.contains("march"), "{passes:?}");
    widen(&mut graph, 2.0);
    let scalars = &graph.options().scalars;
    assert_eq!((scalars["step_voxels"], scalars["segment_steps"]), (1.0, 16.0));
    assert_eq!(number(graph.options(), "march.step_voxels"), None, "widened through its input, not the pass");
    let options = graph.with_scalar("threshold", 0.9);
    graph.scalar_set("threshold", 0.9, options);
    widen(&mut graph, 1.0);
    let scalars = &graph.options().scalars;
    assert!(!scalars.contains_key("step_voxels") && !scalars.contains_key("segment_steps"), "{scalars:?}");
    assert_eq!(scalars["threshold"], 0.9, "the edit made while coarse is kept");
}

fn tf_edits(path: Option<PathBuf>) -> (TfEdits, Volume) {
    let volume = volume();
    let tf = TransferFunction::preset(Preset::ALL[0], volume.value_range);
    (TfEdits::new(tf, path, None, None, &volume, false), volume)
}

#[test]
fn a_tf_point_edit_changes_the_model_and_its_save_reads_back() {
    let (mut tf, volume) = tf_edits(None);
    assert!(!tf.edited());
    let point = ControlPoint { value: 100.0, color: [1.0, 0.0, 0.0], alpha: 0.5 };
    let edit = crate::view::tf_editor::with_point(tf.transfer_function(), point.clone());
    tf.validate(&edit).expect("a valid edit");
    tf.set(edit.clone());
    assert_eq!(tf.transfer_function(), &edit);
    assert!(tf.transfer_function().points.contains(&point));
    assert!(tf.edited(), "differs from what its source gives");
    assert!(tf.save_path().ends_with(SAVED_TF), "a fitted TF is saved as {SAVED_TF}");
    let text = tf.save_text(Path::new("x.tf.ron"));
    assert_eq!(TransferFunction::from_ron_str(&text, Path::new("x.tf.ron")).expect("reads"), edit);
    let (lo, hi) = volume.value_range;
    let width = hi - lo;
    assert!(tf.check_value(lo - width).is_ok() && tf.check_value(hi + width).is_ok());
    let refused = tf.check_value(hi + 2.0 * width).expect_err("two ranges beyond");
    assert!(refused.contains("a TF point must lie within"), "{refused}");
    assert!(tf.check_value(f64::NAN).is_err());
    assert_eq!(tf.histogram().0.len(), HISTOGRAM_BINS);
    assert!(!tf.presets().is_empty());
}

#[test]
fn saving_the_tf_to_its_file_is_no_edit_to_reload_but_a_later_change_is() {
    let dir = scratch("tf_save");
    let file = dir.0.join("tf.ron");
    let (start, _) = tf_edits(None);
    std::fs::write(&file, start.transfer_function().to_ron_string()).expect("writable");
    let (mut tf, volume) = tf_edits(Some(file.clone()));
    assert_eq!(tf.save_path(), file);
    let edit = crate::view::tf_editor::with_point(
        tf.transfer_function(),
        ControlPoint { value: 50.0, color: [0.0, 1.0, 0.0], alpha: 0.25 },
    );
    tf.set(edit.clone());
    assert_eq!(tf.save(&volume).expect("saved"), file);
    assert!(!tf.edited(), "the file gives what is on screen");
    assert!(!tf.needs_reload(std::slice::from_ref(&file)), "its own save");
    assert!(!tf.needs_reload(&[dir.0.join("other.ron")]));
    std::fs::write(&file, start.transfer_function().to_ron_string()).expect("writable");
    assert!(tf.needs_reload(std::slice::from_ref(&file)), "an edit made elsewhere");
    let read = tf.read(&volume).expect("reads");
    tf.reloaded(read);
    assert_eq!(tf.transfer_function(), start.transfer_function());
    assert!(!tf.edited());
}

/// A stand-in for the session: a viewport, a step factor, and a graph that takes steps up to
/// `widest`.
struct Target {
    viewport: (u32, u32),
    step: f64,
    widest: f64,
    resizes: usize,
}

impl LodTarget for Target {
    fn viewport(&self) -> (u32, u32) {
        self.viewport
    }
    fn resize(&mut self, width: u32, height: u32) -> Vec<Event> {
        self.viewport = (width, height);
        self.resizes += 1;
        Vec::new()
    }
    fn step_factor(&self) -> f64 {
        self.step
    }
    fn set_step_factor(&mut self, factor: f64) -> bool {
        if factor > self.widest {
            return false;
        }
        self.step = factor;
        true
    }
    fn next_frame_index(&self) -> u64 {
        0
    }
}

#[test]
fn the_frame_policy_lowers_the_detail_while_moving_and_restores_it_at_rest() {
    let mut target = Target { viewport: (800, 600), step: 1.0, widest: 8.0, resizes: 0 };
    let mut policy = FramePolicy::default();
    policy.observe(0, 400.0);
    policy.apply_lod((800, 600), &mut target);
    assert_eq!((target.viewport, target.step, target.resizes), ((800, 600), 1.0, 0), "at rest: the full image");
    policy.moved();
    policy.apply_lod((800, 600), &mut target);
    // sqrt(66.7 / 400) = 0.41 → the 0.35 scale, samples twice as far apart.
    assert_eq!((target.viewport, target.step), ((280, 210), 2.0));
    policy.apply_lod((800, 600), &mut target);
    assert_eq!(target.resizes, 1, "no resize while the scale holds");
    policy.moved_at(Instant::now() - Duration::from_secs(1));
    policy.apply_lod((800, 600), &mut target);
    assert_eq!((target.viewport, target.step), ((800, 600), 1.0), "rested: full again");
    // Off: never coarse.
    policy.set_lod(false, 15.0);
    policy.moved();
    policy.apply_lod((800, 600), &mut target);
    assert_eq!((target.viewport, target.step), ((800, 600), 1.0));
}

#[test]
fn the_step_widens_to_at_most_eight_and_a_refused_step_is_not_asked_again() {
    let mut target = Target { viewport: (800, 600), step: 1.0, widest: 4.0, resizes: 0 };
    let mut policy = FramePolicy::default();
    policy.observe(0, 3000.0);
    policy.moved();
    policy.apply_lod((800, 600), &mut target);
    assert_eq!((target.viewport, target.step), ((200, 150), 2.0), "the coarsest scale");
    for (frame, ms, step) in [(1, 130.0, 4.0), (2, 130.0, 4.0), (3, 130.0, 4.0)] {
        policy.observe(frame, ms);
        policy.apply_lod((800, 600), &mut target);
        assert_eq!(target.step, step, "frame {frame}: the graph takes ×4 at most");
    }
    assert_eq!(policy.lod().step_factor(), 4.0, "×8 was refused: back to ×4");
    let mut wide = Target { widest: 100.0, step: 1.0, ..target };
    let mut policy = FramePolicy::default();
    policy.observe(0, 3000.0);
    policy.moved();
    for frame in 1..6 {
        policy.apply_lod((800, 600), &mut wide);
        policy.observe(frame, 500.0);
    }
    policy.apply_lod((800, 600), &mut wide);
    assert_eq!(wide.step, 8.0, "never more than eight");
}

#[test]
fn accuracy_is_measured_once_per_view_after_it_rests() {
    let mut policy = FramePolicy::default();
    let t0 = Instant::now();
    policy.changed_at(t0);
    assert!(!policy.measure_at(t0 + Duration::from_millis(100), false, false), "not yet at rest");
    let later = t0 + MEASURE_AFTER + Duration::from_millis(1);
    assert!(!policy.measure_at(later, true, false), "not while dragging");
    assert!(!policy.measure_at(later, false, true), "not while one runs");
    assert!(policy.measure_at(later, false, false));
    assert!(!policy.measure_at(later + Duration::from_secs(5), false, false), "once per view");
    let done = crate::view::accuracy::Accuracy { mean_abs: 0.0, max_abs: 0.0, pixels: 1, stride: 1, ms: 1.0 };
    assert_eq!(policy.accuracy_line(Some(&done), false), done.line());
    assert!(policy.accuracy_line(Some(&done), true).contains("measuring"));
    assert!(policy.accuracy_line(None, false).contains("not measured for this graph"));
    policy.changed();
    assert!(policy.accuracy_line(Some(&done), false).contains("measured once the view rests"));
    // A coarse image is never measured.
    let mut target = Target { viewport: (800, 600), step: 1.0, widest: 8.0, resizes: 0 };
    policy.observe(0, 400.0);
    policy.moved();
    policy.apply_lod((800, 600), &mut target);
    assert!(!policy.measure_at(Instant::now() + MEASURE_AFTER * 2, false, false), "while the step is wide");
}
