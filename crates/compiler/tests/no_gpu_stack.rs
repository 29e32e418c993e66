//! Issue 20: the graph compiler builds without a GPU stack. Walks `Cargo.lock` from
//! `volgraph-compiler` through every dependency the lock file records (normal, build and this
//! crate's dev-dependencies: a superset of `cargo tree -e normal`) and finds no wgpu, wgpu-core
//! or wgpu-hal — only naga and wgpu-types, which are plain data.

use std::collections::{BTreeMap, BTreeSet};

/// `name → dependency names` of every package in the lock file.
fn lock_graph(text: &str) -> BTreeMap<String, Vec<String>> {
    let mut graph = BTreeMap::new();
    for block in text.split("[[package]]").skip(1) {
        let name = block
            .lines()
            .find_map(|l| l.strip_prefix("name = \""))
            .and_then(|l| l.strip_suffix('"'))
            .expect("every package has a name")
            .to_string();
        let deps = match block.split_once("dependencies = [") {
            Some((_, rest)) => rest
                .split(']')
                .next()
                .unwrap_or_default()
                .split(',')
                .filter_map(|d| d.trim().trim_matches('"').split_whitespace().next().map(str::to_string))
                .filter(|d| !d.is_empty())
                .collect(),
            None => Vec::new(),
        };
        graph.insert(name, deps);
    }
    graph
}

#[test]
fn the_compiler_depends_on_no_wgpu() {
    let lock = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../Cargo.lock")).expect("Cargo.lock");
    let graph = lock_graph(&lock);
    let mut seen = BTreeSet::new();
    let mut stack = vec!["volgraph-compiler".to_string()];
    while let Some(name) = stack.pop() {
        if seen.insert(name.clone()) {
            stack.extend(graph.get(&name).cloned().unwrap_or_default());
        }
    }
    assert!(seen.contains("naga") && seen.contains("wgpu-types"), "the walk reached the compiler's dependencies");
    for gpu in ["wgpu", "wgpu-core", "wgpu-hal", "volgraph-core", "volgraph-passes"] {
        assert!(!seen.contains(gpu), "volgraph-compiler reaches {gpu}");
    }
    // The walk is real: from the runtime crate, wgpu is reached.
    let mut from_core = BTreeSet::new();
    let mut stack = vec!["volgraph-core".to_string()];
    while let Some(name) = stack.pop() {
        if from_core.insert(name.clone()) {
            stack.extend(graph.get(&name).cloned().unwrap_or_default());
        }
    }
    assert!(from_core.contains("wgpu"), "volgraph-core reaches wgpu");
}
