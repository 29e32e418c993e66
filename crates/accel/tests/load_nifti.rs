//! Issue 21, items 2–3: NIfTI-1 (written by the nifti crate) and NIfTI-2 (written here, byte by
//! byte from nifti2.h) load in the LPS patient frame: a file whose RAS affine flips or swaps
//! axes gives the same volume as the DICOM series of the same phantom; scl_slope/scl_inter
//! are applied; a 4D file needs a frame; a truncated `.nii.gz` is an error.

mod scanner_support;

use std::path::{Path, PathBuf};

use glam::{DVec3, IVec3, UVec3};
use ndarray::{Array3, Array4, ShapeBuilder};
use nifti::NiftiHeader;
use nifti::writer::WriterOptions;
use scanner_support::*;
use volgraph_accel::load::{LoadOptions, load_volumes};
use volgraph_accel::volume::Volume;
use volgraph_accel::volume_meta::WorldFrame;

fn phantom() -> Volume {
    ct_phantom(UVec3::new(12, 10, 8), DVec3::new(0.7, 0.6, 2.5))
}

/// The phantom's voxels laid out along file axes `axes` (signed world axes, RAS-free: in LPS),
/// as an array indexed [i, j, k] of the file.
fn file_array(volume: &Volume, axes: [IVec3; 3]) -> (Array3<i16>, Layout) {
    let layout = Layout::new(volume.dims, axes[0], axes[1]);
    assert_eq!(layout.normal, axes[2], "the test uses right-handed file axes");
    let d = layout.file_dims;
    let mut a = Array3::<i16>::zeros((d.x as usize, d.y as usize, d.z as usize).f());
    for k in 0..d.z {
        for j in 0..d.y {
            for i in 0..d.x {
                a[[i as usize, j as usize, k as usize]] = value_at(volume, layout.world_index(i, j, k)) as i16;
            }
        }
    }
    (a, layout)
}

/// The sform rows (RAS) of file axes `axes` given in LPS, with the phantom's spacing and the
/// LPS position of file voxel 0.
fn sform(volume: &Volume, layout: &Layout, origin_lps: DVec3) -> [[f32; 4]; 3] {
    let lps_to_ras = DVec3::new(-1.0, -1.0, 1.0);
    let step = |d: IVec3| d.as_dvec3() * volume.spacing * lps_to_ras;
    let first = (origin_lps + layout.world_index(0, 0, 0).as_dvec3() * volume.spacing) * lps_to_ras;
    let cols = [step(layout.row), step(layout.column), step(layout.normal)];
    std::array::from_fn(|r| [cols[0][r] as f32, cols[1][r] as f32, cols[2][r] as f32, first[r] as f32])
}

fn write_nifti1(path: &Path, volume: &Volume, axes: [IVec3; 3], slope: f32, inter: f32) {
    let (array, layout) = file_array(volume, axes);
    let stored = array.mapv(|v| ((v as f32 - inter) / slope).round() as i16);
    let s = sform(volume, &layout, DVec3::ZERO);
    let header = NiftiHeader {
        sform_code: 1,
        qform_code: 0,
        srow_x: s[0],
        srow_y: s[1],
        srow_z: s[2],
        scl_slope: slope,
        scl_inter: inter,
        pixdim: [1.0, volume.spacing.x as f32, volume.spacing.y as f32, volume.spacing.z as f32, 1.0, 1.0, 1.0, 1.0],
        ..NiftiHeader::default()
    };
    WriterOptions::new(path).reference_header(&header).write_nifti(&stored).expect("write nifti");
    if (slope, inter) != (1.0, 0.0) {
        // The crate's writer resets the scale; set it in the header (offsets 112 and 116).
        let mut bytes = std::fs::read(path).expect("read back");
        bytes[112..116].copy_from_slice(&slope.to_le_bytes());
        bytes[116..120].copy_from_slice(&inter.to_le_bytes());
        std::fs::write(path, bytes).expect("patch scale");
    }
}

