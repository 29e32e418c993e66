//! `volgraph passes [KIND]`: every registered pass kind with its summary (and paper section),
//! ports (direction, what they carry, formats), parameters (type, default, range, doc) and the
//! scene features it serves — what a graph author needs without reading the Rust.

use std::fmt::Write as _;

use anyhow::anyhow;
use volgraph_core::params::ParamKind;
use volgraph_core::{Access, Params, PassPlugin, PortKind, Registry};

/// `registry` plus the WGSL-only kinds graph file `path` declares.
pub fn with_graph_kinds(registry: &Registry, path: &std::path::Path) -> anyhow::Result<Registry> {
    let source = crate::inputs::read_graph(path)?;
    let doc = volgraph_core::graph::parse_graph(&source).map_err(|d| anyhow!("{}: {}", path.display(), d.message))?;
    Ok(volgraph_core::wgsl_pass::with_graph_kinds(registry, &doc.kinds))
}

/// The listing of every kind (one line each), or the full description of `kind`.
pub fn describe(registry: &Registry, kind: Option<&str>) -> anyhow::Result<String> {
    let Some(kind) = kind else {
        let mut out = String::new();
        let kinds = registry.kinds();
        let width = kinds.iter().map(|k| k.len()).max().unwrap_or(0);
        for k in kinds {
            let plugin = registry.get(k).expect("listed by the registry");
            let _ = writeln!(out, "{k:width$}  {}", plugin.summary());
        }
        let _ = writeln!(out, "\n`volgraph passes KIND` shows one kind's ports and parameters.");
        return Ok(out);
    };
    let plugin = registry.get(kind).ok_or_else(|| {
        let kinds = registry.kinds();
        let hint = volgraph_core::suggest::closest(kind, kinds.iter().copied())
            .map_or_else(String::new, |c| format!("did you mean \"{c}\"? "));
        anyhow!("no pass kind \"{kind}\"; {hint}known kinds: {}", kinds.join(", "))
    })?;
    Ok(describe_kind(plugin.as_ref()))
}

fn describe_kind(plugin: &dyn PassPlugin) -> String {
    let mut out = String::new();
    let specs = plugin.params();
    let defaults = Params::defaults(&specs);
    let _ = writeln!(out, "{}\n  {}\n", plugin.kind(), plugin.summary());
    let _ = writeln!(out, "ports (with default parameters; some depend on them):");
    for port in plugin.ports(&defaults) {
        let direction = match port.access {
            Access::Read => "in    ",
            Access::Write => "out   ",
            Access::Modify => "in/out",
        };
        let optional = if port.required || !port.is_input() { "" } else { " (optional)" };
        let _ = writeln!(out, "  {direction} {:<14} {}{optional}", port.name, carries(&port.kind));
    }
    if !specs.is_empty() {
        let _ = writeln!(out, "\nparameters:");
    }
    for spec in &specs {
        let (ty, default, range) = match &spec.kind {
            ParamKind::Float { default, min, max } => ("float", format!("{default}"), format!("{min}..={max}")),
            ParamKind::UInt { default, min, max } => ("uint", format!("{default}"), format!("{min}..={max}")),
            ParamKind::Bool { default } => ("bool", format!("{default}"), String::new()),
            ParamKind::Choice { default, options } => ("choice", format!("\"{default}\""), options.join(" | ")),
        };
        let _ = writeln!(out, "  {:<18} {ty:<6} default {default:<10} {range}", spec.name);
        let _ = writeln!(out, "      {}", spec.doc);
    }
    let features = plugin.features();
    if !features.is_empty() {
        let _ = writeln!(out, "\nscheduled only when these scene features are on: {}", features.join(", "));
    }
    let shaders = plugin.shaders(&defaults);
    if !shaders.is_empty() {
        let uses: Vec<String> = shaders.iter().map(|s| format!("shaders/{} ({})", s.file, s.entry_point)).collect();
        let _ = writeln!(out, "\nshaders: {}", uses.join(", "));
    }
    if plugin.is_sink() {
        let _ = writeln!(out, "\na sink: never culled");
    }
    out
}

fn carries(kind: &PortKind) -> String {
    match kind {
        PortKind::Target { formats, .. } => {
            let names: Vec<&str> = formats.iter().map(|f| f.name()).collect();
            format!("target {}", names.join(" | "))
        }
        PortKind::Volume => "the volume (3D texture)".to_string(),
        PortKind::VolumeVoxels => "the volume's voxels (CPU; the pass uploads what it needs)".to_string(),
        PortKind::TransferFunction => "the transfer function (LUT)".to_string(),
        PortKind::LabelTable => "a label table (2D, 256 labels per row)".to_string(),
        PortKind::Owned(t) => format!("owned resource \"{t}\""),
        PortKind::Buffer { bytes, bytes_per_pixel } => {
            format!("storage buffer ({bytes} bytes + {bytes_per_pixel} per pixel)")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_kind_is_listed_and_described() {
        let registry = volgraph_passes::builtin_registry();
        let list = describe(&registry, None).expect("lists");
        for kind in registry.kinds() {
            assert!(list.lines().any(|l| l.starts_with(kind)), "{kind} missing from\n{list}");
            let one = describe(&registry, Some(kind)).expect("describes");
            assert!(one.starts_with(kind) && one.contains("ports"), "{one}");
        }
        let bricks = describe(&registry, Some("raycast_bricks")).expect("describes");
        assert!(
            bricks.contains("brick_cells") && bricks.contains("default 32") && bricks.contains("voxels"),
            "{bricks}"
        );
    }

    /// `--graph` adds the graph's own WGSL-only kinds, with their declared ports and parameters.
    #[test]
    fn a_graphs_wgsl_only_kinds_are_listed_with_it() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/radiology/graphs/mip_enhanced.ron");
        let registry = with_graph_kinds(&volgraph_passes::builtin_registry(), &path).expect("reads");
        let one = describe(&registry, Some("edge_enhance")).expect("describes");
        assert!(one.contains("unsharp masking") && one.contains("strength") && one.contains("enhanced"), "{one}");
    }

    #[test]
    fn an_unknown_kind_names_the_closest() {
        let registry = volgraph_passes::builtin_registry();
        let err = describe(&registry, Some("raycats")).expect_err("unknown").to_string();
        assert!(err.contains("did you mean \"raycast\"") && err.contains("known kinds"), "{err}");
    }
}
