//! The `volgraph set` fuzzer of issue 47: the shipped graph files (`graphs/**`), mutated — hostile
//! tokens, a duplicated map entry, CRLF line ends, a byte-order mark, a `#![enable(...)]` header,
//! comments, cuts — and one random assignment (a parameter or input the graph has, a new one,
//! a name it lacks; values valid, out of range and hostile) applied by [`crate::set_cmd::run`]
//! to a file, read-only now and then. The property:
//! - on an error the file is byte for byte what it was, and no temporary file is left;
//! - on success exactly one value's text changed: one replaced span (the old text one RON value,
//!   the file identical byte for byte before and after it) or, for a parameter the file did not
//!   write, only insertions holding that entry (and a comma); a CRLF file keeps only CRLF ends;
//! - the result reads as the same graph with that one value changed (the parsed graph compared
//!   whole: the copy that takes effect was edited), and `set` compiled it before writing;
//! - a read-only file is never written; no panic, no hang (each case under `HANG_SECONDS`).
//!
//! `VOLGRAPH_FUZZ_CASES` sets the number of cases (default 256 in CI).

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use proptest::prelude::*;
use volgraph_core::graph::ast::{GraphDoc, InputKind, NodeDoc};
use volgraph_core::graph::edit::{SetTarget, TextEdit, apply as apply_edits, edit_for};
use volgraph_core::graph::parse_graph;

mod inputs;

use inputs::*;

const HANG_SECONDS: f64 = 5.0;

