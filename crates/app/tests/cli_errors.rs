//! Bad command-line input gets a clear error naming the flag or file and how to fix it, and
//! exit status 1 — never a panic (status 101) and never an image of garbage.

use std::process::Command;

fn volgraph(args: &[&str]) -> (i32, String) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let out = Command::new(env!("CARGO_BIN_EXE_volgraph"))
        .args(args)
        .current_dir(&root)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .expect("the volgraph binary runs");
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).into_owned())
}

fn out_png() -> String {
    std::env::temp_dir().join("volgraph_cli_errors.png").display().to_string()
}

#[test]
fn missing_graph_file_names_the_file() {
    let (code, err) = volgraph(&["plan", "graphs/nope.ron"]);
    assert_eq!(code, 1);
    assert!(err.contains("graphs/nope.ron: cannot read graph file"), "{err}");
}

#[test]
fn bad_size_names_the_flag_and_the_form() {
    let (code, err) = volgraph(&["plan", "graphs/basic/fragment_raycast.ron", "--size", "512"]);
    assert_eq!(code, 1);
    assert!(err.contains("--size \"512\": expected WIDTHxHEIGHT, e.g. 512x512, each 1..=16384"), "{err}");
}

#[test]
fn bad_camera_names_the_flag_and_the_form() {
    let o = out_png();
    let (code, err) = volgraph(&["render", "graphs/basic/fragment_raycast.ron", "--camera", "30,20", "-o", &o]);
    assert_eq!(code, 1);
    assert!(err.contains("--camera \"30,20\": expected AZIMUTH,ELEVATION,DISTANCE"), "{err}");
}

#[test]
fn raw_volume_of_the_wrong_size_says_expected_and_actual_bytes() {
    let path = std::env::temp_dir().join("tiny_4x4x4_uint8.raw");
    std::fs::write(&path, [0u8; 10]).expect("temp file");
    let o = out_png();
    let (code, err) =
        volgraph(&["render", "graphs/basic/fragment_raycast.ron", "--volume", &path.display().to_string(), "-o", &o]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("tiny_4x4x4_uint8.raw"), "the message names the file: {err}");
    assert!(err.contains("64") && err.contains("10"), "expected vs actual bytes: {err}");
}

#[test]
fn bad_dims_flag_is_explained() {
    let o = out_png();
    let (code, err) = volgraph(&["render", "graphs/basic/fragment_raycast.ron", "--dims", "4x4", "-o", &o]);
    assert_eq!(code, 1);
    assert!(err.contains("--dims \"4x4\": expected XxYxZ with positive integers, e.g. 128x128x64"), "{err}");
}

#[test]
fn malformed_graph_is_reported_with_its_location() {
    let path = std::env::temp_dir().join("volgraph_cli_bad_graph.ron");
    std::fs::write(
        &path,
        "Graph(name: \"x\", passes: [Pass(id: \"a\", kind: \"raycats\")], outputs: {\"image\": \"a.color\"})",
    )
    .expect("temp file");
    let (code, err) = volgraph(&["plan", &path.display().to_string()]);
    assert_eq!(code, 1);
    assert!(err.contains(":1:47: pass \"a\" has unknown kind \"raycats\""), "{err}");
    assert!(err.contains("did you mean \"raycast\"?"), "{err}");
}
