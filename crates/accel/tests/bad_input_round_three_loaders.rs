//! Issue 47 ("Bad input, round three"), the loaders' part: NIfTI headers read before anything is
//! inflated, NIfTI messages that say the file's real datatype, sizes and dimensionality, header
//! spacing held to the same ratio as `--spacing` in every format, and constant integer volumes
//! given their one value as their range, with a note.

mod common;
mod nifti_support;
mod scanner_support;

use std::path::{Path, PathBuf};

use glam::{DVec3, UVec3};
use nifti_support::{NiftiSpec, gzip, voxels};
use volgraph_accel::load::{LoadOptions, LoadedVolume, RawOptions, VolumeHeader, load_volume, load_volumes};

fn load(path: &Path, frame: Option<u64>) -> Result<LoadedVolume, String> {
    load_volumes(&[path.to_path_buf()], &LoadOptions { frame, ..LoadOptions::default() }).map_err(|e| e.to_string())
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("write the fixture");
    path
}

/// `members` gzip members of 64 MiB of zeros each: 64 KiB apiece on disk.
fn zero_members(members: usize) -> Vec<u8> {
    let member = gzip(&vec![0u8; 64 << 20]);
    member.repeat(members)
}

#[test]
fn nii_gz_header_is_read_before_inflating() {
    let dir = common::temp_dir("nii-gz-first");
    // A valid 4×4×4 uint8 file followed by 5 GiB of zeros in further gzip members: only what the
    // header asks for is inflated (the whole stream would not fit the memory of a small machine).
    let zeros = zero_members(80);
    let spec = NiftiSpec::new(1, [4, 4, 4], 1, 2);
    let mut bytes = gzip(&spec.file(&voxels(2, 64, false, |i| i as f64)));
    bytes.extend(&zeros);
    let path = write(&dir, "trailing.nii.gz", &bytes);
    let loaded = load(&path, None).expect("the header's voxels are all there");
    assert_eq!(loaded.volume.dims, UVec3::new(4, 4, 4));
    // 5 GiB of zeros alone: the header (sizeof_hdr 0) is refused after 4 inflated bytes.
    let path = write(&dir, "zeros.nii.gz", &zeros);
    let e = load(&path, None).expect_err("zeros");
    assert_eq!(
        e,
        format!(
            "{}: cannot read the NIfTI file: not a NIfTI file: the header size (sizeof_hdr, bytes 0..4 once inflated) is \
             0, neither 348 (NIfTI-1) nor 540 (NIfTI-2)",
            path.display()
        )
    );
}

#[test]
fn nii_gz_whose_header_claims_more_than_the_file_can_hold_is_refused_before_inflating() {
    let dir = common::temp_dir("nii-gz-claim");
    // 1024 × 1024 × 1024 int16 (2 GiB) in a file of a few hundred bytes: DEFLATE cannot expand
    // that far, so the file is refused at once.
    let spec = NiftiSpec::new(1, [1024, 1024, 1024], 1, 4);
    let path = write(&dir, "claim.nii.gz", &gzip(&spec.file(&[0; 64])));
    let e = load(&path, None).expect_err("too little data");
    assert!(
        e.contains(
            "claim.nii.gz: cannot read the NIfTI file: 1024x1024x1024 int16 voxels need 2147483648 bytes from byte 352"
        ) && e.contains("which inflate to at most")
            && e.contains("truncated"),
        "{e}"
    );
}

#[test]
fn nifti_size_errors_say_the_real_datatype_and_the_dimensions_as_written() {
    let dir = common::temp_dir("nifti-size");
    for (version, big) in [(1, false), (1, true), (2, true)] {
        let mut spec = NiftiSpec::new(version, [300, 2, 8], 1, 8);
        spec.big = big;
        let name = format!("short{version}{big}.nii");
        let path = write(&dir, &name, &spec.file(&voxels(8, 100, big, |_| 1.0)));
        let e = load(&path, None).expect_err("truncated");
        let start = NiftiSpec::data_start(version);
        assert_eq!(
            e,
            format!(
                "{}: cannot read the NIfTI file: 300x2x8 int32 voxels need 19200 bytes from byte {start} (to byte {}), \
                 but the file has {} bytes; the file is truncated (copy it again) or its header (dim, datatype, \
                 vox_offset) is wrong",
                path.display(),
                start + 19200,
                start + 400
            )
        );
    }
    // A hostile dim[0] does not turn the byte order around: the message shows it as written.
    let mut spec = NiftiSpec::new(1, [4, 4, 4], 1, 2);
    spec.dim[0] = 8;
    let path = write(&dir, "eight.nii", &spec.file(&[0; 64]));
    let e = load(&path, None).expect_err("8 axes");
    assert!(e.contains("eight.nii: dim[0] is 8, but only 3D scalar volumes"), "{e}");
}

#[test]
fn nifti_errors_read_as_prose_not_rust_debug_output() {
    let dir = common::temp_dir("nifti-prose");
    let mut spec = NiftiSpec::new(1, [4, 4, 4], 1, 2);
    spec.dim[2] = -3;
    let path = write(&dir, "negative.nii", &spec.file(&[0; 64]));
    let e = load(&path, None).expect_err("negative size");
    assert_eq!(
        e,
        format!(
            "{}: cannot read the NIfTI file: dim[2] is -3 (dim = 4 × -3 × 4); every axis needs at least one voxel",
            path.display()
        )
    );
    let mut spec = NiftiSpec::new(1, [4, 4, 4], 1, 2);
    spec.dim[0] = 5;
    spec.dim[4] = 1;
    spec.dim[5] = 3;
    let path = write(&dir, "vector.nii", &spec.file(&[0; 192]));
    let e = load(&path, None).expect_err("vector data");
    assert!(e.contains("dim = 4 × 4 × 4 × 1 × 3: dim[5] = 3 makes this vector"), "{e}");
}

