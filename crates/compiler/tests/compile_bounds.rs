//! Inputs that used to hang, crash or be ignored silently while compiling: unbounded repeat
//! counts, a byte-order mark, capped counts and options the graph never reads.

mod support;

use volgraph_compiler::compile::{MAX_PLAN_STEPS, MAX_REPEAT_ITERATIONS};
use volgraph_compiler::{CompileOptions, compile};

/// A Krüger–Westermann style loop with `body_passes` passes per iteration (a segment, then
/// termination tests chained on its depth); `count` is spliced in as written.
fn segment_graph(count: &str, body_passes: usize) -> String {
    let extra: String = (1..body_passes)
        .map(|i| {
            let depth = if i == 1 { "seg.depth".to_string() } else { format!("t{}.depth", i - 1) };
            format!(
                "Pass(id: \"t{i}\", kind: \"termination_test\", inputs: {{\"color\": \"seg.color\", \"depth\": \"{depth}\"}}),\n"
            )
        })
        .collect();
    let last_depth = if body_passes > 1 { format!("t{}.depth", body_passes - 1) } else { "seg.depth".to_string() };
    format!(
        r#"Graph(
    name: "loop",
    inputs: {{"volume": Volume, "tf": TransferFunction, "longest_ray_steps": Scalar(256.0), "segment_steps": Scalar(8.0)}},
    passes: [
        Pass(id: "entry", kind: "entry_points"),
        Pass(id: "dirs", kind: "ray_directions", inputs: {{"entry": "entry.entry"}}),
        Pass(id: "clear", kind: "clear_targets"),
        Repeat(
            id: "segments",
            count: {count},
            carry: {{"accum": (init: "clear.color", next: "seg.color"), "depth": (init: "clear.depth", next: "{last_depth}")}},
            body: [
                Pass(id: "seg", kind: "raycast_segment", inputs: {{
                    "entry": "entry.entry", "dir": "dirs.dir", "volume": "input.volume",
                    "tf": "input.tf", "accum": "segments.accum", "depth": "segments.depth",
                }}),
                {extra}
            ],
        ),
    ],
    outputs: {{"image": "segments.accum"}},
)"#
    )
}

#[test]
fn the_largest_allowed_repeat_group_compiles() {
    let text = segment_graph(&format!("Fixed({MAX_REPEAT_ITERATIONS})"), 1);
    let plan = compile("loop.ron", &text, &support::registry(), &CompileOptions::new(64, 64)).expect("at the limit");
    assert_eq!(plan.steps.iter().filter(|s| s.pass_id == "seg").count(), MAX_REPEAT_ITERATIONS as usize);
    // The carried accumulation target is one Modify chain through every iteration: still 2 slots.
    assert!(plan.slots.len() <= 6, "{} slots", plan.slots.len());
}

#[test]
fn a_plan_over_the_step_limit_is_a_located_error() {
    let body = MAX_PLAN_STEPS / MAX_REPEAT_ITERATIONS as usize + 1;
    let text = segment_graph(&format!("Fixed({MAX_REPEAT_ITERATIONS})"), body);
    let err = compile("loop.ron", &text, &support::registry(), &CompileOptions::new(64, 64)).expect_err("too big");
    let message = err.to_string();
    assert!(
        message.starts_with(&format!(
            "loop.ron: the graph unrolls to {} pass instances (\"segments\" 4096 × {body} passes), over the limit of {MAX_PLAN_STEPS}",
            3 + 4096 * body
        )),
        "{message}"
    );
}

#[test]
fn a_count_capped_by_max_is_a_warning_at_the_count() {
    let text = segment_graph("Scene(name: \"longest_ray_steps\", divide_by_input: \"segment_steps\", max: 4)", 1);
    let plan = compile("loop.ron", &text, &support::registry(), &CompileOptions::new(64, 64)).expect("compiles");
    assert_eq!(plan.steps.iter().filter(|s| s.pass_id == "seg").count(), 4);
    assert_eq!(
        plan.warnings.to_string(),
        "loop.ron:10:20: repeat group \"segments\" needs 32 iterations (\"longest_ray_steps\" = 256 divided by \"segment_steps\" (8)) but is capped at max: 4; the work past iteration 4 is not done\n  help: raise max (up to 4096) or do more per iteration (a larger divisor)"
    );
}

#[test]
fn features_and_scalars_the_graph_never_reads_are_named_with_a_guess() {
    let text = segment_graph("Scene(name: \"longest_ray_steps\", divide_by_input: \"segment_steps\")", 1);
    let options = CompileOptions::new(64, 64).with_features(["shadng"]).with_scalar("segment_step", 4.0);
    let plan = compile("loop.ron", &text, &support::registry(), &options).expect("compiles");
    let text = plan.warnings.to_string();
    assert!(text.contains("loop.ron: feature \"shadng\" is not used by graph \"loop\""), "{text}");
    assert!(
        text.contains(
            "loop.ron: scalar \"segment_step\" is not read by graph \"loop\"\n  help: did you mean \"segment_steps\"?"
        ),
        "{text}"
    );
    assert_eq!(
        plan.known_scalars.iter().map(String::as_str).collect::<Vec<_>>(),
        ["longest_ray_steps", "segment_steps"]
    );
}

#[test]
fn a_byte_order_mark_is_not_part_of_the_graph() {
    let text = format!("\u{feff}{}", segment_graph("Fixed(2)", 1));
    let plan = compile("bom.ron", &text, &support::registry(), &CompileOptions::new(64, 64)).expect("BOM accepted");
    assert_eq!(plan.name, "loop");
    // Errors after a BOM still point at the right line and column.
    let broken = text.replace("Fixed(2)", "Fixed(0)");
    let err = compile("bom.ron", &broken, &support::registry(), &CompileOptions::new(64, 64)).expect_err("count 0");
    assert!(err.to_string().starts_with("bom.ron:10:20: repeat group \"segments\" has count 0"), "{err}");
}
