//! Several volume and transfer-function inputs bound by name (issue "several volumes", item 1):
//! `volgraph render --volume NAME=PATH --tf NAME=FILE|PRESET` binds the graph's inputs of that
//! name; a missing one is an error at its line in the graph; an unknown name lists the graph's
//! inputs; volumes on different grids of one frame render together, in different frames are
//! refused; label tables are bound from files with notes for what they lack (the viewer binds
//! names as `render` does: `view::tests::labels`).

use std::path::{Path, PathBuf};
use std::process::Command;

mod support;

/// A graph of two volume inputs, each raycast on its own: `image` from `volume`, `mask_image`
/// from `mask`.
const TWO_VOLUMES: &str = r#"Graph(
    name: "two_volumes",
    description: "the volume and a mask, each raycast on its own",
    inputs: {
        "volume": Volume,
        "mask": Volume,
        "tf": TransferFunction,
    },
    passes: [
        Pass(id: "a", kind: "raycast_compute", params: {"rays": "analytic"}, inputs: {"volume": "input.volume", "tf": "input.tf"}),
        Pass(id: "b", kind: "raycast_compute", params: {"rays": "analytic"}, inputs: {"volume": "input.mask", "tf": "input.tf"}),
    ],
    outputs: {"image": "a.color", "mask_image": "b.color"},
)
"#;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("volgraph-named-inputs-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch");
    std::fs::write(dir.join("two_volumes.ron"), TWO_VOLUMES).expect("graph");
    dir
}

fn volgraph(args: &[&str], dir: &Path) -> (bool, String) {
    let xdg = std::env::temp_dir().join(format!("volgraph-xdg-{}", std::process::id()));
    std::fs::create_dir_all(&xdg).expect("xdg");
    #[cfg(unix)]
    std::os::unix::fs::PermissionsExt::set_mode(&mut std::fs::metadata(&xdg).expect("xdg").permissions(), 0o700);
    let out = Command::new(env!("CARGO_BIN_EXE_volgraph"))
        .args(args)
        .current_dir(dir)
        .env("XDG_RUNTIME_DIR", std::env::var_os("XDG_RUNTIME_DIR").unwrap_or(xdg.into_os_string()))
        .output()
        .expect("runs");
    (out.status.success(), String::from_utf8_lossy(&out.stderr).into_owned())
}

/// The pixels of an EXR.
fn pixels(path: &Path) -> Vec<[f32; 4]> {
    support::read_exr(path).2
}

fn tf() -> String {
    concat!(env!("CARGO_MANIFEST_DIR"), "/../../graphs/tf/marschner_lobb.ron").to_string()
}

