//! Issue 47 ("Bad input, round three"), causes 3 and 4 as they reached `volgraph set`, the
//! writes the viewer shares with it (`atomic_write`) and clap's usage errors: one test per cause,
//! each on a fresh copy of a shipped graph in its own folder.

use std::path::{Path, PathBuf};
use std::process::Command;

use volgraph_core::graph::ast::NodeDoc;
use volgraph_core::graph::parse_graph;

/// A fresh, empty folder for one test.
fn folder(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bad_input_round_three_set").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

/// `graphs/basic/fragment_raycast.ron`: `march.step_voxels` is 0.5, `present` has no params.
fn shipped() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../graphs/basic/fragment_raycast.ron"))
        .expect("the shipped graph")
}

/// Runs volgraph: (exit status, stdout, stderr).
fn volgraph(args: &[&std::ffi::OsStr]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_volgraph")).args(args).output().expect("volgraph runs");
    let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    (out.status.code().unwrap_or(-1), text(&out.stdout), text(&out.stderr))
}

fn set(graph: &Path, assignments: &[&str]) -> (i32, String, String) {
    let mut args = vec![std::ffi::OsStr::new("set"), graph.as_os_str()];
    args.extend(assignments.iter().map(std::ffi::OsStr::new));
    volgraph(&args)
}

/// The value the compiler reads for `pass.param`, as RON text (serde keeps a duplicated key's
/// last copy).
fn param(text: &str, pass: &str, name: &str) -> Option<String> {
    let doc = parse_graph(text.strip_prefix('\u{feff}').unwrap_or(text)).expect("a graph");
    doc.passes.iter().find_map(|n| match n {
        NodeDoc::Pass(p) if p.id == pass => p.params.get(name).map(|v| ron::to_string(v).expect("RON")),
        _ => None,
    })
}

#[cfg(unix)]
#[test]
fn set_through_a_planted_temp_link_leaves_its_target_alone() {
    let dir = folder("planted");
    let graph = dir.join("g.ron");
    std::fs::write(&graph, shipped()).expect("graph");
    let victim = dir.join("victim.txt");
    std::fs::write(&victim, "precious").expect("victim");
    // The name volgraph used to write through, planted as a link to another file.
    let planted = dir.join(".g.ron.volgraph.tmp");
    std::os::unix::fs::symlink(&victim, &planted).expect("plant the link");
    let (code, _, stderr) = set(&graph, &["march.step_voxels=0.25"]);
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(std::fs::read_to_string(&victim).expect("victim"), "precious", "the link's target was overwritten");
    assert!(planted.symlink_metadata().expect("the link").file_type().is_symlink(), "the planted link was replaced");
    assert_eq!(
        param(&std::fs::read_to_string(&graph).expect("graph"), "march", "step_voxels"),
        Some("0.25".to_string())
    );
    // No temporary file of volgraph's own is left beside the graph.
    let left: Vec<String> = std::fs::read_dir(&dir)
        .expect("folder")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".volgraph.tmp") && n != ".g.ron.volgraph.tmp")
        .collect();
    assert!(left.is_empty(), "temporary files left: {left:?}");
}

#[cfg(unix)]
#[test]
fn set_writes_through_a_symlink_to_its_target() {
    let dir = folder("symlink");
    std::fs::create_dir_all(dir.join("real")).expect("real/");
    let target = dir.join("real/g.ron");
    std::fs::write(&target, shipped()).expect("graph");
    let link = dir.join("link.ron");
    std::os::unix::fs::symlink("real/g.ron", &link).expect("link");
    let (code, stdout, stderr) = set(&link, &["march.step_voxels=0.25"]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("link.ron:"), "the user's path is named: {stdout}");
    assert!(link.symlink_metadata().expect("link").file_type().is_symlink(), "the link became a regular file");
    assert_eq!(std::fs::read_link(&link).expect("link"), Path::new("real/g.ron"));
    let edited = std::fs::read_to_string(&target).expect("target");
    assert_eq!(param(&edited, "march", "step_voxels"), Some("0.25".to_string()), "the target is unchanged");
    assert_eq!(edited, shipped().replace("\"step_voxels\": 0.5,", "\"step_voxels\": 0.25,"));
}

#[cfg(unix)]
#[test]
fn set_on_a_read_only_graph_is_refused() {
    use std::os::unix::fs::PermissionsExt as _;
    let dir = folder("read_only");
    let graph = dir.join("g.ron");
    std::fs::write(&graph, shipped()).expect("graph");
    std::fs::set_permissions(&graph, std::fs::Permissions::from_mode(0o444)).expect("chmod");
    let (code, _, stderr) = set(&graph, &["march.step_voxels=0.25"]);
    assert_eq!(code, 1, "a read-only graph was written: {stderr}");
    assert!(
        stderr.contains(&format!("{} is read-only; make it writable (chmod u+w) or save elsewhere", graph.display())),
        "{stderr}"
    );
    assert_eq!(std::fs::read_to_string(&graph).expect("graph"), shipped(), "the file changed");
    assert_eq!(std::fs::metadata(&graph).expect("meta").permissions().mode() & 0o777, 0o444);
}

