//! Issue 19, "bad input, round two": one regression test per class that still failed, each
//! named for what broke. Every case runs the real binary, bounded in time (a hang is a
//! failure, not a stuck test run), and checks the exit code and the message; none may panic.

use std::io::Read as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

struct Run {
    code: i32,
    stdout: Vec<u8>,
    stderr: String,
}

/// Runs volgraph with `args`, killing it (and failing) after `limit`.
fn volgraph_within(args: &[&str], limit: Duration) -> Run {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut child = Command::new(env!("CARGO_BIN_EXE_volgraph"))
        .args(args)
        .current_dir(&root)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .env("RUST_BACKTRACE", "1")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the volgraph binary runs");
    let (mut out, mut err) = (child.stdout.take().expect("piped"), child.stderr.take().expect("piped"));
    let out_reader = std::thread::spawn(move || {
        let mut b = Vec::new();
        let _ = out.read_to_end(&mut b);
        b
    });
    let err_reader = std::thread::spawn(move || {
        let mut b = Vec::new();
        let _ = err.read_to_end(&mut b);
        b
    });
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("waits") {
            break status;
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{args:?} hung: still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let run = Run {
        code: status.code().unwrap_or(-1),
        stdout: out_reader.join().unwrap_or_default(),
        stderr: String::from_utf8_lossy(&err_reader.join().unwrap_or_default()).into_owned(),
    };
    assert_ne!(run.code, 101, "{args:?} panicked:\n{}", run.stderr);
    assert!(!run.stderr.contains("stack backtrace"), "{args:?} printed a backtrace:\n{}", run.stderr);
    run
}

fn volgraph(args: &[&str]) -> Run {
    volgraph_within(args, Duration::from_secs(120))
}

fn temp_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("volgraph-round-two-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn s(p: &Path) -> String {
    p.display().to_string()
}

const GRAPH: &str = "graphs/basic/fragment_raycast.ron";

fn assert_fails_with(run: &Run, code: i32, expected: &str, what: &str) {
    assert_eq!(run.code, code, "{what}: exit {} with:\n{}", run.code, run.stderr);
    assert!(run.stderr.contains(expected), "{what}: expected {expected:?} in:\n{}", run.stderr);
}

/// Class 2: a FIFO given as graph, scene or transfer function blocked forever; `/dev/zero`
/// was read until memory ran out. Both are refused before they are opened.
#[cfg(unix)]
#[test]
fn special_files_as_graph_scene_or_tf_are_refused_at_once() {
    let dir = temp_dir();
    let fifo = dir.join("pipe.ron");
    let _ = std::fs::remove_file(&fifo);
    let made = Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs");
    assert!(made.success(), "mkfifo");
    let out = s(&dir.join("out.png"));
    let limit = Duration::from_secs(60);
    for special in [s(&fifo), "/dev/zero".to_string()] {
        let kind = if special == "/dev/zero" { "is a device" } else { "is a FIFO (named pipe)" };
        let run = volgraph_within(&["plan", &special], limit);
        assert_fails_with(&run, 1, &format!("{kind}, not a graph file"), "graph");
        let run = volgraph_within(&["render", "--scene", &special, "-o", &out], limit);
        assert_fails_with(&run, 1, &format!("{kind}, not a scene file"), "scene");
        let run = volgraph_within(&["render", GRAPH, "--tf", &special, "--size", "16x16", "-o", &out], limit);
        assert_fails_with(&run, 1, &format!("{kind}, not a transfer function"), "tf");
    }
}

/// Class 2: a camera path with a keyframe at frame 10⁹ rendered 10⁹ frames; at 2³²−1 it wrapped
/// to 0 frames and wrote a black PNG.
#[test]
fn a_camera_path_longer_than_the_frame_cap_is_an_error() {
    let dir = temp_dir();
    for frame in ["1000000000", "4294967295"] {
        let scene = dir.join(format!("path_{frame}.ron"));
        std::fs::write(
            &scene,
            format!(
                "Scene(graph: \"{}\", volume: Generated(\"ml16\"), camera: Path(keyframes: [\
                 (frame: 0, azimuth: 0, elevation: 0, distance: 3), (frame: {frame}, azimuth: 90, elevation: 0, distance: 3)]))",
                s(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(GRAPH))
            ),
        )
        .expect("write");
        let run = volgraph(&["render", "--scene", &s(&scene), "-o", &s(&dir.join("path.png"))]);
        assert_fails_with(&run, 1, &format!("keyframe 1: frame {frame} is beyond the last frame"), frame);
    }
}

/// Class 5: names, kinds and ids holding ESC/BEL were printed raw by `plan`, `--dot` and the
/// diagnostics (setting the terminal title, clearing the screen). They are escaped.
#[test]
fn control_characters_from_a_graph_never_reach_the_terminal() {
    let dir = temp_dir();
    let source =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(GRAPH)).expect("the graph");
    let evil = "\u{1b}]0;pwned\u{7}\u{1b}[2J";
    // A description printed by plan, and a misspelled kind quoted back by a diagnostic.
    let named = source.replacen("name: \"", &format!("name: \"{evil}"), 1);
    let bad_kind = source.replacen("kind: \"present\"", &format!("kind: \"pres{evil}\""), 1);
    for (file, text, code) in [("named.ron", &named, 0), ("bad_kind.ron", &bad_kind, 1)] {
        let path = dir.join(file);
        std::fs::write(&path, text).expect("write");
        for extra in [&[][..], &["--dot"][..]] {
            let mut args = vec!["plan", path.to_str().expect("utf-8 path")];
            args.extend_from_slice(extra);
            let run = volgraph(&args);
            assert_eq!(run.code, code, "{file} {extra:?}:\n{}", run.stderr);
            let all = [run.stdout.as_slice(), run.stderr.as_bytes()].concat();
            assert!(!all.contains(&0x1b) && !all.contains(&0x07), "{file} {extra:?}: raw ESC/BEL printed");
            assert!(
                String::from_utf8_lossy(&all).contains("\\x1b]0;pwned\\x07"),
                "{file} {extra:?}: escaped form shown"
            );
        }
    }
}

