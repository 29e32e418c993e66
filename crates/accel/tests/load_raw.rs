//! Headerless `.raw` loading: the name convention, RawOptions overrides, byte order, float
//! repair, and the size / layout errors word for word.

mod common;

use glam::{DVec3, UVec3};
use volgraph_accel::generate;
use volgraph_accel::load::{
    Endianness, LoadError, RawOptions, VolumeFormat, check_texture_limit, load_volume, parse_raw_name,
};
use volgraph_accel::volume::{Volume, VoxelData, VoxelType};

fn write(dir: &std::path::Path, name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("write test file");
    path
}

#[test]
fn name_convention_is_parsed() {
    assert_eq!(
        parse_raw_name("hydrogen_atom_128x128x128_uint8.raw"),
        Some(("hydrogen_atom".to_string(), [128, 128, 128], Some("uint8".to_string())))
    );
    assert_eq!(
        parse_raw_name("lobster_301x324x56_u16"),
        Some(("lobster".to_string(), [301, 324, 56], Some("u16".to_string())))
    );
    assert_eq!(parse_raw_name("ct_8x8x8.raw"), Some(("ct".to_string(), [8, 8, 8], None)));
    assert_eq!(parse_raw_name("plain.raw"), None);
    assert_eq!(parse_raw_name("a_8x8_uint8.raw"), None, "two dimensions are not a volume");
    for (token, t) in
        [("uint8", VoxelType::U8), ("u16", VoxelType::U16), ("I16", VoxelType::I16), ("float32", VoxelType::F32)]
    {
        assert_eq!(VoxelType::from_name(token), Some(t));
    }
}

#[test]
fn uint8_round_trip_by_name() {
    let dir = common::temp_dir("raw-u8");
    let ml = generate::marschner_lobb(20);
    let path = write(&dir, "ml_20x20x20_uint8.raw", &common::voxel_bytes(&ml.data, false));
    let loaded = load_volume(&path, &RawOptions::default()).expect("load");
    assert_eq!(loaded.volume.data, ml.data);
    assert_eq!(loaded.volume.dims, UVec3::splat(20));
    assert_eq!(loaded.volume.spacing, DVec3::ONE);
    assert_eq!(loaded.volume.name, "ml");
    assert_eq!(loaded.volume.value_range, (0.0, 255.0));
    assert_eq!(loaded.report.format, VolumeFormat::Raw);
    assert_eq!(loaded.report.non_finite_replaced(), 0);
}

#[test]
fn sixteen_bit_round_trips_in_both_byte_orders() {
    let dir = common::temp_dir("raw-16");
    let dims = UVec3::new(5, 3, 2);
    let u16s: Vec<u16> = (0..30u16).map(|i| i * 2001).collect();
    let i16s: Vec<i16> = (0..30i16).map(|i| i * 1000 - 15000).collect();
    for big in [false, true] {
        let endianness = if big { Endianness::Big } else { Endianness::Little };
        for data in [VoxelData::U16(u16s.clone()), VoxelData::I16(i16s.clone())] {
            let name = format!("v_5x3x2_{}.raw", data.type_name());
            let path = write(&dir, &name, &common::voxel_bytes(&data, big));
            let opts = RawOptions { endianness, ..RawOptions::default() };
            let loaded = load_volume(&path, &opts).expect("load");
            assert_eq!(loaded.volume.dims, dims);
            assert_eq!(loaded.volume.data, data, "{name}, big endian = {big}");
        }
    }
}

#[test]
fn options_override_the_name_and_set_spacing() {
    let dir = common::temp_dir("raw-opts");
    let data = VoxelData::U16((0..24u16).collect());
    // The name claims uint8 4x4x4 (64 bytes); the file is 2x3x4 uint16 (48 bytes).
    let path = write(&dir, "x_4x4x4_uint8.raw", &common::voxel_bytes(&data, false));
    let opts = RawOptions {
        dims: Some(UVec3::new(2, 3, 4)),
        dtype: Some(VoxelType::U16),
        spacing: Some(DVec3::new(1.0, 1.0, 2.5)),
        ..RawOptions::default()
    };
    let loaded = load_volume(&path, &opts).expect("load");
    assert_eq!(loaded.volume.data, data);
    assert_eq!(loaded.volume.spacing, DVec3::new(1.0, 1.0, 2.5));
    // A file with no convention in its name loads with options alone.
    let plain = write(&dir, "plain.raw", &common::voxel_bytes(&data, false));
    assert_eq!(load_volume(&plain, &opts).expect("load").volume.data, data);
}