#[test]
fn frame_on_a_3d_nifti_says_the_file_is_3d() {
    let dir = common::temp_dir("nifti-frame-3d");
    let spec = NiftiSpec::new(1, [4, 4, 4], 1, 2);
    let path = write(&dir, "three.nii", &spec.file(&[0; 64]));
    let e = load(&path, Some(1)).expect_err("no frame 1");
    assert_eq!(
        e,
        format!(
            "{}: --frame picks a volume of a 4D NIfTI file, but this file holds a single 3D volume: there are no frames \
             to pick; remove --frame",
            path.display()
        )
    );
    assert!(load(&path, Some(0)).is_ok(), "frame 0 of a 3D file is the file");
}

const RATIO_MESSAGE: &str =
    "the longest voxel side is 1.0e6 times the shortest; at most 1e4, or the volume renders black";

#[test]
fn header_spacing_with_a_million_to_one_ratio_is_refused_in_every_format() {
    let dir = common::temp_dir("spacing-ratio");
    let mut spec = NiftiSpec::new(1, [4, 4, 4], 1, 2);
    spec.pixdim[3] = 1e6;
    let nifti = write(&dir, "flat.nii", &spec.file(&[1; 64]));
    let mut nrrd = b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4 4 4\nspacings: 1 1 1e6\nencoding: raw\n\n".to_vec();
    nrrd.extend([1u8; 64]);
    let nrrd = write(&dir, "flat.nrrd", &nrrd);
    let mut mha = b"ObjectType = Image\nNDims = 3\nDimSize = 4 4 4\nElementSpacing = 1 1 1e6\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n".to_vec();
    mha.extend([1u8; 64]);
    let mha = write(&dir, "flat.mha", &mha);
    let phantom = scanner_support::ct_phantom(UVec3::new(4, 4, 3), DVec3::new(1.0, 1.0, 1e6));
    let series = dir.join("series");
    scanner_support::write_series(&series, &phantom, &scanner_support::SeriesSpec::default());
    for path in [&nifti, &nrrd, &mha, &series] {
        let e = load(path, None).expect_err("a million to one");
        assert!(e.starts_with(&format!("{}: the header's voxel spacing (", path.display())), "{e}");
        assert!(e.contains(RATIO_MESSAGE) && e.contains("override it with --spacing X,Y,Z"), "{e}");
        // --spacing overrides the header, and is held to the same bound.
        let fixed = RawOptions { spacing: Some(DVec3::new(1.0, 1.0, 2.0)), ..RawOptions::default() };
        assert_eq!(load_volume(path, &fixed).expect("overridden").volume.spacing, DVec3::new(1.0, 1.0, 2.0));
        let wide = RawOptions { spacing: Some(DVec3::new(1e6, 1.0, 1.0)), ..RawOptions::default() };
        let e = load_volume(path, &wide).expect_err("--spacing too").to_string();
        assert!(e.contains("--spacing (1000000, 1, 1): ") && e.contains(RATIO_MESSAGE), "{e}");
    }
    // A box read (render --distributed) reads the header alone, and is held to the same bound.
    for path in [&nrrd, &mha, &series] {
        let e = VolumeHeader::read(path, &LoadOptions::default()).map(|_| ()).expect_err("a box read").to_string();
        assert!(e.contains("the header's voxel spacing (") && e.contains(RATIO_MESSAGE), "{e}");
    }
}

#[test]
fn constant_integer_volumes_get_their_value_as_range_and_a_note() {
    let dir = common::temp_dir("constant");
    let spec = NiftiSpec::new(1, [4, 4, 4], 1, 4);
    let nifti = write(&dir, "flat16.nii", &spec.file(&voxels(4, 64, false, |_| 7.0)));
    let mut nrrd = b"NRRD0004\ntype: short\ndimension: 3\nsizes: 4 4 4\nendian: little\nencoding: raw\n\n".to_vec();
    nrrd.extend(std::iter::repeat_n(7i16.to_le_bytes(), 64).flatten());
    let nrrd = write(&dir, "flat16.nrrd", &nrrd);
    for path in [&nifti, &nrrd] {
        let loaded = load(path, None).expect("loads");
        assert_eq!(loaded.volume.value_range, (7.0, 7.0), "{}", path.display());
        assert!(
            loaded.report.notes.iter().any(|n| n.starts_with("every voxel holds the value 7: the volume is constant")),
            "{:?}",
            loaded.report.notes
        );
    }
    // 8-bit data keeps the type range its texture is normalized by, and gets the note.
    let spec = NiftiSpec::new(1, [4, 4, 4], 1, 2);
    let path = write(&dir, "flat8.nii", &spec.file(&[9; 64]));
    let loaded = load(&path, None).expect("loads");
    assert!(
        loaded.report.notes.iter().any(|n| n.starts_with("every voxel holds the value 9")),
        "{:?}",
        loaded.report.notes
    );
    // A volume that is not constant keeps its fitted range and gets no such note.
    let path = write(&dir, "ramp.nii", &NiftiSpec::new(1, [4, 4, 4], 1, 4).file(&voxels(4, 64, false, |i| i as f64)));
    let loaded = load(&path, None).expect("loads");
    assert_eq!(loaded.volume.value_range, (0.0, 63.0));
    assert!(loaded.report.notes.iter().all(|n| !n.contains("constant")), "{:?}", loaded.report.notes);
}