/// Class 6: a typo in `when: [...]` turned a pass off for good, with no word.
#[test]
fn a_misspelled_when_feature_is_an_error_with_a_suggestion() {
    let dir = temp_dir();
    let source =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(GRAPH)).expect("the graph");
    let gated = source.replacen(
        "id: \"present\",",
        "id: \"present\", when: [\"shadng\"], otherwise: {\"display\": \"march.color\"},",
        1,
    );
    assert_ne!(gated, source, "the graph has a present pass to gate");
    let path = dir.join("when.ron");
    std::fs::write(&path, gated).expect("write");
    let run = volgraph(&["plan", &s(&path)]);
    assert_fails_with(&run, 1, "pass \"present\" is gated on feature \"shadng\", which no scene effect", "when");
    assert!(run.stderr.contains("did you mean \"shading\"?"), "{}", run.stderr);
    // With --features shadng the user means it: no error about the name.
    let run = volgraph(&["plan", &s(&path), "--features", "shadng"]);
    assert!(!run.stderr.contains("is gated on feature"), "{}", run.stderr);
}

/// Class 6: `--shaders` naming a missing folder or a file was ignored (the built-in shaders
/// ran); `--turn NaN` was accepted.
#[test]
fn a_missing_shader_folder_and_a_nan_turn_are_refused() {
    let dir = temp_dir();
    let out = s(&dir.join("x.png"));
    let missing = s(&dir.join("no-such-folder"));
    let run = volgraph(&["render", GRAPH, "--shaders", &missing, "-o", &out]);
    assert_fails_with(&run, 1, "does not exist; give the folder that holds the .wgsl files", "--shaders missing");
    let file = dir.join("a-file.wgsl");
    std::fs::write(&file, "").expect("write");
    let run = volgraph(&["render", GRAPH, "--shaders", &s(&file), "-o", &out]);
    assert_fails_with(&run, 1, "is not a folder", "--shaders file");
    let run = volgraph(&["view", GRAPH, "--turn", "NaN"]);
    assert_fails_with(&run, 2, "expected finite degrees per frame", "--turn NaN");
}

/// Class 6: a PNG written to a full disk reported success at small sizes (the encoder's
/// buffered writer dropped the error). `full.png` is a link to `/dev/full`, where every write
/// fails with "no space left on device".
#[cfg(target_os = "linux")]
#[test]
fn a_write_to_a_full_disk_is_an_error() {
    let dir = temp_dir();
    let link = dir.join("full.png");
    let _ = std::fs::remove_file(&link);
    std::os::unix::fs::symlink("/dev/full", &link).expect("symlink");
    let run = volgraph(&["render", GRAPH, "--size", "16x16", "-o", &s(&link)]);
    assert_fails_with(&run, 1, "cannot write PNG", "PNG to /dev/full");
    assert!(run.stderr.to_lowercase().contains("no space left"), "{}", run.stderr);
}

