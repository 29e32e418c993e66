//! Issue 47 (bad input, round three), the viewer's part. A view saved as a scene ("save view",
//! `LiveSession::save_view`, what the window's button and `save-scene` call) must render back
//! pixel for pixel: each test here opens a live session on the headless GPU the way `volgraph
//! view` opens it, writes its image as `render` writes one, saves the view, and runs `volgraph
//! render --scene` from another folder on the saved scene. The window's own failures (a
//! screenshot onto a FIFO, two screenshots in a row, "save TF" of a preset) run the real
//! viewer under Xvfb (skipped with a note where Xvfb is missing, a failure under CI).

mod support;
#[path = "support/xvfb.rs"]
mod xvfb;

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Arc;
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::load::LoadOptions;
use volgraph_accel::transfer_function::ControlPoint;
use volgraph_accel::volume::{Volume, VoxelData};
use volgraph_app::view::session::{LiveSession, SessionArgs};
use xvfb::Xvfb;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("round_three_views").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch");
    dir
}

/// A live session as `volgraph view GRAPH --volume VOLUME --tf TF` (with `raw`'s flags) opens
/// it, at 48×48.
fn open(graph: &Path, volume: &[PathBuf], raw: LoadOptions<'static>, tf: Option<&Path>) -> LiveSession {
    let gpu = Arc::new(
        volgraph_core::runtime::Gpu::new_headless()
            .expect("a Vulkan adapter (Mesa lavapipe on machines without a GPU)"),
    );
    let args = SessionArgs {
        environment: None,
        scene: None,
        graph: graph.to_path_buf(),
        volume: volume.to_vec(),
        raw,
        tf: tf.map(Path::to_path_buf),
        tf_map: None,
        viewport: (48, 48),
        features: Vec::new(),
        shaders: None,
        gpu_memory_mb: None,
        memory_mb: None,
        cuts: Default::default(),
        lights: Default::default(),
        named: Vec::new(),
        named_tfs: Vec::new(),
    };
    match LiveSession::open(gpu, &args) {
        Ok((session, _)) => session,
        Err(e) => panic!("the session opens: {}", volgraph_app::cli::error_text(&e)),
    }
}

fn camera() -> OrbitCamera {
    OrbitCamera { azimuth_deg: 35.0, elevation_deg: 20.0, distance: 2.4, ..OrbitCamera::default() }
}

/// The view on screen as `render` writes it: the PNG of `display` (sRGB bytes), else `image`.
fn view_image(session: &mut LiveSession, path: &Path) -> image::RgbaImage {
    session.submit(&camera(), None).expect("a frame");
    session.runtime.finish();
    let output = session.shown_output();
    let image = session.runtime.read_output(output).expect("the output");
    let plan = session.plan().expect("a plan");
    let srgb = image.channels == 4
        && plan.outputs.get(output).is_some_and(|&r| {
            matches!(
                plan.resources[r].desc,
                volgraph_core::plan::ResourceDesc::Target { format: volgraph_core::TargetFormat::Rgba8Unorm, .. }
            )
        });
    volgraph_app::image_out::write_png(path, &image, srgb).expect("written");
    read_rgba(path)
}

fn read_rgba(path: &Path) -> image::RgbaImage {
    image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgba8()
}

/// Runs `volgraph ARGS` in `cwd`.
fn volgraph_in(cwd: &Path, args: &[&str]) -> std::process::Output {
    let out = Command::new(env!("CARGO_BIN_EXE_volgraph"))
        .args(args)
        .current_dir(cwd)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .expect("the volgraph binary runs");
    assert_ne!(out.status.code(), Some(101), "{args:?} panicked:\n{}", String::from_utf8_lossy(&out.stderr));
    out
}

