//! Every ```` ```ron ```` block of `docs/graph_format.md` is a complete graph that compiles with
//! the test registry, with every scene feature off and on, so the documented format cannot
//! drift from the parser and checker.

mod support;

use volgraph_core::{CompileOptions, compile};

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

fn doc() -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/graph_format.md");
    std::fs::read_to_string(path).expect("docs/graph_format.md exists")
}

#[test]
fn every_ron_example_in_the_graph_format_doc_compiles() {
    let blocks = ron_blocks(&doc());
    assert!(blocks.len() >= 3, "expected the multipass, history and minimal examples, found {}", blocks.len());
    let all_features = ["reprojection", "antialias", "shading"];
    for (line, text) in &blocks {
        let name = format!("docs/graph_format.md (block at line {line})");
        for options in [CompileOptions::new(1920, 1080), CompileOptions::new(1920, 1080).with_features(all_features)] {
            if let Err(d) = compile(&name, text, &support::registry(), &options) {
                panic!("{d}\n\n{text}");
            }
        }
    }
}

#[test]
fn multipass_example_unrolls_its_segments() {
    let blocks = ron_blocks(&doc());
    let (_, text) = blocks.iter().find(|(_, t)| t.contains("kw_multipass")).expect("the multipass example");
    let plan =
        compile("kw.ron", text, &support::registry(), &CompileOptions::new(800, 600)).unwrap_or_else(|d| panic!("{d}"));
    // ceil(512 / 8) = 64 iterations of two passes, plus entry, dirs, clear and present, less
    // the last termination test: nothing reads the depth after the final segment, so it is culled.
    assert_eq!(plan.steps.len(), 4 + 2 * 64 - 1);
    let last: Vec<&str> = plan.steps[plan.steps.len() - 3..].iter().map(|s| s.label.as_str()).collect();
    assert_eq!(last, ["segments[62]/term", "segments[63]/seg", "present"]);
    assert_eq!(plan.resources[plan.outputs["image"]].name, "segments[63]/seg.color");
}

#[test]
fn history_example_gates_reprojection_and_antialiasing() {
    let blocks = ron_blocks(&doc());
    let (_, text) = blocks.iter().find(|(_, t)| t.contains("klein_coherence")).expect("the history example");
    let off = compile("klein.ron", text, &support::registry(), &CompileOptions::new(800, 600))
        .unwrap_or_else(|d| panic!("{d}"));
    let labels: Vec<&str> = off.steps.iter().map(|s| s.label.as_str()).collect();
    assert_eq!(labels, ["entry", "dirs", "march", "present"]);
    let on = compile(
        "klein.ron",
        text,
        &support::registry(),
        &CompileOptions::new(800, 600).with_features(["reprojection", "antialias"]),
    )
    .unwrap_or_else(|d| panic!("{d}"));
    let labels: Vec<&str> = on.steps.iter().map(|s| s.label.as_str()).collect();
    assert_eq!(labels, ["entry", "dirs", "splat", "fill", "march", "aa", "present"]);
    assert!(on.slots[on.resources[on.history["prev_hit"].source].slot.expect("a target")].persistent);
}

#[test]
fn block_extraction_finds_fenced_ron_only() {
    let md = "text\n```ron\nGraph()\n```\n```rust\nfn x() {}\n```\n```ron\nA\nB\n```\n";
    assert_eq!(ron_blocks(md), [(3, "Graph()\n".to_string()), (9, "A\nB\n".to_string())]);
}
