//! The reload logic without a window: a live session on the headless GPU, changed the way the
//! viewer changes it (file edits, sliders, features, resizes), with its events and images checked.

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

fn open(s: &Scratch, tf: Option<PathBuf>) -> LiveSession {
    let gpu = Arc::new(Gpu::new_headless().expect("a Vulkan adapter (Mesa lavapipe on machines without a GPU)"));
    let args = SessionArgs {
        scene: None,
        graph: s.graph.clone(),
        volume: Vec::new(),
        raw: Default::default(),
        tf,
        tf_map: None,
        viewport: (48, 48),
        features: Vec::new(),
        shaders: Some(s.shaders.clone()),
        gpu_memory_mb: None,
        cuts: Default::default(),
    };
    let (session, loaded) = LiveSession::open(gpu, &args).unwrap_or_else(|_| panic!("the scratch graph loads"));
    assert!(matches!(loaded, Event::Loaded { .. }), "{loaded}");
    session
}

fn frame(session: &mut LiveSession) -> Vec<f32> {
    session.submit(&OrbitCamera::default(), None).expect("frame");
    session.runtime.finish();
    session.runtime.read_output("image").expect("image").data
}

fn edit(path: &Path, from: &str, to: &str) {
    let text = std::fs::read_to_string(path).expect("readable");
    assert!(text.contains(from), "{} has no {from:?}", path.display());
    std::fs::write(path, text.replacen(from, to, 1)).expect("writable");
}

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

#[test]
fn a_broken_graph_keeps_the_last_good_one_and_a_fix_recovers() {
    let s = scratch("graph", "graphs/basic/fragment_raycast.ron");
    let mut session = open(&s, None);
    let good = frame(&mut session);
    edit(&s.graph, "kind: \"raycast\"", "kind: \"raycats\"");
    let events = session.files_changed(std::slice::from_ref(&s.graph));
    let [Event::Error { what, message }] = events.as_slice() else { panic!("{events:?}") };
    assert_eq!(what, "graph");
    assert!(message.contains("graph.ron:") && message.contains("did you mean \"raycast\"?"), "{message}");
    assert!(events[0].to_string().ends_with("keeping the last good graph"), "{}", events[0]);
    assert_eq!(frame(&mut session), good, "the last good graph keeps rendering");
    edit(&s.graph, "kind: \"raycats\"", "kind: \"raycast\"");
    let events = session.files_changed(std::slice::from_ref(&s.graph));
    assert!(matches!(events.as_slice(), [Event::Reloaded { .. }, Event::Recovered { .. }]), "{events:?}");
    assert!(session.error().is_none());
    let _ = std::fs::remove_dir_all(&s.dir);
}

#[test]
fn a_shader_edit_rebuilds_only_its_pipelines_and_a_broken_shader_is_located() {
    let s = scratch("shader", "graphs/basic/fragment_raycast.ron");
    let mut session = open(&s, None);
    let good = frame(&mut session);
    let present = s.shaders.join("present.wgsl");
    assert!(session.watched_files().iter().any(|f| f.ends_with("shaders/present.wgsl")), "shaders are watched");
    // A change that compiles: only the present pass is rebuilt.
    edit(&present, "fn cs_present", "// edited\nfn cs_present");
    let events = session.files_changed(std::slice::from_ref(&present));
    let [Event::Reloaded { what, detail, .. }] = events.as_slice() else { panic!("{events:?}") };
    assert_eq!(what, "shader present.wgsl");
    assert!(detail.contains("3 nodes kept, 0 updated in place, 1 built; 1 pipelines built"), "{detail}");
    // A broken import: located in the imported file, and the image stays.
    let common = s.shaders.join("common/fullscreen.wgsl");
    edit(&common, "fn vs_fullscreen", "fn vs_fullscreen oops");
    let events = session.files_changed(std::slice::from_ref(&common));
    let [Event::Error { message, .. }] = events.as_slice() else { panic!("{events:?}") };
    assert!(message.contains("common/fullscreen.wgsl:"), "the error names the imported file: {message}");
    assert_eq!(frame(&mut session), good);
    edit(&common, "fn vs_fullscreen oops", "fn vs_fullscreen");
    let events = session.files_changed(std::slice::from_ref(&common));
    assert!(matches!(events.as_slice(), [Event::Reloaded { .. }, Event::Recovered { .. }]), "{events:?}");
    assert_eq!(frame(&mut session), good, "a comment changes no pixel");
    let _ = std::fs::remove_dir_all(&s.dir);
}

