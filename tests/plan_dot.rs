//! `volgraph plan GRAPH --dot`: every graph's picture names every scheduled step and value,
//! greys its culled and gated passes, boxes its repeat groups and dashes its history edges.

use volgraph_core::{CompileOptions, compile};
use volgraph_passes::builtin_registry;
use volgraph_tests::{graph_files, relative_name};

#[test]
fn every_graph_draws_its_plan() {
    let registry = builtin_registry();
    let (mut groups, mut history, mut greyed) = (0, 0, 0);
    for path in graph_files().expect("graphs/ is readable") {
        let name = relative_name(&path);
        let source = std::fs::read_to_string(&path).expect("readable");
        let plan = compile(&name, &source, &registry, &CompileOptions::new(640, 480)).expect("compiles");
        let dot = plan.to_dot();
        assert!(dot.starts_with("digraph ") && dot.trim_end().ends_with('}'), "{name}");
        assert_eq!(dot.matches('{').count(), dot.matches('}').count(), "{name}: balanced braces");
        for (i, step) in plan.steps.iter().enumerate() {
            assert!(
                dot.contains(&format!("\"{}. {}\\n{}\"", i + 1, step.label, step.kind)),
                "{name}: step {}",
                step.label
            );
        }
        for r in &plan.resources {
            assert!(dot.contains(&r.name), "{name}: value {}", r.name);
        }
        for id in plan.culled.iter().chain(plan.gated.iter().map(|(id, _)| id)) {
            assert!(dot.contains(&format!("\"{id}\\n")) && dot.contains("color=grey60"), "{name}: greyed {id}");
            greyed += 1;
        }
        if plan.steps.iter().any(|s| s.iteration.is_some()) {
            assert!(dot.contains("subgraph \"cluster_"), "{name}: repeat group boxed");
            groups += 1;
        }
        if !plan.history.is_empty() {
            assert!(dot.contains("style=dashed, label="), "{name}: history edge dashed");
            history += 1;
        }
    }
    // The graphs exercise repeat groups and history; culling is checked below.
    assert!(groups > 0 && history > 0, "groups {groups}, history {history}, greyed {greyed}");
}

/// A pass no output reads is culled, and drawn greyed and dashed.
#[test]
fn a_culled_pass_is_greyed() {
    let graph = std::fs::read_to_string(volgraph_tests::repo_root().join("graphs/basic/compute_raycast.ron"))
        .expect("readable");
    // A second present pass that no output reads.
    let source = graph.replacen(
        "        Pass(\n            id: \"present\",",
        "        Pass(id: \"unused\", kind: \"present\", inputs: {\"color\": \"march.color\"}),\n        Pass(\n            id: \"present\",",
        1,
    );
    assert_ne!(source, graph, "the graph has the pass this test copies");
    let plan = compile("culled.ron", &source, &builtin_registry(), &CompileOptions::new(64, 64)).expect("compiles");
    assert_eq!(plan.culled, vec!["unused".to_string()]);
    let dot = plan.to_dot();
    assert!(dot.contains("\"culled.unused\" [shape=box, style=dashed, color=grey60"), "{dot}");
}
