//! `volgraph set` (issue "The viewer as a workbench", item 2): values written into a graph file
//! at their place. Every shipped graph round-trips — each value in the file set to another text
//! of a valid value changes exactly one line, and set back gives the file byte for byte — and
//! bad values and unknown names are refused with the file untouched.

use std::path::{Path, PathBuf};
use std::process::Command;

use volgraph_core::graph::ast::{InputKind, NodeDoc};
use volgraph_core::graph::edit::{SetTarget, edit_for};
use volgraph_core::graph::parse_graph;

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("set_values");
    std::fs::create_dir_all(&dir).expect("scratch");
    dir.join(name)
}

fn shipped_graphs() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).expect("graphs/").flatten() {
            let p = entry.path();
            if p.is_dir() && p.file_name().is_some_and(|n| n != "tf") {
                walk(&p, out);
            } else if p.extension().is_some_and(|e| e == "ron") {
                out.push(p);
            }
        }
    }
    let mut out = Vec::new();
    walk(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../../graphs"), &mut out);
    out.sort();
    out
}

/// Every value the file writes that `set` can target: numeric parameters and Scalar inputs.
fn numeric_targets(source: &str) -> Vec<SetTarget> {
    let doc = parse_graph(source).expect("a shipped graph parses");
    let mut targets = Vec::new();
    let passes = doc.passes.iter().flat_map(|n| match n {
        NodeDoc::Pass(p) => vec![p],
        NodeDoc::Repeat(r) => r.body.iter().collect(),
    });
    for p in passes {
        for (name, value) in &p.params {
            if matches!(value, ron::Value::Number(_)) {
                targets.push(SetTarget::Param { pass: p.id.clone(), param: name.clone() });
            }
        }
    }
    for (name, kind) in &doc.inputs {
        if matches!(kind, InputKind::Scalar(_)) {
            targets.push(SetTarget::Input(name.clone()));
        }
    }
    targets
}

/// Another text of the same number: `0.5` → `0.50`, `8` → `8.0` where the parameter is a float
/// (an integer parameter keeps its text; setting it is then a no-op that must leave the file
/// byte for byte).
fn other_text(text: &str) -> String {
    if text.contains('.') && !text.contains(['e', 'E']) { format!("{text}0") } else { text.to_string() }
}

#[test]
fn every_shipped_graph_round_trips_value_by_value() {
    let mut checked = 0;
    for graph in shipped_graphs() {
        let original = std::fs::read_to_string(&graph).expect("read");
        let copy = scratch(&graph.file_name().expect("name").to_string_lossy());
        std::fs::write(&copy, &original).expect("copy");
        for target in numeric_targets(&original) {
            let edit = edit_for(&original, &target, "0").expect("a value the file writes");
            let span = edit[0].span;
            let text = original[span.start..span.end].to_string();
            let changed = other_text(&text);
            volgraph_app::set_cmd::run(&copy, &[format!("{target}={changed}")]).unwrap_or_else(|e| {
                panic!("{}: {target}={changed}: {}", graph.display(), volgraph_app::cli::error_text(&e))
            });
            let edited = std::fs::read_to_string(&copy).expect("read");
            let differing = original.lines().zip(edited.lines()).filter(|(a, b)| a != b).count();
            assert_eq!(original.lines().count(), edited.lines().count(), "{}: {target}: lines added", graph.display());
            assert_eq!(differing, usize::from(changed != text), "{}: {target}: a one-line diff", graph.display());
            volgraph_app::set_cmd::run(&copy, &[format!("{target}={text}")]).expect("set back");
            assert_eq!(
                std::fs::read_to_string(&copy).expect("read"),
                original,
                "{}: {target} round trip",
                graph.display()
            );
            checked += 1;
        }
    }
    assert!(checked > 50, "only {checked} values found in the shipped graphs");
}

fn volgraph(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_volgraph")).args(args).output().expect("runs");
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[test]
fn bad_values_and_unknown_names_leave_the_file_untouched() {
    let original = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../graphs/kruger_westermann_2003/rc_b.ron"),
    )
    .expect("read");
    let copy = scratch("rc_b_refused.ron");
    std::fs::write(&copy, &original).expect("copy");
    let c = copy.to_str().expect("utf-8");
    for (assignment, expected) in [
        ("input.threshold=7", "outside its range"),
        ("mrach.step_voxels=0.5", "did you mean \"march\"?"),
        ("input.treshold=0.9", "did you mean \"input.threshold\"?"),
        ("march.step_voxles=0.5", "step_voxels"),
        ("march.step_voxels=0.5 0.25", "is not a RON value"),
        ("march", "expected PASS.PARAM=VALUE"),
    ] {
        let (code, stderr) = volgraph(&["set", c, assignment]);
        assert_ne!(code, 0, "{assignment} was accepted");
        assert!(stderr.contains(expected), "{assignment}: {stderr}");
        assert_eq!(std::fs::read_to_string(&copy).expect("read"), original, "{assignment} changed the file");
    }
    // A located error: the line and column of the value.
    let (_, stderr) = volgraph(&["set", c, "input.threshold=7"]);
    assert!(stderr.contains("rc_b_refused.ron:"), "{stderr}");
    // A built-in name is not a file to edit.
    let (code, stderr) = volgraph(&["set", "basic/fragment_raycast", "march.step_voxels=1"]);
    assert_ne!(code, 0);
    assert!(stderr.contains("is a built-in graph"), "{stderr}");
    // Several values at once, and a parameter the file does not write yet.
    let (code, stderr) = volgraph(&["set", c, "input.threshold=0.9", "present.background=0.25"]);
    assert_eq!(code, 0, "{stderr}");
    let edited = std::fs::read_to_string(&copy).expect("read");
    assert!(edited.contains("Scalar(0.9)") && edited.contains("\"background\": 0.25"), "{edited}");
    parse_graph(&edited).expect("still a graph");
}
