//! `docs/writing_a_pass.md` quotes this crate: every ```` ```rust ````, ```` ```wgsl ```` and
//! ```` ```ron ```` block must appear verbatim in its sources, shaders and graphs (so the guide's
//! code is code that compiles and is tested here), and every graph of the crate plans with
//! volgraph's registry plus this crate's.

use std::path::{Path, PathBuf};

fn crate_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The text of every file with extension `ext` under `dir`, concatenated.
fn texts(dir: &Path, ext: &str) -> String {
    let mut out = String::new();
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir).expect("dir").map(|e| e.expect("entry").path()).collect();
    entries.sort();
    for path in entries.into_iter().filter(|p| p.extension().is_some_and(|e| e == ext)) {
        out.push_str(&std::fs::read_to_string(&path).expect("readable"));
        out.push('\n');
    }
    out
}

/// The fenced blocks of `markdown` in language `lang`.
fn blocks<'a>(markdown: &'a str, lang: &str) -> Vec<&'a str> {
    let fence = format!("```{lang}\n");
    let mut out = Vec::new();
    let mut rest = markdown;
    while let Some(start) = rest.find(&fence) {
        let body = &rest[start + fence.len()..];
        let end = body.find("```").expect("closed block");
        out.push(&body[..end]);
        rest = &body[end + 3..];
    }
    out
}

#[test]
fn every_code_block_of_the_guide_is_quoted_from_this_crate() {
    let guide = std::fs::read_to_string(crate_dir().join("../../docs/writing_a_pass.md")).expect("the guide");
    for (lang, dir, ext) in [("rust", "src", "rs"), ("wgsl", "shaders", "wgsl"), ("ron", "graphs", "ron")] {
        let sources = texts(&crate_dir().join(dir), ext);
        let found = blocks(&guide, lang);
        assert!(!found.is_empty(), "the guide shows {lang} code");
        for block in found {
            assert!(sources.contains(block), "this {lang} block of the guide is not in {dir}/*.{ext}:\n{block}");
        }
    }
}

#[test]
fn every_graph_of_the_crate_plans() {
    let mut registry = volgraph_passes::builtin_registry();
    volgraph_example_radiology::register(&mut registry);
    let dir = crate_dir().join("graphs");
    let mut planned = 0;
    for entry in std::fs::read_dir(&dir).expect("graphs/") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "ron") {
            let source = std::fs::read_to_string(&path).expect("readable");
            let name = path.file_name().expect("name").to_string_lossy().to_string();
            let plan = volgraph_core::compile(&name, &source, &registry, &volgraph_core::CompileOptions::new(640, 480))
                .unwrap_or_else(|d| panic!("{d}"));
            assert!(plan.steps.iter().any(|s| s.kind == "edge_enhance") && plan.steps.iter().any(|s| s.kind == "mip"));
            planned += 1;
        }
    }
    assert!(planned > 0);
}
