//! Every WGSL module under `shaders/` is assembled with `#import` and validated with naga, and
//! every failure is reported at once (STYLE.md "Passes, resources, shaders"; model: rerun's
//! `tests/shader_validation.rs`). Shared files under `shaders/common/` are checked through the
//! modules that import them; one that no module imports is validated on its own.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use naga::valid::{Capabilities, ValidationFlags, Validator};
use volgraph_core::shader_source::{assemble_with, default_shader_root};

/// `.wgsl` files directly in `dir`, as paths relative to the shader root (`prefix` + name).
fn wgsl_files(dir: &Path, prefix: &str) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: cannot list shaders: {e}", dir.display()))
        .filter_map(|entry| entry.ok())
        .map(|entry| entry.file_name().to_string_lossy().into_owned())
        .filter(|name| name.ends_with(".wgsl"))
        .map(|name| format!("{prefix}{name}"))
        .collect();
    names.sort();
    names
}

/// Assembles and validates `relative`; the module on success, naga's full diagnostic otherwise.
/// Files come from the folder on disk, then the generated `pass_params!` structs
/// (`params/NAME.wgsl`), as the runtime reads them with `--shaders`.
fn validate(root: &Path, relative: &str) -> Result<(naga::Module, Vec<PathBuf>), String> {
    validate_with(root, relative, &[])
}

/// [`validate`] with the `#if` names `defines` on.
fn validate_with(root: &Path, relative: &str, defines: &[&str]) -> Result<(naga::Module, Vec<PathBuf>), String> {
    let sources = volgraph_core::shader_source::ShaderSources::new()
        .with_disk(root)
        .with_generated(volgraph_passes::uniform_imports());
    let defines = defines.iter().map(|d| d.to_string()).collect();
    let source = assemble_with(&sources, relative, &defines).map_err(|e| e.to_string())?;
    let module = naga::front::wgsl::parse_str(&source.text)
        .map_err(|e| format!("parse error:\n{}", e.emit_to_string(&source.text)))?;
    Validator::new(ValidationFlags::all(), Capabilities::all())
        .validate(&module)
        .map_err(|e| format!("validation error:\n{}", e.emit_to_string(&source.text)))?;
    Ok((module, source.disk_paths()))
}

/// The resource globals of `module`: name → (group, binding).
fn bindings(module: &naga::Module) -> Vec<(String, u32, u32)> {
    module
        .global_variables
        .iter()
        .filter_map(|(_, var)| {
            let rb = var.binding.as_ref()?;
            Some((var.name.clone().unwrap_or_default(), rb.group, rb.binding))
        })
        .collect()
}

/// `#if` combinations the raycasters compile (crates/passes/src/march.rs): leaping over block
/// flags or the distance map, start estimates with leap hits, several volumes (on a device with
/// subgroups too: `Gpu::device_defines`), shadows.
const SETTINGS: &[&[&str]] = &[
    &["LEAP", "LEAP_BLOCKS"],
    &["LEAP", "LEAP_CUBES"],
    &["START", "LEAP_HITS", "FIRST_VISIBLE"],
    &["FUSION", "FUSION_LABELS", "FUSION_LABEL_READS"],
    &["FUSION", "FUSION_LABEL_MAP", "FUSION_LABEL_READS"],
    &["FUSION", "FUSION_LABEL_MAP", "FUSION_LABEL_READS", "LABELS_NEAREST"],
    &["FUSION", "FUSION_LABELS", "FUSION_LABEL_READS", "SUBGROUPS"],
    &["FUSION", "FUSION_LABEL_MAP", "FUSION_LABEL_READS", "SUBGROUPS"],
    &["FUSION", "FUSION_LABEL_MAP", "FUSION_LABEL_READS", "LABELS_NEAREST", "SUBGROUPS"],
    &["FUSION", "FUSION_SCALAR", "FUSION_OVERLAY", "FUSION_LABEL_READS", "SUBGROUPS"],
    &["FUSION", "FUSION_SCALAR"],
    &["FUSION", "FUSION_SCALAR", "FUSION_OVERLAY", "FUSION_LABEL_READS"],
    &["FUSION", "FUSION_SCALAR", "FUSION_THIRD"],
    &["FUSION", "FUSION_SCALAR", "FUSION_THIRD", "FUSION_FOURTH", "FUSION_OVERLAY", "FUSION_LABEL_READS"],
    &["FUSION", "FUSION_SCALAR", "FUSION_OVERLAY", "FUSION_LABEL_READS", "LABELS_NEAREST"],
    &["SHADOWS"],
    &["SHADOWS", "SHADING"],
    &["AMBIENT_OCCLUSION"],
    &["AMBIENT_OCCLUSION", "SHADING"],
    &["AMBIENT_OCCLUSION", "SHADOWS", "SHADING"],
];

