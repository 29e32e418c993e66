//! "Simulate only the effects a scene calls for": a pass compiles only the shader code its
//! parameters ask for. Each plugin names the entry points it will use (`PassPlugin::shaders`)
//! and the `#if` names its modules are assembled with (`PassPlugin::shader_defines`: the scene
//! effects it was asked for); code in an `#if` that is off is not in the module at all, and of
//! what is, wgpu hands the driver one entry point at a time and naga's backends emit only the
//! functions reachable from it. These tests assemble each module as the pass does, walk naga's
//! IR from each entry point and check which effects' code is reachable — for the isosurface and
//! every scene effect (shading, pre-integration, tricubic, jitter) on every graph that takes it.

use std::collections::BTreeSet;

use volgraph_core::runtime::shaders::parse_and_validate;
use volgraph_core::shader_source::{ShaderSources, assemble_with, default_shader_root};
use volgraph_core::{CompileOptions, compile};
use volgraph_passes::builtin_registry;

mod support;

/// Names of the functions reachable from entry point `entry` of `file`.
fn reachable(file: &str, entry: &str) -> BTreeSet<String> {
    reachable_with(file, entry, &[])
}

/// Names of the functions reachable from entry point `entry` of `file` assembled with `defines`.
fn reachable_with(file: &str, entry: &str, defines: &[&str]) -> BTreeSet<String> {
    let sources =
        ShaderSources::new().with_disk(default_shader_root()).with_generated(volgraph_passes::uniform_imports());
    let defines: BTreeSet<String> = defines.iter().map(|d| d.to_string()).collect();
    let source = assemble_with(&sources, file, &defines).expect("shader loads");
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
    let defines = plugin.shader_defines(&step.params);
    uses.iter().flat_map(|u| reachable_with(u.file, u.entry_point, &defines)).collect()
}

/// Each scene effect and a function only its code calls.
const EFFECT_MARKERS: [(&str, &str); 6] = [
    ("shading", "lighting"),
    ("shadows", "light_transmittance"),
    ("ambient_occlusion", "ambient_occlusion"),
    ("preintegration", "lookup_preintegrated"),
    ("tricubic", "sample_tricubic"),
    ("jitter", "pcg_hash"),
];

/// The DVR graphs that take every effect, one per raycaster family.
const DVR_GRAPHS: [&str; 9] = support::EFFECT_GRAPHS;

#[test]
fn every_scene_effect_is_compiled_only_when_the_scene_turns_it_on() {
    for graph in DVR_GRAPHS {
        let none = march_code(graph, CompileOptions::new(64, 64));
        for (effect, marker) in EFFECT_MARKERS {
            assert!(!none.contains(marker), "{graph}: {effect} is off, yet {marker} is compiled: {none:?}");
            let on = march_code(graph, CompileOptions::new(64, 64).with_features([effect]));
            assert!(on.contains(marker), "{graph}: {effect} is on, so {marker} is compiled: {on:?}");
            for (other, other_marker) in EFFECT_MARKERS.iter().filter(|(o, _)| *o != effect) {
                assert!(!on.contains(*other_marker), "{graph} with {effect} only compiles no {other}: {on:?}");
            }
        }
    }
}

/// The functions the pass `pass` of `graph` compiles, with the `#if` names the runtime adds for
/// the scene's cuts (`volgraph_compiler::cut_effects`, given to every pass that honours them).
fn pass_code_with_cuts(graph: &str, pass: &str, options: CompileOptions) -> BTreeSet<String> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../graphs").join(graph);
    let source = std::fs::read_to_string(path).expect("graph");
    let registry = builtin_registry();
    let plan = compile(graph, &source, &registry, &options).expect("compiles");
    let step = plan.steps.iter().find(|s| s.pass_id == pass).expect("the step");
    let plugin = registry.get(&step.kind).expect("registered");
    assert!(plugin.takes_cuts(), "{}: the raycasters take cuts", step.kind);
    let cuts = volgraph_core::cut_effects::defines_of(&plan.features);
    let mut defines = plugin.shader_defines(&step.params);
    defines.extend(volgraph_core::cut_effects::defines_for_pass(plugin.as_ref(), &cuts));
    let wired = step.wired_ports();
    plugin
        .shaders_wired(&step.params, &wired)
        .iter()
        .flat_map(|u| {
            let mut d = defines.clone();
            d.extend(u.defines.iter().copied());
            reachable_with(u.file, u.entry_point, &d)
        })
        .collect()
}

