//! The bench code path end to end on a tiny case, and its flag errors word for word. No timing
//! is asserted: only that the report has its fields and finite numbers.

use std::path::PathBuf;

use volgraph_core::runtime::Gpu;

use super::args::GraphsArgs;
use super::{run, write_outputs};

fn basic_graph(name: &str) -> PathBuf {
    PathBuf::from("graphs/basic").join(name)
}

fn finite(v: &serde_json::Value, field: &str) -> f64 {
    let x = v[field].as_f64().unwrap_or_else(|| panic!("field {field} is not a number in {v}"));
    assert!(x.is_finite(), "field {field} = {x} is not finite");
    x
}

#[test]
fn tiny_sweep_writes_json_with_every_field_finite() {
    // Under CI a missing adapter is a failure, never a skip.
    let gpu =
        std::sync::Arc::new(Gpu::new_headless().expect("a Vulkan adapter (Mesa lavapipe on machines without a GPU)"));
    let dir = std::env::temp_dir().join(format!("volgraph-bench-graphs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir is writable");
    let args = GraphsArgs {
        graphs: vec![
            basic_graph("fragment_raycast.ron"),
            basic_graph("compute_raycast.ron"),
            basic_graph("not_written_yet.ron"),
        ],
        datasets: vec!["ml16".to_string()],
        size: vec!["32x32".to_string()],
        frames: Some(2),
        scale: 1.0,
        tf: vec!["opaque".to_string()],
        sweep: Some("march.step_voxels=0.5,1".to_string()),
        accuracy_size: 16,
        reference_step: 0.25,
        spp_size: 16,
        json: Some(dir.join("bench.json")),
        plot: Some(dir.join("bench.png")),
        quiet: true,
        ..GraphsArgs::default()
    };
    let config = args.resolve().expect("valid flags");
    let report = run::run(gpu.clone(), &config).expect("the bench runs");
    write_outputs(&config, &report, &report.to_markdown()).expect("outputs are written");

    let text = std::fs::read_to_string(dir.join("bench.json")).expect("JSON written");
    let json: serde_json::Value = serde_json::from_str(&text).expect("valid JSON");
    assert_eq!(json["baseline"], "fragment_raycast");
    assert_eq!(json["sweep"], "march.step_voxels");
    let rows = json["rows"].as_array().expect("rows");
    assert_eq!(rows.len(), 4, "2 graphs × 2 sweep values");
    for row in rows {
        assert!(finite(row, "median_ms") > 0.0);
        finite(row, "min_ms");
        finite(row, "max_ms");
        finite(row, "median_wall_ms");
        assert!(finite(row, "speedup_vs_baseline") > 0.0);
        assert!(finite(row, "samples_per_pixel") > 0.0);
        assert!(finite(row, "msamples_per_s") > 0.0);
        assert!(row["clock"] == "gpu" || row["clock"] == "wall");
        finite(&row["error"], "max_abs");
        finite(&row["error"], "mean_abs");
        assert!(row["pareto"].is_boolean());
        if row["clock"] == "gpu" {
            let passes = row["pass_ms"].as_object().expect("pass_ms");
            assert!(passes.contains_key("march"), "per-pass times name the march pass: {passes:?}");
        }
    }
    let skipped = json["skipped"].as_array().expect("skipped");
    assert!(
        skipped.iter().any(|s| s["what"].as_str().is_some_and(|w| w.ends_with("not_written_yet.ron"))),
        "a missing graph is reported as skipped: {skipped:?}"
    );
    assert!(std::fs::metadata(dir.join("bench.png")).is_ok_and(|m| m.len() > 0), "plot written");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn peer_preset_without_its_peer_measures_against_its_first_graph() {
    // The `peer` preset's baseline is VTK; `--no-peer` (a machine without VTK) once failed with
    // "--baseline \"vtk_fixed_point\": not one of the graphs".
    // The command line's defaults for what `Default` leaves at zero.
    let peer = |no_peer: bool| GraphsArgs {
        preset: Some("peer".to_string()),
        no_peer,
        scale: 1.0,
        accuracy_size: 128,
        reference_step: 0.1,
        spp_size: 128,
        ..GraphsArgs::default()
    };
    let config = peer(true).resolve().expect("the peer preset resolves without its peer");
    assert_eq!(config.baseline, "single_pass_ess_ert");
    assert!(!config.peer);
    assert_eq!(peer(false).resolve().expect("the peer preset resolves").baseline, "vtk_fixed_point");
}

fn error_of(args: GraphsArgs) -> String {
    match args.resolve() {
        Ok(_) => panic!("expected an error"),
        Err(e) => format!("{e:#}"),
    }
}

#[test]
fn bad_flags_name_the_flag_and_the_fix() {
    let graphs = vec![basic_graph("fragment_raycast.ron")];
    assert_eq!(
        error_of(GraphsArgs { preset: Some("kw".to_string()), scale: 1.0, ..GraphsArgs::default() }),
        "--preset \"kw\": no such preset; choose one of: basic, kw2003-table1, thesis-tables, peer, klein2005, ruijters2006, effects-off"
    );
    assert_eq!(
        error_of(GraphsArgs {
            graphs: graphs.clone(),
            baseline: Some("rc".to_string()),
            scale: 1.0,
            ..GraphsArgs::default()
        }),
        "--baseline \"rc\": not one of the graphs (fragment_raycast); name a graph by its file stem"
    );
    assert_eq!(
        error_of(GraphsArgs {
            graphs: graphs.clone(),
            sweep: Some("step=1,2".to_string()),
            scale: 1.0,
            ..GraphsArgs::default()
        }),
        "--sweep \"step=1,2\": the key must be PASS.PARAM; expected PASS.PARAM=V1,V2,..., e.g. march.step_voxels=0.25,0.5,1,2"
    );
    for (set, why) in [
        ("iso=0.2", "the key must be PASS.PARAM or input.NAME"),
        ("input.iso_value", "no '='"),
        ("input.iso_value=low", "the value is not a number"),
        ("input.iso_value=inf", "the value is not finite"),
    ] {
        assert_eq!(
            error_of(GraphsArgs {
                graphs: graphs.clone(),
                set: vec![set.to_string()],
                scale: 1.0,
                reference_step: 0.1,
                accuracy_size: 128,
                ..GraphsArgs::default()
            }),
            format!(
                "--set \"{set}\": {why}; expected PASS.PARAM=NUMBER or input.NAME=NUMBER, e.g. input.iso_value=0.2"
            )
        );
    }
    assert_eq!(
        error_of(GraphsArgs { graphs, scale: 0.0, ..GraphsArgs::default() }),
        "--scale 0: expected a factor in (0, 8], e.g. 0.25 to render a quarter of each side"
    );
}
