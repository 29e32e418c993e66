//! What a built-in pass declares in `PassPlugin::shaders` (the list `volgraph plan` checks
//! bindings with) is what its node builds: for every shipped graph, effects off and on, each
//! pass's declared `(file, entry point)` pairs are built by `create`, and `create` builds
//! nothing else but the fullscreen triangle's vertex stage (which binds nothing).

use volgraph_core::binding_rules::port_infos;
use volgraph_core::runtime::{CreateContext, PipelineCache, RUNTIME_VERTEX_STAGES, ShaderLibrary};
use volgraph_core::{CompileOptions, compile};
use volgraph_passes::{builtin_registry, builtin_shaders};

mod support;

fn graph_files(dir: &std::path::Path, out: &mut Vec<std::path::PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("graphs/") {
        let path = entry.expect("entry").path();
        if path.is_dir() && !path.ends_with("tf") {
            graph_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "ron") {
            out.push(path);
        }
    }
}

#[test]
fn every_pass_builds_exactly_the_shaders_it_declares() {
    let gpu = support::gpu();
    let registry = builtin_registry();
    let shaders = ShaderLibrary::new(builtin_shaders());
    let pipelines = PipelineCache::default();
    let mut files = Vec::new();
    graph_files(&support::graph_path(""), &mut files);
    let volume = volgraph_accel::generate::marschner_lobb(16);
    let mut failures = Vec::new();
    let mut checked = 0;
    for path in files {
        let source = std::fs::read_to_string(&path).expect("readable");
        for features in [vec![], vec!["shading", "preintegration", "jitter", "tricubic"]] {
            let mut options = CompileOptions::new(64, 64).with_features(features.clone());
            options.scene = volgraph_core::runtime::scene_values_of(&volgraph_core::runtime::VolumeDesc::of(&volume));
            // A graph that stops compiling is a failure, never a graph left unchecked.
            let plan = match compile(&path.display().to_string(), &source, &registry, &options) {
                Ok(plan) => plan,
                Err(d) => {
                    failures.push(format!("{} {features:?} does not compile:\n{d}", path.display()));
                    continue;
                }
            };
            // A graph's own WGSL-only kinds (`graphs/basic/mip.ron`) join the built-in ones.
            let kinds = volgraph_core::wgsl_pass::with_graph_kinds(&registry, &plan.kinds);
            for step in plan.steps.iter().filter(|s| s.iteration.is_none_or(|(i, _)| i == 0)) {
                let plugin = kinds.get(&step.kind).expect("a built-in kind or one the graph declares");
                let ports = port_infos(&plan, step, &plugin.ports(&step.params));
                let ctx = CreateContext::new(
                    &gpu,
                    &shaders,
                    &pipelines,
                    &step.pass_id,
                    &step.params,
                    &ports,
                    plugin.as_ref(),
                );
                if let Err(e) = plugin.create(&ctx) {
                    failures.push(format!("{}: {}: create failed: {e}", path.display(), step.pass_id));
                    continue;
                }
                checked += 1;
                let built = ctx.built_entry_points();
                let wired: Vec<&str> = ports.iter().filter(|p| p.bound).map(|p| p.name.as_str()).collect();
                let declared: std::collections::BTreeSet<(String, String)> = plugin
                    .shaders_wired(&step.params, &wired)
                    .iter()
                    .map(|u| (u.file.to_string(), u.entry_point.to_string()))
                    .collect();
                // The pre-integration and opacity tables come in an f32 and an f16 variant; the
                // device decides which one is built, so declaring both is right.
                let alternative = |(file, entry): &(String, String)| {
                    let other = entry.replace("table32", "table16").replace("table16_", "table32");
                    let other = if other == *entry { entry.replace("table16", "table32") } else { other };
                    built.contains(&(file.clone(), other))
                };
                for d in declared.difference(&built).filter(|d| !alternative(d)) {
                    failures.push(format!(
                        "{} {features:?}: {} declares {d:?} but does not build it",
                        path.display(),
                        step.kind
                    ));
                }
                // Vertex stages are declared like the others, but for the runtime's own: the
                // fullscreen triangle, which binds nothing, and the footprint fan (`frame`).
                for b in built.difference(&declared).filter(|(_, e)| !RUNTIME_VERTEX_STAGES.contains(&e.as_str())) {
                    failures.push(format!(
                        "{} {features:?}: {} builds {b:?} without declaring it",
                        path.display(),
                        step.kind
                    ));
                }
            }
        }
    }
    assert!(checked > 50, "{checked} passes created");
    failures.sort();
    failures.dedup();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