/// Crop and clip (issue 24 §3) are frame effects: a scene that cuts nothing compiles no cut code
/// into any raycaster, and each cut compiles only its own.
#[test]
fn a_cut_is_compiled_only_when_the_scene_cuts() {
    for (graph, pass) in [
        ("basic/fragment_raycast.ron", "march"),
        ("modern/fastest.ron", "march"),
        ("kruger_westermann_2003/rc_b_leap.ron", "march"),
        ("ruijters_vilanova_2006/bricks_octree_ert.ron", "march"),
        ("klein_2005/leap_iso.ron", "march"),
    ] {
        let none = pass_code_with_cuts(graph, pass, CompileOptions::new(64, 64));
        assert!(none.contains("own_segment"), "{graph}: the window cut is always there: {none:?}");
        assert!(!none.contains("crop_segment") && !none.contains("clip_segment"), "{graph}: no cut code: {none:?}");
        let crop = pass_code_with_cuts(graph, pass, CompileOptions::new(64, 64).with_features(["crop"]));
        assert!(crop.contains("crop_segment") && !crop.contains("clip_segment"), "{graph} with a crop: {crop:?}");
        let clip = pass_code_with_cuts(graph, pass, CompileOptions::new(64, 64).with_features(["clip"]));
        assert!(clip.contains("clip_segment") && !clip.contains("crop_segment"), "{graph} with a clip: {clip:?}");
    }
    // Capping (the cut faces' flat shading) comes with shading and a cut, and only then.
    for graph in ["basic/fragment_raycast.ron", "modern/fastest.ron"] {
        let shaded = pass_code_with_cuts(graph, "march", CompileOptions::new(64, 64).with_features(["shading"]));
        assert!(shaded.contains("lighting") && !shaded.contains("cap_normal"), "{graph}: {shaded:?}");
        for cut in ["crop", "clip"] {
            let capped =
                pass_code_with_cuts(graph, "march", CompileOptions::new(64, 64).with_features(["shading", cut]));
            assert!(capped.contains("cap_normal"), "{graph} shaded with a {cut}: {capped:?}");
        }
        let unshaded = pass_code_with_cuts(graph, "march", CompileOptions::new(64, 64).with_features(["crop"]));
        assert!(!unshaded.contains("cap_normal"), "{graph}: no shading, no capping: {unshaded:?}");
    }
}

#[test]
fn the_isosurface_takes_tricubic_and_jitter() {
    let plain = march_code("basic/isosurface.ron", CompileOptions::new(64, 64));
    let both = march_code("basic/isosurface.ron", CompileOptions::new(64, 64).with_features(["tricubic", "jitter"]));
    assert!(!plain.contains("sample_tricubic") && !plain.contains("pcg_hash"), "{plain:?}");
    assert!(both.contains("sample_tricubic") && both.contains("pcg_hash"), "{both:?}");
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
fn only_the_leaping_segment_loop_compiles_empty_space_code() {
    // raycast_segment compiles LEAP + LEAP_BLOCKS only when its `empty` port is wired
    // (rc_b_leap.ron): the shared core's leap over the block flags.
    let plain = reachable("raycast_segment.wgsl", "fs_dvr");
    let leaping = reachable_with("raycast_segment.wgsl", "fs_dvr", &["LEAP", "LEAP_BLOCKS"]);
    let empty_space = |f: &String| {
        ["leap", "leap_stop", "leaping_for", "empty_region_at", "block_at", "block_grid"].contains(&f.as_str())
    };
    assert!(!plain.iter().any(empty_space), "{plain:?}");
    assert!(
        leaping.contains("leap") && leaping.contains("empty_region_at") && leaping.contains("block_at"),
        "{leaping:?}"
    );
}