#[test]
fn every_shader_validates() {
    let root = default_shader_root();
    let top = wgsl_files(&root, "");
    let common = wgsl_files(&root.join("common"), "common/");
    // A project with no shaders would pass vacuously; these are the ones the passes need.
    for needed in ["entry_points.wgsl", "ray_directions.wgsl", "raycast.wgsl", "raycast_compute.wgsl"] {
        assert!(top.iter().any(|t| t == needed), "shaders/{needed} is missing (found: {top:?})");
    }

    let mut failures = Vec::new();
    let mut imported = BTreeSet::new();
    for name in &top {
        match validate(&root, name) {
            Ok((_, files)) => imported.extend(files.into_iter().filter_map(|f| f.canonicalize().ok())),
            Err(e) => failures.push(format!("shaders/{name}: {e}")),
        }
        // Files a module imports only under an `#if` (the empty-space providers of the shared
        // march need the importer's `block_edge()`) are checked through it with the settings
        // the passes compile; a combination a module does not take may fail to assemble.
        for defines in SETTINGS {
            if let Ok((_, files)) = validate_with(&root, name, defines) {
                imported.extend(files.into_iter().filter_map(|f| f.canonicalize().ok()));
            }
        }
    }
    for name in &common {
        let path = root.join(name).canonicalize().unwrap_or_else(|_| root.join(name));
        if imported.contains(&path) {
            continue;
        }
        if let Err(e) = validate(&root, name) {
            failures.push(format!("shaders/{name} (imported by no module, validated alone): {e}"));
        }
    }
    assert!(failures.is_empty(), "{} shader(s) failed:\n\n{}", failures.len(), failures.join("\n\n"));
}

/// The executor binds by global name (naga reflection), so binding numbers only have to be
/// distinct within a module: every built-in shader declares `@binding(auto)` and the assembler
/// numbers them (`shader_source::number_auto_bindings`) across `#import`ed files — no file has
/// to know another's numbers. Everything is in @group(0), and after assembly the numbers are
/// distinct (naga's validator rejects a clash).
#[test]
fn bindings_are_in_group_zero_and_numbered_from_declarations() {
    let root = default_shader_root();
    let mut failures = Vec::new();
    for name in wgsl_files(&root, "") {
        let text = std::fs::read_to_string(root.join(&name)).unwrap_or_default();
        for (i, line) in text.lines().enumerate() {
            if line.contains("@binding(") && !line.contains("@binding(auto)") && !line.trim_start().starts_with("//") {
                failures.push(format!("shaders/{name}:{}: a hand-numbered binding; write @binding(auto)", i + 1));
            }
        }
        let Ok((module, _)) = validate(&root, &name) else {
            continue; // reported by `every_shader_validates`
        };
        let mut seen = std::collections::BTreeSet::new();
        for (global, group, binding) in bindings(&module) {
            if group != 0 {
                failures.push(format!("shaders/{name}: `{global}` is in @group({group}); everything is in @group(0)"));
            }
            if !seen.insert(binding) {
                failures.push(format!("shaders/{name}: binding {binding} used twice"));
            }
        }
    }
    assert!(failures.is_empty(), "{} binding problem(s):\n{}", failures.len(), failures.join("\n"));
}