fn load(path: &Path, frame: Option<u64>) -> Result<volgraph_accel::load::LoadedVolume, String> {
    load_volumes(&[path.to_path_buf()], &LoadOptions { frame, ..LoadOptions::default() }).map_err(|e| e.to_string())
}

fn values(v: &Volume) -> Vec<f64> {
    (0..v.voxel_count()).map(|i| v.raw_value(i)).collect()
}

#[test]
fn a_ras_file_and_its_flipped_twins_load_as_the_lps_phantom() {
    let phantom = phantom();
    let dir = scratch("nifti_flips");
    // LPS axes of the file: plain LPS; RAS (x, y flipped, what most NIfTI writers produce); an
    // axis swap.
    for (i, axes) in [[IVec3::X, IVec3::Y, IVec3::Z], [-IVec3::X, -IVec3::Y, IVec3::Z], [IVec3::Y, IVec3::X, -IVec3::Z]]
        .into_iter()
        .enumerate()
    {
        for name in [format!("p{i}.nii"), format!("p{i}.nii.gz")] {
            let path = dir.join(&name);
            write_nifti1(&path, &phantom, axes, 1.0, 0.0);
            let loaded = load(&path, None).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(loaded.volume.dims, phantom.dims, "{name}");
            assert!((loaded.volume.spacing - phantom.spacing).abs().max_element() < 1e-6, "{name}");
            assert_eq!(values(&loaded.volume), values(&phantom), "{name}: voxels");
            assert_eq!(loaded.volume.meta.frame, WorldFrame::Lps);
        }
    }
}

#[test]
fn the_nifti_and_the_dicom_of_one_phantom_are_the_same_volume() {
    let phantom = phantom();
    let dir = scratch("nifti_vs_dicom");
    write_series(
        &dir.join("series"),
        &phantom,
        &SeriesSpec { row: IVec3::Y, column: -IVec3::X, ..SeriesSpec::default() },
    );
    write_nifti1(&dir.join("twin.nii.gz"), &phantom, [-IVec3::X, -IVec3::Y, IVec3::Z], 1.0, 0.0);
    let dicom = load_volumes(&[dir.join("series")], &LoadOptions::default()).expect("dicom");
    let nifti = load(&dir.join("twin.nii.gz"), None).expect("nifti");
    assert_eq!(dicom.volume.dims, nifti.volume.dims);
    assert_eq!(values(&dicom.volume), values(&nifti.volume));
}

#[test]
fn scl_slope_and_inter_are_applied() {
    let phantom = phantom();
    let path = scratch("nifti_scale").join("scaled.nii");
    write_nifti1(&path, &phantom, [IVec3::X, IVec3::Y, IVec3::Z], 2.0, -24.0);
    let loaded = load(&path, None).expect("loads");
    // Phantom values are even after −24 … not all: compare with the rounding the writer did.
    let want: Vec<f64> = values(&phantom).iter().map(|&v| ((v + 24.0) / 2.0).round() * 2.0 - 24.0).collect();
    let wrong = values(&loaded.volume).iter().zip(&want).filter(|(a, b)| a != b).count();
    assert_eq!(wrong, 0, "{wrong} voxels differ");
}

#[test]
fn a_4d_file_needs_a_frame() {
    let phantom = phantom();
    let path = scratch("nifti_4d").join("series.nii.gz");
    let (array, layout) = file_array(&phantom, [IVec3::X, IVec3::Y, IVec3::Z]);
    let d = layout.file_dims;
    let mut four = Array4::<i16>::zeros((d.x as usize, d.y as usize, d.z as usize, 3).f());
    for t in 0..3 {
        four.index_axis_mut(ndarray::Axis(3), t).assign(&array.mapv(|v| v + 100 * t as i16));
    }
    let s = sform(&phantom, &layout, DVec3::ZERO);
    let header = NiftiHeader { sform_code: 1, srow_x: s[0], srow_y: s[1], srow_z: s[2], ..NiftiHeader::default() };
    WriterOptions::new(&path).reference_header(&header).write_nifti(&four).expect("write");
    let e = load(&path, None).expect_err("4D");
    assert!(e.contains("holds 3 volumes (a 4D series); no --frame was given: pick one with --frame N (0..=2)"), "{e}");
    let e = load(&path, Some(3)).expect_err("past the end");
    assert!(e.contains("--frame 3 is past the end"), "{e}");
    let second = load(&path, Some(2)).expect("frame 2");
    let want: Vec<f64> = values(&phantom).iter().map(|v| v + 200.0).collect();
    assert_eq!(values(&second.volume), want);
}

