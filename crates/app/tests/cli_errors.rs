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
    assert!(
        err.contains("graphs/nope.ron: cannot read the graph file: no such file, nor a built-in graph of that name"),
        "{err}"
    );
    assert!(err.contains("`volgraph graphs` lists the built-in ones"), "{err}");
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

/// `volgraph plan` checks shader bindings without a GPU: a shader global renamed away from its
/// port in a workspace's shader copy is an error naming the pass, the shader and the ports.
#[test]
fn plan_catches_a_shader_binding_that_matches_no_port() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = std::env::temp_dir().join(format!("volgraph_plan_bindings_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    copy_dir(&root.join("shaders"), &dir.join("shaders"));
    std::fs::copy(root.join("graphs/basic/compute_raycast.ron"), dir.join("compute_raycast.ron")).expect("copy");
    // The compute raycaster's `dir` is declared by the shared pixel ray it imports.
    let shader = dir.join("shaders/common/pixel_ray.wgsl");
    let text = std::fs::read_to_string(&shader).expect("read");
    let renamed = text
        .replace("var dir: texture_2d<f32>;", "var dirs: texture_2d<f32>;")
        .replace("textureLoad(dir, ", "textureLoad(dirs, ");
    assert_ne!(renamed, text, "the shader has the global this test renames");
    std::fs::write(&shader, renamed).expect("write");
    let (code, err) = volgraph(&["plan", &dir.join("compute_raycast.ron").display().to_string()]);
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("pass \"march\" (raycast_compute): raycast_compute.wgsl: global \"dirs\" is neither a port")
            && err.contains("(ports: entry, dir, empty, distance, volume, tf, color)"),
        "{err}"
    );
}

/// Code a wired input compiles in is checked at plan time too: the single-pass renderer with
/// `empty` wired leaps (`#if LEAP`), so a misnamed global inside the leap code is a plan error,
/// not a failure at the first frame.
#[test]
fn plan_checks_the_code_a_wired_input_compiles_in() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = std::env::temp_dir().join(format!("volgraph_plan_wired_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    copy_dir(&root.join("shaders"), &dir.join("shaders"));
    std::fs::copy(root.join("graphs/modern/single_pass_ess_ert.ron"), dir.join("ess.ron")).expect("copy");
    let shader = dir.join("shaders/common/pixel_march.wgsl");
    let text = std::fs::read_to_string(&shader).expect("read");
    let renamed = text
        .replace("var<uniform> blocks: BlockSize;", "var<uniform> block_edges: BlockSize;")
        .replace("return blocks.block_size;", "return block_edges.block_size;");
    assert_ne!(renamed, text, "the shader has the global this test renames");
    std::fs::write(&shader, renamed).expect("write");
    let (code, err) = volgraph(&["plan", &dir.join("ess.ron").display().to_string()]);
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("pass \"march\" (raycast): raycast.wgsl: global \"block_edges\" is neither a port"), "{err}");
}

fn copy_dir(from: &std::path::Path, to: &std::path::Path) {
    std::fs::create_dir_all(to).expect("mkdir");
    for entry in std::fs::read_dir(from).expect("read_dir") {
        let path = entry.expect("entry").path();
        let target = to.join(path.file_name().expect("name"));
        if path.is_dir() {
            copy_dir(&path, &target);
        } else {
            std::fs::copy(&path, &target).expect("copy");
        }
    }
}

/// `--volume` takes a name where no such file is, as `bench graphs --datasets` does: a generated
/// volume renders; an unknown name says what names there are (the data folder's datasets and the
/// generated ones); a bad edge says its range.
#[test]
fn a_volume_name_is_a_dataset_or_a_generated_volume() {
    let o = out_png();
    let (code, err) =
        volgraph(&["render", "graphs/basic/fragment_raycast.ron", "--volume", "sphere24", "--size", "32x32", "-o", &o]);
    assert_eq!(code, 0, "{err}");
    // A dataset of the data folder by its short name, with its manifest row's spacing (the
    // lobster's voxels are 1.4 deep): `info` reads `--volume`'s way too.
    if volgraph_accel::data_dir::require_dataset("lobster").is_some() {
        let (code, err) = volgraph(&[
            "render",
            "graphs/basic/fragment_raycast.ron",
            "--volume",
            "lobster",
            "--size",
            "32x32",
            "-o",
            &o,
        ]);
        assert_eq!(code, 0, "{err}");
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let info = Command::new(env!("CARGO_BIN_EXE_volgraph")).args(["info", "lobster"]).current_dir(&root).output();
        let info = info.expect("the volgraph binary runs");
        let text = String::from_utf8_lossy(&info.stdout);
        assert!(info.status.success() && text.contains("301 × 324 × 56") && text.contains("1.4"), "{text}");
    }
    let (code, err) =
        volgraph(&["render", "graphs/basic/fragment_raycast.ron", "--volume", "no_such_volume", "-o", &o]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("no_such_volume: no such file or folder, and not a volume's name"), "{err}");
    assert!(
        err.contains("ml<N>, mlf<N>, sphere<N>, noise<N>, vessels<N>, tooth<N>, organs<N> or organs_labels<N>"),
        "{err}"
    );
    // A name is no file: the flags of a file's layout are refused, not silently dropped.
    let (code, err) =
        volgraph(&["render", "graphs/basic/fragment_raycast.ron", "--volume", "sphere24", "--dims", "8x8x8", "-o", &o]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("sphere24 names a volume, not a file: --dims"), "{err}");
    let (code, err) = volgraph(&["render", "graphs/basic/fragment_raycast.ron", "--volume", "ml1", "-o", &o]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("\"ml1\"") && err.contains("edge must be 2..="), "{err}");
}
