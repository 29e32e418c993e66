//! Issue 47 ("Bad input, round three"), found in review: a `.nii.gz` whose header claims a
//! frame near the DEFLATE bound but whose stream ends early is "truncated" without the claimed
//! frame ever being reserved (a small hostile file under `ulimit -v` got "cannot allocate"
//! instead), and a non-finite `scl_inter` is ignored with a note naming it (it turned every
//! voxel into NaN, then into one constant).
//!
//! The first test loads the file in a copy of this test binary run under `ulimit -v` 512 MiB,
//! so a reservation of the claimed gigabyte fails there (as it did) instead of being
//! overcommitted unseen.

mod common;
mod nifti_support;

use std::path::{Path, PathBuf};
use std::process::Command;

use nifti_support::{NiftiSpec, gzip, voxels};
use volgraph_accel::load::{LoadOptions, LoadedVolume, load_volumes};
use volgraph_accel::volume::VoxelData;

/// Set (to the file to load) in the copy of this binary run under the address-space limit.
const UNDER_LIMIT: &str = "VOLGRAPH_TEST_NII_GZ_UNDER_ULIMIT";

fn load(path: &Path) -> Result<LoadedVolume, String> {
    load_volumes(&[path.to_path_buf()], &LoadOptions::default()).map_err(|e| e.to_string())
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("write the fixture");
    path
}

#[test]
fn nii_gz_ending_early_is_truncated_without_reserving_the_claimed_frame() {
    if let Some(path) = std::env::var_os(UNDER_LIMIT) {
        return truncated_under_the_limit(Path::new(&path));
    }
    let dir = common::temp_dir("nii-gz-short-stream");
    // 1000 × 1000 × 1000 uint8 (1 GB) claimed by a file of about 1 MiB: incompressible bytes, so
    // the file is large enough for DEFLATE's 1032:1 bound to allow the claim, and the stream
    // ends after 1 MiB of voxels.
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let noise: Vec<u8> = (0..1 << 20)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 24) as u8
        })
        .collect();
    let spec = NiftiSpec::new(1, [1000, 1000, 1000], 1, 2);
    let bytes = gzip(&spec.file(&noise));
    assert!(bytes.len() as u64 * 1032 > 1_000_000_352, "the file must pass the DEFLATE bound: {}", bytes.len());
    let path = write(&dir, "short.nii.gz", &bytes);
    drop((noise, bytes));
    let out = Command::new("sh")
        .args(["-c", "ulimit -v 524288; exec \"$0\" \"$@\""])
        .arg(std::env::current_exe().expect("the test binary"))
        .args(["--exact", "nii_gz_ending_early_is_truncated_without_reserving_the_claimed_frame", "--nocapture"])
        .env(UNDER_LIMIT, &path)
        .output()
        .expect("sh runs the test binary");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "under ulimit -v 512 MiB:\n{stdout}\n{stderr}");
    assert!(stdout.contains("1 passed"), "the check did not run:\n{stdout}\n{stderr}");
}

/// Loads the file named by [`UNDER_LIMIT`] in this process (run under `ulimit -v` 512 MiB).
fn truncated_under_the_limit(path: &Path) {
    let e = load(path).expect_err("the stream ends early");
    assert!(!e.contains("cannot allocate"), "the claimed frame was reserved whole: {e}");
    assert!(
        e.contains("short.nii.gz: cannot read the NIfTI file: 1000x1000x1000 uint8 voxels need 1000000000 bytes")
            && e.contains(&format!("but the file holds {} bytes once inflated", 352 + (1 << 20)))
            && e.contains("the file is truncated"),
        "{e}"
    );
}

/// The voxels of a uint8 volume, sorted (the order does not matter here).
fn sorted_u8(loaded: &LoadedVolume) -> Vec<u8> {
    let VoxelData::U8(values) = &loaded.volume.data else { panic!("not uint8 voxels") };
    let mut sorted = values.clone();
    sorted.sort_unstable();
    sorted
}

#[test]
fn non_finite_scl_inter_is_ignored_with_a_note_naming_it() {
    let dir = common::temp_dir("nifti-scl-inter");
    for (inter, shown) in [(f64::NAN, "NaN"), (f64::INFINITY, "inf"), (f64::NEG_INFINITY, "-inf")] {
        let mut spec = NiftiSpec::new(1, [4, 4, 4], 1, 2);
        spec.scl = (2.0, inter);
        let path = write(&dir, &format!("inter{shown}.nii"), &spec.file(&voxels(2, 64, false, |i| i as f64)));
        let loaded = load(&path).expect("loads");
        // The slope is still applied; the intercept is 0, so the volume is not one constant.
        assert_eq!(sorted_u8(&loaded), (0..64).map(|i| 2 * i).collect::<Vec<u8>>(), "{shown}");
        assert_eq!(loaded.report.nan_replaced + loaded.report.pos_inf_replaced + loaded.report.neg_inf_replaced, 0);
        assert!(
            loaded.report.notes.iter().any(|n| n.starts_with(&format!("scl_inter is {shown}, not a number to add"))),
            "{shown}: {:?}",
            loaded.report.notes
        );
    }
    // A finite intercept is still applied, with no note.
    let mut spec = NiftiSpec::new(1, [4, 4, 4], 1, 2);
    spec.scl = (2.0, 10.0);
    let path = write(&dir, "inter10.nii", &spec.file(&voxels(2, 64, false, |i| i as f64)));
    let loaded = load(&path).expect("loads");
    assert_eq!(sorted_u8(&loaded), (0..64).map(|i| 10 + 2 * i).collect::<Vec<u8>>());
    assert!(loaded.report.notes.iter().all(|n| !n.contains("scl_inter")), "{:?}", loaded.report.notes);
}
