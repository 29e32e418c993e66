//! Every graph example in the docs (each ```` ```ron ```` block holding a whole `Graph(...)` in
//! `docs/*.md`, the README and the example crates' READMEs) compiles with the built-in passes,
//! with every scene feature off and on, and its shaders' bindings check out as `volgraph plan`
//! checks them: the documented format cannot drift from the kinds, parameters and ports that
//! exist (issue 19: the examples in `docs/graph_format.md` had drifted).

use std::path::{Path, PathBuf};

use volgraph_core::{CompileOptions, check_plan_bindings, compile};
use volgraph_passes::{builtin_registry, builtin_shaders};

/// The contents of the ```` ```ron ```` fenced blocks of a markdown text, with their 1-based
/// starting line.
fn ron_blocks(markdown: &str) -> Vec<(usize, String)> {
    let mut blocks = Vec::new();
    let mut current: Option<(usize, String)> = None;
    for (i, line) in markdown.lines().enumerate() {
        match &mut current {
            None if line.trim_start() == "```ron" => current = Some((i + 2, String::new())),
            Some(_) if line.trim_start() == "```" => blocks.extend(current.take()),
            Some((_, text)) => {
                text.push_str(line);
                text.push('\n');
            }
            None => {}
        }
    }
    blocks
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

/// Markdown files that may hold graph examples.
fn doc_files() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .expect("docs/ is readable")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    files.push(root().join("README.md"));
    files.push(root().join("scenes/README.md"));
    files.push(root().join("examples/radiology/README.md"));
    files.retain(|p| p.is_file());
    files.sort();
    files
}

/// `(file:line, text)` of every block that is a whole graph (not a fragment such as a
/// `kinds:` excerpt).
fn graph_examples() -> Vec<(String, String)> {
    let mut out = Vec::new();
    for file in doc_files() {
        let text = std::fs::read_to_string(&file).expect("readable");
        let name = file.strip_prefix(root()).unwrap_or(&file).display().to_string();
        for (line, block) in ron_blocks(&text) {
            let code: String =
                block.lines().filter(|l| !l.trim_start().starts_with("//")).collect::<Vec<_>>().join("\n");
            if code.trim_start().trim_start_matches(|c: char| c != 'G').starts_with("Graph(") {
                out.push((format!("{name}:{line}"), block));
            }
        }
    }
    out
}

#[test]
fn every_graph_example_in_the_docs_plans_with_the_built_in_passes() {
    let examples = graph_examples();
    assert!(
        examples.len() >= 3,
        "expected at least the multipass, history and minimal examples of docs/graph_format.md, found {examples:?}"
    );
    let registry = builtin_registry();
    let sources = builtin_shaders();
    let all = ["antialias", "shading", "preintegration", "jitter", "tricubic"];
    let mut failures = Vec::new();
    for (name, text) in &examples {
        for options in [CompileOptions::new(256, 256), CompileOptions::new(256, 256).with_features(all)] {
            match compile(name, text, &registry, &options) {
                Ok(plan) => {
                    let problems = check_plan_bindings(&plan, &registry, &sources);
                    if !problems.is_empty() {
                        let list: Vec<String> = problems.iter().map(|d| d.message.clone()).collect();
                        failures.push(format!("{name}: bindings:\n{}", list.join("\n")));
                    }
                }
                Err(d) => failures.push(format!("{name}:\n{d}")),
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn the_multipass_example_unrolls_its_segments() {
    let examples = graph_examples();
    let (name, text) = examples.iter().find(|(_, t)| t.contains("kw_multipass")).expect("the multipass example");
    let plan =
        compile(name, text, &builtin_registry(), &CompileOptions::new(800, 600)).unwrap_or_else(|d| panic!("{d}"));
    // ceil(512 / 8) = 64 iterations of two passes, plus entry, dirs, init and present, less
    // the last termination test: nothing reads the depth after the final segment, so it is culled.
    assert_eq!(plan.steps.len(), 4 + 2 * 64 - 1);
    let last: Vec<&str> = plan.steps[plan.steps.len() - 3..].iter().map(|s| s.label.as_str()).collect();
    assert_eq!(last, ["segments[62]/term", "segments[63]/seg", "present"]);
    assert_eq!(plan.resources[plan.outputs["image"]].name, "segments[63]/seg.accum");
}

#[test]
fn the_coherence_example_gates_antialiasing() {
    let examples = graph_examples();
    let (name, text) = examples.iter().find(|(_, t)| t.contains("klein_coherence")).expect("the Klein example");
    let registry = builtin_registry();
    let off = compile(name, text, &registry, &CompileOptions::new(64, 64)).unwrap_or_else(|d| panic!("{d}"));
    assert!(!off.steps.iter().any(|s| s.kind == "antialias"), "antialias is off by default");
    let on = compile(name, text, &registry, &CompileOptions::new(64, 64).with_features(["antialias"]))
        .unwrap_or_else(|d| panic!("{d}"));
    assert!(on.steps.iter().any(|s| s.kind == "antialias"), "--features antialias schedules it");
}

#[test]
fn block_extraction_finds_fenced_ron_only() {
    let md = "text\n```ron\nGraph()\n```\n```rust\nfn x() {}\n```\n```ron\nA\nB\n```\n";
    assert_eq!(ron_blocks(md), [(3, "Graph()\n".to_string()), (9, "A\nB\n".to_string())]);
}
