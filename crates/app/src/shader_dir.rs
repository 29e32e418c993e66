//! Where shaders come from for a graph: the shaders compiled into the binary, with a folder on
//! disk in front of them when one is given (`--shaders DIR`) or found beside the graph's
//! workspace (a `shaders/common/frame.wgsl` in the graph's folder or one of its parents). A
//! developer's edits then show up (and hot-reload in `volgraph view`); an installed binary run
//! anywhere else uses its own copy.

use std::path::{Path, PathBuf};

use volgraph_core::shader_source::ShaderSources;

/// How far up from the graph file to look for a `shaders/` folder.
const LEVELS: usize = 4;

/// The `shaders/` folder of the workspace holding `graph`, if any.
pub fn find_beside(graph: &Path) -> Option<PathBuf> {
    let start = graph.canonicalize().ok()?;
    start
        .ancestors()
        .skip(1)
        .take(LEVELS)
        .map(|dir| dir.join("shaders"))
        .find(|dir| dir.join("common/frame.wgsl").is_file())
}

/// `shaders/` folders of the graph's own project: beside the graph file or in its parent (an
/// example crate's `graphs/` and `shaders/`), holding WGSL-only pass kinds and shaders of
/// external crates; they do not need volgraph's `common/` files.
pub fn graph_local(graph: &Path) -> Vec<PathBuf> {
    let Some(dir) = graph.canonicalize().ok().and_then(|g| g.parent().map(Path::to_path_buf)) else {
        return Vec::new();
    };
    [Some(dir.join("shaders")), dir.parent().map(|p| p.join("shaders"))]
        .into_iter()
        .flatten()
        .filter(|d| d.is_dir())
        .collect()
}

/// The sources for `graph`: `explicit` or the folder found beside it first, then the graph's own
/// `shaders/` folders ([`graph_local`]), then the built-in shaders; the first disk folder used,
/// if any.
pub fn sources_for(graph: &Path, explicit: Option<&Path>) -> (ShaderSources, Option<PathBuf>) {
    let disk = explicit.map(Path::to_path_buf).or_else(|| find_beside(graph));
    let mut sources = crate::program::shaders();
    let mut local = graph_local(graph);
    local.retain(|d| {
        Some(d) != disk.as_ref() && d.canonicalize().ok() != disk.as_ref().and_then(|x| x.canonicalize().ok())
    });
    for dir in local.into_iter().rev() {
        sources = sources.prepend_disk(dir);
    }
    match &disk {
        Some(dir) => (sources.prepend_disk(dir.clone()), disk),
        None => (sources, None),
    }
}