/// Saves the session's view to `dir/saved/view.scene.ron`, renders that scene from
/// `dir/elsewhere` (neither the scene's folder nor the test's), and checks that the image equals
/// the view on screen pixel for pixel and shows something. Returns the scene's text.
fn assert_renders_back(session: &mut LiveSession, dir: &Path) -> String {
    let on_screen = view_image(session, &dir.join("on_screen.png"));
    let lit = on_screen.pixels().filter(|p| p[0] > 20 || p[1] > 20 || p[2] > 20).count();
    assert!(lit > 20, "the view shows the volume ({lit} lit pixels)");
    let scene = dir.join("saved").join("view.scene.ron");
    std::fs::create_dir_all(scene.parent().expect("a folder")).expect("folder");
    session.save_view(&camera(), (48, 48), &scene).expect("the view is saved");
    let text = std::fs::read_to_string(&scene).expect("the scene");
    let elsewhere = dir.join("elsewhere");
    std::fs::create_dir_all(&elsewhere).expect("folder");
    let out_png = dir.join("from_scene.png");
    let out = volgraph_in(
        &elsewhere,
        &["render", "--scene", &scene.display().to_string(), "-o", &out_png.display().to_string()],
    );
    assert!(out.status.success(), "render --scene of\n{text}\nfailed: {}", String::from_utf8_lossy(&out.stderr));
    let from_scene = read_rgba(&out_png);
    assert_eq!(from_scene.dimensions(), on_screen.dimensions(), "{text}");
    let differing = on_screen.pixels().zip(from_scene.pixels()).filter(|(a, b)| a != b).count();
    assert_eq!(differing, 0, "{differing} pixels differ between the view and render --scene of\n{text}");
    text
}

/// A CT in HU (int16) written as a headerless raw file named without its layout.
fn write_raw_ct(path: &Path) -> Volume {
    let ct = support::ct(24, "ct");
    let VoxelData::I16(values) = &ct.data else { panic!("int16") };
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(path, bytes).expect("raw written");
    ct
}

/// Issue 47 §5: a view of a built-in graph (`basic/fragment_raycast`) with a TF preset
/// (`--tf ct-bone`) was saved by those names, which the scene resolved only in its own folder.
#[test]
fn a_saved_view_of_a_built_in_graph_and_a_tf_preset_renders_back_from_any_folder() {
    let dir = scratch("builtin_names");
    let raw = dir.join("ct_24x20x16_int16.raw");
    write_raw_ct(&raw);
    let mut session =
        open(Path::new("basic/fragment_raycast"), &[raw], LoadOptions::default(), Some(Path::new("ct-bone")));
    let text = assert_renders_back(&mut session, &dir);
    assert!(text.contains("graph: \"basic/fragment_raycast\""), "{text}");
    assert!(text.contains("transfer_function: Preset(\"ct-bone\")"), "{text}");
    // A built-in TF by its path in the repository (no such file in the test's folder).
    let dir = scratch("builtin_tf");
    let tf = Path::new("graphs/tf/marschner_lobb.ron");
    assert!(!tf.exists(), "the test runs where graphs/tf is not");
    let mut session =
        open(Path::new("basic/fragment_raycast"), &[PathBuf::from("ml32")], LoadOptions::default(), Some(tf));
    let text = assert_renders_back(&mut session, &dir);
    assert!(text.contains("transfer_function: File(\"graphs/tf/marschner_lobb.ron\")"), "{text}");
}