/// A scratch fragment raycast opened with a copy of `graphs/tf/default.ron` (the copy's path).
fn open_with_tf_copy(name: &str) -> (Scratch, LiveSession, PathBuf) {
    let s = scratch(name, "graphs/basic/fragment_raycast.ron");
    let tf = s.dir.join("tf.ron");
    std::fs::copy(root().join("graphs/tf/default.ron"), &tf).expect("tf copy");
    let session = open(&s, Some(tf.clone()));
    (s, session, tf)
}

#[test]
fn a_transfer_function_edit_uploads_the_lut_and_a_bad_one_is_kept_out() {
    let (s, mut session, tf) = open_with_tf_copy("tf");
    let before = frame(&mut session);
    let uploads = session.runtime.uploads();
    std::fs::copy(root().join("graphs/tf/opaque.ron"), &tf).expect("another tf");
    let events = session.files_changed(std::slice::from_ref(&tf));
    assert!(matches!(events.as_slice(), [Event::Reloaded { .. }]), "{events:?}");
    assert_eq!(session.runtime.uploads(), uploads + 1, "one LUT upload, no volume upload");
    assert_ne!(frame(&mut session), before);
    std::fs::write(&tf, "(domain: (1, 0), points: [])").expect("tf");
    let events = session.files_changed(std::slice::from_ref(&tf));
    let [Event::Error { what, message }] = events.as_slice() else { panic!("{events:?}") };
    assert_eq!(what, "transfer function");
    assert!(message.contains("tf.ron: domain (1, 0) is not a range"), "{message}");
    let _ = std::fs::remove_dir_all(&s.dir);
}

/// Issue 24 §1: the TF editor's edit is applied at once (one LUT upload, the image changes),
/// "save on change" writes the file as it came (RON here) and the watcher does not reload the
/// viewer's own write; a later edit by someone else still reloads.
#[test]
fn a_tf_editor_edit_applies_at_once_and_saves_without_reloading_itself() {
    let (s, mut session, tf_path) = open_with_tf_copy("tf-editor");
    let before = frame(&mut session);
    let uploads = session.runtime.uploads();
    let mut tf = session.transfer_function().clone();
    let (lo, hi) = tf.domain;
    tf.points.push(volgraph_accel::transfer_function::ControlPoint {
        value: lo + 0.55 * (hi - lo),
        color: [1.0, 0.1, 0.1],
        alpha: 0.9,
    });
    tf.points.sort_by(|a, b| a.value.total_cmp(&b.value));
    session.workbench_mut().tf.save_on_change = true;
    let events = session.edit_transfer_function(tf.clone());
    assert!(matches!(events.as_slice(), [Event::Reloaded { .. }, Event::Saved { .. }]), "{events:?}");
    assert_eq!(session.runtime.uploads(), uploads + 1, "one LUT upload, no volume upload");
    assert_ne!(frame(&mut session), before, "the edit shows at once");
    let saved = volgraph_accel::transfer_function::TransferFunction::load(&tf_path).expect("the saved TF reads");
    assert_eq!(saved, tf, "saved as edited");
    assert!(session.files_changed(std::slice::from_ref(&tf_path)).is_empty(), "its own write is no reload");
    std::fs::copy(root().join("graphs/tf/opaque.ron"), &tf_path).expect("someone else's edit");
    let events = session.files_changed(std::slice::from_ref(&tf_path));
    assert!(matches!(events.as_slice(), [Event::Reloaded { .. }]), "{events:?}");
    // A bad edit (a colour out of range) is refused with its message; the last TF stays.
    let mut bad = session.transfer_function().clone();
    bad.points[0].color = [2.0, 0.0, 0.0];
    let events = session.edit_transfer_function(bad);
    assert!(matches!(events.as_slice(), [Event::Error { .. }]), "{events:?}");
    // Saving over something that is not a file is refused, naming it; nothing is left behind.
    std::fs::remove_file(&tf_path).expect("remove the TF");
    std::fs::create_dir(&tf_path).expect("a directory in its place");
    let events = session.save_transfer_function_events();
    let [Event::NotSaved { message, .. }] = events.as_slice() else { panic!("{events:?}") };
    assert!(message.contains("tf.ron: is a directory, not a file to write"), "{message}");
    let leftovers: Vec<_> = std::fs::read_dir(&s.dir)
        .expect("dir")
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
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

/// A pass that builds fine but records a dispatch with no pipeline set: wgpu only rejects it
/// when the frame's commands are finished, after the plan was applied.
struct BadDraw;

struct BadDrawNode {
    pipeline: volgraph_core::runtime::ComputePassPipeline,
}

impl volgraph_core::PassNode for BadDrawNode {
    fn record(
        &mut self,
        ctx: &mut volgraph_core::runtime::RecordContext<'_>,
    ) -> Result<(), volgraph_core::runtime::PassError> {
        let _ = &self.pipeline;
        let mut pass = ctx.begin_compute_pass();
        pass.dispatch_workgroups(1, 1, 1);
        Ok(())
    }
}

fn bad_draw() -> volgraph_core::plugin::ShaderUse {
    volgraph_core::plugin::ShaderUse::new("present.wgsl", "cs_present").binds(&["params"])
}

impl volgraph_core::PassDecl for BadDraw {
    fn kind(&self) -> &'static str {
        "bad_draw"
    }
    fn summary(&self) -> &'static str {
        "test: records an invalid dispatch"
    }
    fn ports(&self, _p: &volgraph_core::Params) -> Vec<volgraph_core::PortSpec> {
        vec![
            volgraph_core::PortSpec::read(
                "color",
                volgraph_core::PortKind::target(&[
                    volgraph_core::TargetFormat::Rgba32Float,
                    volgraph_core::TargetFormat::Rgba16Float,
                ]),
            ),
            volgraph_core::PortSpec::write(
                "display",
                volgraph_core::PortKind::target(&[volgraph_core::TargetFormat::Rgba8Unorm]),
            ),
        ]
    }
    fn shaders(&self, _p: &volgraph_core::Params) -> Vec<volgraph_core::plugin::ShaderUse> {
        vec![bad_draw()]
    }
}

