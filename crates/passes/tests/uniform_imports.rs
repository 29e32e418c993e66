//! Issue 42: uniform blocks are declared once, in Rust (`pass_params!`, vector members
//! included), and the `params/NAME.wgsl` files shaders import are gathered from what the
//! registered kinds declare (`KindLookup::uniform_imports`), not from a hand list: every import
//! a shipped shader names is generated, and every generated struct is imported by some shader.

use std::collections::BTreeSet;

use volgraph_compiler::shader_source::default_shader_root;

/// Every `#import "params/…"` path in the WGSL under `dir`.
fn imported_params(dir: &std::path::Path, found: &mut BTreeSet<String>) {
    for entry in std::fs::read_dir(dir).expect("shader folder") {
        let path = entry.expect("entry").path();
        if path.is_dir() {
            imported_params(&path, found);
        } else if path.extension().is_some_and(|e| e == "wgsl") {
            let text = std::fs::read_to_string(&path).expect("wgsl");
            for line in text.lines() {
                if let Some(rest) = line.trim().strip_prefix("#import \"params/") {
                    found.insert(format!("params/{}", rest.trim_end_matches('"')));
                }
            }
        }
    }
}

#[test]
fn every_params_import_is_generated_from_a_declared_block_and_every_block_is_imported() {
    let mut imported = BTreeSet::new();
    imported_params(&default_shader_root(), &mut imported);
    let generated: BTreeSet<String> = volgraph_passes::uniform_imports().into_iter().map(|(path, _)| path).collect();
    // The node-filled blocks that were hand-written three times (Rust, WGSL, layout list).
    for block in ["AaParams", "BrickParams", "DistanceParams", "SegmentParams", "SplatParams"] {
        assert!(generated.contains(&format!("params/{block}.wgsl")), "{block} is not generated: {generated:?}");
    }
    let missing: Vec<_> = imported.difference(&generated).collect();
    assert!(missing.is_empty(), "shaders import params files no kind declares: {missing:?}");
    let unused: Vec<_> = generated.difference(&imported).collect();
    assert!(unused.is_empty(), "generated structs no shader imports: {unused:?}");
}

#[test]
fn a_generated_struct_carries_its_members_docs_and_vector_types() {
    let imports = volgraph_passes::uniform_imports();
    let (_, bricks) = imports.iter().find(|(p, _)| p == "params/BrickParams.wgsl").expect("bricks");
    assert!(bricks.contains("    grid: vec4<u32>,\n"), "{bricks}");
    assert!(bricks.contains("    atlas: vec4<f32>,\n"), "{bricks}");
    assert!(bricks.contains("// Atlas size in texels (xyz)."), "{bricks}");
    assert!(!bricks.contains("_pad"), "five vec4s need no padding: {bricks}");
}
