//! `volgraph set GRAPH PASS.PARAM=VALUE… input.NAME=VALUE…`: values written into a graph file at
//! their place — only the values' text changes, comments, order, layout, line endings, a
//! byte-order mark and `#![enable(...)]` attributes stay (`volgraph_core::graph::edit`). A key
//! the file writes twice is set where it takes effect (its last copy) and the earlier copies are
//! named. The edited text is compiled first: a bad value or an unknown name is a located error
//! (with a "did you mean") and the file is left untouched; the write is atomic
//! ([`crate::atomic_write`]: through a symbolic link to its target, never over a read-only file).

use std::path::Path;

use anyhow::anyhow;
use volgraph_core::compile;
use volgraph_core::graph::edit::{SetTarget, apply, edit_for, shadowed_copies};
use volgraph_core::graph::spans::line_col;

use crate::cli::{CliError, compile_options, display_name};

/// Sets every `TARGET=VALUE` of `assignments` in graph file `graph`; returns one line per value
/// (`file:line: march.step_voxels = 0.25 (was 0.5)`).
pub fn run(graph: &Path, assignments: &[String]) -> Result<String, CliError> {
    if graph.symlink_metadata().is_err() && crate::builtin_graphs::find(graph).is_some() {
        return Err(CliError::Other(anyhow!(
            "{}: is a built-in graph (compiled into volgraph), not a file: `set` edits a graph file; write it out \
             with `volgraph graphs --export {}` and give the path it prints",
            graph.display(),
            crate::builtin_graphs::normalized(graph)
        )));
    }
    let source = volgraph_accel::input_file::read_text(graph, "graph file").map_err(|e| anyhow!("{e}"))?;
    if assignments.is_empty() {
        return Err(CliError::Other(anyhow!("nothing to set: give PASS.PARAM=VALUE or input.NAME=VALUE")));
    }
    let shown = graph.display();
    // Applied one after another, each on the text the ones before it left (two new parameters
    // of a pass without `params` make one map); `at` follows each value's place as later edits
    // insert text before it.
    let mut edited = source.clone();
    // Per assignment: what, the value, where it now is, its note, and where the copies it
    // shadows are (offsets, moved with every later edit as `at` is).
    let mut done: Vec<(SetTarget, String, usize, String, Vec<usize>)> = Vec::new();
    for assignment in assignments {
        let Some((target, value)) = assignment.split_once('=') else {
            return Err(anyhow!("\"{assignment}\": expected PASS.PARAM=VALUE or input.NAME=VALUE").into());
        };
        let target = SetTarget::parse(target.trim()).map_err(|e| anyhow!("{e}"))?;
        if done.iter().any(|(t, ..)| *t == target) {
            return Err(anyhow!("{target} is set twice; give each name once").into());
        }
        let edit = edit_for(&edited, &target, value).map_err(|e| anyhow!("{shown}: {e}"))?;
        let last = edit.last().ok_or_else(|| anyhow!("{shown}: internal: no edit for {target}"))?;
        let was = &edited[last.span.start..last.span.end];
        let note = if was.is_empty() { "not in the file".to_string() } else { format!("was {was}") };
        let shadowed: Vec<usize> = shadowed_copies(&edited, &target).iter().map(|s| s.start).collect();
        // This edit moves every place found so far that lies after the text it replaces.
        let moved = |at: &mut usize| {
            let before: Vec<_> = edit.iter().filter(|e| e.span.end <= *at).collect();
            for e in before {
                *at = (*at + e.text.len()).saturating_sub(e.span.end - e.span.start);
            }
        };
        for (_, _, at, _, copies) in &mut done {
            moved(at);
            copies.iter_mut().for_each(moved);
        }
        let mut shadowed = shadowed;
        shadowed.iter_mut().for_each(moved);
        let at = last.span.start;
        edited = apply(&edited, &edit);
        done.push((target, value.trim().to_string(), at, note, shadowed));
    }
    // Checked like a compile: the edited text must compile, else nothing is written.
    let options = compile_options("256x256", &[], &[])?;
    compile(&display_name(graph), &edited, &crate::program::registry(), &options).map_err(CliError::Graph)?;
    if edited != source {
        crate::atomic_write::write_atomically(graph, &edited)?;
    }
    let lines = done
        .iter()
        .map(|(target, value, at, note, copies)| {
            let mut note = note.clone();
            if !copies.is_empty() {
                let lines: Vec<String> = copies.iter().map(|c| line_col(&edited, *c).0.to_string()).collect();
                note += &format!(
                    "; line {} writes it too, with no effect: the last copy counts — delete the other",
                    lines.join(", ")
                );
            }
            format!("{shown}:{}: {target} = {value} ({note})", line_col(&edited, *at).0)
        })
        .collect::<Vec<_>>()
        .join("\n");
    Ok(lines + "\n")
}
