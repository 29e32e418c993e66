//! Issue 20: the programs work with no source tree in reach. The binaries are copied into a
//! temporary folder and run from an empty working folder, with an empty data folder (so only
//! generated datasets exist): `graphs`, `render NAME`, a `bench graphs --preset` and a tiny
//! `sweep` must all work from what is compiled in. Where the stock `volgraph` binary was built
//! beside `volgraph-bench` (always under `cargo test --workspace`), its `bench` and `sweep`
//! are run too: they hand over to the copied `volgraph-bench`.

use std::path::Path;

mod support;

use support::sandbox;

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).expect("the JSON was written")).expect("JSON")
}

#[test]
fn graphs_and_render_by_name() {
    let s = sandbox("render");
    // The program says what it is: volgraph's about line, not a subcommand group's.
    let help = String::from_utf8_lossy(&s.run(&s.bench, &["--help"]).stdout).into_owned();
    assert!(help.starts_with("volgraph: GPU volume rendering"), "{help}");
    assert!(help.contains("sweep") && help.contains("bench") && help.contains("render"), "{help}");
    let listing = String::from_utf8_lossy(&s.run(&s.bench, &["graphs"]).stdout).into_owned();
    assert!(listing.contains("kruger_westermann_2003/rc_b") && listing.contains("modern/fastest"), "{listing}");
    s.run(&s.bench, &["render", "kruger_westermann_2003/rc_b", "--size", "32x32", "-o", "rc_b.png"]);
    let png = std::fs::read(s.work.join("rc_b.png")).expect("the image was written");
    assert!(png.starts_with(b"\x89PNG"), "a PNG");
}

#[test]
fn a_preset_runs_on_the_built_in_graphs() {
    let s = sandbox("preset");
    // The preset's own dataset (hydrogen_atom) is not in the empty data folder: it is measured
    // as the generated stand-in, labelled so, with a note.
    let args =
        ["bench", "graphs", "--preset", "basic", "--size", "32x32", "--frames", "2", "--quiet", "--json", "basic.json"];
    let out = s.run(&s.bench, &args);
    let text = String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    assert!(!text.contains("left out of this run"), "a preset graph was left out:\n{text}");
    assert!(text.contains("dataset hydrogen_atom is not in the data folder"), "the stand-in is explained:\n{text}");
    let report = json(&s.work.join("basic.json"));
    let rows = report["rows"].as_array().expect("rows");
    let graphs: Vec<&str> = rows.iter().map(|r| r["graph"].as_str().expect("a graph label")).collect();
    for expected in ["fragment_raycast", "compute_raycast"] {
        assert!(graphs.contains(&expected), "{expected} measured: {graphs:?}");
    }
    for row in rows {
        assert_eq!(row["dataset"], "hydrogen_atom→ml64", "{row}");
    }
}

#[test]
fn a_tiny_sweep_runs_on_the_built_in_graphs() {
    let s = sandbox("sweep");
    let args = [
        "sweep",
        "--knobs",
        "step",
        "--datasets",
        "ml64",
        "--size",
        "32x32",
        "--frames",
        "1",
        "--accuracy-size",
        "16",
        "--json",
        "sweep.json",
    ];
    let mut programs = vec![s.bench.clone()];
    programs.extend(s.stock.clone());
    for program in programs {
        let _ = std::fs::remove_file(s.work.join("sweep.json"));
        s.run(&program, &args);
        let report = json(&s.work.join("sweep.json"));
        let rows = report["rows"].as_array().expect("rows");
        assert_eq!(rows.len(), 4, "one row per step value on ml64 ({}): {report}", program.display());
        for row in rows {
            let error = row["mean_error"].as_f64().expect("an error against the reference");
            assert!(error.is_finite(), "{row}");
        }
    }
}