fn cases() -> u32 {
    std::env::var("VOLGRAPH_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(256)
}

struct Seeds {
    texts: Vec<String>,
    /// The folder the case's graph file is written in.
    dir: PathBuf,
}

fn seeds() -> &'static Seeds {
    static SEEDS: OnceLock<Seeds> = OnceLock::new();
    SEEDS.get_or_init(|| {
        fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
            let Ok(entries) = std::fs::read_dir(dir) else { return };
            for p in entries.flatten().map(|e| e.path()) {
                if p.is_dir() && p.file_name().is_some_and(|n| n != "tf") {
                    walk(&p, out);
                } else if p.extension().is_some_and(|e| e == "ron") {
                    out.push(p);
                }
            }
        }
        let mut files = Vec::new();
        walk(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../../graphs"), &mut files);
        files.sort();
        let dir = std::env::temp_dir().join(format!("volgraph-set-fuzz-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let _ = std::fs::create_dir_all(&dir);
        Seeds { texts: files.iter().filter_map(|p| std::fs::read_to_string(p).ok()).collect(), dir }
    })
}

/// What one case gave.
#[derive(Debug, PartialEq, Eq, PartialOrd, Ord, Clone, Copy)]
enum Outcome {
    /// Refused, the file untouched: the mutated file is no graph.
    RefusedBrokenFile,
    /// Refused: a pass, parameter or input the graph does not have.
    RefusedUnknownName,
    /// Refused: not one plain RON value, or not a Scalar input.
    RefusedBadValue,
    /// Refused: the edited graph does not compile (a value out of range, a file that parsed but
    /// does not check).
    RefusedDoesNotCompile,
    /// Refused for another reason.
    RefusedOther,
    /// A read-only file refused.
    RefusedReadOnly,
    /// One value's text replaced.
    Replaced,
    /// A parameter the file did not write added.
    Inserted,
    /// The value already had that text: nothing written.
    Unchanged,
}

fn no_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

/// `doc` with `target` set to `value`, as the compiler would read it.
fn expected_doc(mut doc: GraphDoc, target: &SetTarget, value: &str) -> Result<GraphDoc, String> {
    match target {
        SetTarget::Input(name) => {
            let kind: InputKind =
                ron::from_str(&format!("Scalar({value})")).map_err(|e| format!("Scalar({value}): {e}"))?;
            doc.inputs.insert(name.clone(), kind);
        }
        SetTarget::Param { pass, param } => {
            let value: ron::Value = ron::from_str(value).map_err(|e| format!("{value}: {e}"))?;
            let passes = doc.passes.iter_mut().flat_map(|n| match n {
                NodeDoc::Pass(p) => vec![p],
                NodeDoc::Repeat(r) => r.body.iter_mut().collect(),
            });
            let p = passes.filter(|p| &p.id == pass).last().ok_or("the pass is not in the graph")?;
            p.params.insert(param.clone(), value);
        }
    }
    Ok(doc)
}

/// Checks the text of a successful edit: one value replaced, or only the new entry inserted.
fn check_text(
    original: &str,
    edited: &str,
    edits: &[TextEdit],
    target: &SetTarget,
    value: &str,
) -> Result<Outcome, String> {
    if apply_edits(original, edits) != edited {
        return Err("the file is not the original with the reported edits".into());
    }
    if original.contains('\n')
        && !original.replace("\r\n", "").contains('\n')
        && edited.replace("\r\n", "").contains('\n')
    {
        return Err("a CRLF file got an LF line end".into());
    }
    match edits {
        [e] if e.span.start < e.span.end => {
            let old = &original[e.span.start..e.span.end];
            ron::from_str::<ron::Value>(old).map_err(|_| format!("the replaced text {old:?} is not one value"))?;
            let tail = original.len() - e.span.end;
            let same_outside = edited.as_bytes()[..e.span.start] == original.as_bytes()[..e.span.start]
                && edited.as_bytes()[edited.len() - tail..] == original.as_bytes()[e.span.end..];
            if !same_outside || &edited[e.span.start..edited.len() - tail] != value {
                return Err("bytes outside the value's span changed".into());
            }
            Ok(Outcome::Replaced)
        }
        _ if edits.iter().all(|e| e.span.start == e.span.end) => {
            let SetTarget::Param { param, .. } = target else { return Err("an input was inserted".into()) };
            let entry = format!("\"{param}\": {value}");
            let inserted: String = edits.iter().map(|e| e.text.as_str()).collect();
            let rest = inserted.replacen(&entry, "", 1).replacen("params: {}", "", 1);
            if !inserted.contains(&entry) || rest.chars().any(|c| !(c.is_whitespace() || c == ',')) {
                return Err(format!("inserted {inserted:?}, not only the entry {entry}"));
            }
            Ok(Outcome::Inserted)
        }
        _ => Err(format!("edits that replace more than one value: {edits:?}")),
    }
}

fn run_case(bytes: &[u8], target: &str, value: &str, read_only: bool) -> Result<Outcome, String> {
    let dir = &seeds().dir;
    let path = dir.join("g.ron");
    let _ = set_writable(&path);
    std::fs::write(&path, bytes).map_err(|e| format!("writing the case: {e}"))?;
    if read_only {
        set_read_only(&path).map_err(|e| format!("chmod: {e}"))?;
    }
    let assignment = format!("{target}={value}");
    let outcome = crate::set_cmd::run(&path, std::slice::from_ref(&assignment));
    let after = std::fs::read(&path).map_err(|e| format!("reading back: {e}"))?;
    let left: Vec<_> = std::fs::read_dir(dir)
        .map_err(|e| e.to_string())?
        .flatten()
        .map(|e| e.file_name())
        .filter(|n| n != "g.ron")
        .collect();
    if !left.is_empty() {
        return Err(format!("files left beside the graph: {left:?}"));
    }
    let error = match outcome {
        Err(e) => Some((matches!(e, crate::cli::CliError::Graph(_)), crate::cli::error_text(&e))),
        Ok(_) => None,
    };
    if let Some((compile_error, e)) = error {
        if after != bytes {
            return Err(format!("refused ({e}) but the file changed"));
        }
        if e.trim().is_empty() {
            return Err("an empty error".into());
        }
        let has = |words: &[&str]| words.iter().any(|w| e.contains(w));
        return Ok(match () {
            () if compile_error => Outcome::RefusedDoesNotCompile,
            () if read_only && has(&["is read-only"]) => Outcome::RefusedReadOnly,
            () if has(&["the graph does not parse", "not valid UTF-8", "could not be read for positions"]) => {
                Outcome::RefusedBrokenFile
            }
            () if has(&["has no pass", "has no input", "expected PASS.PARAM"]) => Outcome::RefusedUnknownName,
            () if has(&["not a RON value", "control character", "plain RON value", "not a Scalar"]) => {
                Outcome::RefusedBadValue
            }
            () => Outcome::RefusedOther,
        });
    }
    let original = std::str::from_utf8(bytes).map_err(|_| "set accepted a file that is not UTF-8".to_string())?;
    let edited = std::str::from_utf8(&after).map_err(|_| "set wrote a file that is not UTF-8".to_string())?;
    let target = SetTarget::parse(target)?;
    let value = value.trim();
    let edits = edit_for(original, &target, value)?;
    if after == bytes {
        // Only where the value already had that text: else `set` said yes and wrote nothing.
        if apply_edits(original, &edits) != original {
            return Err("set succeeded but the file was not written".into());
        }
        return Ok(Outcome::Unchanged);
    }
    if read_only {
        return Err("a read-only file was written".into());
    }
    let outcome = check_text(original, edited, &edits, &target, value)?;
    let before = parse_graph(no_bom(original)).map_err(|d| format!("the original does not parse: {}", d.message))?;
    let after = parse_graph(no_bom(edited)).map_err(|d| format!("the result does not parse: {}", d.message))?;
    let expected = expected_doc(before, &target, value)?;
    if format!("{after:?}") != format!("{expected:?}") {
        return Err(format!("the result is not the graph with {target} = {value}:\n{after:?}\nexpected\n{expected:?}"));
    }
    Ok(outcome)
}

#[cfg(unix)]
fn set_read_only(path: &Path) -> std::io::Result<()> {
    use std::os::unix::fs::PermissionsExt as _;
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o444))
}

