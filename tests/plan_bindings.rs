//! Every shipped graph passes the plan-time shader binding check (`check_plan_bindings`, what
//! `volgraph plan` runs) with the built-in shaders, with its scene effects off and on, so each
//! built-in pass's declared shader uses (`PassPlugin::shaders`: files, entry points, the names it
//! binds itself) match its shaders.

use volgraph_core::{CompileOptions, check_plan_bindings, compile};
use volgraph_passes::{builtin_registry, builtin_shaders};
use volgraph_tests::{graph_files, relative_name};

#[test]
fn every_graph_binds_its_shaders_at_plan_time() {
    let registry = builtin_registry();
    let sources = builtin_shaders();
    let mut failures = Vec::new();
    let mut checked = 0;
    for path in graph_files().expect("graphs/ is readable") {
        let name = relative_name(&path);
        let source = std::fs::read_to_string(&path).expect("readable");
        for features in [vec![], vec!["shading", "preintegration", "jitter", "tricubic"]] {
            let options = CompileOptions::new(320, 240).with_features(features.clone());
            // A graph that stops compiling is a failure, never a graph left unchecked.
            let plan = match compile(&name, &source, &registry, &options) {
                Ok(plan) => plan,
                Err(d) => {
                    failures.push(format!("{name} {features:?} does not compile:\n{d}"));
                    continue;
                }
            };
            checked += 1;
            for d in check_plan_bindings(&plan, &registry, &sources) {
                failures.push(format!("{name} {features:?}: {}", d.message));
            }
        }
    }
    assert!(checked > 20, "{checked} plans checked");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
