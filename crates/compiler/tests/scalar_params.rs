//! Scalar graph inputs shared by several passes: a parameter written `"input.NAME"` takes the
//! scene's value of that Scalar input (its declared default when the scene sets none), and a
//! repeat count can divide by the same input (`divide_by_input`), so Krüger–Westermann's M
//! (steps per segment) lives in one place and the loop count can never disagree with it.

mod support;

use volgraph_compiler::{CompileOptions, compile};

const GRAPH: &str = r#"Graph(
    name: "shared scalars",
    inputs: {"volume": Volume, "tf": TransferFunction, "K": Scalar(100.0), "M": Scalar(8.0)},
    passes: [
        Pass(id: "entry", kind: "entry_points"),
        Pass(id: "dirs", kind: "ray_directions", inputs: {"entry": "entry.entry"}),
        Pass(id: "clear", kind: "clear_targets"),
        Repeat(
            id: "segments",
            count: Scene(name: "K", divide_by_input: "M"),
            carry: {"accum": (init: "clear.color", next: "seg.color"), "depth": (init: "clear.depth", next: "seg.depth")},
            body: [
                Pass(id: "seg", kind: "raycast_segment", params: {"steps": "input.M"}, inputs: {
                    "entry": "entry.entry", "dir": "dirs.dir", "volume": "input.volume", "tf": "input.tf",
                    "accum": "segments.accum", "depth": "segments.depth",
                }),
            ],
        ),
    ],
    outputs: {"image": "segments.accum"},
)"#;

fn segments(options: &CompileOptions) -> (usize, Vec<u64>) {
    let plan = compile("shared.ron", GRAPH, &support::registry(), options).expect("compiles");
    let steps: Vec<u64> = plan.steps.iter().filter(|s| s.pass_id == "seg").map(|s| s.params.uint("steps")).collect();
    (steps.len(), steps)
}

#[test]
fn parameters_and_repeat_count_read_the_declared_default() {
    let (count, steps) = segments(&CompileOptions::new(8, 8));
    assert_eq!(count, 13, "ceil(100 / 8)");
    assert!(steps.iter().all(|s| *s == 8), "every iteration reads M = 8: {steps:?}");
}

#[test]
fn a_scene_value_changes_the_parameter_and_the_count_together() {
    let (count, steps) = segments(&CompileOptions::new(8, 8).with_scalar("M", 32.0).with_scalar("K", 200.0));
    assert_eq!(count, 7, "ceil(200 / 32)");
    assert!(steps.iter().all(|s| *s == 32), "every iteration reads M = 32: {steps:?}");
}

#[test]
fn a_scalar_reference_is_checked_like_a_written_value() {
    // Out of range after substitution: the parameter's own range applies.
    let err = compile("shared.ron", GRAPH, &support::registry(), &CompileOptions::new(8, 8).with_scalar("M", 5000.0))
        .expect_err("steps = 5000 is outside 1..=1024");
    let text = err.to_string();
    assert!(text.contains("parameter \"steps\" of pass \"seg\" is 5000, outside its range"), "{text}");
    // A reference to something that is not a Scalar input.
    let broken = GRAPH.replace("\"steps\": \"input.M\"", "\"steps\": \"input.volume\"");
    let err =
        compile("shared.ron", &broken, &support::registry(), &CompileOptions::new(8, 8)).expect_err("not a scalar");
    let text = err.to_string();
    assert!(
        text.contains("parameter \"steps\" of pass \"seg\" reads \"input.volume\", which is not a Scalar graph input"),
        "{text}"
    );
}

/// Issue 21, item 4–5: an isovalue in the data's units, or `Auto`, resolved against the bound
/// volume's range and automatic iso value (the scene values the application supplies).
const DATA_GRAPH: &str = r#"Graph(
    name: "data units",
    inputs: {"volume": Volume, "tf": TransferFunction, "iso": Data(Auto), "hu": Data(Value(300.0))},
    passes: [
        Pass(id: "entry", kind: "entry_points"),
        Pass(id: "dirs", kind: "ray_directions", inputs: {"entry": "entry.entry"}),
        Pass(id: "auto", kind: "raycast", params: {"mode": "iso", "iso_value": "input.iso"}, inputs: {
            "entry": "entry.entry", "dir": "dirs.dir", "volume": "input.volume", "tf": "input.tf",
        }),
        Pass(id: "fixed", kind: "raycast", params: {"mode": "iso", "iso_value": "input.hu"}, inputs: {
            "entry": "entry.entry", "dir": "dirs.dir", "volume": "input.volume", "tf": "input.tf",
        }),
    ],
    outputs: {"a": "auto.color", "b": "fixed.color"},
)"#;

fn iso_values(options: &CompileOptions) -> (f64, f64) {
    let plan = compile("data.ron", DATA_GRAPH, &support::registry(), options).expect("compiles");
    let iso = |id: &str| plan.steps.iter().find(|s| s.pass_id == id).expect("pass").params.float("iso_value");
    (iso("auto"), iso("fixed"))
}

#[test]
fn data_inputs_take_the_volumes_units_and_its_automatic_value() {
    use volgraph_compiler::graph::ast::{DATA_AUTO_ISO, DATA_HIGH, DATA_LOW};
    // A CT in HU: −1024 … 3071.
    let mut ct = CompileOptions::new(8, 8);
    ct.scene.extend([
        (DATA_LOW.to_string(), -1024.0),
        (DATA_HIGH.to_string(), 3071.0),
        (DATA_AUTO_ISO.to_string(), 0.17),
    ]);
    let (auto, fixed) = iso_values(&ct);
    assert_eq!(auto, 0.17);
    assert!((fixed - (300.0 + 1024.0) / 4095.0).abs() < 1e-12, "{fixed}");
    // A user value is in data units too.
    let (_, fixed) = iso_values(&ct.clone().with_scalar("hu", -1024.0));
    assert_eq!(fixed, 0.0);
    // Without a volume (planning only): Auto is 0.5, values are taken as normalized.
    let out_of_range = compile("data.ron", DATA_GRAPH, &support::registry(), &CompileOptions::new(8, 8));
    assert!(out_of_range.is_err(), "300 as a normalized value is outside 0..=1");
}
