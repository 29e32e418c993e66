//! The graphs travel with the binary (issue 20, item 3): from a folder without the source tree,
//! `volgraph graphs` lists them and a name that is not a file plans and renders the built-in
//! graph; a file of that name wins.

use std::path::{Path, PathBuf};
use std::process::Command;

fn empty_folder(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("volgraph-builtin-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn volgraph(cwd: &Path, args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_volgraph"))
        .args(args)
        .current_dir(cwd)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .expect("the volgraph binary runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn built_in_graphs_are_listed_and_render_by_name_from_any_folder() {
    let dir = empty_folder("any");
    let (code, out, err) = volgraph(&dir, &["graphs"]);
    assert_eq!(code, 0, "{err}");
    for expected in [
        "kruger_westermann_2003/rc_b",
        "Krüger & Westermann 2003",
        "klein_2005/leap_iso",
        "ruijters_vilanova_2006/bricks_octree",
        "compute_raycast_2013/compute_shader",
    ] {
        assert!(out.contains(expected), "missing {expected:?} in\n{out}");
    }
    let (code, out, err) = volgraph(&dir, &["plan", "kruger_westermann_2003/rc_b", "--size", "64x64"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.starts_with("plan \"kw03_rc_b\""), "{out}");
    let png = dir.join("leap.png");
    let (code, _, err) =
        volgraph(&dir, &["render", "klein_2005/leap_iso", "--size", "32x32", "-o", png.to_str().expect("utf-8")]);
    assert_eq!(code, 0, "{err}");
    assert!(png.is_file(), "the built-in graph rendered");
    // A misspelled name says what exists.
    let (code, _, err) = volgraph(&dir, &["plan", "klein_2005/leap_isso"]);
    assert_eq!(code, 1);
    assert!(err.contains("did you mean the built-in graph \"klein_2005/leap_iso\"?"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_file_of_the_same_name_wins_over_the_built_in_graph() {
    let dir = empty_folder("wins");
    std::fs::create_dir_all(dir.join("klein_2005")).expect("folder");
    let mine =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../graphs/basic/compute_raycast.ron"))
            .expect("a graph");
    std::fs::write(dir.join("klein_2005/leap_iso.ron"), mine).expect("write");
    let (code, out, err) = volgraph(&dir, &["plan", "klein_2005/leap_iso.ron", "--size", "64x64"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.starts_with("plan \"compute_raycast\""), "the file on disk, not the built-in graph:\n{out}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 20, item 5: a stock graph declares a WGSL-only pass kind (`basic/mip`); the stock
/// binary lists its kind with `passes --graph` and renders it by name from any folder (its
/// shader is compiled in with the built-in ones).
#[test]
fn the_stock_wgsl_only_kind_is_listed_and_renders() {
    let dir = empty_folder("wgsl-kind");
    let (code, out, err) = volgraph(&dir, &["passes", "--graph", "basic/mip", "mip_projection"]);
    assert_eq!(code, 0, "{err}");
    for expected in ["mip_projection", "level", "width", "step_voxels", "graph_kinds/mip_projection.wgsl"] {
        assert!(out.contains(expected), "missing {expected:?} in\n{out}");
    }
    let png = dir.join("mip.png");
    let (code, _, err) =
        volgraph(&dir, &["render", "basic/mip", "--size", "32x32", "-o", png.to_str().expect("utf-8")]);
    assert_eq!(code, 0, "{err}");
    let image = std::fs::read(&png).expect("the image was written");
    assert!(image.starts_with(b"\x89PNG"), "a PNG");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 20, item 2: the stock binary hands `bench` and `sweep` to `volgraph-bench`; where that
/// program is neither beside it nor on PATH, the message says how to get it.
#[test]
fn bench_without_the_bench_program_says_how_to_install_it() {
    let dir = empty_folder("no-bench");
    let copied = dir.join("volgraph");
    std::fs::copy(env!("CARGO_BIN_EXE_volgraph"), &copied).expect("copy the binary");
    // Another test thread forking while the copy was open for writing holds it open until its
    // child execs: running the copy then fails with "Text file busy" for a moment. Try again.
    let run = || {
        Command::new(&copied)
            .args(["sweep", "--knobs", "step"])
            .current_dir(&dir)
            .env("PATH", dir.join("no-such-folder"))
            .output()
    };
    let mut out = run();
    for _ in 0..20 {
        match &out {
            Err(e) if e.kind() == std::io::ErrorKind::ExecutableFileBusy => {
                std::thread::sleep(std::time::Duration::from_millis(50));
                out = run();
            }
            _ => break,
        }
    }
    let out = out.expect("runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("volgraph-bench") && err.contains("cargo install --path crates/bench"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
