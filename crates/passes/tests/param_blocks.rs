//! Issue 42: a block of settings declares its parameters, the `#if` names it implies and what a
//! change of it does to a built node once (`volgraph_compiler::block`); every built-in kind
//! lists its blocks and its parameters, defines and in-place rule are derived from them.

use volgraph_compiler::block::{OnChange, block_params};
use volgraph_compiler::{KindLookup, ParamValue, Params, PassDecl};
use volgraph_passes::builtin_registry;

fn decl(kind: &str) -> std::sync::Arc<dyn PassDecl> {
    builtin_registry().decl(kind).unwrap_or_else(|| panic!("kind {kind}"))
}

fn with(kind: &str, edits: &[(&str, ParamValue)]) -> Params {
    let mut params = Params::defaults(&decl(kind).params());
    for (name, value) in edits {
        params.set(name, value.clone());
    }
    params
}

#[test]
fn every_kind_with_parameters_takes_them_from_its_blocks() {
    let registry = builtin_registry();
    for kind in registry.kind_names() {
        let decl = registry.decl(kind).expect("registered");
        let params: Vec<_> = decl.params().iter().map(|s| s.name).collect();
        if params.is_empty() {
            continue;
        }
        let from_blocks: Vec<_> = block_params(&decl.blocks()).iter().map(|s| s.name).collect();
        assert_eq!(params, from_blocks, "{kind} declares parameters outside its blocks");
    }
}

#[test]
fn a_kind_that_takes_the_sampling_block_compiles_the_jitter_it_asks_for() {
    // The bug class of the issue: a kind took `Sampling` and forgot its defines, and jitter
    // silently did nothing. The block brings them now: every kind declaring `jitter` compiles
    // JITTER when it is on.
    let registry = builtin_registry();
    let mut kinds = Vec::new();
    for kind in registry.kind_names() {
        let decl = registry.decl(kind).expect("registered");
        if !decl.params().iter().any(|s| s.name == "jitter") {
            continue;
        }
        let on = with(kind, &[("jitter", ParamValue::Bool(true))]);
        let off = with(kind, &[]);
        assert!(decl.shader_defines(&on).contains(&"JITTER"), "{kind} does not compile the jitter it declares");
        assert!(!decl.shader_defines(&off).contains(&"JITTER"), "{kind} compiles jitter that is off");
        kinds.push(kind);
    }
    for family in ["raycast", "raycast_compute", "raycast_segment", "raycast_bricks", "antialias", "termination_test"] {
        assert!(kinds.contains(&family), "{family} takes the sampling block: {kinds:?}");
    }
}

#[test]
fn in_place_blocks_update_in_place_and_rebuild_blocks_rebuild() {
    let cases: [(&str, &str, ParamValue, bool); 11] = [
        // The raycasters' uniform values.
        ("raycast", "step_voxels", ParamValue::Float(0.25), true),
        // The level of detail's doubled step: the node holds both correction variants.
        ("raycast_compute", "step_voxels", ParamValue::Float(1.0), true),
        ("raycast_compute", "ambient", ParamValue::Float(0.3), true),
        ("raycast_bricks", "threshold", ParamValue::Float(0.9), true),
        ("antialias", "contrast", ParamValue::Float(0.2), true),
        // An effect is compiled in (and its table made with the node): a rebuild.
        ("raycast", "shading", ParamValue::Bool(true), false),
        // Pipeline shape: the workgroup, the bricks, a mode that picks another entry point.
        ("raycast_compute", "workgroup_x", ParamValue::UInt(16), false),
        ("raycast_bricks", "brick_cells", ParamValue::UInt(16), false),
        ("raycast", "mode", ParamValue::Choice("iso".into()), false),
        // The segment loop writes its uniforms once: every change rebuilds.
        ("raycast_segment", "step_voxels", ParamValue::Float(0.25), false),
        // Present's background is a uniform the node rewrites.
        ("present", "background", ParamValue::Float(0.5), true),
    ];
    for (kind, name, value, in_place) in cases {
        let decl = decl(kind);
        let old = with(kind, &[]);
        let new = with(kind, &[(name, value.clone())]);
        assert_ne!(old, new, "{kind}.{name}: the edit changes something");
        assert_eq!(decl.updates_in_place(&old, &new), in_place, "{kind}.{name} = {value}");
    }
}

#[test]
fn a_block_says_once_what_its_change_does() {
    // The effect switches rebuild wherever they are taken; the sampling block of the raycasters
    // that rewrite their uniform is taken in place.
    for kind in ["raycast", "raycast_compute", "raycast_bricks", "antialias", "raycast_segment"] {
        let blocks = decl(kind).blocks();
        let effects = blocks.iter().find(|b| b.name == "EffectFlags").expect("effects");
        assert_eq!(effects.on_change, OnChange::Rebuild, "{kind}");
    }
}
