//! Rust and WGSL agree on the `#if` names: every `#if NAME` / `#if !NAME` in a shader under
//! `shaders/` is a constant of `volgraph_passes::defines` (the built-in passes') or one of the
//! compiler's frame defines (`volgraph_compiler::cut_effects`: the cuts and the sort-last
//! window) or the device's (`Gpu::device_defines`), and every such name is used by some shader. A misspelt define in Rust no longer
//! compiles (the passes name them through the constants); one in WGSL, or a define left behind
//! when its code went, fails here.

use std::collections::BTreeSet;
use std::path::Path;

use volgraph_core::cut_effects::frame_defines;
use volgraph_passes::defines::BUILT_IN;

/// Every `#if` name of the `.wgsl` files under `dir`, with the file that names it.
fn shader_defines(dir: &Path, out: &mut BTreeSet<(String, String)>) {
    for entry in std::fs::read_dir(dir).expect("shaders/ is readable") {
        let path = entry.expect("entry").path();
        if path.is_dir() {
            shader_defines(&path, out);
        } else if path.extension().is_some_and(|e| e == "wgsl") {
            let text = std::fs::read_to_string(&path).expect("shader reads");
            for line in text.lines() {
                if let Some(rest) = line.trim_start().strip_prefix("#if ") {
                    let name = rest.trim().trim_start_matches('!').to_string();
                    out.insert((name, path.display().to_string()));
                }
            }
        }
    }
}

#[test]
fn every_wgsl_define_has_its_rust_twin_and_the_reverse() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shaders");
    let mut found = BTreeSet::new();
    shader_defines(&root, &mut found);
    let frame: Vec<&str> = frame_defines(&["crop".to_string(), "clip".to_string()], true);
    // What the device can do (`Gpu::device_defines`).
    let device = [volgraph_core::runtime::SUBGROUPS_DEFINE];
    let known: BTreeSet<&str> =
        BUILT_IN.iter().copied().chain(frame.iter().copied()).chain(device.iter().copied()).collect();
    assert_eq!(known.len(), BUILT_IN.len() + frame.len() + device.len(), "a name is declared twice: {known:?}");
    let unknown: Vec<_> = found.iter().filter(|(name, _)| !known.contains(name.as_str())).collect();
    assert!(
        unknown.is_empty(),
        "#if names without a Rust constant (add them to crates/passes/src/defines.rs): {unknown:?}"
    );
    let used: BTreeSet<&str> = found.iter().map(|(name, _)| name.as_str()).collect();
    let unused: Vec<&&str> = known.iter().filter(|name| !used.contains(**name)).collect();
    assert!(unused.is_empty(), "Rust defines no shader uses: {unused:?}");
    assert!(found.len() >= 25, "the scan found the shaders' defines: {found:?}");
}
