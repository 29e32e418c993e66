//! MetaImage round trips: `.mhd` + detached data and `.mha` with LOCAL data, plain and zlib
//! compressed, little and big endian, in every supported type.

mod common;

use std::path::{Path, PathBuf};

use glam::{DVec3, UVec3};
use volgraph_accel::generate;
use volgraph_accel::load::{RawOptions, VolumeFormat, load_volume};
use volgraph_accel::volume::{Volume, VoxelData};

fn met_type(data: &VoxelData) -> &'static str {
    match data {
        VoxelData::U8(_) => "MET_UCHAR",
        VoxelData::U16(_) => "MET_USHORT",
        VoxelData::I16(_) => "MET_SHORT",
        VoxelData::F32(_) => "MET_FLOAT",
    }
}

fn write_meta(dir: &Path, volume: &Volume, compressed: bool, big: bool, local: bool) -> PathBuf {
    let d = volume.dims;
    let mut data = common::voxel_bytes(&volume.data, big);
    if compressed {
        data = common::zlib(&data);
    }
    let data_name = format!("{}.{}", volume.name, if compressed { "zraw" } else { "raw" });
    let header = format!(
        "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = {}\nCompressedData = {}\nTransformMatrix = 1 0 0 0 1 0 0 0 1\nOffset = 0 0 0\nElementSpacing = 1 0.5 2\nDimSize = {} {} {}\nElementType = {}\nElementDataFile = {}\n",
        if big { "True" } else { "False" },
        if compressed { "True" } else { "False" },
        d.x,
        d.y,
        d.z,
        met_type(&volume.data),
        if local { "LOCAL" } else { &data_name },
    );
    if local {
        let path = dir.join(format!("{}.mha", volume.name));
        let mut bytes = header.into_bytes();
        bytes.extend_from_slice(&data);
        std::fs::write(&path, bytes).expect("write mha");
        path
    } else {
        std::fs::write(dir.join(&data_name), &data).expect("write data");
        let path = dir.join(format!("{}.mhd", volume.name));
        std::fs::write(&path, header).expect("write mhd");
        path
    }
}

#[test]
fn every_type_compression_and_layout_round_trips() {
    let dir = common::temp_dir("meta");
    let dims = UVec3::new(3, 5, 4);
    let n = 60;
    let volumes = [
        generate::checkerboard(10, 3),
        Volume::new("u16", dims, DVec3::ONE, VoxelData::U16((0..n).map(|i| (i * 1091) as u16).collect())),
        Volume::new("i16", dims, DVec3::ONE, VoxelData::I16((0..n).map(|i| (i * 541) as i16 - 16000).collect())),
        Volume::new("f32", dims, DVec3::ONE, VoxelData::F32((0..n).map(|i| (i as f32).sqrt() - 3.0).collect())),
    ];
    for volume in &volumes {
        for compressed in [false, true] {
            for big in [false, true] {
                for local in [false, true] {
                    let what = format!("{} compressed {compressed} big {big} local {local}", volume.name);
                    let path = write_meta(&dir, volume, compressed, big, local);
                    let loaded = load_volume(&path, &RawOptions::default()).unwrap_or_else(|e| panic!("{what}: {e}"));
                    assert_eq!(loaded.volume.data, volume.data, "{what}");
                    assert_eq!(loaded.volume.dims, volume.dims, "{what}");
                    assert_eq!(loaded.volume.spacing, DVec3::new(1.0, 0.5, 2.0), "{what}");
                    assert_eq!(loaded.report.format, VolumeFormat::MetaImage);
                }
            }
        }
    }
}

#[test]
fn header_size_skips_bytes_of_a_detached_file() {
    let dir = common::temp_dir("meta-hs");
    let mut bytes = vec![9u8; 16];
    bytes.extend(0u8..8);
    std::fs::write(dir.join("v.raw"), &bytes).expect("write");
    for (size, name) in [("16", "a.mhd"), ("-1", "b.mhd")] {
        let header = format!(
            "NDims = 3\nDimSize = 2 2 2\nElementType = MET_UCHAR\nHeaderSize = {size}\nElementDataFile = v.raw\n"
        );
        std::fs::write(dir.join(name), header).expect("write");
        let loaded = load_volume(&dir.join(name), &RawOptions::default()).expect("load");
        assert_eq!(loaded.volume.data, VoxelData::U8((0u8..8).collect()), "HeaderSize = {size}");
    }
}