/// Issue 47 §5: `--dims` (with `--dtype`), `--series` and `--frame` were dropped from the saved
/// view, and the saved scene was then refused (a raw file without its layout, a folder of two
/// series, a 4D file).
#[test]
fn a_saved_view_keeps_dims_series_and_frame() {
    // A raw file whose name does not say its layout.
    let dir = scratch("dims");
    let raw = dir.join("scan.raw");
    write_raw_ct(&raw);
    let options = LoadOptions {
        raw: volgraph_accel::load::RawOptions {
            dims: Some(glam::UVec3::new(24, 20, 16)),
            dtype: Some(volgraph_accel::volume::VoxelType::I16),
            ..Default::default()
        },
        ..Default::default()
    };
    let mut session =
        open(&root().join("graphs/basic/fragment_raycast.ron"), &[raw], options, Some(Path::new("ct-bone")));
    let text = assert_renders_back(&mut session, &dir);
    assert!(text.contains("dims: (24, 20, 16), dtype: \"int16\""), "{text}");

    // A folder of two DICOM series.
    let dir = scratch("series");
    let folder = dir.join("scans");
    volgraph_accel::load::dicom::write_ct_series(&folder.join("a"), &support::ct(20, "first")).expect("written");
    volgraph_accel::load::dicom::write_ct_series(&folder.join("b"), &support::ct(24, "second")).expect("written");
    for f in std::fs::read_dir(folder.join("b")).expect("dir").flatten() {
        let mut o = dicom_object::open_file(f.path()).expect("slice");
        o.put(dicom_core::DataElement::new(
            dicom_dictionary_std::tags::SERIES_INSTANCE_UID,
            dicom_core::VR::UI,
            dicom_core::value::PrimitiveValue::from("2.25.99"),
        ));
        o.write_to_file(f.path()).expect("rewritten");
    }
    let options = LoadOptions { series: Some("2".into()), ..Default::default() };
    let mut session =
        open(&root().join("graphs/basic/fragment_raycast.ron"), &[folder], options, Some(Path::new("ct-bone")));
    let text = assert_renders_back(&mut session, &dir);
    assert!(text.contains("series: \"2\""), "{text}");

    // A 4D NIfTI file: frame 1 of 2.
    let dir = scratch("frame");
    let nifti = dir.join("scan.nii");
    support::write_nifti_4d(&nifti, &support::ct(20, "ct"));
    let options = LoadOptions { frame: Some(1), ..Default::default() };
    let mut session =
        open(&root().join("graphs/basic/fragment_raycast.ron"), &[nifti], options, Some(Path::new("ct-bone")));
    let text = assert_renders_back(&mut session, &dir);
    assert!(text.contains("frame: 1"), "{text}");
}

/// Issue 47 §5: `--spacing` was dropped from the saved view without a word, and the scene drew
/// another box (32 % of the pixels differed).
#[test]
fn a_saved_view_keeps_the_voxel_spacing() {
    let dir = scratch("spacing");
    let options = LoadOptions {
        raw: volgraph_accel::load::RawOptions { spacing: Some(glam::DVec3::new(1.0, 1.0, 2.5)), ..Default::default() },
        ..Default::default()
    };
    let graph = root().join("graphs/basic/fragment_raycast.ron");
    let mut session = open(&graph, &[PathBuf::from("ml32")], options.clone(), None);
    let text = assert_renders_back(&mut session, &dir);
    assert!(text.contains("spacing: (1.0, 1.0, 2.5)"), "{text}");
    // The default volume (no --volume) takes --spacing as well: it is saved as Generated("ml64").
    let dir = scratch("spacing_default");
    let mut session = open(&graph, &[], options, None);
    let text = assert_renders_back(&mut session, &dir);
    assert!(text.contains("Generated(\"ml64\")") && text.contains("spacing: (1.0, 1.0, 2.5)"), "{text}");
}

/// Issue 47 §5: `view --volume ml32` drew a TF fitted to the data, and its saved
/// `Generated("ml32")` rendered with Marschner–Lobb's: two rules for one volume.
#[test]
fn a_viewed_generated_volume_and_its_saved_scene_get_the_same_default_tf() {
    let dir = scratch("generated_tf");
    let mut session =
        open(&root().join("graphs/basic/fragment_raycast.ron"), &[PathBuf::from("ml32")], LoadOptions::default(), None);
    let text = assert_renders_back(&mut session, &dir);
    assert!(text.contains("volume: Generated(\"ml32\")") && !text.contains("transfer_function"), "{text}");
}

