//! Helpers for volgraph's workspace-level integration tests (`tests/*.rs` at the repository
//! root): finding the graph files of the repository and comparing text against golden files.
//!
//! This package (`volgraph-tests`) exists so tests that need several crates at once — the
//! built-in passes from `volgraph-passes` compiled by `volgraph-core` — have a home; it is not
//! published and has no API beyond these helpers.

use std::fs;
use std::path::{Path, PathBuf};

/// The environment variable that, set to `1`, makes golden comparisons rewrite the golden files
/// instead of failing.
pub const BLESS_VAR: &str = "VOLGRAPH_BLESS";

/// The repository root (where the workspace `Cargo.toml` lives).
pub fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Whether `VOLGRAPH_BLESS=1` is set.
pub fn blessing() -> bool {
    std::env::var(BLESS_VAR).is_ok_and(|v| v == "1")
}

/// Every `*.ron` graph under `graphs/`, recursively, sorted, except `graphs/tf/` (transfer
/// functions, not graphs). New graphs are picked up without touching any test.
pub fn graph_files() -> std::io::Result<Vec<PathBuf>> {
    let root = repo_root().join("graphs");
    let mut out = Vec::new();
    collect_ron(&root, &root.join("tf"), &mut out)?;
    out.sort();
    Ok(out)
}

fn collect_ron(dir: &Path, skip: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    for entry in fs::read_dir(dir)? {
        let path = entry?.path();
        if path.is_dir() {
            if path != skip {
                collect_ron(&path, skip, out)?;
            }
        } else if path.extension().is_some_and(|e| e == "ron") {
            out.push(path);
        }
    }
    Ok(())
}

/// `path` relative to the repository root with `/` separators, as shown in messages and used
/// as the file name when compiling (so golden text does not depend on the checkout location).
pub fn relative_name(path: &Path) -> String {
    let rel = path.strip_prefix(repo_root()).unwrap_or(path);
    rel.components().map(|c| c.as_os_str().to_string_lossy()).collect::<Vec<_>>().join("/")
}

/// Compares `actual` with the golden file at `golden`. With `VOLGRAPH_BLESS=1` the file is
/// (re)written and the comparison passes. Otherwise a missing or different file is an `Err`
/// describing the first differing line, so a failing test says what changed.
pub fn check_golden(golden: &Path, actual: &str) -> Result<(), String> {
    if blessing() {
        return fs::write(golden, actual).map_err(|e| format!("{}: cannot write: {e}", golden.display()));
    }
    let expected = fs::read_to_string(golden).map_err(|e| {
        format!("{}: cannot read the golden file ({e}); run with {BLESS_VAR}=1 to create it", golden.display())
    })?;
    if expected == actual {
        return Ok(());
    }
    Err(format!(
        "{} differs from the output: {}\n--- expected\n{expected}\n--- actual\n{actual}\n(run with {BLESS_VAR}=1 to accept)",
        golden.display(),
        first_difference(&expected, actual)
    ))
}

/// `line N: expected "..." but got "..."` for the first line where two texts differ.
pub fn first_difference(expected: &str, actual: &str) -> String {
    let mut e = expected.lines();
    let mut a = actual.lines();
    let mut n = 1;
    loop {
        match (e.next(), a.next()) {
            (None, None) => return "the texts differ only in line endings".to_string(),
            (x, y) if x == y => n += 1,
            (x, y) => {
                return format!("line {n}: expected {:?} but got {:?}", x.unwrap_or("<end>"), y.unwrap_or("<end>"));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_difference_names_the_line() {
        assert_eq!(first_difference("a\nb\nc", "a\nx\nc"), "line 2: expected \"b\" but got \"x\"");
        assert_eq!(first_difference("a\n", "a\nb"), "line 2: expected \"<end>\" but got \"b\"");
    }

    #[test]
    fn graph_files_skip_transfer_functions() {
        let files = graph_files().expect("graphs/ is readable");
        assert!(files.iter().any(|f| f.ends_with("graphs/basic/fragment_raycast.ron")));
        assert!(files.iter().all(|f| !f.starts_with(repo_root().join("graphs/tf"))));
    }
}
