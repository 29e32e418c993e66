//! The reload logic without a window: a live session on the headless GPU, changed the way the
//! viewer changes it (file edits, sliders, features, resizes), with its events and images checked.
//! Here: the helpers, and the panel's edits (parameters, write-back, the "set" field, the probe,
//! the live error, a resize, the level of detail's step); `tests/reload.rs`: file edits (graph,
//! shaders, transfer function); `tests/gpu_errors.rs`: frames the GPU rejects; `tests/labels.rs`:
//! the label list; `tests/named_tfs.rs`: one TF editor per scalar volume.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use volgraph_accel::camera::OrbitCamera;
use volgraph_core::runtime::Gpu;

use super::session::{Event, LiveSession, SessionArgs};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A scratch copy of a graph and of the shader folder, so tests can edit both.
struct Scratch {
    dir: PathBuf,
    graph: PathBuf,
    shaders: PathBuf,
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("scratch dir");
    for entry in std::fs::read_dir(from).expect("readable").flatten() {
        let target = to.join(entry.file_name());
        if entry.path().is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), &target).expect("copy");
        }
    }
}

fn scratch(name: &str, graph: &str) -> Scratch {
    let dir = std::env::temp_dir().join(format!("volgraph-live-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    copy_dir(&root().join("shaders"), &dir.join("shaders"));
    let graph_path = dir.join("graph.ron");
    std::fs::copy(root().join(graph), &graph_path).expect("graph copy");
    Scratch { shaders: dir.join("shaders"), graph: graph_path, dir }
}

/// The session arguments of a scratch graph: its shaders, a 48×48 viewport, `volume` (empty:
/// the generated default) and `tf`; nothing named.
fn session_args(s: &Scratch, volume: &[&str], tf: Option<PathBuf>) -> SessionArgs {
    SessionArgs {
        environment: None,
        scene: None,
        graph: s.graph.clone(),
        volume: volume.iter().map(PathBuf::from).collect(),
        raw: Default::default(),
        tf,
        tf_map: None,
        viewport: (48, 48),
        features: Vec::new(),
        shaders: Some(s.shaders.clone()),
        gpu_memory_mb: None,
        memory_mb: None,
        cuts: Default::default(),
        lights: Default::default(),
        named: Vec::new(),
        named_tfs: Vec::new(),
    }
}

/// The headless GPU.
fn gpu() -> Arc<Gpu> {
    Arc::new(Gpu::new_headless().expect("a Vulkan adapter (Mesa lavapipe on machines without a GPU)"))
}

fn open(s: &Scratch, tf: Option<PathBuf>) -> LiveSession {
    let (session, loaded) =
        LiveSession::open(gpu(), &session_args(s, &[], tf)).unwrap_or_else(|_| panic!("the scratch graph loads"));
    assert!(matches!(loaded, Event::Loaded { .. }), "{loaded}");
    session
}

fn frame(session: &mut LiveSession) -> Vec<f32> {
    session.submit(&OrbitCamera::default(), None).expect("frame");
    session.runtime.finish();
    session.runtime.read_output("image").expect("image").data
}

/// `n` frames seen by `camera` through the session's own frame path (what the window calls,
/// estimates and reverts included), waited for.
fn frames(session: &mut LiveSession, n: u32, camera: &OrbitCamera) {
    for _ in 0..n {
        session.frame(camera, None).expect("a frame");
    }
    session.runtime.finish();
}

fn edit(path: &Path, from: &str, to: &str) {
    let text = std::fs::read_to_string(path).expect("readable");
    assert!(text.contains(from), "{} has no {from:?}", path.display());
    std::fs::write(path, text.replacen(from, to, 1)).expect("writable");
}

/// A scratch fragment raycast opened with a copy of `graphs/tf/default.ron` (the copy's path).
fn open_with_tf_copy(name: &str) -> (Scratch, LiveSession, PathBuf) {
    let s = scratch(name, "graphs/basic/fragment_raycast.ron");
    let tf = s.dir.join("tf.ron");
    std::fs::copy(root().join("graphs/tf/default.ron"), &tf).expect("tf copy");
    let session = open(&s, Some(tf.clone()));
    (s, session, tf)
}

mod gpu_errors;
mod labels;
mod named_tfs;
mod reload;
mod slices;
mod streaming;

#[test]
fn a_parameter_edit_is_written_in_place_and_changes_the_image() {
    let s = scratch("param", "graphs/basic/fragment_raycast.ron");
    let mut session = open(&s, None);
    let before = frame(&mut session);
    let events = session.set_param("march", "step_voxels", ron::Value::from(1.5));
    assert_eq!(events.len(), 1, "{events:?}");
    let Event::Reloaded { what, detail, .. } = &events[0] else { panic!("{}", events[0]) };
    assert_eq!(what, "parameter march.step_voxels");
    assert!(detail.contains("1 updated in place, 0 built; 0 pipelines built"), "{detail}");
    assert_ne!(frame(&mut session), before, "the new step reached the shader");
    let _ = std::fs::remove_dir_all(&s.dir);
}

/// The panel's "write to graph file": the slider's value lands in the file at its place (a
/// one-line diff), the session runs from the file with the same image, and the watcher does not
/// reload the viewer's own write.
#[test]
fn a_parameter_moved_in_the_panel_is_written_back_into_the_graph_file() {
    let s = scratch("write_back", "graphs/basic/fragment_raycast.ron");
    let original = std::fs::read_to_string(&s.graph).expect("readable");
    let mut session = open(&s, None);
    session.set_param("march", "step_voxels", ron::Value::from(1.5));
    let moved = frame(&mut session);
    let lines = session.write_back().expect("written");
    assert_eq!(lines.len(), 1, "{lines:?}");
    assert!(lines[0].contains("march.step_voxels = 1.5 (was 0.5)"), "{lines:?}");
    let written = std::fs::read_to_string(&s.graph).expect("readable");
    let diff: Vec<(&str, &str)> = original.lines().zip(written.lines()).filter(|(a, b)| a != b).collect();
    assert_eq!(diff, vec![("                \"step_voxels\": 0.5,", "                \"step_voxels\": 1.5,")]);
    assert!(session.files_changed(std::slice::from_ref(&s.graph)).is_empty(), "its own write is not reloaded");
    assert_eq!(frame(&mut session), moved, "the file now says what the slider said");
    assert!(session.write_back().expect("nothing left").is_empty());
    let _ = std::fs::remove_dir_all(&s.dir);
}

/// Issue 24 §4: the value under the cursor, where its ray first becomes visible, in the data's
/// units; nothing off the volume; a crop moves it to the crop face.
#[test]
fn the_value_under_the_cursor_is_where_the_ray_first_becomes_visible() {
    let s = scratch("probe", "graphs/basic/fragment_raycast.ron");
    let mut session = open(&s, None);
    let camera = volgraph_accel::camera::OrbitCamera {
        azimuth_deg: 0.0,
        elevation_deg: 0.0,
        distance: 3.2,
        ..Default::default()
    };
    let centre = session.probe_line(&camera, (24.0, 24.0)).expect("the volume is under the centre");
    assert!(centre.starts_with("under the cursor: ") && centre.contains("at voxel ("), "{centre}");
    assert_eq!(session.probe_line(&camera, (0.5, 0.5)), None, "the corner's ray misses the volume");
    let cut = volgraph_accel::cuts::Cuts::new(
        Some(volgraph_accel::cuts::CropBox::new(glam::DVec3::ZERO, glam::DVec3::new(1.0, 1.0, 0.5)).expect("box")),
        &[],
    )
    .expect("cuts");
    session.set_cuts(cut);
    let cropped = session.probe_line(&camera, (24.0, 24.0));
    assert_ne!(cropped, Some(centre), "the crop moves (or removes) what is under the cursor");
    let _ = std::fs::remove_dir_all(&s.dir);
}

/// Issue 45 item 3: in the patient frame the cursor's readout says where in the patient, in mm
/// by side (R/L, A/P, I/S); a volume in index axes says no such thing.
#[test]
fn the_cursor_readout_gives_the_patient_point_in_mm() {
    use volgraph_accel::volume::{Volume, VoxelData};
    let s = scratch("patient", "graphs/basic/fragment_raycast.ron");
    // A 24³ CT in HU: a soft-tissue ball in air, written as a DICOM series (LPS, with an origin).
    let n = 24u32;
    let values: Vec<i16> = (0..n * n * n)
        .map(|i| {
            let p = glam::DVec3::new((i % n) as f64, ((i / n) % n) as f64, (i / (n * n)) as f64) + 0.5;
            if (p / n as f64 - 0.5).length() < 0.35 { 40 } else { -1000 }
        })
        .collect();
    let ct = Volume::new("ball", glam::UVec3::splat(n), glam::DVec3::new(0.8, 0.8, 2.0), VoxelData::I16(values));
    let series = s.dir.join("series");
    volgraph_accel::load::dicom::write_ct_series(&series, &ct).expect("written");
    let series = series.display().to_string();
    let (mut session, _) =
        LiveSession::open(gpu(), &session_args(&s, &[series.as_str()], None)).unwrap_or_else(|_| panic!("opens"));
    frame(&mut session);
    let camera = OrbitCamera { azimuth_deg: 0.0, elevation_deg: 0.0, distance: 3.2, ..Default::default() };
    let line = session.probe_line(&camera, (24.0, 24.0)).expect("the ball is under the centre");
    assert!(line.contains(" mm") && [" L ", " R "].iter().any(|side| line.contains(side)), "{line}");
    assert!(
        ["P ", "A "].iter().any(|side| line.contains(side)) && ["S ", "I "].iter().any(|s| line.contains(s)),
        "{line}"
    );
    // The generated default volume lies in index axes: no patient point.
    let plain = open(&s, None).probe_line(&camera, (24.0, 24.0)).expect("the volume is under the centre");
    assert!(!plain.contains(" mm"), "{plain}");
    let _ = std::fs::remove_dir_all(&s.dir);
}

/// Issue 24 §5: the view's error against the converged reference, as the panel shows it: a
/// coarser step costs accuracy, a finer one gains it back.
#[test]
fn the_live_error_follows_the_step() {
    let s = scratch("accuracy", "graphs/basic/fragment_raycast.ron");
    let mut session = open(&s, None);
    let camera = volgraph_accel::camera::OrbitCamera::default();
    let error_at = |session: &mut LiveSession, step: f64| {
        let events =
            session.set_param("march", "step_voxels", ron::Value::Number(ron::value::Number::F64(step.into())));
        assert!(matches!(events.as_slice(), [Event::Reloaded { .. }]), "{events:?}");
        session.frame(&camera, None).expect("a frame");
        session.runtime.finish();
        let job = session.accuracy_job(&camera).expect("fragment_raycast has an image and a march");
        let a = super::accuracy::measure(&job);
        assert!(a.pixels > 100 && a.line().contains("mean"), "{a:?}");
        a.mean_abs
    };
    let coarse = error_at(&mut session, 2.0);
    let fine = error_at(&mut session, 0.25);
    // The step's discretization error falls with the step (a factor 8 here, so at least 2); at
    // 0.25 voxels on this smooth volume it stays under one 8-bit level of the 0.1 reference.
    assert!(coarse > 2.0 * fine, "step 2 (mean {coarse:.2e}) vs step 0.25 (mean {fine:.2e})");
    assert!(fine < 1.0 / 255.0, "a fine step is close to the converged reference: {fine:.2e}");
    let _ = std::fs::remove_dir_all(&s.dir);
}

/// A path tracer's panel shows the view's estimated error (issue "light that scatters", item
/// 3): from the second sample on, it follows 1/√spp, and a moved camera starts it over.
#[test]
fn the_path_tracer_shows_its_estimated_error() {
    let s = scratch("noise", "graphs/cinematic/path_traced.ron");
    let mut session = open(&s, None);
    let camera = OrbitCamera::default();
    frames(&mut session, 1, &camera);
    assert_eq!(session.noise_line(), None, "one sample has no estimate");
    frames(&mut session, 15, &camera);
    let at_16 = session.noise_line().expect("an estimate at 16 spp");
    assert!(at_16.contains("at 16 spp") && at_16.contains("means at 8 and 16 spp"), "{at_16}");
    frames(&mut session, 48, &camera);
    let at_64 = session.noise_line().expect("an estimate at 64 spp");
    let value = |line: &str| -> f64 {
        let after = line.split("estimated error ").nth(1).expect("a figure");
        after.split('/').next().expect("a figure").parse().expect("a number")
    };
    // 4× the samples halve the noise (1.5–2.7×: two estimates of an RMS over 2,304 pixels).
    let ratio = value(&at_16) / value(&at_64);
    assert!((1.5..=2.7).contains(&ratio), "{at_16} → {at_64}");
    frames(&mut session, 1, &OrbitCamera { azimuth_deg: camera.azimuth_deg + 5.0, ..camera });
    assert_eq!(session.noise_line(), None, "a moved camera starts the mean, and its estimate, over");
    let _ = std::fs::remove_dir_all(&s.dir);
}

/// The reprojecting path tracer (its `samples` output: each pixel's own count) shows an
/// estimated error too, counted from when the view came to rest, each pixel weighted by its
/// counts; a move starts it over.
#[test]
fn the_reprojecting_path_tracer_estimates_its_error_once_the_view_rests() {
    let s = scratch("noise_moving", "graphs/cinematic/path_traced_moving.ron");
    let mut session = open(&s, None);
    let camera = OrbitCamera::default();
    frames(&mut session, 16, &camera);
    let rested = session.noise_line().expect("an estimate 16 frames at rest");
    assert!(rested.contains("8 and 16 frames after the view rested"), "{rested}");
    let turned = OrbitCamera { azimuth_deg: camera.azimuth_deg + 2.0, ..camera };
    frames(&mut session, 1, &turned);
    assert_eq!(session.noise_line(), None, "a move starts the estimate over");
    frames(&mut session, 31, &turned);
    let again = session.noise_line().expect("an estimate after the move");
    assert!(again.contains("16 and 32 frames after the view rested"), "{again}");
    let value: f64 = again
        .split("estimated error ")
        .nth(1)
        .and_then(|t| t.split('/').next())
        .and_then(|t| t.parse().ok())
        .expect("a figure");
    assert!(value > 0.0 && value < 255.0, "{again}");
    let _ = std::fs::remove_dir_all(&s.dir);
}

/// The panel at 800×600 (issue 45 item 3), through egui's test harness: it takes a side of the
/// window, not half of it (the image is drawn in the rest, `window::image_size`), its buttons
/// stay in the window whatever the sections above them hold, and what does not fit scrolls into
/// view.
#[test]
fn the_panel_leaves_the_image_its_side_and_keeps_its_buttons_in_reach_at_800_by_600() {
    use egui_kittest::Harness;
    use egui_kittest::kittest::Queryable as _;

    let s = scratch("layout", "graphs/basic/fragment_raycast.ron");
    let mut session = open(&s, None);
    frame(&mut session);
    let window = egui::Rect::from_min_size(egui::Pos2::ZERO, egui::Vec2::new(800.0, 600.0));
    let timings = super::panel::Timings::default();
    let lod = super::lod::Lod::default();
    let mut h = Harness::builder().with_size(window.size()).build_ui_state(
        |ui, width: &mut f32| {
            let shown = super::panel::show(ui, &session, &timings, "lavapipe", None, &lod, "");
            *width = shown.width;
        },
        0.0f32,
    );
    h.run();
    let width = *h.state();
    // At most half the window (the image keeps the other half, `window::image_size`); its
    // natural width is ~320–380 points.
    assert!(width > 100.0 && width <= 400.0, "the panel is {width} points of 800");
    // Open every section the tall way: the parameters of every pass, the plan's text.
    h.get_by_label("Parameters").click();
    h.run();
    h.get_by_label("Plan").click();
    h.run();
    // (With the buttons after the sections, as before this foot, "screenshot" lay at y 593–613:
    // outside.)
    for button in ["screenshot", "reset camera", "write to graph file", "save view"] {
        let rect = h.get_by_label(button).rect();
        assert!(window.contains_rect(rect), "\"{button}\" at {rect:?} is outside the window");
        assert!(rect.min.x >= 800.0 - width - 1.0, "\"{button}\" is in the panel");
    }
    // The sections scroll (the wheel over the panel): the plan's header moves up, toward the
    // text below it that did not fit.
    let before = h.get_by_label("Plan").rect();
    for _ in 0..3 {
        h.get_by_label("Plan").scroll_down();
        h.run();
    }
    let after = h.get_by_label("Plan").rect();
    assert!(after.min.y < before.min.y - 100.0, "the panel scrolled: {before:?} → {after:?}");
    assert!(h.get_by_label("save view").rect().max.y <= window.max.y, "the buttons stay put");
    let _ = std::fs::remove_dir_all(&s.dir);
}

#[test]
fn a_resize_rebuilds_no_pipeline() {
    let s = scratch("resize", "graphs/basic/fragment_raycast.ron");
    let mut session = open(&s, None);
    frame(&mut session);
    let events = session.resize(64, 40);
    let [Event::Reloaded { what, detail, .. }] = events.as_slice() else { panic!("{events:?}") };
    assert_eq!(what, "viewport 64x40");
    assert!(detail.contains("0 pipelines built"), "{detail}");
    assert!(detail.contains("0 built"), "no node depends on the viewport: {detail}");
    let image = {
        session.submit(&OrbitCamera::default(), None).expect("frame");
        session.runtime.read_output("image").expect("image")
    };
    assert_eq!((image.width, image.height), (64, 40));
    let _ = std::fs::remove_dir_all(&s.dir);
}

/// The level of detail's wider step reaches what is computed from a step input: the
/// Krüger–Westermann graphs wire `step_voxels` and `segment_steps` to inputs, which their repeat
/// group divides the longest ray by, so twice the step and twice the segment length are a
/// quarter of the segments (not the same count of segments each marching further). A parameter
/// moved while it is coarse is kept when the view refines.
#[test]
fn the_coarse_step_widens_the_step_inputs_and_quarters_the_segments() {
    let s = scratch("coarse_step", "graphs/kruger_westermann_2003/rc_b.ron");
    let mut session = open(&s, None);
    let segments = |session: &LiveSession| {
        let plan = session.plan().expect("a plan");
        plan.steps.iter().filter(|st| st.pass_id == "march").count()
    };
    let full = segments(&session);
    let sharp = frame(&mut session);
    assert!(session.set_step_factor(2.0), "the wider step applies");
    let coarse = segments(&session);
    assert_eq!(
        coarse,
        full.div_ceil(4),
        "{full} segments at the graph's values, {coarse} at twice the step and length"
    );
    let step = session.plan().expect("plan").steps.iter().find(|st| st.pass_id == "march").expect("march");
    assert_eq!(step.params.float("step_voxels"), 1.0, "the input's 0.5, doubled");
    assert_eq!(step.params.uint("segment_steps"), 16, "the input's 8, doubled");
    session.set_param("march", "threshold", ron::Value::from(0.9));
    assert!(session.set_step_factor(1.0), "back to the graph's step");
    assert_eq!(segments(&session), full);
    let step = session.plan().expect("plan").steps.iter().find(|st| st.pass_id == "march").expect("march");
    assert_eq!(step.params.float("step_voxels"), 0.5);
    assert_eq!(step.params.uint("segment_steps"), 8);
    assert_eq!(step.params.float("threshold"), 0.9, "the edit made while coarse is kept");
    session.set_param("march", "threshold", ron::Value::from(0.95));
    assert_eq!(frame(&mut session), sharp, "the graph's own image again");
    let _ = std::fs::remove_dir_all(&s.dir);
    // A slicer's slices get twice as far apart.
    let s = scratch("coarse_slices", "graphs/kruger_westermann_2003/sbvr.ron");
    let mut session = open(&s, None);
    let spacing = |session: &LiveSession| {
        let plan = session.plan().expect("a plan");
        plan.steps.iter().find(|st| st.pass_id == "slices").expect("slices").params.float("slice_voxels")
    };
    assert_eq!(spacing(&session), 0.5);
    assert!(session.set_step_factor(2.0));
    assert_eq!(spacing(&session), 1.0);
    // ×2 → ×4 widens the graph's spacing, not ×2's.
    assert!(session.set_step_factor(4.0));
    assert_eq!(spacing(&session), 2.0);
    assert!(session.set_step_factor(1.0));
    assert_eq!(spacing(&session), 0.5);
    let _ = std::fs::remove_dir_all(&s.dir);
}

/// The panel's "set" field driven with egui's test harness: a value outside the parameter's
/// range and a misspelt name typed into it are refused with their messages (the image and plan
/// stay), a good value applies. The sliders clamp, so this field is where bad values can be typed.
#[test]
fn a_bad_value_typed_into_the_set_field_is_refused_with_its_message() {
    use egui_kittest::Harness;
    use egui_kittest::kittest::Queryable as _;

    let s = scratch("assign", "graphs/basic/fragment_raycast.ron");
    let mut session = open(&s, None);
    let before = frame(&mut session);
    let mut h = Harness::builder().with_size(egui::Vec2::new(480.0, 240.0)).build_ui_state(
        |ui, session: &mut LiveSession| {
            if let Some(text) = super::panel::assign_field(ui) {
                session.assign(&text);
            }
            if let Some((what, message)) = session.error() {
                ui.label(format!("error in {what}: {message}"));
            }
        },
        session,
    );
    let submit = |h: &mut Harness<'_, LiveSession>, text: &str| {
        h.get_by_label("set").focus();
        h.run();
        // Select what the field holds, type over it, press Enter.
        h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::A);
        h.get_by_label("set").type_text(text);
        h.run();
        h.key_press(egui::Key::Enter);
        h.run();
    };
    submit(&mut h, "march.step_voxels=-1");
    let message = |h: &Harness<'_, LiveSession>| h.state().error().map(|(_, m)| m.to_string()).unwrap_or_default();
    let refused = message(&h);
    assert!(refused.contains("step_voxels") && refused.contains("-1"), "the message names the value: {refused}");
    assert!(h.query_by_label_contains("error in set march.step_voxels=-1").is_some(), "shown in the panel");
    submit(&mut h, "march.step_voxle=1");
    let refused = message(&h);
    assert!(refused.contains("did you mean") && refused.contains("step_voxels"), "a did-you-mean: {refused}");
    assert!(h.query_by_label_contains("did you mean").is_some(), "shown in the panel");
    let session = h.state_mut();
    assert_eq!(frame(session), before, "nothing bad reached the graph");
    drop(h);
    let mut session = open(&s, None);
    let events = session.assign("march.step_voxels=1.5");
    assert!(matches!(events.first(), Some(Event::Reloaded { .. })), "{events:?}");
    assert_ne!(frame(&mut session), before, "a good value applies");
    let _ = std::fs::remove_dir_all(&s.dir);
}