#[test]
fn set_keeps_crlf_line_endings() {
    let dir = folder("crlf");
    let graph = dir.join("g.ron");
    let original = shipped().replace('\n', "\r\n");
    std::fs::write(&graph, &original).expect("graph");
    // A value replaced, a parameter added to a map, and a `params` map made for a pass.
    let (code, _, stderr) = set(&graph, &["march.step_voxels=0.25", "march.max_steps=512", "present.background=0.2"]);
    assert_eq!(code, 0, "{stderr}");
    let edited = std::fs::read_to_string(&graph).expect("graph");
    let bare = edited.match_indices('\n').filter(|(i, _)| !edited[..*i].ends_with('\r')).count();
    assert_eq!(bare, 0, "LF-only line ends in a CRLF file:\n{edited:?}");
    assert_eq!(edited.matches("\r\n").count(), original.matches("\r\n").count() + 2, "two lines added");
    assert!(edited.contains("\"max_steps\": 512,\r\n"), "{edited:?}");
    assert!(edited.contains("params: {\"background\": 0.2},\r\n"), "{edited:?}");
    assert_eq!(param(&edited, "march", "max_steps"), Some("512".to_string()));
}

#[test]
fn set_accepts_a_bom_and_an_enable_header() {
    let dir = folder("bom_enable");
    let graph = dir.join("g.ron");
    let original = format!("\u{feff}#![enable(implicit_some)]\n{}", shipped());
    std::fs::write(&graph, &original).expect("graph");
    let g = graph.as_os_str();
    let (code, _, stderr) = volgraph(&[std::ffi::OsStr::new("plan"), g]);
    assert_eq!(code, 0, "plan accepts the graph: {stderr}");
    let (code, stdout, stderr) = set(&graph, &["march.step_voxels=0.25", "input.x=1"]);
    assert_ne!(code, 0, "an unknown input is refused");
    assert!(stderr.contains("the graph has no input \"x\""), "{stdout}{stderr}");
    let (code, stdout, stderr) = set(&graph, &["march.step_voxels=0.25"]);
    assert_eq!(code, 0, "{stderr}");
    // Line 1 is the mark and the header, so the shipped line number moves by one.
    let line = shipped().lines().position(|l| l.contains("\"step_voxels\"")).expect("the line") + 2;
    assert!(stdout.contains(&format!("g.ron:{line}: march.step_voxels = 0.25 (was 0.5)")), "{stdout}");
    let edited = std::fs::read_to_string(&graph).expect("graph");
    assert_eq!(edited, original.replace("\"step_voxels\": 0.5,", "\"step_voxels\": 0.25,"), "only the value changed");
}

#[test]
fn set_edits_the_duplicate_key_that_takes_effect() {
    let dir = folder("duplicate");
    let graph = dir.join("g.ron");
    let original =
        shipped().replace("\"threshold\": 1.0,", "\"threshold\": 1.0,\n                \"step_voxels\": 0.75,");
    assert_eq!(param(&original, "march", "step_voxels"), Some("0.75".to_string()), "the last copy counts");
    std::fs::write(&graph, &original).expect("graph");
    let (code, stdout, stderr) = set(&graph, &["march.step_voxels=0.25"]);
    assert_eq!(code, 0, "{stderr}");
    let edited = std::fs::read_to_string(&graph).expect("graph");
    assert_eq!(param(&edited, "march", "step_voxels"), Some("0.25".to_string()), "the graph still uses 0.75");
    assert_eq!(edited, original.replace("\"step_voxels\": 0.75,", "\"step_voxels\": 0.25,"), "the first copy edited");
    let first = original.lines().position(|l| l.contains("\"step_voxels\": 0.5")).expect("first copy") + 1;
    let last = original.lines().position(|l| l.contains("\"step_voxels\": 0.75")).expect("last copy") + 1;
    assert!(
        stdout.contains(&format!("g.ron:{last}: march.step_voxels = 0.25 (was 0.75; line {first} writes it too")),
        "{stdout}"
    );
}

#[test]
fn a_failed_write_names_the_users_path_not_the_temporary_file() {
    let dir = folder("failed_write");
    // A folder that is not there: creating the temporary file fails.
    let path = dir.join("missing/view.tf.ron");
    let e = volgraph_app::atomic_write::write_atomically(&path, "text").expect_err("no folder to write in");
    let text = format!("{e:#}");
    assert!(text.starts_with(&format!("{}: cannot write", path.display())), "{text}");
    assert!(!text.contains(".volgraph.tmp"), "the hidden temporary file is named: {text}");
}

#[cfg(unix)]
#[test]
fn clap_usage_error_escapes_control_characters() {
    use std::os::unix::ffi::OsStrExt as _;
    let hostile = std::ffi::OsStr::from_bytes(b"--x\x1b]0;pwned\x07\x1b[2J");
    for args in [vec![std::ffi::OsStr::new("plan"), std::ffi::OsStr::new("g.ron"), hostile], vec![hostile]] {
        let (code, _, stderr) = volgraph(&args);
        assert_eq!(code, 2, "a usage error's status: {stderr}");
        assert!(!stderr.contains(['\u{1b}', '\u{7}']), "raw control characters reach the terminal: {stderr:?}");
        assert!(stderr.contains("\\x1b]0;pwned\\x07\\x1b[2J"), "the argument is shown escaped: {stderr}");
    }
    let (code, stdout, _) = volgraph(&[std::ffi::OsStr::new("--version")]);
    assert_eq!((code, stdout.starts_with("volgraph ")), (0, true), "{stdout}");
    let (code, stdout, _) = volgraph(&[std::ffi::OsStr::new("set"), std::ffi::OsStr::new("--help")]);
    assert_eq!(code, 0);
    assert!(stdout.contains("Usage: volgraph set"), "{stdout}");
}
