//! Every WGSL module under `shaders/` is assembled with `#import` and validated with naga, and
//! every failure is reported at once (STYLE.md "Passes, resources, shaders"; model: rerun's
//! `tests/shader_validation.rs`). Shared files under `shaders/common/` are checked through the
//! modules that import them; one that no module imports is validated on its own.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use naga::valid::{Capabilities, ValidationFlags, Validator};
use volgraph_core::shader_source::{default_shader_root, load_shader};

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
fn validate(root: &Path, relative: &str) -> Result<(naga::Module, Vec<PathBuf>), String> {
    let source = load_shader(root, relative).map_err(|e| e.to_string())?;
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

/// The executor binds by global name (naga reflection), so binding numbers are free per module,
/// but everything is in @group(0), and a module that imports a shared common file keeps that
/// file's globals at the slots it declares (binding numbers are unique within a module: naga's
/// validator already rejects a clash).
#[test]
fn bindings_are_in_group_zero_and_shared_globals_keep_their_slots() {
    let root = default_shader_root();
    // (global, declaring file, binding)
    let shared = [
        ("frame", "common/frame.wgsl", 0),
        ("volume", "common/volume.wgsl", 1),
        ("linear_clamp", "common/volume.wgsl", 2),
        ("tf", "common/volume.wgsl", 3),
        ("params", "common/raycast_params.wgsl", 4),
    ];
    let mut failures = Vec::new();
    for name in wgsl_files(&root, "") {
        let Ok((module, files)) = validate(&root, &name) else {
            continue; // reported by `every_shader_validates`
        };
        let imports = |common: &str| files.iter().any(|f| f.ends_with(common));
        for (global, group, binding) in bindings(&module) {
            if group != 0 {
                failures.push(format!("shaders/{name}: `{global}` is in @group({group}); everything is in @group(0)"));
            }
            if let Some((_, file, want)) = shared.iter().find(|(n, _, _)| *n == global)
                && imports(file)
                && binding != *want
            {
                failures.push(format!(
                    "shaders/{name}: `{global}` (from shaders/{file}) is at @binding({binding}), expected {want}"
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{} binding problem(s):\n{}", failures.len(), failures.join("\n"));
}