/// Issue 47 §5: a TF edited after "save TF" was saved with the view as the file, which held
/// the stale TF (a user got a pink box for a skull). The edited TF is written beside the scene
/// and the scene reads it; the TF's own file keeps what "save TF" wrote.
#[test]
fn a_tf_edited_after_save_tf_is_saved_with_the_view() {
    let dir = scratch("stale_tf");
    let tf = dir.join("tf.ron");
    std::fs::copy(root().join("graphs/tf/marschner_lobb.ron"), &tf).expect("tf copy");
    let mut session = open(
        &root().join("graphs/basic/fragment_raycast.ron"),
        &[PathBuf::from("ml32")],
        LoadOptions::default(),
        Some(&tf),
    );
    let point = |value: f64, color: [f64; 3], alpha: f64| ControlPoint { value, color, alpha };
    let edit = |session: &mut LiveSession, p: ControlPoint| {
        let next = volgraph_app::view::tf_editor::with_point(session.transfer_function(), p);
        let events = session.edit_transfer_function(next);
        assert!(session.error().is_none(), "{events:?}");
    };
    edit(&mut session, point(100.0, [0.2, 0.9, 0.2], 0.6));
    session.save_transfer_function().expect("save TF");
    let saved_tf = std::fs::read_to_string(&tf).expect("tf");
    edit(&mut session, point(160.0, [1.0, 0.0, 0.6], 1.0));
    let text = assert_renders_back(&mut session, &dir);
    assert_eq!(std::fs::read_to_string(&tf).expect("tf"), saved_tf, "the TF's file is not changed by save view");
    let beside = dir.join("saved").join("view.scene.tf.ron");
    assert!(
        text.contains(&format!("File({:?})", beside.canonicalize().expect("written").display().to_string())),
        "{text}"
    );
    // Without a further edit the view refers to the TF's file again.
    session.save_transfer_function().expect("save TF");
    let scene = dir.join("saved").join("again.scene.ron");
    session.save_view(&camera(), (48, 48), &scene).expect("saved");
    let text = std::fs::read_to_string(&scene).expect("scene");
    assert!(text.contains(&format!("File({:?})", tf.canonicalize().expect("tf").display().to_string())), "{text}");
}

// --- The window, under Xvfb ---

/// Displays apart from viewer_window.rs's (60..120), so the two test binaries can run at once.
fn start_xvfb() -> Option<Xvfb> {
    xvfb::start_xvfb(130..190, "320x240x24")
}

/// What a viewer run printed, and how it ended (`None`: killed after the time limit).
struct ViewerRun {
    status: Option<std::process::ExitStatus>,
    stdout: String,
    stderr: String,
}

/// Runs `volgraph view ARGS --script` in `cwd` on `x`'s display; once it has loaded, writes the
/// script `lines` and waits up to 60 s for it to end (killed after that).
fn run_viewer(x: &Xvfb, cwd: &Path, args: &[&str], lines: &[&str]) -> ViewerRun {
    run_viewer_with(x, cwd, args, |_, _| {}, lines, false)
}

/// [`run_viewer`], each `screenshot PATH` line waited for (the viewer printing that it wrote
/// it) before the next line is written: the lines after it act on a later frame.
fn run_viewer_paced(x: &Xvfb, cwd: &Path, args: &[&str], lines: &[&str]) -> ViewerRun {
    run_viewer_with(x, cwd, args, |_, _| {}, lines, true)
}