impl volgraph_core::PassPlugin for BadDraw {
    fn create(
        &self,
        ctx: &volgraph_core::runtime::CreateContext<'_>,
    ) -> Result<Box<dyn volgraph_core::PassNode>, volgraph_core::runtime::PassError> {
        let pipeline = ctx.compute_pipeline(&volgraph_core::runtime::ComputePipelineSpec::of(&bad_draw()))?;
        Ok(Box::new(BadDrawNode { pipeline }))
    }
}

#[test]
fn a_frame_the_gpu_rejects_puts_the_last_good_graph_back() {
    let s = scratch("frame-error", "graphs/basic/fragment_raycast.ron");
    let gpu = Arc::new(Gpu::new_headless().expect("a Vulkan adapter (Mesa lavapipe on machines without a GPU)"));
    let mut registry = volgraph_passes::builtin_registry();
    registry.register(BadDraw);
    let args = SessionArgs {
        scene: None,
        graph: s.graph.clone(),
        volume: Vec::new(),
        raw: Default::default(),
        tf: None,
        tf_map: None,
        viewport: (48, 48),
        features: Vec::new(),
        shaders: Some(s.shaders.clone()),
        gpu_memory_mb: None,
        cuts: Default::default(),
    };
    let (mut session, _) = LiveSession::open_with(gpu, &args, registry).unwrap_or_else(|_| panic!("loads"));
    let camera = OrbitCamera::default();
    assert!(session.frame(&camera, None).expect("a good frame").is_empty());
    session.runtime.finish();
    let good = session.runtime.read_output("image").expect("image").data;
    // The edit applies (the pass builds), but its frame fails on the GPU.
    edit(&s.graph, "kind: \"present\"", "kind: \"bad_draw\"");
    let events = session.reload_graph();
    assert!(matches!(events.as_slice(), [Event::Reloaded { .. }]), "{events:?}");
    let events = session.frame(&camera, None).expect("recovers by itself");
    let [Event::Error { what, message }] = events.as_slice() else { panic!("{events:?}") };
    assert_eq!(what, "frame");
    assert!(message.contains("the last graph that rendered is back"), "{message}");
    assert!(session.frame(&camera, None).expect("the last good graph renders").is_empty());
    session.runtime.finish();
    assert_eq!(session.runtime.read_output("image").expect("image").data, good);
    assert_eq!(session.plan().expect("plan").steps.iter().filter(|s| s.kind == "present").count(), 1);
    let _ = std::fs::remove_dir_all(&s.dir);
}