#[test]
fn spacing_option_overrides_the_header() {
    let dir = common::temp_dir("meta-sp");
    let path = write_meta(&dir, &generate::zeros(4), false, false, true);
    let opts = RawOptions { spacing: Some(DVec3::new(2.0, 2.0, 3.0)), ..RawOptions::default() };
    assert_eq!(load_volume(&path, &opts).expect("load").volume.spacing, DVec3::new(2.0, 2.0, 3.0));
}

#[test]
fn transform_matrix_flips_are_honoured_and_rotations_rejected() {
    let dir = common::temp_dir("mhd-transform");
    // File axis 0 runs along −x: the stored rows are mirrored.
    let stored: Vec<u8> = vec![1, 0, 3, 2, 5, 4, 7, 6];
    std::fs::write(dir.join("f.raw"), &stored).expect("write");
    let header = "NDims = 3\nTransformMatrix = -1 0 0 0 1 0 0 0 1\nElementSpacing = 2 1 1\nDimSize = 2 2 2\nElementType = MET_UCHAR\nElementDataFile = f.raw\n";
    std::fs::write(dir.join("f.mhd"), header).expect("write");
    let loaded = load_volume(&dir.join("f.mhd"), &RawOptions::default()).expect("a flip is honoured");
    assert_eq!(loaded.volume.data, VoxelData::U8((0u8..8).collect()));
    assert_eq!(loaded.volume.spacing, glam::DVec3::new(2.0, 1.0, 1.0));
    let rotated = header.replace("-1 0 0 0 1 0 0 0 1", "0.8 0.6 0 -0.6 0.8 0 0 0 1");
    std::fs::write(dir.join("r.mhd"), rotated).expect("write");
    let err = load_volume(&dir.join("r.mhd"), &RawOptions::default()).expect_err("rotated");
    assert!(err.to_string().contains("r.mhd:2: TransformMatrix"), "{err}");
    assert!(err.to_string().contains("are not along the volume's axes"), "{err}");
}

/// Issue 19: `ElementDataFile` before `DimSize` said "no DimSize field" (the field is there,
/// after the line that ends the header), and a NaN TransformMatrix came out as spacing 0.
#[test]
fn fields_after_the_data_file_and_non_finite_matrices_are_named() {
    let dir = common::temp_dir("mhd-order");
    std::fs::write(dir.join("v.raw"), [0u8; 8]).expect("write");
    let header = "NDims = 3\nElementType = MET_UCHAR\nElementDataFile = v.raw\nDimSize = 2 2 2\n";
    std::fs::write(dir.join("late.mhd"), header).expect("write");
    let err = load_volume(&dir.join("late.mhd"), &RawOptions::default()).expect_err("DimSize after the data file");
    let text = err.to_string();
    assert!(text.contains("late.mhd:3: ElementDataFile must be the last field"), "{text}");
    assert!(text.contains("move DimSize above ElementDataFile"), "{text}");
    let nan = "NDims = 3\nTransformMatrix = NaN 0 0 0 1 0 0 0 1\nDimSize = 2 2 2\nElementType = MET_UCHAR\nElementDataFile = v.raw\n";
    std::fs::write(dir.join("nan.mhd"), nan).expect("write");
    let err = load_volume(&dir.join("nan.mhd"), &RawOptions::default()).expect_err("NaN matrix").to_string();
    assert!(err.contains("nan.mhd:2:") && err.contains("nine finite numbers"), "{err}");
}

/// `Offset` is the first stored voxel's centre; the volume's origin is its world-lowest voxel's
/// after the reorder (file axis 0 runs along −x here: it starts 2 mm further along x).
#[test]
fn the_offset_places_the_volume() {
    let dir = common::temp_dir("mhd-offset");
    std::fs::write(dir.join("f.raw"), [0u8; 8]).expect("write");
    let header = "NDims = 3\nTransformMatrix = -1 0 0 0 1 0 0 0 1\nOffset = 10 20 30\nElementSpacing = 2 1 1\nDimSize = 2 2 2\nElementType = MET_UCHAR\nElementDataFile = f.raw\n";
    std::fs::write(dir.join("f.mhd"), header).expect("write");
    let loaded = load_volume(&dir.join("f.mhd"), &RawOptions::default()).expect("loads");
    assert_eq!(loaded.volume.meta.origin, Some(DVec3::new(8.0, 20.0, 30.0)));
    let bad = header.replace("Offset = 10 20 30", "Offset = 10 inf 30");
    std::fs::write(dir.join("bad.mhd"), bad).expect("write");
    let err = load_volume(&dir.join("bad.mhd"), &RawOptions::default()).expect_err("infinite offset").to_string();
    assert!(err.contains("bad.mhd:3:") && err.contains("three finite numbers"), "{err}");
}
