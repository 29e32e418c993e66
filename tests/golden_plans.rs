//! Every graph under `graphs/` (except the transfer functions in `graphs/tf/`) compiles with the
//! built-in passes at 1920x1080 with no features, and its `volgraph plan` text is kept next to
//! it as `NAME.plan.txt`, so a change in ordering, culling or pooling shows up in review.
//! `VOLGRAPH_BLESS=1 cargo test -p volgraph-tests --test golden_plans` rewrites them.

// The compiler's `compile` (`volgraph_compiler`) turns each graph into its plan; the built-in
// passes contribute only their declarations (`builtin_kinds`, which volgraph-passes builds
// without its `gpu` feature: crates/passes/tests/declarations_without_gpu.rs).
use volgraph_compiler::{CompileOptions, KindLookup, compile};
use volgraph_passes::builtin_kinds;
use volgraph_tests::{check_golden, graph_files, relative_name};

#[test]
fn every_graph_matches_its_golden_plan() {
    let files = graph_files().expect("graphs/ is readable");
    assert!(files.len() >= 3, "expected the graphs/basic files, found {files:?}");
    let declarations = builtin_kinds();
    let kinds: &dyn KindLookup = &declarations;
    let options = CompileOptions::new(1920, 1080);
    let mut failures = Vec::new();
    for path in &files {
        let name = relative_name(path);
        let source = match std::fs::read_to_string(path) {
            Ok(s) => s,
            Err(e) => {
                failures.push(format!("{name}: cannot read: {e}"));
                continue;
            }
        };
        match compile(&name, &source, kinds, &options) {
            Ok(plan) => {
                let golden = path.with_extension("plan.txt");
                if let Err(e) = check_golden(&golden, &plan.to_text()) {
                    failures.push(e);
                }
            }
            Err(diagnostics) => failures.push(format!("{name} does not compile:\n{diagnostics}")),
        }
    }
    assert!(failures.is_empty(), "{} of {} graphs failed:\n\n{}", failures.len(), files.len(), failures.join("\n\n"));
}

/// The golden text is what `volgraph plan` prints: a pooled plan of the fragment raycaster
/// reuses no slot across formats, keeps the graph outputs alive to the end and names them.
#[test]
fn fragment_raycast_plan_names_outputs_and_slots() {
    let path = volgraph_tests::repo_root().join("graphs/basic/fragment_raycast.ron");
    let source = std::fs::read_to_string(&path).expect("graphs/basic/fragment_raycast.ron exists");
    let plan = compile("fragment_raycast.ron", &source, &builtin_kinds(), &CompileOptions::new(1920, 1080))
        .unwrap_or_else(|d| panic!("{d}"));
    let text = plan.to_text();
    assert!(text.starts_with("plan \"fragment_raycast\" at 1920x1080, features: none\n"), "{text}");
    // Each input the application binds, by name and kind (issue 43: graphs with several).
    assert!(text.contains("\ninputs: tf (TransferFunction), volume (Volume)\n"), "{text}");
    assert!(text.contains("output image: march.color\n"), "{text}");
    assert!(text.contains("output display: present.display\n"), "{text}");
    let labels: Vec<&str> = plan.steps.iter().map(|s| s.label.as_str()).collect();
    assert_eq!(labels, ["entry", "dirs", "march", "present"]);
}