#[test]
fn the_viewer_counts_frames_from_reprojected_starts_and_an_isovalue_edit_restarts_them() {
    let s = scratch("klein", "graphs/klein_2005/leap_iso.ron");
    let mut session = open(&s, None);
    for f in 0..3 {
        let camera = OrbitCamera { azimuth_deg: 30.0 + f as f64, ..OrbitCamera::default() };
        session.submit(&camera, None).expect("frame");
    }
    let stats = session.runtime.history_stats();
    assert_eq!((stats.frames_from_history, stats.run, stats.restarts), (2, 2, 0), "{stats:?}");
    assert_eq!(
        super::panel::history_line(&stats),
        "history: 2 frames from the last frame's (2 in a row now), 0 restarts"
    );
    // An isovalue edit changes the raycaster, which the graph's history resets on.
    edit(&s.graph, "\"iso_value\": Scalar(0.3)", "\"iso_value\": Scalar(0.4)");
    let events = session.files_changed(std::slice::from_ref(&s.graph));
    assert!(matches!(events.as_slice(), [Event::Reloaded { .. }]), "{events:?}");
    session.submit(&OrbitCamera { azimuth_deg: 33.0, ..OrbitCamera::default() }, None).expect("frame");
    let stats = session.runtime.history_stats();
    assert_eq!((stats.frames_from_history, stats.run, stats.restarts), (2, 0, 1), "{stats:?}");
    session.submit(&OrbitCamera { azimuth_deg: 34.0, ..OrbitCamera::default() }, None).expect("frame");
    assert_eq!(session.runtime.history_stats().run, 1);
    // The panel says what the graph's bypass did: one line per bypass, with its measure.
    session.runtime.finish();
    let status = session.runtime.bypass_status();
    assert_eq!(status.len(), 1, "{status:?}");
    let line = crate::render::bypass_line(&status[0]);
    assert!(line.starts_with("bypass reprojection: left out in "), "{line}");
    assert!(line.contains("threshold 16"), "{line}");
    let _ = std::fs::remove_dir_all(&s.dir);
}

/// WGSL-only passes of both forms, declared in the graph, run like built-ins and hot-reload: a
/// fragment-form `tint` and a compute-form `invert` after the raycast equal their CPU arithmetic
/// on the raycast's own image; an edit of the fragment shader file rebuilds its node and the new
/// image follows; a parameter edit in the graph updates it in place.
#[test]
fn wgsl_only_passes_of_both_forms_render_and_hot_reload() {
    let s = scratch("wgsl-only", "graphs/basic/compute_raycast.ron");
    std::fs::write(
        s.shaders.join("tint.wgsl"),
        "#import \"common/fullscreen.wgsl\"\n\
         struct Params { gain: f32 }\n\
         @group(0) @binding(auto) var<uniform> params: Params;\n\
         @group(0) @binding(auto) var color: texture_2d<f32>;\n\
         struct Out { @location(0) tinted: vec4<f32> }\n\
         @fragment fn fs_main(v: FullscreenVertex) -> Out {\n\
             let c = textureLoad(color, vec2<i32>(v.clip.xy), 0);\n\
             return Out(vec4<f32>(c.rgb * params.gain, c.a));\n\
         }\n",
    )
    .expect("write");
    std::fs::write(
        s.shaders.join("invert.wgsl"),
        "@group(0) @binding(auto) var color: texture_2d<f32>;\n\
         @group(0) @binding(auto) var inverted: texture_storage_2d<rgba16float, write>;\n\
         @compute @workgroup_size(8, 8) fn cs_main(@builtin(global_invocation_id) id: vec3<u32>) {\n\
             let size = textureDimensions(color);\n\
             if (id.x >= size.x || id.y >= size.y) { return; }\n\
             let c = textureLoad(color, vec2<i32>(id.xy), 0);\n\
             textureStore(inverted, vec2<i32>(id.xy), vec4<f32>(vec3<f32>(1.0) - c.rgb, c.a));\n\
         }\n",
    )
    .expect("write");
    edit(
        &s.graph,
        "    passes: [",
        "    kinds: {\n\
         \"tint\": WgslKind(shader: \"tint.wgsl\", form: Fragment, inputs: {\"color\": Target},\n\
             outputs: {\"tinted\": Rgba16Float}, params: [(name: \"gain\", default: 1.0, min: 0.0, max: 4.0)]),\n\
         \"invert\": WgslKind(shader: \"invert.wgsl\", inputs: {\"color\": Target}, outputs: {\"inverted\": Rgba16Float}),\n\
         },\n    passes: [\n\
         Pass(id: \"tint\", kind: \"tint\", params: {\"gain\": 0.5}, inputs: {\"color\": \"march.color\"}),\n\
         Pass(id: \"inv\", kind: \"invert\", inputs: {\"color\": \"tint.tinted\"}),",
    );
    edit(&s.graph, "\"image\": \"march.color\",", "\"image\": \"inv.inverted\",\n        \"raw\": \"march.color\",");
    let mut session = open(&s, None);
    // The expected image from the raycast's own output: 1 - gain·rgb, alpha kept.
    let check = |session: &mut LiveSession, gain: f32| {
        let image = frame(session);
        let raw = session.runtime.read_output("raw").expect("raw").data;
        assert!(raw.chunks(4).any(|p| p[3] > 0.0), "the volume is in view");
        let worst = image
            .chunks(4)
            .zip(raw.chunks(4))
            .flat_map(|(i, r)| {
                (0..4).map(move |c| {
                    let want = if c == 3 { r[3] } else { 1.0 - gain * r[c] };
                    (i[c] - want).abs()
                })
            })
            .fold(0.0f32, f32::max);
        // Two f16 roundings of values ≤ 1 (tint's target, then invert's).
        assert!(worst <= 2e-3, "gain {gain}: largest difference {worst}");
    };
    check(&mut session, 0.5);
    // A shader edit: the file is watched, the node rebuilt, the image follows.
    let tint = s.shaders.join("tint.wgsl");
    assert!(session.watched_files().iter().any(|f| f.ends_with("shaders/tint.wgsl")), "WGSL-only shaders are watched");
    edit(&tint, "c.rgb * params.gain", "c.rgb * params.gain * 0.5");
    let events = session.files_changed(std::slice::from_ref(&tint));
    assert!(matches!(events.as_slice(), [Event::Reloaded { .. }]), "{events:?}");
    check(&mut session, 0.25);
    // A parameter edit in the graph: updated in place.
    edit(&s.graph, "params: {\"gain\": 0.5}", "params: {\"gain\": 1.0}");
    let events = session.files_changed(std::slice::from_ref(&s.graph));
    let [Event::Reloaded { detail, .. }] = events.as_slice() else { panic!("{events:?}") };
    assert!(detail.contains("1 updated in place"), "{detail}");
    check(&mut session, 0.5);
    let _ = std::fs::remove_dir_all(&s.dir);
}

