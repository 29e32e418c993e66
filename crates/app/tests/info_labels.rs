//! `volgraph info --labels` / `--label-table` (issue "several volumes", item 6): a label map's
//! labels — value, name, voxels, volume in mL — named by an ITK-SNAP or 3D Slicer table, a
//! default palette without one, notes for values the table lacks and labels the map lacks, and
//! a located error for a bad table or a volume that holds no labels.
//!
//! The counts were cross-checked once against nibabel + numpy (a 64³ NIfTI of three spheres at
//! 0.8 × 0.8 × 2 mm written by nibabel: `np.unique` gave 7123, 2969 and 485 voxels = 9.117,
//! 3.800 and 0.621 mL, which `volgraph info seg.nii.gz --labels` printed); here an NRRD is made
//! in-tree so the test needs no Python.

use std::path::Path;
use std::process::Command;

/// An 8 × 8 × 4 uint16 NRRD in LPS at 0.5 × 0.5 × 2 mm (0.5 mm³ a voxel): label 3 in the first
/// 16 voxels, 65535 in the last 2, else 0.
fn label_map(dir: &Path) -> std::path::PathBuf {
    label_map_with(dir, "seg.nrrd", "")
}

/// [`label_map`] as `name`, with `keys` (`key:=value` lines) in its header.
fn label_map_with(dir: &Path, name: &str, keys: &str) -> std::path::PathBuf {
    let mut data = vec![0u16; 256];
    data[..16].fill(3);
    data[254..].fill(65_535);
    let mut bytes = b"NRRD0004\ntype: uint16\ndimension: 3\nsizes: 8 8 4\nspace: left-posterior-superior\n\
space directions: (0.5,0,0) (0,0.5,0) (0,0,2)\nspace origin: (0,0,0)\nencoding: raw\nendian: little\n"
        .to_vec();
    bytes.extend(keys.as_bytes());
    bytes.push(b'\n');
    bytes.extend(data.iter().flat_map(|v| v.to_le_bytes()));
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("write nrrd");
    path
}

