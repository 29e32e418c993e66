//! Hot reload: a graph, shader or transfer-function file edited on disk, a broken edit kept out
//! with its located message and a fix recovering; WGSL-only passes; history across an edit.

use super::*;

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
        crate::view::panel::history_line(&stats),
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