#[test]
fn each_named_volume_reaches_the_input_of_its_name() {
    let dir = scratch("bind");
    let tf = tf();
    // Renders output `output` of the two-volume graph with `volumes` to `out`, returning its pixels.
    let render = |volumes: &[&str], output: &str, out: &str| {
        let mut args = vec!["render", "two_volumes.ron"];
        for v in volumes {
            args.extend(["--volume", v]);
        }
        args.extend(["--tf", &tf, "--output", output, "-o", out]);
        let (ok, err) = volgraph(&args, &dir);
        assert!(ok, "{err}");
        pixels(&dir.join(out))
    };
    // The mask output of the sphere/ml pair is the ml volume's raycast: the same image as
    // binding ml32 alone and reading the graph's first output.
    let named = render(&["volume=sphere32", "mask=ml32"], "mask_image", "named.exr");
    let alone = render(&["ml32"], "image", "alone.exr");
    assert!(named == alone, "the mask input got ml32 and is raycast exactly as ml32 alone");
    assert!(alone.iter().any(|p| p[3] > 0.1), "something is drawn");
    // And the primary input got the sphere: its image differs from ml32's.
    let sphere = render(&["volume=sphere32", "mask=ml32"], "image", "sphere.exr");
    assert!(sphere != alone, "the volume input got the sphere");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_missing_unknown_or_misplaced_input_is_an_error_that_says_what_to_give() {
    let dir = scratch("errors");
    let (ok, err) = volgraph(&["render", "two_volumes.ron", "--volume", "volume=ml32", "-o", "x.png"], &dir);
    assert!(!ok);
    assert!(
        err.contains("two_volumes.ron:6:9: volume input \"mask\" has nothing bound; give --volume mask=PATH"),
        "{err}"
    );
    let (ok, err) = volgraph(
        &[
            "render",
            "two_volumes.ron",
            "--volume",
            "volume=ml32",
            "--volume",
            "mask=ml32",
            "--volume",
            "pet=ml32",
            "-o",
            "x.png",
        ],
        &dir,
    );
    assert!(!ok);
    assert!(
        err.contains(
            "--volume pet=…: graph \"two_volumes\" has no volume input \"pet\"; its volume inputs are: mask, volume"
        ),
        "{err}"
    );
    // Different grids of one frame are marched together, each sampled where it lies; volumes in
    // different frames (index axes against the patient frame) are refused, naming both.
    let (ok, err) = volgraph(
        &["render", "two_volumes.ron", "--volume", "volume=ml32", "--volume", "mask=ml48", "-o", "x.png"],
        &dir,
    );
    assert!(ok, "{err}");
    let (ok, err) = volgraph(
        &["render", "two_volumes.ron", "--volume", "volume=ml32", "--volume", "mask=organs_labels32", "-o", "x.png"],
        &dir,
    );
    assert!(!ok);
    assert!(
        err.contains("--volume mask=…: ") && err.contains("lies in index axes (the file gives no orientation) and"),
        "{err}"
    );
    let (ok, err) =
        volgraph(&["render", "two_volumes.ron", "--volume", "volume=ml32", "--volume", "ml32", "-o", "x.png"], &dir);
    assert!(!ok && err.contains("give every volume a name when one has one"), "{err}");
    let (ok, err) = volgraph(&["render", "two_volumes.ron", "--tf", "ct-bone", "--tf", "ct-lung", "-o", "x.png"], &dir);
    assert!(!ok && err.contains("--tf is given twice without a name"), "{err}");
    let (ok, err) = volgraph(&["render", "two_volumes.ron", "--tf", "pet_tf=ct-bone", "-o", "x.png"], &dir);
    assert!(
        !ok && err.contains("has no transfer-function input \"pet_tf\"; its transfer-function inputs are: tf"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_scene_names_its_inputs_too() {
    let dir = scratch("scene");
    let tf = tf();
    std::fs::write(
        dir.join("both.ron"),
        format!(
            "Scene(graph: \"two_volumes.ron\", volume: Generated(\"sphere32\"), volumes: {{\"mask\": \"ml32\"}}, \
             transfer_function: File(\"{tf}\"))"
        ),
    )
    .expect("scene");
    let (ok, err) = volgraph(&["render", "--scene", "both.ron", "--output", "mask_image", "-o", "scene.exr"], &dir);
    assert!(ok, "{err}");
    let (ok, err) = volgraph(
        &["render", "two_volumes.ron", "--volume", "ml32", "--tf", &tf, "--output", "image", "-o", "alone.exr"],
        &dir,
    );
    assert!(ok, "{err}");
    assert!(pixels(&dir.join("scene.exr")) == pixels(&dir.join("alone.exr")), "the scene's mask is ml32");
    // A name that is no identifier, or `volume` (the scene's `volume:`), is an error naming the field.
    std::fs::write(dir.join("bad.ron"), "Scene(volume: Generated(\"ml32\"), volumes: {\"2nd\": \"ml32\"})")
        .expect("scene");
    let (ok, err) = volgraph(&["render", "two_volumes.ron", "--scene", "bad.ron", "-o", "x.png"], &dir);
    assert!(!ok && err.contains("volumes") && err.contains("\"2nd\" is no input name"), "{err}");
    std::fs::write(dir.join("twice.ron"), "Scene(volume: Generated(\"ml32\"), volumes: {\"volume\": \"ml32\"})")
        .expect("scene");
    let (ok, err) = volgraph(&["render", "two_volumes.ron", "--scene", "twice.ron", "-o", "x.png"], &dir);
    assert!(!ok && err.contains("\"volume\" is the scene's `volume:`"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `graphs/multi/`: a label table file binds the `LabelTable` input, with a note for the map's
/// values it does not name and one for the labels it names that the map lacks; only the visible
/// label shows; a float volume that is no label map is an error naming a voxel.
#[test]
fn a_label_table_file_colours_the_map_and_says_what_it_lacks() {
    let dir = scratch("tables");
    // The liver shown, the kidneys, spleen and aorta hidden (alpha 0), the vertebra (6) unnamed.
    let table = "1 liver 255 0 0 255\n2 k 0 0 0 0\n3 k 0 0 0 0\n4 s 0 0 0 0\n5 a 0 0 0 0\n9 nothing 0 0 255 255\n";
    std::fs::write(dir.join("liver.txt"), table).expect("table");
    let inside = |table: &str| {
        let table = format!("label_table={table}");
        let args = [
            "render",
            "multi/ct_inside_labels",
            "--volume",
            "volume=organs32",
            "--volume",
            "labels=organs_labels32",
            "--tf",
            &table,
            "--size",
            "64x64",
            "-o",
            "inside.exr",
        ];
        let (ok, err) = volgraph(&args, &dir);
        assert!(ok, "{err}");
        (pixels(&dir.join("inside.exr")).iter().filter(|p| p[3] > 0.01).count(), err)
    };
    let (liver, err) = inside("liver.txt");
    assert!(err.contains("1 label value(s) of organs_labels_32 have no entry in liver.txt (6)"), "{err}");
    assert!(err.contains("liver.txt names 1 label(s) that organs_labels_32 does not hold (9)"), "{err}");
    // Every organ in the default palette shows more of the scan than the liver alone.
    let (all, _) = inside("default");
    assert!(liver > 20 && all > liver + 20, "liver {liver} pixels, all organs {all}");
    let (ok, err) = volgraph(&["render", "multi/labels", "--volume", "mlf32", "-o", "x.png"], &dir);
    assert!(!ok);
    assert!(err.contains("--tf label_table: ") && err.contains("is not a label map: voxel ("), "{err}");
}

/// Two DICOM series of different frames of reference (FrameOfReferenceUID) are refused, naming
/// both UIDs and the flag; `--allow-frame-mismatch` shows them as placed, with a warning.
#[test]
fn dicom_series_of_different_frames_of_reference_are_refused_unless_allowed() {
    let dir = scratch("frames");
    let mut ct = volgraph_accel::organs::organs_ct(16);
    ct.meta.frame_of_reference = Some("1.2.3.4".into());
    volgraph_accel::load::dicom::write_ct_series(&dir.join("ct"), &ct).expect("series");
    ct.meta.frame_of_reference = Some("1.2.3.5".into());
    volgraph_accel::load::dicom::write_ct_series(&dir.join("pet"), &ct).expect("series");
    let mut args = vec![
        "render",
        "multi/pet_ct",
        "--volume",
        "volume=ct",
        "--volume",
        "pet=pet",
        "--size",
        "32x32",
        "-o",
        "x.png",
    ];
    let (ok, err) = volgraph(&args, &dir);
    assert!(!ok);
    assert!(
        err.contains("--volume pet=…: ")
            && err.contains("different DICOM frames of reference (1.2.3.4 and 1.2.3.5)")
            && err.contains("--allow-frame-mismatch"),
        "{err}"
    );
    args.push("--allow-frame-mismatch");
    let (ok, err) = volgraph(&args, &dir);
    assert!(ok, "{err}");
    assert!(err.contains("warning: --volume pet=…: ") && err.contains("shown as placed"), "{err}");
}

/// A 4D NIfTI's volumes as channels: `--volume volume=cells.nii#0 --volume channel2=cells.nii#1`
/// binds volume 0 and volume 1 of one file to `multi/channels`; the two frames differ (the
/// second holds the first's values halved; one TF in data units), so binding frame 0 twice gives
/// another image; a frame the file lacks is an error naming the input.
#[test]
fn a_4d_files_volumes_bind_as_channels() {
    let dir = scratch("channels");
    support::write_nifti_4d(&dir.join("cells.nii"), &support::ct(20, "cells"));
    // One TF in data units for both channels, so the halved frame looks fainter.
    let tf = "TransferFunction(domain: (-1000.0, 1000.0), points: [(value: -200.0, color: (0.0, 1.0, 0.0), \
              alpha: 0.0), (value: 1000.0, color: (0.0, 1.0, 0.0), alpha: 0.6)])";
    std::fs::write(dir.join("green.ron"), tf).expect("tf");
    let render = |second: &str, out: &str| {
        let second = format!("channel2=cells.nii#{second}");
        let args = [
            "render",
            "multi/channels",
            "--volume",
            "volume=cells.nii#0",
            "--volume",
            &second,
            "--tf",
            "green.ron",
            "--tf",
            "channel2_tf=green.ron",
            "--size",
            "48x48",
            "-o",
            out,
        ];
        volgraph(&args, &dir)
    };
    let (ok, err) = render("1", "both.exr");
    assert!(ok, "{err}");
    let (ok, err) = render("0", "same.exr");
    assert!(ok, "{err}");
    let (both, same) = (pixels(&dir.join("both.exr")), pixels(&dir.join("same.exr")));
    assert!(both.iter().any(|p| p[3] > 0.01), "the channels show");
    assert!(both.iter().zip(&same).any(|(a, b)| (a[3] - b[3]).abs() > 1e-3), "frame 1 is not frame 0");
    let (ok, err) = render("7", "none.exr");
    assert!(!ok && err.contains("--volume channel2=…: "), "{err}");
}

/// Four channels of one 4D file: `multi/channels4` binds its four volumes by name, each with its
/// own TF; every channel adds light (the fourth bound to frame 0 again gives another image); a
/// channel left unbound is an error naming it.
#[test]
fn four_channels_of_a_4d_file_bind_by_name() {
    let dir = scratch("channels4");
    support::write_nifti_channels(&dir.join("cells.nii"), &support::ct(20, "cells"), 4);
    for (name, (r, g, b)) in [("green", (0, 1, 0)), ("magenta", (1, 0, 1)), ("cyan", (0, 1, 1)), ("yellow", (1, 1, 0))]
    {
        let tf = format!(
            "TransferFunction(domain: (-1000.0, 1000.0), points: [(value: -200.0, color: ({r}.0, {g}.0, {b}.0), \
             alpha: 0.0), (value: 1000.0, color: ({r}.0, {g}.0, {b}.0), alpha: 0.5)])"
        );
        std::fs::write(dir.join(format!("{name}.ron")), tf).expect("tf");
    }
    let render = |fourth: Option<&str>, out: &str| {
        let mut args = vec![
            "render",
            "multi/channels4",
            "--volume",
            "volume=cells.nii#0",
            "--volume",
            "channel2=cells.nii#1",
            "--volume",
            "channel3=cells.nii#2",
            "--tf",
            "green.ron",
            "--tf",
            "channel2_tf=magenta.ron",
            "--tf",
            "channel3_tf=cyan.ron",
            "--tf",
            "channel4_tf=yellow.ron",
            "--size",
            "48x48",
            "-o",
            out,
        ];
        if let Some(f) = fourth {
            args.extend(["--volume", f]);
        }
        volgraph(&args, &dir)
    };
    let (ok, err) = render(Some("channel4=cells.nii#3"), "four.exr");
    assert!(ok, "{err}");
    let (ok, err) = render(Some("channel4=cells.nii#0"), "again.exr");
    assert!(ok, "{err}");
    let (four, again) = (pixels(&dir.join("four.exr")), pixels(&dir.join("again.exr")));
    assert!(four.iter().any(|p| p[3] > 0.01), "the channels show");
    assert!(four.iter().zip(&again).any(|(a, b)| (a[2] - b[2]).abs() > 1e-3), "frame 3 is not frame 0");
    let (ok, err) = render(None, "three.exr");
    assert!(!ok && err.contains("channel4"), "{err}");
}

/// A DICOM SEG over its scan (issue "several volumes", item 3): the phantom's label map written
/// as a BINARY SEG (`write_segmentation`, its organs as segments with their names and colours)
/// binds as `--volume labels=seg.dcm` and names its own labels — the image is the one the
/// generated map with the phantom's table gives, within the one step of 255 that colours take
/// through DICOM's 16-bit CIELab; `info --labels` lists its segments by name.
#[test]
fn a_dicom_seg_binds_as_the_label_map_it_holds_with_its_own_names() {
    let dir = scratch("dicom-seg");
    let labels = volgraph_accel::organs::organs_labels(32);
    let names: Vec<(u8, String, [u8; 3])> =
        volgraph_accel::organs::label_table().labels.iter().map(|(v, l)| (*v as u8, l.name.clone(), l.rgb)).collect();
    let names: Vec<(u8, &str, [u8; 3])> = names.iter().map(|(v, n, c)| (*v, n.as_str(), *c)).collect();
    volgraph_accel::load::dicom::write_segmentation(&dir.join("seg.dcm"), &labels, &names).expect("SEG");
    let render = |map: &str, out: &str| {
        let map = format!("labels={map}");
        let args = [
            "render",
            "multi/ct_with_labels",
            "--volume",
            "volume=organs32",
            "--volume",
            &map,
            "--size",
            "64x64",
            "-o",
            out,
        ];
        let (ok, err) = volgraph(&args, &dir);
        assert!(ok, "{err}");
        pixels(&dir.join(out))
    };
    let from_seg = render("seg.dcm", "seg.exr");
    let generated = render("organs_labels32", "generated.exr");
    let worst = from_seg
        .iter()
        .zip(&generated)
        .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
        .fold(0.0f32, f32::max);
    let tinted = from_seg.iter().filter(|p| p[3] > 0.05).count();
    assert!(tinted > 200, "the scan shows ({tinted} pixels)");
    assert!(worst <= 1.5 / 255.0, "largest difference {} / 255", worst * 255.0);

    let out = Command::new(env!("CARGO_BIN_EXE_volgraph"))
        .args(["info", "seg.dcm", "--labels"])
        .current_dir(&dir)
        .output()
        .expect("runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    for (_, name, _) in &names {
        assert!(text.contains(name), "{name} missing from:\n{text}");
    }
}

/// A graph of several volume inputs given one volume: each other input gets it too (a CT as its
/// own PET), said in a note naming the input and how to name each, never silently.
#[test]
fn one_volume_for_a_graph_of_several_says_it_is_bound_to_each() {
    let dir = scratch("one_for_several");
    let out = dir.join("one.png").display().to_string();
    let (ok, stderr) =
        volgraph(&["render", "multi/pet_ct", "--volume", "organs32", "--size", "32x32", "-o", &out], &dir);
    assert!(ok, "{stderr}");
    assert!(
        stderr.contains("reads the volume input \"pet\" too") && stderr.contains("--volume pet=other.nii.gz"),
        "{stderr}"
    );
    let (ok, stderr) = volgraph(
        &[
            "render",
            "multi/ct_with_labels",
            "--volume",
            "volume=organs32",
            "--volume",
            "labels=organs_labels32",
            "--size",
            "32x32",
            "-o",
            &out,
        ],
        &dir,
    );
    assert!(ok && !stderr.contains("too, and no --volume"), "{stderr}");
}

/// Three volumes in one graph: `multi/pet_ct_inside_labels` binds the CT, a second scalar volume
/// and a label map by name (each checked against the frame volume's frame), the label table
/// given by name; the image shows only what lies inside the visible labels, so hiding them all
/// (an ITK-SNAP table with every label invisible) leaves it empty.
#[test]
fn three_volumes_bind_by_name() {
    let dir = scratch("three_volumes");
    let render = |labels: &str, table: Option<&str>, out: &str| {
        let labels = format!("labels={labels}");
        let mut args = vec![
            "render",
            "multi/pet_ct_inside_labels",
            "--volume",
            "volume=organs32",
            "--volume",
            "pet=organs32",
            "--volume",
            &labels,
            "--size",
            "32x32",
            "--output",
            "image",
            "-o",
            out,
        ];
        if let Some(t) = table {
            args.extend(["--tf", t]);
        }
        volgraph(&args, &dir)
    };
    let (ok, stderr) = render("organs_labels32", None, "shown.exr");
    assert!(ok && !stderr.contains("too, and no --volume"), "{stderr}");
    // A scan given as the label map is the map's flag's fault, not a table's never given.
    let (ok, stderr) = render("organs32", None, "scan.exr");
    assert!(!ok && stderr.contains("--volume labels=…: organs_32 is not a label map"), "{stderr}");
    let visible = |file: &str| support::read_exr(&dir.join(file)).2.iter().filter(|p| p[3] > 2.0 / 255.0).count();
    assert!(visible("shown.exr") > 20, "the organs show inside their labels");
    let hidden: String = (1..=6).map(|v| format!("{v} 255 0 0 1 0 1 \"label {v}\"\n")).collect();
    std::fs::write(dir.join("hidden.txt"), hidden).expect("table");
    let (ok, stderr) = render("organs_labels32", Some("label_table=hidden.txt"), "hidden.exr");
    assert!(ok, "{stderr}");
    assert_eq!(visible("hidden.exr"), 0, "every label hidden: nothing inside");
}