fn info(args: &[&str], dir: &Path) -> (bool, String, String) {
    let out =
        Command::new(env!("CARGO_BIN_EXE_volgraph")).arg("info").args(args).current_dir(dir).output().expect("runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("volgraph-info-labels-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch");
    dir
}

#[test]
fn a_label_map_lists_its_labels_with_voxels_and_millilitres() {
    let dir = scratch("palette");
    label_map(&dir);
    let (ok, out, err) = info(&["seg.nrrd", "--labels"], &dir);
    assert!(ok, "{err}");
    assert!(out.contains("labels       2 labels and the background (0), names from default palette"), "{out}");
    // 16 voxels × 0.5 mm³ = 0.008 mL; 2 voxels = 0.001 mL.
    let row =
        |value: &str| out.lines().find(|l| l.split_whitespace().next() == Some(value)).unwrap_or_default().to_string();
    assert!(row("3").contains("Label 3") && row("3").contains(" 16 ") && row("3").ends_with("0.008 mL"), "{out}");
    assert!(row("65535").contains(" 2 ") && row("65535").ends_with("0.001 mL"), "{out}");
    assert!(row("0").contains(" 238 ") && row("0").ends_with("(hidden)"), "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_table_names_the_labels_and_notes_what_does_not_match() {
    let dir = scratch("table");
    label_map(&dir);
    std::fs::write(
        dir.join("organs.ctbl"),
        "# Color table file organs.ctbl\n0 background 0 0 0 0\n3 portal_vein 0 0 255 255\n9 aorta 255 0 0 255\n",
    )
    .expect("table");
    let (ok, out, err) = info(&["seg.nrrd", "--label-table", "organs.ctbl"], &dir);
    assert!(ok, "{err}");
    assert!(out.contains("names from organs.ctbl"), "{out}");
    assert!(out.lines().any(|l| l.trim_start().starts_with("3  portal vein")), "{out}");
    assert!(
        out.contains("note: 1 value of the map has no entry in the table (65535): shown with the default palette"),
        "{out}"
    );
    assert!(out.contains("note: the table names 1 label the map lacks (9)"), "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_bad_table_or_a_scan_is_an_error_that_says_where() {
    let dir = scratch("bad");
    label_map(&dir);
    std::fs::write(dir.join("bad.txt"), "    1   255    0    0        1  1  1    \"a\"\n    1   0 0 0  1 1 1 \"b\"\n")
        .expect("table");
    let (ok, _, err) = info(&["seg.nrrd", "--label-table", "bad.txt"], &dir);
    assert!(!ok);
    assert!(err.contains("bad.txt:2: label 1 is described twice; keep one line for it"), "{err}");
    let (ok, _, err) = info(&["seg.nrrd", "--label-table", "missing.txt"], &dir);
    assert!(!ok && err.contains("missing.txt: cannot read the label table"), "{err}");
    // A float volume of non-integers is no label map: the error names a voxel.
    std::fs::write(
        dir.join("scan_2x2x2_float32.raw"),
        [0.0f32, 0.5, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0].iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>(),
    )
    .expect("raw");
    let (ok, _, err) = info(&["scan_2x2x2_float32.raw", "--labels"], &dir);
    assert!(!ok && err.contains("is not a label map: voxel (1, 0, 0) holds 0.5"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_slicer_segmentation_names_its_own_segments() {
    let dir = scratch("seg");
    let keys = "Segment0_Color:=0.866667 0.509804 0.396078\nSegment0_LabelValue:=3\nSegment0_Layer:=0\nSegment0_Name:=liver\n\
                Segment1_LabelValue:=65535\nSegment1_Name:=portal vein\nSegment2_LabelValue:=1\nSegment2_Layer:=1\n";
    label_map_with(&dir, "organs.seg.nrrd", keys);
    let (ok, out, err) = info(&["organs.seg.nrrd", "--labels"], &dir);
    assert!(ok, "{err}");
    assert!(out.contains("names from organs.seg.nrrd"), "{out}");
    assert!(out.lines().any(|l| l.trim_start().starts_with("3  liver")), "{out}");
    assert!(out.lines().any(|l| l.trim_start().starts_with("65535  portal vein")), "{out}");
    assert!(out.contains("1 segment of other layers (overlapping segments) left out"), "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn several_named_volumes_are_described_with_how_they_lie_to_each_other() {
    let dir = scratch("several");
    let (ok, out, err) = info(&["ct=organs32", "seg=organs_labels32"], &dir);
    assert!(ok, "{err}");
    assert!(out.starts_with("ct: organs32\n") && out.contains("\nseg: organs_labels32\n"), "{out}");
    assert!(out.contains("ct and seg: the same grid in the patient frame"), "{out}");
    let (ok, out, err) = info(&["a=ml32", "b=ml48"], &dir);
    assert!(ok, "{err}");
    // 32³ inside 48³ from the same corner: all of the first, (32/48)³ = 29.6 % of the second.
    assert!(out.contains("a and b: boxes overlap in index space (no patient frame) over 100.0 % of the first and 29.6 % of the second"), "{out}");
    let (ok, out, err) = info(&["ct=organs32", "other=ml32"], &dir);
    assert!(ok, "{err}");
    assert!(out.contains("ct and other: different frames"), "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_label_table_that_is_no_regular_text_file_is_refused_at_once() {
    let dir = scratch("hostile");
    label_map(&dir);
    std::fs::create_dir_all(dir.join("folder")).expect("folder");
    std::fs::write(dir.join("binary.txt"), [0xff, 0xfe, 0x00]).expect("binary");
    let mut cases = vec![("folder", "is a directory"), ("binary.txt", "not UTF-8"), ("/dev/zero", "is a device")];
    #[cfg(unix)]
    {
        // A FIFO would block a plain read for ever.
        for name in ["labels.fifo", "fifo.seg.nrrd"] {
            let made = Command::new("mkfifo").arg(dir.join(name)).status().is_ok_and(|s| s.success());
            assert!(made, "mkfifo {name}");
            cases.push((name, "is a FIFO"));
        }
    }
    for (table, want) in cases {
        let (ok, _, err) = info(&["seg.nrrd", "--label-table", table], &dir);
        assert!(!ok && err.contains(want), "{table}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
