//! "Simulate only the effects a scene calls for": a pass compiles only the shader code its
//! parameters ask for. Each plugin names the entry points it will use (`PassPlugin::shaders`);
//! wgpu hands the driver one entry point at a time and naga's backends emit only the functions
//! reachable from it, so code unreachable from the chosen entry point is never compiled. These
//! tests walk naga's IR from each entry point and check which effects' code is reachable.

use std::collections::BTreeSet;

use volgraph_core::runtime::shaders::parse_and_validate;
use volgraph_core::shader_source::{default_shader_root, load_shader};
use volgraph_core::{CompileOptions, compile};
use volgraph_passes::builtin_registry;

/// Names of the functions reachable from entry point `entry` of `file`.
fn reachable(file: &str, entry: &str) -> BTreeSet<String> {
    let source = load_shader(&default_shader_root(), file).expect("shader loads");
    let (module, _) = parse_and_validate(file, &source.text).expect("shader validates");
    let ep = module.entry_points.iter().find(|e| e.name == entry).unwrap_or_else(|| panic!("{file} has {entry}"));
    let mut seen = BTreeSet::new();
    let mut stack = Vec::new();
    calls(&ep.function.body, &mut stack);
    while let Some(h) = stack.pop() {
        let f = &module.functions[h];
        let name = f.name.clone().unwrap_or_default();
        if seen.insert(name) {
            calls(&f.body, &mut stack);
        }
    }
    seen
}

fn calls(block: &naga::Block, out: &mut Vec<naga::Handle<naga::Function>>) {
    for statement in block.iter() {
        match statement {
            naga::Statement::Call { function, .. } => out.push(*function),
            naga::Statement::Block(b) => calls(b, out),
            naga::Statement::If { accept, reject, .. } => {
                calls(accept, out);
                calls(reject, out);
            }
            naga::Statement::Switch { cases, .. } => cases.iter().for_each(|c| calls(&c.body, out)),
            naga::Statement::Loop { body, continuing, .. } => {
                calls(body, out);
                calls(continuing, out);
            }
            _ => {}
        }
    }
}

/// The (file, entry point) pairs the "march" pass of `graph` will compile, and the union of the
/// functions they reach.
fn march_code(graph: &str, options: CompileOptions) -> BTreeSet<String> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../graphs").join(graph);
    let source = std::fs::read_to_string(path).expect("graph");
    let registry = builtin_registry();
    let plan = compile(graph, &source, &registry, &options).expect("compiles");
    let step = plan.steps.iter().find(|s| s.pass_id == "march").expect("a march step");
    let plugin = registry.get(&step.kind).expect("registered");
    let uses = plugin.shaders(&step.params);
    assert!(!uses.is_empty(), "{} declares its shaders", step.kind);
    uses.iter().flat_map(|u| reachable(u.file, u.entry_point)).collect()
}

#[test]
fn direct_volume_rendering_compiles_no_isosurface_code() {
    let code = march_code("basic/fragment_raycast.ron", CompileOptions::new(64, 64));
    assert!(code.contains("march_dvr"), "the DVR integral is compiled: {code:?}");
    for iso_only in ["march_iso", "shade_iso"] {
        assert!(!code.contains(iso_only), "{iso_only} is not compiled for DVR: {code:?}");
    }
}

#[test]
fn the_isosurface_compiles_shading_and_no_compositing() {
    let code = march_code("basic/isosurface.ron", CompileOptions::new(64, 64));
    assert!(code.contains("march_iso") && code.contains("shade_iso"), "{code:?}");
    assert!(!code.contains("march_dvr"), "the DVR integral is not compiled for the isosurface: {code:?}");
}

#[test]
fn switching_the_effect_by_a_parameter_override_switches_the_code() {
    let code = march_code("basic/fragment_raycast.ron", CompileOptions::new(64, 64).with_param("march", "mode", "iso"));
    assert!(code.contains("shade_iso") && !code.contains("march_dvr"), "{code:?}");
}

#[test]
fn only_the_leaping_segment_entry_point_compiles_empty_space_code() {
    // raycast_segment picks fs_dvr_leap only when its `empty` port is wired (rc_b_leap.ron).
    let plain = reachable("raycast_segment.wgsl", "fs_dvr");
    let leaping = reachable("raycast_segment.wgsl", "fs_dvr_leap");
    assert!(!plain.iter().any(|f| f.starts_with("block_")), "{plain:?}");
    assert!(leaping.contains("block_is_empty") && leaping.contains("block_exit_t"), "{leaping:?}");
}