/// Issue 19: a hot-reloaded shader that naga accepts but the GPU rejects (a params struct
/// larger than the uniform the pass binds) made the viewer quit: the rollback re-applied the
/// last good graph, which read the bad shader from disk again. The last good *compiled*
/// modules come back instead, and the window keeps rendering the last good image until the
/// file is fixed.
#[test]
fn a_shader_edit_the_gpu_rejects_keeps_the_last_good_pipelines() {
    let s = scratch("gpu-rejects-shader", "graphs/basic/fragment_raycast.ron");
    let mut session = open(&s, None);
    let camera = OrbitCamera::default();
    assert!(session.frame(&camera, None).expect("a good frame").is_empty());
    session.runtime.finish();
    let good = session.runtime.read_output("image").expect("image").data;
    let present = s.shaders.join("present.wgsl");
    // The struct written out in full with trailing padding: the members the pass declares are
    // all there (the layout check accepts it), but the block outgrows the buffer.
    edit(
        &present,
        "#import \"params/PresentParams.wgsl\"",
        "struct PresentParams {\n    background: f32,\n    _pad0: f32,\n    _pad1: f32,\n    _pad2: f32,\n    _pad_larger_than_declared: vec4<f32>,\n}",
    );
    let events = session.files_changed(std::slice::from_ref(&present));
    assert!(matches!(events.as_slice(), [Event::Reloaded { .. }]), "naga accepts the edit: {events:?}");
    let events = session.frame(&camera, None).expect("recovers by itself");
    let [Event::Error { what, message }] = events.as_slice() else { panic!("{events:?}") };
    assert_eq!(what, "frame");
    assert!(message.contains("the last graph that rendered is back"), "{message}");
    // The failure names the pass and the binding, not wgpu's "binding index 1".
    assert!(
        message.contains("pass \"present\": present/cs_present: uniform \"params\" (@binding(1)) is 32 bytes in the shader but the buffer the pass binds holds 16"),
        "{message}"
    );
    for _ in 0..2 {
        assert!(session.frame(&camera, None).expect("the last good pipelines render").is_empty());
    }
    session.runtime.finish();
    assert_eq!(session.runtime.read_output("image").expect("image").data, good);
    // Fixing the file reloads it like any edit.
    edit(&present, "    _pad_larger_than_declared: vec4<f32>,\n", "");
    let events = session.files_changed(std::slice::from_ref(&present));
    assert!(events.iter().any(|e| matches!(e, Event::Reloaded { .. })), "{events:?}");
    assert!(session.frame(&camera, None).expect("the fixed shader renders").is_empty());
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