/// Issue 45 item 3: "save image…" renders the view again at the size asked for (not the
/// window's image stretched), at full quality, and gives the window its viewport back; a size
/// of 0 or a FIFO as the file is refused by name.
#[test]
fn save_image_renders_the_view_at_the_size_asked_for_and_restores_the_window() {
    let s = scratch("save-image", "graphs/basic/fragment_raycast.ron");
    let mut session = open(&s, None);
    frame(&mut session);
    let camera = OrbitCamera::default();
    let path = s.dir.join("big.png");
    session.save_image(&camera, (96, 64), &path).expect("saved");
    let saved = image::open(&path).expect("a PNG").to_rgba8();
    assert_eq!(saved.dimensions(), (96, 64));
    assert_eq!(session.options().viewport, (48, 48), "the window's viewport is back");
    // The same view rendered at 96×64 by `render`'s own path: the same pixels.
    session.resize(96, 64);
    frame(&mut session);
    let direct = session.runtime.read_output(session.shown_output()).expect("image");
    let expected = s.dir.join("direct.png");
    crate::image_out::write_png(&expected, &direct, session.shown_output() == "display").expect("written");
    assert_eq!(saved, image::open(&expected).expect("a PNG").to_rgba8(), "the saved image is a render at its size");
    session.resize(48, 48);
    let zero = session.save_image(&camera, (0, 64), &s.dir.join("zero.png")).expect_err("refused");
    assert!(format!("{zero:#}").contains("1 to 16384 pixels"), "{zero:#}");
    #[cfg(unix)]
    {
        let fifo = s.dir.join("fifo.png");
        assert!(std::process::Command::new("mkfifo").arg(&fifo).status().is_ok_and(|st| st.success()));
        let refused = session.save_image(&camera, (32, 32), &fifo).expect_err("a FIFO is no file");
        assert!(format!("{refused:#}").contains("FIFO") || format!("{refused:#}").contains("fifo"), "{refused:#}");
    }
    assert_eq!(session.options().viewport, (48, 48));
    let _ = std::fs::remove_dir_all(&s.dir);
}