/// [`run_viewer`], calling `during` with the event lines (and the list of those seen) once the
/// viewer has loaded, before the script lines are written.
fn run_viewer_with(
    x: &Xvfb,
    cwd: &Path,
    args: &[&str],
    during: impl FnOnce(&Receiver<String>, &mut Vec<String>),
    lines: &[&str],
    pace_screenshots: bool,
) -> ViewerRun {
    let mut viewer = Command::new(env!("CARGO_BIN_EXE_volgraph"))
        .arg("view")
        .args(args)
        .args(["--size", "32x32", "--no-panel", "--script"])
        .current_dir(cwd)
        .env("DISPLAY", &x.display)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the volgraph binary runs");
    let (tx, rx): (_, Receiver<String>) = channel();
    let stdout = viewer.stdout.take().expect("stdout");
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let stderr = viewer.stderr.take().expect("stderr");
    let errors = std::thread::spawn(move || std::io::read_to_string(stderr).unwrap_or_default());
    let mut seen = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(60);
    while let Some(left) = deadline.checked_duration_since(Instant::now()) {
        match rx.recv_timeout(left) {
            Ok(line) => {
                let loaded = line.starts_with("loaded ");
                seen.push(line);
                if loaded {
                    break;
                }
            }
            Err(_) => break,
        }
    }
    during(&rx, &mut seen);
    let mut stdin = viewer.stdin.take().expect("stdin");
    for line in lines {
        let _ = writeln!(stdin, "{line}");
        // Paced: wait until the viewer says it wrote PATH, so the lines after it reach a later
        // frame.
        if let Some(path) = line.strip_prefix("screenshot ").filter(|_| pace_screenshots) {
            let until = Instant::now() + Duration::from_secs(20);
            while !seen.iter().any(|l| l == &format!("screenshot {path}")) {
                match until.checked_duration_since(Instant::now()).map(|left| rx.recv_timeout(left)) {
                    Some(Ok(l)) => seen.push(l),
                    _ => break,
                }
            }
        }
    }
    drop(stdin);
    let status = loop {
        match viewer.try_wait() {
            Ok(Some(status)) => break Some(status),
            Ok(None) if Instant::now() < deadline => std::thread::sleep(Duration::from_millis(50)),
            _ => {
                let _ = viewer.kill();
                let _ = viewer.wait();
                break None;
            }
        }
    };
    seen.extend(rx.try_iter());
    ViewerRun { status, stdout: seen.join("\n"), stderr: errors.join().unwrap_or_default() }
}

fn mkfifo(path: &Path) {
    let made = Command::new("mkfifo").arg(path).status().expect("mkfifo runs");
    assert!(made.success(), "mkfifo {}", path.display());
}

