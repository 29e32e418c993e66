//! Issue 20: the graph compiler builds without a GPU stack. Walks `Cargo.lock` from
//! `volgraph-compiler` through every dependency the lock file records (normal, build and this
//! crate's dev-dependencies: a superset of `cargo tree -e normal`) and finds no wgpu, wgpu-core
//! or wgpu-hal — only naga and wgpu-types, which are plain data. Issue 42: nor the volume
//! loaders' stack (DICOM, JPEG 2000) or rayon, which `volgraph-accel` brings; the compiler takes
//! its cuts and text-file reading from `volgraph-base`.

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

/// The workspace's `Cargo.lock` as a graph.
fn workspace_lock() -> BTreeMap<String, Vec<String>> {
    let lock = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../Cargo.lock")).expect("Cargo.lock");
    lock_graph(&lock)
}

/// Every package reached from `root` in `graph`, `root` included.
fn reached(graph: &BTreeMap<String, Vec<String>>, root: &str) -> BTreeSet<String> {
    let mut seen = BTreeSet::new();
    let mut stack = vec![root.to_string()];
    while let Some(name) = stack.pop() {
        if seen.insert(name.clone()) {
            stack.extend(graph.get(&name).cloned().unwrap_or_default());
        }
    }
    seen
}

#[test]
fn the_compiler_depends_on_no_wgpu() {
    let graph = workspace_lock();
    let seen = reached(&graph, "volgraph-compiler");
    assert!(seen.contains("naga") && seen.contains("wgpu-types"), "the walk reached the compiler's dependencies");
    for gpu in ["wgpu", "wgpu-core", "wgpu-hal", "volgraph-core", "volgraph-passes"] {
        assert!(!seen.contains(gpu), "volgraph-compiler reaches {gpu}");
    }
    // The walk is real: from the runtime crate, wgpu is reached.
    assert!(reached(&graph, "volgraph-core").contains("wgpu"), "volgraph-core reaches wgpu");
}

/// The packages of the volume loaders' stack and of rayon among `names`.
fn loader_stack(names: &BTreeSet<String>) -> Vec<&str> {
    names
        .iter()
        .map(String::as_str)
        .filter(|n| ["dicom", "jpeg", "openjp2", "rayon"].iter().any(|w| n.contains(w)))
        .collect()
}

#[test]
fn the_compiler_depends_on_no_volume_loader_or_rayon() {
    let graph = workspace_lock();
    let seen = reached(&graph, "volgraph-compiler");
    assert!(seen.contains("volgraph-base"), "the walk reached the compiler's dependencies");
    assert!(!seen.contains("volgraph-accel"), "volgraph-compiler reaches volgraph-accel");
    let found = loader_stack(&seen);
    assert!(found.is_empty(), "volgraph-compiler reaches {found:?}");
    // The walk is real: from the CPU data crate, DICOM and rayon are reached.
    let accel = reached(&graph, "volgraph-accel");
    let from_accel = loader_stack(&accel);
    assert!(
        from_accel.iter().any(|n| n.contains("dicom")) && from_accel.contains(&"rayon"),
        "volgraph-accel reaches the DICOM stack and rayon: {from_accel:?}"
    );
}