/// Class 6: a TF whose domain misses the data's values rendered a uniform box, with no word.
#[test]
fn a_transfer_function_beside_the_data_is_a_warning() {
    let dir = temp_dir();
    let tf = dir.join("far.ron");
    std::fs::write(
        &tf,
        "TransferFunction(domain: (1000.0, 2000.0), points: [\
         (value: 1000.0, color: (1.0, 1.0, 1.0), alpha: 0.5), (value: 2000.0, color: (1.0, 0.0, 0.0), alpha: 1.0)])",
    )
    .expect("write");
    let run = volgraph(&["render", GRAPH, "--size", "16x16", "--tf", &s(&tf), "-o", &s(&dir.join("far.png"))]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(run.stderr.contains("lies wholly above the volume's values"), "{}", run.stderr);
}

/// Class 7: `view --screenshot x.jpg` was blamed on `-o`.
#[test]
fn a_screenshot_name_is_blamed_on_its_own_flag() {
    let run = volgraph(&["view", GRAPH, "--screenshot", "x.jpg"]);
    assert_fails_with(&run, 1, "--screenshot x.jpg:", "--screenshot");
    assert!(!run.stderr.contains("-o x.jpg"), "{}", run.stderr);
}

/// Class 6: a WGSL-only kind whose shader's `@workgroup_size` differs from its `workgroup`
/// wrote a quarter of the image with exit 0; `volgraph plan` now names both.
#[test]
fn a_wgsl_kind_unlike_its_shader_is_a_plan_error() {
    let dir = temp_dir().join("wgsl-kind");
    std::fs::create_dir_all(dir.join("shaders")).expect("dir");
    std::fs::write(
        dir.join("shaders/tint.wgsl"),
        "struct Params { gain: f32 }\n@group(0) @binding(auto) var<uniform> params: Params;\n\
         @group(0) @binding(auto) var out: texture_storage_2d<rgba16float, write>;\n\
         @compute @workgroup_size(16, 16) fn cs_main(@builtin(global_invocation_id) id: vec3<u32>) {\n\
         textureStore(out, vec2<i32>(id.xy), vec4<f32>(params.gain)); }\n",
    )
    .expect("write");
    let graph = dir.join("tint.ron");
    std::fs::write(
        &graph,
        "Graph(name: \"tint\", inputs: {}, kinds: {\"tint\": WgslKind(shader: \"tint.wgsl\", outputs: {\"out\": Rgba16Float},\n\
         workgroup: (8, 8), params: [(name: \"gain\", default: 1.0, min: 0.0, max: 2.0)])},\n\
         passes: [Pass(id: \"t\", kind: \"tint\")], outputs: {\"image\": \"t.out\"})\n",
    )
    .expect("write");
    let run = volgraph(&["plan", &s(&graph)]);
    assert_fails_with(&run, 1, "@workgroup_size(16, 16, 1) but the kind declares workgroup: (8, 8)", "workgroup");
}

/// Class 6: `--gpu-memory-mb` given to a graph without a brick pool was ignored in silence.
#[test]
fn a_memory_budget_for_a_graph_without_a_pool_is_named() {
    let dir = temp_dir();
    let run =
        volgraph(&["render", GRAPH, "--size", "16x16", "--gpu-memory-mb", "64", "-o", &s(&dir.join("budget.png"))]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(
        run.stderr.contains("--gpu-memory-mb 64: graph \"fragment_raycast\" has no pass that streams"),
        "{}",
        run.stderr
    );
}

/// Class 7: an OS error was printed twice (in the message and again as its source).
#[test]
fn an_os_error_is_printed_once() {
    let dir = temp_dir();
    let tf = s(&dir.join("no_such_tf.ron"));
    let run = volgraph(&["render", "basic/fragment_raycast", "--tf", &tf, "-o", &s(&dir.join("x.png"))]);
    assert_fails_with(&run, 1, "no_such_tf.ron: cannot read the transfer function: No such file or directory", "tf");
    assert_eq!(run.stderr.matches("No such file or directory").count(), 1, "{}", run.stderr);
    // A missing scene names the built-in scenes instead of an OS error.
    let scene = s(&dir.join("no_such_scene.ron"));
    let run = volgraph(&["render", "--scene", &scene, "-o", &s(&dir.join("x.png"))]);
    assert_fails_with(&run, 1, "no_such_scene.ron: no such scene file, nor a built-in scene", "scene");
    assert!(run.stderr.contains("engine_cut_open"), "{}", run.stderr);
}
