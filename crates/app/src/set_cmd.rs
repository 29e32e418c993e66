//! `volgraph set GRAPH PASS.PARAM=VALUE… input.NAME=VALUE…`: values written into a graph file at
//! their place — only the values' text changes, comments, order and layout stay
//! (`volgraph_core::graph::edit`). The edited text is compiled first: a bad value or an unknown
//! name is a located error (with a "did you mean") and the file is left untouched; the write is
//! atomic (a sibling temporary file renamed over the graph).

use std::path::Path;

use anyhow::anyhow;
use volgraph_core::compile;
use volgraph_core::graph::edit::{SetTarget, TextEdit, apply, edit_for};
use volgraph_core::graph::spans::line_col;

use crate::cli::{CliError, compile_options, display_name};

/// Sets every `TARGET=VALUE` of `assignments` in graph file `graph`; returns one line per value
/// (`file:line: march.step_voxels = 0.25 (was 0.5)`).
pub fn run(graph: &Path, assignments: &[String]) -> Result<String, CliError> {
    if graph.symlink_metadata().is_err() && crate::builtin_graphs::find(graph).is_some() {
        return Err(CliError::Other(anyhow!(
            "{}: is a built-in graph (compiled into volgraph), not a file: `set` edits a graph file; copy it from \
             graphs/ in the source tree and give that path",
            graph.display()
        )));
    }
    let source = volgraph_accel::input_file::read_text(graph, "graph file").map_err(|e| anyhow!("{e}"))?;
    if assignments.is_empty() {
        return Err(CliError::Other(anyhow!("nothing to set: give PASS.PARAM=VALUE or input.NAME=VALUE")));
    }
    let mut edits: Vec<(SetTarget, String, Vec<TextEdit>)> = Vec::new();
    for assignment in assignments {
        let Some((target, value)) = assignment.split_once('=') else {
            return Err(anyhow!("\"{assignment}\": expected PASS.PARAM=VALUE or input.NAME=VALUE").into());
        };
        let target = SetTarget::parse(target.trim()).map_err(|e| anyhow!("{e}"))?;
        if edits.iter().any(|(t, _, _)| *t == target) {
            return Err(anyhow!("{target} is set twice; give each name once").into());
        }
        let edit = edit_for(&source, &target, value).map_err(|e| anyhow!("{}: {e}", graph.display()))?;
        edits.push((target, value.trim().to_string(), edit));
    }
    let all: Vec<TextEdit> = edits.iter().flat_map(|(_, _, e)| e.iter().cloned()).collect();
    let edited = apply(&source, &all);
    // Checked like a compile: the edited text must compile, else nothing is written.
    let options = compile_options("256x256", &[], &[])?;
    compile(&display_name(graph), &edited, &crate::program::registry(), &options).map_err(CliError::Graph)?;
    crate::atomic_write::write_atomically(graph, &edited)?;
    let lines = edits
        .iter()
        .map(|(target, value, edit)| {
            let first = &edit[edit.len() - 1];
            let (line, _) = line_col(&source, first.span.start);
            let was = &source[first.span.start..first.span.end];
            let was = if was.is_empty() { "not in the file".to_string() } else { format!("was {was}") };
            format!("{}:{line}: {target} = {value} ({was})", graph.display())
        })
        .collect::<Vec<_>>()
        .join("\n");
    Ok(lines + "\n")
}