/// Issue 47 §2: a screenshot onto a FIFO (a script's `screenshot PATH`, or `--screenshot PATH`)
/// froze the viewer: writing blocked until a reader came, and `quit` was never read. It is
/// refused with the path named, and the viewer goes on.
#[cfg(unix)]
#[test]
fn a_screenshot_onto_a_fifo_is_refused_and_quit_is_still_read() {
    let dir = scratch("fifo");
    let fifo = dir.join("shot.png");
    mkfifo(&fifo);
    let fifo_arg = fifo.display().to_string();
    // `--screenshot FIFO`: refused before a window opens.
    let out = volgraph_in(&dir, &["view", "basic/fragment_raycast", "--screenshot", &fifo_arg, "--frames", "1"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains(&format!("--screenshot {fifo_arg}: is a FIFO (named pipe)")), "{stderr}");
    let Some(x) = start_xvfb() else { return };
    let ok = dir.join("ok.png");
    let run = run_viewer(
        &x,
        &dir,
        &["basic/fragment_raycast"],
        &[&format!("screenshot {fifo_arg}"), &format!("screenshot {}", ok.display()), "quit"],
    );
    assert!(run.status.is_some(), "the viewer froze (killed after 60 s):\n{}\n{}", run.stdout, run.stderr);
    assert!(run.status.is_some_and(|s| s.success()), "{}\n{}", run.stdout, run.stderr);
    assert!(run.stderr.contains(&format!("{fifo_arg}: is a FIFO (named pipe), not a file")), "{}", run.stderr);
    assert!(ok.is_file(), "the next screenshot is written:\n{}", run.stdout);
}

/// Issue 47 §5: two script screenshots in a row wrote only the last.
#[test]
fn two_script_screenshots_in_a_row_write_two_files() {
    let dir = scratch("two_shots");
    let Some(x) = start_xvfb() else { return };
    let (a, b) = (dir.join("a.png"), dir.join("b.png"));
    let run = run_viewer(
        &x,
        &dir,
        &["basic/fragment_raycast"],
        &[&format!("screenshot {}", a.display()), &format!("screenshot {}", b.display()), "quit"],
    );
    assert!(run.status.is_some_and(|s| s.success()), "{}\n{}", run.stdout, run.stderr);
    for shot in [&a, &b] {
        assert!(shot.is_file(), "{} is written:\n{}", shot.display(), run.stdout);
        assert!(run.stdout.contains(&format!("screenshot {}", shot.display())), "{}", run.stdout);
    }
}

/// Issue 47 §4 (the viewer's side): "save TF" after `--tf ct-bone` wrote a file named `ct-bone`
/// (no extension, in the current folder), which then shadowed the preset there. The edit goes
/// to `ct-bone.tf.ron`, the line says where, and `--tf ct-bone` is the preset still.
#[test]
fn save_tf_of_a_preset_writes_a_tf_file_that_does_not_shadow_the_preset() {
    let dir = scratch("preset_save");
    let Some(x) = start_xvfb() else { return };
    let raw = dir.join("ct_24x20x16_int16.raw");
    write_raw_ct(&raw);
    let run = run_viewer(
        &x,
        &dir,
        &["basic/fragment_raycast", "--volume", &raw.display().to_string(), "--tf", "ct-bone"],
        &["tf-point 500 1,0,0,1", "tf-save", "quit"],
    );
    assert!(run.status.is_some_and(|s| s.success()), "{}\n{}", run.stdout, run.stderr);
    let saved = dir.join("ct-bone.tf.ron");
    assert!(
        run.stdout.contains(&format!("saved transfer function {}", saved.canonicalize().expect("saved").display())),
        "{}",
        run.stdout
    );
    assert!(!dir.join("ct-bone").exists(), "no file shadows the preset");
    let text = std::fs::read_to_string(&saved).expect("the saved TF");
    assert!(text.contains("500.0"), "{text}");
}

/// Waits up to 30 s for an event line starting with `prefix`; `false` if none came.
fn wait_for(lines: &Receiver<String>, seen: &mut Vec<String>, prefix: &str) -> bool {
    let deadline = Instant::now() + Duration::from_secs(30);
    while let Some(left) = deadline.checked_duration_since(Instant::now()) {
        match lines.recv_timeout(left) {
            Ok(line) => {
                let found = line.starts_with(prefix);
                seen.push(line);
                if found {
                    return true;
                }
            }
            Err(_) => return false,
        }
    }
    false
}

/// Issue 47 §6: the viewer stopped watching a graph whose folder was deleted and made again
/// (the folder's watch died with it): edits after that never reloaded.
#[test]
fn a_graph_whose_folder_was_deleted_and_made_again_still_reloads() {
    let dir = scratch("folder_again");
    let Some(x) = start_xvfb() else { return };
    let folder = dir.join("graphs");
    std::fs::create_dir_all(&folder).expect("folder");
    let graph = folder.join("graph.ron");
    let text = std::fs::read_to_string(root().join("graphs/basic/fragment_raycast.ron")).expect("graph");
    assert!(text.contains("\"step_voxels\": 0.5"), "the graph sets its step");
    std::fs::write(&graph, &text).expect("graph");
    let (mut deleted_seen, mut reloaded) = (false, false);
    let run = run_viewer_with(
        &x,
        &dir,
        &[&graph.display().to_string()],
        |lines, seen| {
            std::fs::remove_dir_all(&folder).expect("delete the folder");
            deleted_seen = wait_for(lines, seen, "error in graph");
            std::fs::create_dir_all(&folder).expect("make it again");
            std::fs::write(&graph, &text).expect("the graph again");
            wait_for(lines, seen, "recovered");
            // An edit after the folder came back.
            std::thread::sleep(Duration::from_millis(300));
            std::fs::write(&graph, text.replacen("\"step_voxels\": 0.5", "\"step_voxels\": 0.75", 1)).expect("edit");
            reloaded = wait_for(lines, seen, "reloaded graph");
        },
        &["quit"],
        false,
    );
    assert!(run.status.is_some_and(|s| s.success()), "{}\n{}", run.stdout, run.stderr);
    assert!(deleted_seen, "the deleted graph is an error:\n{}", run.stdout);
    assert!(reloaded, "the edit after the folder came back is reloaded:\n{}", run.stdout);
}

// --- The reviewer's findings on the fixes above ---

/// A TF edit on `ml32`, so "save view" has a TF to write beside the scene.
fn session_with_an_edited_tf() -> LiveSession {
    let mut session =
        open(&root().join("graphs/basic/fragment_raycast.ron"), &[PathBuf::from("ml32")], LoadOptions::default(), None);
    let next = volgraph_app::view::tf_editor::with_point(
        session.transfer_function(),
        ControlPoint { value: 120.0, color: [1.0, 0.2, 0.2], alpha: 0.8 },
    );
    let events = session.edit_transfer_function(next);
    assert!(session.error().is_none(), "{events:?}");
    assert!(session.tf_edited());
    session
}

/// Review of issue 47: "save view" wrote `NAME.tf.ron` before it knew the scene could be
/// written: a scene path that is a FIFO, a folder or a read-only file left a TF file behind.
/// Every refusal now writes nothing; a save that writes the TF says so, and says when it
/// replaced this scene name's own companion from an earlier save.
#[cfg(unix)]
#[test]
fn a_refused_save_view_writes_no_tf_file() {
    use std::os::unix::fs::PermissionsExt as _;
    let dir = scratch("refused_save_view");
    let session = session_with_an_edited_tf();
    let fifo = dir.join("fifo.ron");
    mkfifo(&fifo);
    let folder = dir.join("folder.ron");
    std::fs::create_dir_all(&folder).expect("folder");
    let read_only = dir.join("ro.ron");
    std::fs::write(&read_only, "old").expect("file");
    std::fs::set_permissions(&read_only, std::fs::Permissions::from_mode(0o444)).expect("chmod");
    for (scene, words) in [(&fifo, "FIFO"), (&folder, "folder"), (&read_only, "read-only")] {
        let e = session.save_view(&camera(), (48, 48), scene).expect_err("refused");
        let text = format!("{e:#}");
        assert!(text.contains(&scene.display().to_string()) && text.contains(words), "{text}");
        let tf = volgraph_app::scene::tf_file_beside(scene);
        assert!(tf.symlink_metadata().is_err(), "{} was written though the scene was refused", tf.display());
    }
    assert_eq!(std::fs::read_to_string(&read_only).expect("file"), "old");
    // A scene whose TF path is a FIFO is refused too, before the scene is written.
    let scene = dir.join("piped.ron");
    mkfifo(&volgraph_app::scene::tf_file_beside(&scene));
    let e = session.save_view(&camera(), (48, 48), &scene).expect_err("refused");
    assert!(format!("{e:#}").contains("FIFO"), "{e:#}");
    assert!(!scene.exists(), "the scene was written though its TF could not be");
    // A good path: the TF is written and reported new, then reported as replaced.
    let scene = dir.join("good.ron");
    let first = session.save_view(&camera(), (48, 48), &scene).expect("saved").expect("a TF file");
    assert_eq!(first.path, volgraph_app::scene::tf_file_beside(&scene));
    assert!(!first.replaced && first.path.is_file() && scene.is_file());
    let again = session.save_view(&camera(), (48, 48), &scene).expect("saved").expect("a TF file");
    assert!(again.replaced, "the second save replaces the scene's own TF file and says so");
}

/// Review of issue 47: a scene's TF named by a preset's or a built-in TF's name (`File("ct-bone")`,
/// `File("graphs/tf/vessels.ron")`, no such file beside the scene) was read as a file relative to
/// the current folder where one was there: the scene's image depended on where it was rendered
/// from. It is the built-in itself, from any folder.
#[test]
fn a_scenes_built_in_tf_name_is_not_read_from_the_current_folder() {
    let dir = scratch("tf_names_cwd");
    let clean = dir.join("clean");
    let shadowed = dir.join("shadowed");
    std::fs::create_dir_all(shadowed.join("graphs/tf")).expect("folders");
    std::fs::create_dir_all(&clean).expect("folder");
    // What a current folder might hold under those names: a TF that would render differently.
    let other_tf = "TransferFunction(domain: (0.0, 255.0), points: [(value: 0.0, color: (0.0, 0.0, 1.0), \
                    alpha: 1.0), (value: 255.0, color: (0.0, 0.0, 1.0), alpha: 1.0)])";
    std::fs::write(shadowed.join("ct-bone"), other_tf).expect("file");
    std::fs::write(shadowed.join("graphs/tf/vessels.ron"), other_tf).expect("file");
    for (name, tf) in [("preset", "ct-bone"), ("builtin", "graphs/tf/vessels.ron")] {
        let scene = dir.join(format!("{name}.scene.ron"));
        std::fs::write(
            &scene,
            format!(
                "Scene(graph: \"basic/fragment_raycast\", volume: Generated(\"ml32\"), transfer_function: \
                 File({tf:?}), viewport: (32, 32))"
            ),
        )
        .expect("scene");
        let render = |cwd: &Path| {
            let png = cwd.join(format!("{name}.png"));
            let out = volgraph_in(
                cwd,
                &["render", "--scene", &scene.display().to_string(), "-o", &png.display().to_string()],
            );
            assert!(out.status.success(), "{name} from {}: {}", cwd.display(), String::from_utf8_lossy(&out.stderr));
            read_rgba(&png)
        };
        let (a, b) = (render(&clean), render(&shadowed));
        assert!(a == b, "{name}: the scene's image depends on the current folder ({tf} there)");
    }
}

/// Review of issue 47: a screenshot was checked, then written by `image.save(path)`, which
/// blocks on a FIFO made in between. It is now written by `write_bytes_atomically`, which never
/// opens the path: the PNG's bytes arrive whole, and a FIFO is refused without blocking.
#[cfg(unix)]
#[test]
fn a_screenshot_is_written_without_opening_its_path() {
    let dir = scratch("bytes_atomic");
    let png = dir.join("shot.png");
    let image = image::RgbaImage::from_pixel(3, 2, image::Rgba([10, 20, 30, 255]));
    let mut bytes = Vec::new();
    image.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png).expect("encoded");
    volgraph_app::atomic_write::write_bytes_atomically(&png, &bytes).expect("written");
    assert_eq!(std::fs::read(&png).expect("read"), bytes);
    assert_eq!(read_rgba(&png), image);
    let fifo = dir.join("fifo.png");
    mkfifo(&fifo);
    let (tx, rx) = channel();
    std::thread::spawn(move || {
        let _ = tx.send(volgraph_app::atomic_write::write_bytes_atomically(&fifo, b"png").map_err(|e| e.to_string()));
    });
    let result = rx.recv_timeout(Duration::from_secs(20)).expect("the write onto a FIFO returned");
    assert!(result.as_ref().is_err_and(|e| e.contains("FIFO")), "{result:?}");
    let names: Vec<_> = std::fs::read_dir(&dir).expect("dir").flatten().map(|e| e.file_name()).collect();
    assert_eq!(names.len(), 2, "no temporary file stays: {names:?}");
}

