//! A graph's `bypass:` is checked like the rest of the file: every way leaving passes out could
//! change the image other than as declared is a located error with a fix (`graphs/klein_2005/
//! leap_iso_splats.ron` edited one way at a time: the per-pixel splats, whose hole fill reads
//! the splat), and a good one is listed in the plan.

use volgraph_core::{CompileOptions, compile};
use volgraph_passes::builtin_registry;

mod support;

const GRAPH: &str = "klein_2005/leap_iso_splats.ron";

/// The shipped graph with `from` replaced by `to` (which must occur).
fn edited(from: &str, to: &str) -> String {
    let source = support::graph_source(GRAPH);
    assert!(source.contains(from), "{GRAPH} contains {from}");
    source.replacen(from, to, 1)
}

/// The 1-based line of the first occurrence of `needle` in `source`.
fn line_of(source: &str, needle: &str) -> usize {
    source[..source.find(needle).unwrap_or_else(|| panic!("{needle} in the graph"))].lines().count()
}

/// The diagnostics of `source`, which must not compile.
fn errors_of(source: &str) -> String {
    match compile("leap_iso_splats.ron", source, &builtin_registry(), &CompileOptions::new(64, 64)) {
        Ok(_) => panic!("compiled:\n{source}"),
        Err(d) => d.to_string(),
    }
}

/// Asserts `errors` has a problem on `line` whose text holds every one of `phrases`.
fn assert_reported(errors: &str, line: usize, phrases: &[&str]) {
    let at = format!("leap_iso_splats.ron:{line}:");
    assert!(
        errors.lines().any(|l| l.starts_with(&at)) && phrases.iter().all(|p| errors.contains(p)),
        "expected {phrases:?} at {at}, got:\n{errors}"
    );
}

const RULE: &str =
    r#""reprojection": (passes: ["splat", "holes"], measure: "march.leapable", below: "input.reproject_below")"#;

#[test]
fn the_shipped_bypass_is_in_the_plan() {
    let plan = compile(GRAPH, &support::graph_source(GRAPH), &builtin_registry(), &CompileOptions::new(64, 64))
        .unwrap_or_else(|d| panic!("{d}"));
    let text = plan.to_text();
    assert!(
        text.contains(
            "bypass reprojection: leaves out splat, holes while march.leapable < 16 per pixel (then clears holes.start)"
        ),
        "{text}"
    );
    // The threshold is a Scalar input, so a scene (or `--sweep input.reproject_below=…`) sets it.
    let options = CompileOptions::new(64, 64).with_scalar("reproject_below", 8.0);
    let plan = compile(GRAPH, &support::graph_source(GRAPH), &builtin_registry(), &options).expect("compiles");
    assert_eq!(plan.bypass[0].below, 8.0);
}

#[test]
fn an_unknown_pass_is_named_with_a_guess() {
    let source = edited(RULE, &RULE.replace(r#""splat", "holes""#, r#""splats", "holes""#));
    let errors = errors_of(&source);
    assert_reported(
        &errors,
        line_of(&source, "\"reprojection\""),
        &["names pass \"splats\", which the graph does not have", "did you mean \"splat\""],
    );
}

#[test]
fn a_reader_that_does_not_take_zeros_as_none_is_refused() {
    // Only the splat: hole fill would read its zeros as "no splat landed" and still run.
    let source = edited(RULE, &RULE.replace(r#"["splat", "holes"]"#, r#"["splat"]"#));
    let errors = errors_of(&source);
    assert_reported(
        &errors,
        line_of(&source, "\"splats\": \"splat.start\""),
        &[
            "input \"splats\" of pass \"holes\" reads \"splat.start\"",
            "does not read zeros as \"none\"",
            "add \"holes\" to the bypass",
        ],
    );
}

#[test]
fn the_measure_must_be_a_buffer_of_a_pass_that_runs() {
    let target = edited(RULE, &RULE.replace("march.leapable", "march.leap_hit"));
    assert_reported(
        &errors_of(&target),
        line_of(&target, "\"reprojection\""),
        &["which is not a buffer pass \"march\" writes"],
    );

    let uncounted = edited(r#""count_leapable": true"#, r#""count_leapable": false"#);
    assert_reported(
        &errors_of(&uncounted),
        line_of(&uncounted, "\"reprojection\""),
        &["measures \"march.leapable\", which is not a buffer", "count_leapable"],
    );

    let inside = edited(RULE, &RULE.replace(r#"["splat", "holes"]"#, r#"["splat", "holes", "march"]"#));
    let errors = errors_of(&inside);
    assert_reported(&errors, line_of(&inside, "\"reprojection\""), &["is one of the passes it leaves out"]);
    // …and its image and history would go stale.
    assert!(
        errors.contains("graph output \"image\" is \"march.color\", which bypass \"reprojection\" may leave unwritten"),
        "{errors}"
    );
    assert!(errors.contains("history \"hits\" keeps \"march.leap_hit\""), "{errors}");
}

#[test]
fn an_output_of_a_left_out_pass_is_refused() {
    let source = edited(r#""image": "march.color","#, r#""image": "march.color", "starts": "holes.start","#);
    let errors = errors_of(&source);
    assert_reported(
        &errors,
        line_of(&source, "\"starts\""),
        &["graph output \"starts\" is \"holes.start\"", "a pass that always runs"],
    );
}

#[test]
fn a_threshold_must_be_a_positive_number_or_a_scalar_input() {
    for (below, phrase) in [
        ("-1.0", "threshold -1 is not a positive number"),
        ("0.0", "threshold 0 is not a positive number"),
        (r#""input.reproject_belw""#, "is below \"input.reproject_belw\", which is not a Scalar graph input"),
        (r#""reproject_below""#, "is below \"reproject_below\", which is not a Scalar graph input"),
    ] {
        let source = edited(RULE, &RULE.replace(r#""input.reproject_below""#, below));
        assert_reported(&errors_of(&source), line_of(&source, "\"reprojection\""), &[phrase]);
    }
    // A misspelt field is the format's own located error.
    let source = edited(RULE, &RULE.replace("below:", "bellow:"));
    let errors = errors_of(&source);
    assert!(errors.contains("bellow"), "{errors}");
}
