//! Error messages for malformed graph files, word for word.
//!
//! Every `NAME.ron` under `tests/graphs/malformed/` (workspace root) must fail to compile with
//! the test registry, and the `Display` of its `Diagnostics` (`file:line:col: message` and an
//! indented `help:` line per problem) must equal `NAME.expected`. `VOLGRAPH_BLESS=1` rewrites
//! the expected files; review them by eye: each must say what is wrong, where, and how to fix.

mod support;

use std::fs;
use std::path::{Path, PathBuf};

use volgraph_compiler::{CompileOptions, compile};

fn malformed_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/graphs/malformed")
}

fn blessing() -> bool {
    std::env::var("VOLGRAPH_BLESS").is_ok_and(|v| v == "1")
}

/// The `.ron` files, sorted.
fn cases() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = fs::read_dir(malformed_dir())
        .expect("tests/graphs/malformed exists")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .collect();
    files.sort();
    files
}

/// The diagnostics text of one file, named as it would be from the workspace root.
fn diagnostics_of(path: &Path) -> Result<String, String> {
    let name = format!("tests/graphs/malformed/{}", path.file_name().and_then(|n| n.to_str()).unwrap_or("?"));
    let source = fs::read_to_string(path).map_err(|e| format!("{name}: cannot read: {e}"))?;
    match compile(&name, &source, &support::registry(), &CompileOptions::new(1920, 1080)) {
        Ok(_) => Err(format!("{name} compiled, but it is in the malformed folder")),
        Err(d) => Ok(format!("{d}\n")),
    }
}

#[test]
fn malformed_graphs_report_exact_messages() {
    let cases = cases();
    assert!(cases.len() >= 12, "expected at least 12 malformed graphs, found {}", cases.len());
    let mut failures = Vec::new();
    for path in &cases {
        let actual = match diagnostics_of(path) {
            Ok(text) => text,
            Err(e) => {
                failures.push(e);
                continue;
            }
        };
        let expected_path = path.with_extension("expected");
        if blessing() {
            fs::write(&expected_path, &actual).expect("the malformed folder is writable");
            continue;
        }
        match fs::read_to_string(&expected_path) {
            Ok(expected) if expected == actual => {}
            Ok(expected) => {
                failures.push(format!("{}:\n--- expected\n{expected}--- actual\n{actual}", expected_path.display()))
            }
            Err(e) => {
                failures.push(format!("{}: {e} (run with VOLGRAPH_BLESS=1 to create it)", expected_path.display()))
            }
        }
    }
    assert!(failures.is_empty(), "{} of {} cases failed:\n\n{}", failures.len(), cases.len(), failures.join("\n"));
}

/// Each expected file is located: every problem line starts with the file name and either a
/// `line:col` or the pass and field, and carries a `help:` line saying how to fix it.
#[test]
fn every_expected_message_is_located_and_helpful() {
    for path in cases() {
        let expected = fs::read_to_string(path.with_extension("expected")).unwrap_or_default();
        let name = format!("tests/graphs/malformed/{}", path.file_name().and_then(|n| n.to_str()).unwrap_or("?"));
        let problems: Vec<&str> = expected.lines().filter(|l| !l.starts_with("  help: ")).collect();
        assert!(!problems.is_empty(), "{}: no problem reported", path.display());
        for line in &problems {
            let rest = line
                .strip_prefix(&format!("{name}:"))
                .unwrap_or_else(|| panic!("{line:?} does not start with {name}:"));
            let located = rest.split(':').take(2).all(|n| n.parse::<u32>().is_ok()) || rest.starts_with(" pass \"");
            assert!(located, "{line:?} has no line:col and no pass/field");
        }
        let helps = expected.lines().filter(|l| l.starts_with("  help: ")).count();
        assert_eq!(helps, problems.len(), "{}: every problem needs a help line:\n{expected}", path.display());
    }
}

/// The several-errors case reports every problem of the file, not just the first.
#[test]
fn several_errors_are_reported_at_once() {
    let path = malformed_dir().join("several_errors.ron");
    let text = diagnostics_of(&path).expect("several_errors.ron fails to compile");
    let problems = text.lines().filter(|l| !l.starts_with("  help: ")).count();
    assert!(problems >= 4, "expected at least 4 problems, got:\n{text}");
}