/// The label list's switches from a script (`label VALUE show|hide|only`, `label all`), as the
/// panel's do: hiding the liver of the organ phantom changes the window's image, showing every
/// label again changes it back from that.
#[test]
fn script_label_commands_hide_and_show_labels() {
    let dir = scratch("label_script");
    let Some(x) = start_xvfb() else { return };
    let shot = |name: &str| dir.join(name);
    let lines = [
        format!("screenshot {}", shot("all.png").display()),
        "label 1 hide".to_string(),
        format!("screenshot {}", shot("no_liver.png").display()),
        "label all".to_string(),
        format!("screenshot {}", shot("again.png").display()),
        "label 7 shown".to_string(),
        "quit".to_string(),
    ];
    let lines: Vec<&str> = lines.iter().map(String::as_str).collect();
    let run = run_viewer_paced(&x, &dir, &["multi/labels", "--volume", "organs_labels32"], &lines);
    assert!(run.status.is_some_and(|s| s.success()), "{}\n{}", run.stdout, run.stderr);
    let (all, no_liver, again) =
        (read_rgba(&shot("all.png")), read_rgba(&shot("no_liver.png")), read_rgba(&shot("again.png")));
    assert_ne!(all, no_liver, "hiding label 1 changes the image");
    assert_ne!(no_liver, again, "showing every label changes it back");
    assert!(
        run.stderr.contains("label 7 shown") && run.stderr.contains("write label VALUE show|hide|only"),
        "{}",
        run.stderr
    );
}