#[test]
fn float_nan_and_inf_are_replaced_and_counted() {
    let dir = common::temp_dir("raw-f32");
    let (volume, (nan, pos, neg)) = generate::non_finite_f32(8);
    assert!(nan > 0 && pos > 0 && neg > 0, "the generator plants all three kinds");
    let path = write(&dir, "nf_8x8x8_f32.raw", &common::voxel_bytes(&volume.data, false));
    let loaded = load_volume(&path, &RawOptions::default()).expect("load");
    let report = &loaded.report;
    assert_eq!((report.nan_replaced, report.pos_inf_replaced, report.neg_inf_replaced), (nan, pos, neg));
    // The finite values are the ramp x = 0..7, so the range is (0, 7); NaN and -Inf become the
    // minimum 0, +Inf the maximum 7.
    assert_eq!(loaded.volume.value_range, (0.0, 7.0));
    let VoxelData::F32(out) = &loaded.volume.data else { panic!("float32 expected") };
    let VoxelData::F32(orig) = &volume.data else { panic!("float32 expected") };
    for (i, (&o, &l)) in orig.iter().zip(out).enumerate() {
        let expected = if o.is_nan() || o == f32::NEG_INFINITY {
            0.0
        } else if o == f32::INFINITY {
            7.0
        } else {
            o
        };
        assert_eq!(l, expected, "voxel {i}");
    }
}

#[test]
fn size_mismatch_says_expected_and_actual_bytes() {
    let dir = common::temp_dir("raw-size");
    let path = write(&dir, "short_4x4x4_uint16.raw", &[0u8; 100]);
    let err = load_volume(&path, &RawOptions::default()).expect_err("100 bytes is not 4x4x4 uint16");
    assert_eq!(
        err.to_string(),
        format!(
            "{}: 4x4x4 uint16 voxels need 128 bytes, but the data has 100 bytes; check the dimensions and type in the file name (name_XxYxZ_dtype.raw), or give them with --dims XxYxZ --dtype TYPE (RawOptions::dims and ::dtype in code)",
            path.display()
        )
    );
}

#[test]
fn unknown_layout_unsupported_type_and_zero_dims_are_errors() {
    let dir = common::temp_dir("raw-layout");
    let plain = write(&dir, "plain.raw", &[0u8; 8]);
    let err = load_volume(&plain, &RawOptions::default()).expect_err("no layout");
    assert_eq!(
        err.to_string(),
        format!(
            "{}: cannot tell the voxel dimensions of a raw file; name the file like `name_256x256x128_uint8.raw` (types: uint8, uint16, int16, float32) or give it with --dims (RawOptions::dims in code)",
            plain.display()
        )
    );
    let no_type = write(&dir, "t_2x2x2.raw", &[0u8; 8]);
    let err = load_volume(&no_type, &RawOptions::default()).expect_err("no type");
    assert!(matches!(err, LoadError::RawUnknownLayout { field: "dtype", .. }), "{err}");

    let double = write(&dir, "d_2x2x2_float64.raw", &[0u8; 64]);
    let err = load_volume(&double, &RawOptions::default()).expect_err("float64");
    assert_eq!(
        err.to_string(),
        format!(
            "{}: unsupported voxel type \"float64\"; supported: uint8, uint16, int16, float32 (or u8, u16, i16, f32) (convert the data to one of them)",
            double.display()
        )
    );
    let zero = write(&dir, "z_0x4x4_uint8.raw", &[]);
    let err = load_volume(&zero, &RawOptions::default()).expect_err("zero dim");
    assert_eq!(
        err.to_string(),
        format!("{}: dimensions 0x4x4 contain a zero; every axis needs at least one voxel", zero.display())
    );
    let missing = dir.join("gone_2x2x2_uint8.raw");
    assert!(matches!(load_volume(&missing, &RawOptions::default()), Err(LoadError::Io { .. })));
    let unknown = dir.join("volume.vtk");
    assert_eq!(
        load_volume(&unknown, &RawOptions::default()).expect_err("vtk").to_string(),
        format!(
            "{}: unknown volume format \"vtk\"; use .raw, .nrrd, .nhdr, .mhd, .mha, .nii, .nii.gz, or DICOM (a folder of slices, .dcm files)",
            unknown.display()
        )
    );
}

#[test]
fn texture_limit_names_the_axis_and_bricking() {
    let volume = Volume::new("tall", UVec3::new(4, 4, 3000), DVec3::ONE, VoxelData::U8(vec![0; 4 * 4 * 3000]));
    assert!(check_texture_limit(&volume, 4096).is_ok());
    assert_eq!(
        check_texture_limit(&volume, 2048).expect_err("3000 > 2048").to_string(),
        "volume \"tall\": z size 3000 exceeds the device's 3D texture limit of 2048; split it into bricks (volgraph_accel::bricks), which lifts this limit, or downsample it"
    );
}

/// Issue 19: `NAME_2x2x2_uint8.RAW` (upper case, as Windows tools write it) was loaded as a
/// raw file but its name was not read, so it asked for --dims.
#[test]
fn an_upper_case_extension_is_read_like_a_lower_case_one() {
    assert_eq!(parse_raw_name("ct_2x2x2_uint8.RAW"), Some(("ct".to_string(), [2, 2, 2], Some("uint8".to_string()))));
    let dir = common::temp_dir("raw-upper");
    let path = write(&dir, "ct_2x2x2_uint8.RAW", &[0, 1, 2, 3, 4, 5, 6, 7]);
    let loaded = load_volume(&path, &RawOptions::default()).expect("the name gives the layout");
    assert_eq!(loaded.volume.dims, UVec3::new(2, 2, 2));
}