#[cfg(unix)]
fn set_writable(path: &Path) -> std::io::Result<()> {
    use std::os::unix::fs::PermissionsExt as _;
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o644))
}

#[cfg(not(unix))]
fn set_read_only(path: &Path) -> std::io::Result<()> {
    let mut p = std::fs::metadata(path)?.permissions();
    p.set_readonly(true);
    std::fs::set_permissions(path, p)
}

#[cfg(not(unix))]
fn set_writable(path: &Path) -> std::io::Result<()> {
    let mut p = std::fs::metadata(path)?.permissions();
    p.set_readonly(false);
    std::fs::set_permissions(path, p)
}

/// Cases run so far (each counted once it passed; a failing case stops the run).
static DONE: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

#[test]
fn set_on_mutated_graphs_edits_one_value_or_leaves_the_file_untouched() {
    let count = seeds().texts.len();
    assert!(count >= 10, "the shipped graphs ({count})");
    let strategy = (
        0..count,
        prop_oneof![1 => Just(Vec::new()), 3 => proptest::collection::vec(mutation(), 1..4)],
        pick(),
        prop_oneof![4 => 0..VALID, 4 => 0..VALUES.len(), 1 => Just(usize::MAX)],
        proptest::bool::weighted(0.05),
    );
    type Case = (usize, Vec<Mutation>, Pick, usize, bool);
    let prepared = |(seed, mutations, pick, value, read_only): &Case| {
        let bytes = mutate(&seeds().texts[*seed], mutations);
        let (target, declared_value) = target_text(&String::from_utf8_lossy(&bytes), pick);
        // usize::MAX: the value the file writes now, written again (a no-op).
        let value = declared_value.unwrap_or_else(|| {
            VALUES.get(*value).map_or_else(
                || {
                    let text = String::from_utf8_lossy(&bytes).into_owned();
                    SetTarget::parse(&target)
                        .ok()
                        .and_then(|t| edit_for(&text, &t, "0").ok())
                        .and_then(|e| e.first().map(|e| text[e.span.start..e.span.end].to_string()))
                        .unwrap_or_default()
                },
                |v| (*v).to_string(),
            )
        });
        (bytes, target, value, *read_only)
    };
    let run = crate::fuzz_runner::fuzz(
        &strategy,
        cases(),
        HANG_SECONDS,
        |case| {
            let (bytes, target, value, read_only) = prepared(case);
            format!("set {target}={value:?} (read-only: {read_only}) on\n{}", String::from_utf8_lossy(&bytes))
        },
        |case| {
            let (bytes, target, value, read_only) = prepared(case);
            let outcome = run_case(&bytes, &target, &value, read_only);
            // A long run says how far it got (a run stopped early is reported by its count).
            let done = DONE.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if done.is_multiple_of(50_000) {
                eprintln!("set fuzz: {done} cases passed so far");
            }
            outcome
        },
    );
    let _ = std::fs::remove_dir_all(&seeds().dir);
    if let Some(failure) = run.failure {
        panic!("{failure}");
    }
    let (total, counts) = (run.total(), &run.counts);
    eprintln!(
        "set fuzz: {total} cases, 0 panics, 0 hangs (slowest {:.1} ms), 0 files changed on error, 0 wrong edits; \
         outcomes {counts:?}",
        run.slowest.as_secs_f64() * 1e3
    );
    // Not vacuous: values replaced, entries inserted and assignments refused.
    if total >= 200 {
        for outcome in [Outcome::RefusedDoesNotCompile, Outcome::Replaced, Outcome::Inserted] {
            assert!(counts.contains_key(&outcome), "no {outcome:?}: {counts:?}");
        }
    }
}

#[test]
fn mutations_do_what_they_say() {
    let text = "a: 1,\nb: 2,\n";
    assert_eq!(mutate(text, &[Mutation::DuplicateLine(0.0, None)]), b"a: 1,\na: 1,\nb: 2,\n");
    assert_eq!(mutate(text, &[Mutation::DuplicateLine(0.0, Some(12))]), b"a: 1,\na: 0.25,\nb: 2,\n");
    assert_eq!(mutate(text, &[Mutation::Crlf, Mutation::Bom]), "\u{feff}a: 1,\r\nb: 2,\r\n".as_bytes());
}