/// A NIfTI-2 file written field by field (nifti2.h offsets).
fn write_nifti2(path: &Path, volume: &Volume, axes: [IVec3; 3]) {
    let (array, layout) = file_array(volume, axes);
    let s = sform(volume, &layout, DVec3::ZERO);
    let mut h = vec![0u8; 544];
    let put = |h: &mut Vec<u8>, at: usize, bytes: &[u8]| h[at..at + bytes.len()].copy_from_slice(bytes);
    put(&mut h, 0, &540i32.to_le_bytes());
    put(&mut h, 4, b"n+2\0\r\n\x1a\n");
    put(&mut h, 12, &4i16.to_le_bytes()); // int16
    put(&mut h, 14, &16i16.to_le_bytes());
    let d = layout.file_dims;
    for (i, v) in [3i64, d.x as i64, d.y as i64, d.z as i64, 1, 1, 1, 1].iter().enumerate() {
        put(&mut h, 16 + 8 * i, &v.to_le_bytes());
    }
    for (i, v) in [1.0f64, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0].iter().enumerate() {
        put(&mut h, 104 + 8 * i, &v.to_le_bytes());
    }
    put(&mut h, 168, &544i64.to_le_bytes());
    put(&mut h, 176, &1.0f64.to_le_bytes());
    put(&mut h, 348, &1i32.to_le_bytes()); // sform_code
    for (r, row) in s.iter().enumerate() {
        for (c, v) in row.iter().enumerate() {
            put(&mut h, 400 + 32 * r + 8 * c, &(*v as f64).to_le_bytes());
        }
    }
    for v in array.t().iter() {
        h.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::write(path, h).expect("write nifti-2");
}

#[test]
fn nifti_2_loads_like_nifti_1() {
    let phantom = phantom();
    let path = scratch("nifti2").join("two.nii");
    write_nifti2(&path, &phantom, [-IVec3::X, -IVec3::Y, IVec3::Z]);
    let loaded = load(&path, None).expect("nifti-2");
    assert_eq!(loaded.volume.dims, phantom.dims);
    assert!((loaded.volume.spacing - phantom.spacing).abs().max_element() < 1e-6);
    assert_eq!(values(&loaded.volume), values(&phantom));
}

#[test]
fn truncated_and_wrong_files_are_errors_not_panics() {
    let phantom = phantom();
    let dir = scratch("nifti_bad");
    let good = dir.join("good.nii.gz");
    write_nifti1(&good, &phantom, [IVec3::X, IVec3::Y, IVec3::Z], 1.0, 0.0);
    let bytes = std::fs::read(&good).expect("read");
    let cut: PathBuf = dir.join("cut.nii.gz");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).expect("write");
    let e = load(&cut, None).expect_err("truncated");
    assert!(e.contains("cut.nii.gz") && (e.contains("truncated") || e.contains("decompress")), "{e}");
    let junk = dir.join("junk.nii");
    std::fs::write(&junk, b"hello, not a header").expect("write");
    let e = load(&junk, None).expect_err("junk");
    assert!(e.contains("junk.nii: cannot read the NIfTI file: not a NIfTI file"), "{e}");
    // Every prefix of a real file: an error or a volume, never a panic.
    let raw = dir.join("plain.nii");
    write_nifti1(&raw, &phantom, [IVec3::X, IVec3::Y, IVec3::Z], 1.0, 0.0);
    let bytes = std::fs::read(&raw).expect("read");
    for n in (0..bytes.len()).step_by(97) {
        let _ = volgraph_accel::load::nifti::parse(&raw, &bytes[..n], None);
    }
}
