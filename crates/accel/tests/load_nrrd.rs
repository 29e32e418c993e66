//! NRRD round trips: generated volumes written as attached `.nrrd` (raw and gzip) and detached
//! `.nhdr`, in every supported type and both byte orders, read back voxel for voxel.

mod common;

use std::path::{Path, PathBuf};

use glam::{DVec3, UVec3};
use volgraph_accel::generate;
use volgraph_accel::load::{RawOptions, VolumeFormat, load_volume};
use volgraph_accel::volume::{Volume, VoxelData};

fn nrrd_type(data: &VoxelData) -> &'static str {
    match data {
        VoxelData::U8(_) => "uchar",
        VoxelData::U16(_) => "unsigned short",
        VoxelData::I16(_) => "short",
        VoxelData::F32(_) => "float",
    }
}

/// Writes `volume` as NRRD; `detached` writes `<name>.nhdr` + `<name>.raw(.gz)`.
fn write_nrrd(dir: &Path, volume: &Volume, gzip: bool, big: bool, detached: bool, extra: &str) -> PathBuf {
    let d = volume.dims;
    let mut data = common::voxel_bytes(&volume.data, big);
    if gzip {
        data = common::gzip(&data);
    }
    let name = &volume.name;
    let data_name = format!("{name}.raw{}", if gzip { ".gz" } else { "" });
    let mut header = format!(
        "NRRD0004\n# written by the volgraph tests\ntype: {}\ndimension: 3\nspace: left-posterior-superior\nsizes: {} {} {}\n{extra}endian: {}\nencoding: {}\ncontent: test:=value\nkinds: domain domain domain\n",
        nrrd_type(&volume.data),
        d.x,
        d.y,
        d.z,
        if big { "big" } else { "little" },
        if gzip { "gzip" } else { "raw" },
    );
    let path;
    if detached {
        header.push_str(&format!("data file: {data_name}\n"));
        std::fs::write(dir.join(&data_name), &data).expect("write data");
        path = dir.join(format!("{name}.nhdr"));
        std::fs::write(&path, header).expect("write header");
    } else {
        header.push('\n');
        let mut bytes = header.into_bytes();
        bytes.extend_from_slice(&data);
        path = dir.join(format!("{name}.nrrd"));
        std::fs::write(&path, bytes).expect("write nrrd");
    }
    path
}

fn test_volumes() -> Vec<Volume> {
    let ml = generate::marschner_lobb(12);
    let dims = UVec3::new(5, 4, 3);
    let n = 60;
    let u16s = VoxelData::U16((0..n).map(|i| (i * 1093) as u16).collect());
    let i16s = VoxelData::I16((0..n).map(|i| (i * 547) as i16 - 16000).collect());
    let f32s = VoxelData::F32((0..n).map(|i| (i as f32 - 20.0) * 0.37).collect());
    vec![
        ml,
        Volume::new("u16", dims, DVec3::ONE, u16s),
        Volume::new("i16", dims, DVec3::ONE, i16s),
        Volume::new("f32", dims, DVec3::ONE, f32s),
    ]
}

#[test]
fn every_type_encoding_and_layout_round_trips() {
    let dir = common::temp_dir("nrrd");
    for volume in test_volumes() {
        for (gzip, big, detached) in [
            (false, false, false),
            (true, false, false),
            (false, true, false),
            (false, false, true),
            (true, true, true),
        ] {
            let sub = dir.join(format!("{}-{gzip}-{big}-{detached}", volume.name));
            std::fs::create_dir_all(&sub).expect("mkdir");
            let path = write_nrrd(&sub, &volume, gzip, big, detached, "spacings: 1 1 1\n");
            let loaded = load_volume(&path, &RawOptions::default())
                .unwrap_or_else(|e| panic!("gzip {gzip}, big {big}, detached {detached}: {e}"));
            let what = format!("{} gzip {gzip} big {big} detached {detached}", volume.name);
            assert_eq!(loaded.volume.data, volume.data, "{what}");
            assert_eq!(loaded.volume.dims, volume.dims, "{what}");
            assert_eq!(loaded.report.format, VolumeFormat::Nrrd);
            assert_eq!(loaded.report.non_finite_replaced(), 0);
            let data_file = if detached {
                format!("{}.raw{}", volume.name, if gzip { ".gz" } else { "" })
            } else {
                format!("{}.nrrd", volume.name)
            };
            assert_eq!(loaded.report.data_path, sub.join(data_file), "{what}");
        }
    }
}

#[test]
fn spacing_comes_from_spacings_or_direction_lengths() {
    let dir = common::temp_dir("nrrd-spacing");
    let volume = generate::sphere(6, 0.5);
    let path = write_nrrd(&dir, &volume, false, false, false, "spacings: 0.5 0.5 2\n");
    assert_eq!(load_volume(&path, &RawOptions::default()).expect("load").volume.spacing, DVec3::new(0.5, 0.5, 2.0));
    let path = write_nrrd(&dir, &volume, false, false, false, "space directions: (1,0,0) (0, 2, 0) (0,0,3)\n");
    let loaded = load_volume(&path, &RawOptions::default()).expect("load");
    assert_eq!(loaded.volume.spacing, DVec3::new(1.0, 2.0, 3.0));
    assert_eq!(loaded.volume.name, "sphere_6");
    assert!(loaded.report.notes.is_empty(), "axis directions need no reordering: {:?}", loaded.report.notes);
}

/// A volume whose every voxel differs, so any flip or swap shows.
fn ramp(dims: UVec3) -> Volume {
    let n = (dims.x * dims.y * dims.z) as usize;
    Volume::new("ramp", dims, DVec3::ONE, VoxelData::U16((0..n).map(|i| i as u16).collect()))
}

/// `volume` stored the way a scanner that lists file axis 0 along −y, file axis 1 along +x and
/// file axis 2 along −z would store it.
fn stored_flipped_and_swapped(volume: &Volume) -> Volume {
    let d = volume.dims;
    let VoxelData::U16(values) = &volume.data else { unreachable!() };
    let file_dims = UVec3::new(d.y, d.x, d.z);
    let mut out = Vec::new();
    for k in 0..file_dims.z {
        for j in 0..file_dims.y {
            for i in 0..file_dims.x {
                // world x = j, world y = (ny-1) - i, world z = (nz-1) - k
                let (x, y, z) = (j, d.y - 1 - i, d.z - 1 - k);
                out.push(values[volume.index(x, y, z)]);
            }
        }
    }
    Volume::new("flipped", file_dims, DVec3::ONE, VoxelData::U16(out))
}

#[test]
fn flipped_and_swapped_axes_are_reordered_into_world_order() {
    let dir = common::temp_dir("nrrd-flip");
    let world = ramp(UVec3::new(4, 3, 2));
    let stored = stored_flipped_and_swapped(&world);
    let path = write_nrrd(&dir, &stored, false, true, false, "space directions: (0,-1.5,0) (1,0,0) (0,0,-2)\n");
    let loaded = load_volume(&path, &RawOptions::default()).expect("load");
    assert_eq!(loaded.volume.dims, world.dims);
    assert_eq!(loaded.volume.data, world.data, "the voxels come back in world order");
    assert_eq!(loaded.volume.spacing, DVec3::new(1.0, 1.5, 2.0));
    assert_eq!(
        loaded.report.notes,
        vec!["voxels reordered to world axes (file axis 0 → −y, 1 → +x, 2 → −z): flips and axis swaps in the header are honoured".to_string()]
    );
}

#[test]
fn oblique_directions_are_rejected_with_the_header_line() {
    let dir = common::temp_dir("nrrd-oblique");
    let volume = generate::sphere(6, 0.5);
    let path = write_nrrd(&dir, &volume, false, false, false, "space directions: (0.6,0.8,0) (0, 2, 0) (0,0,-3)\n");
    let err = load_volume(&path, &RawOptions::default()).expect_err("a rotated grid cannot be drawn unresampled");
    let text = err.to_string();
    assert!(
        text.contains("sphere_6.nrrd:7: space directions (0.6,0.8,0) (0,2,0) (0,0,-3) are not along the volume's axes"),
        "{text}"
    );
    assert!(text.contains("resample the volume"), "{text}");
}

#[test]
fn a_missing_detached_data_file_names_the_header_line() {
    let dir = common::temp_dir("nrrd-missing-data");
    let header = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\ndata file: gone.raw\n";
    std::fs::write(dir.join("v.nhdr"), header).expect("write");
    let err = load_volume(&dir.join("v.nhdr"), &RawOptions::default()).expect_err("no data file");
    let text = err.to_string();
    assert!(text.contains("v.nhdr:6: the header's data file \"gone.raw\" points to"), "{text}");
    assert!(text.contains("gone.raw, which cannot be read"), "{text}");
}

#[test]
fn a_byte_order_mark_before_the_magic_is_accepted() {
    let dir = common::temp_dir("nrrd-bom");
    let mut bytes = vec![0xEF, 0xBB, 0xBF];
    bytes.extend_from_slice(b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n");
    bytes.extend(0u8..8);
    std::fs::write(dir.join("bom.nrrd"), bytes).expect("write");
    let loaded = load_volume(&dir.join("bom.nrrd"), &RawOptions::default()).expect("a BOM is not part of the magic");
    assert_eq!(loaded.volume.data, VoxelData::U8((0u8..8).collect()));
}

#[test]
fn float_repairs_are_reported() {
    let dir = common::temp_dir("nrrd-nan");
    let (volume, (nan, pos, neg)) = generate::non_finite_f32(6);
    let path = write_nrrd(&dir, &volume, true, false, false, "");
    let loaded = load_volume(&path, &RawOptions::default()).expect("load");
    let r = &loaded.report;
    assert_eq!((r.nan_replaced, r.pos_inf_replaced, r.neg_inf_replaced), (nan, pos, neg));
    assert_eq!(loaded.volume.value_range, (0.0, 5.0), "finite values are the ramp 0..5");
}

#[test]
fn missing_endian_defaults_to_little_with_a_note() {
    let dir = common::temp_dir("nrrd-endian");
    let data: Vec<u16> = vec![1, 256, 65535, 7, 8, 9, 10, 11];
    let mut bytes = b"NRRD0005\ntype: uint16\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n".to_vec();
    bytes.extend(data.iter().flat_map(|v| v.to_le_bytes()));
    let path = dir.join("noendian.nrrd");
    std::fs::write(&path, bytes).expect("write");
    let loaded = load_volume(&path, &RawOptions::default()).expect("load");
    assert_eq!(loaded.volume.data, VoxelData::U16(data));
    assert_eq!(loaded.report.notes, vec!["no \"endian\" field; read as little endian".to_string()]);
}

#[test]
fn byte_skip_minus_one_reads_the_end_of_the_data_file() {
    let dir = common::temp_dir("nrrd-skip");
    let mut data = vec![0xAAu8; 10]; // junk before the voxels
    data.extend(0u8..8);
    std::fs::write(dir.join("v.bin"), &data).expect("write");
    let header = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\nbyte skip: -1\ndata file: v.bin\n";
    std::fs::write(dir.join("v.nhdr"), header).expect("write");
    let loaded = load_volume(&dir.join("v.nhdr"), &RawOptions::default()).expect("load");
    assert_eq!(loaded.volume.data, VoxelData::U8((0u8..8).collect()));
    let header = header.replace("-1", "10");
    std::fs::write(dir.join("w.nhdr"), header).expect("write");
    let loaded = load_volume(&dir.join("w.nhdr"), &RawOptions::default()).expect("load");
    assert_eq!(loaded.volume.data, VoxelData::U8((0u8..8).collect()));
}

/// Issue 19: `kinds: RGB-color …` and `3-vector` files were read as scalar volumes (the
/// components interleaved along an axis). Vector and colour axes are refused, naming the line.
#[test]
fn vector_and_colour_kinds_are_refused() {
    let dir = common::temp_dir("nrrd-kinds");
    for kinds in ["RGB-color domain domain", "domain 3-vector domain", "domain domain list"] {
        let header = format!("NRRD0004\ntype: uchar\ndimension: 3\nsizes: 3 2 2\nencoding: raw\nkinds: {kinds}\n\n");
        let mut bytes = header.into_bytes();
        bytes.extend(0u8..12);
        std::fs::write(dir.join("v.nrrd"), bytes).expect("write");
        let err = load_volume(&dir.join("v.nrrd"), &RawOptions::default()).expect_err(kinds).to_string();
        assert!(err.contains("v.nrrd:6:") && err.contains("renders scalar volumes"), "{kinds}: {err}");
    }
    let header = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\nkinds: domain space ???\n\n";
    let mut bytes = header.as_bytes().to_vec();
    bytes.extend(0u8..8);
    std::fs::write(dir.join("ok.nrrd"), bytes).expect("write");
    load_volume(&dir.join("ok.nrrd"), &RawOptions::default()).expect("spatial kinds are scalar volumes");
}

/// Issue 21, item 3: NRRD's `space` is honoured. A RAS file (what 3D Slicer writes) whose
/// directions are the identity runs along −x and −y in LPS: it loads as the LPS file whose
/// directions flip those axes, and as an LPS volume.
#[test]
fn an_ras_space_is_turned_into_lps() {
    use volgraph_accel::load::parse_nrrd;
    use volgraph_accel::volume_meta::WorldFrame;
    let data: Vec<u8> = (0..24).collect();
    let header = |space: &str, dirs: &str| {
        let mut bytes = format!(
            "NRRD0004\ntype: uint8\ndimension: 3\nspace: {space}\nsizes: 2 3 4\nspace directions: {dirs}\nencoding: raw\n\n"
        )
        .into_bytes();
        bytes.extend_from_slice(&data);
        bytes
    };
    let path = std::path::Path::new("twin.nrrd");
    let ras = parse_nrrd(path, &header("right-anterior-superior", "(1,0,0) (0,1,0) (0,0,1)")).expect("RAS");
    let lps = parse_nrrd(path, &header("left-posterior-superior", "(-1,0,0) (0,-1,0) (0,0,1)")).expect("LPS");
    assert_eq!(ras.volume.data, lps.volume.data);
    assert_eq!(ras.volume.meta.frame, WorldFrame::Lps);
    assert_ne!(ras.volume.data, volgraph_accel::volume::VoxelData::U8(data.clone()), "the axes were flipped");
    let scanner = parse_nrrd(path, &header("scanner-xyz", "(1,0,0) (0,1,0) (0,0,1)")).expect("scanner");
    assert_eq!(scanner.volume.data, volgraph_accel::volume::VoxelData::U8(data));
    assert_eq!(scanner.volume.meta.frame, WorldFrame::Named("scanner-xyz".into()));
}

/// `space origin` is the first stored voxel's centre; after the voxels are reordered into world
/// order the volume's origin is its world-lowest voxel's centre (a flipped axis starts at its
/// other end), in LPS for an anatomical space (RAS origins negate x and y).
#[test]
fn the_space_origin_places_the_volume_in_the_patient_frame() {
    let dir = common::temp_dir("nrrd-origin");
    let world = ramp(UVec3::new(4, 3, 2));
    let stored = stored_flipped_and_swapped(&world);
    let extra = "space directions: (0,-1.5,0) (1,0,0) (0,0,-2)\nspace origin: (10, 20, 30)\n";
    let path = write_nrrd(&dir, &stored, false, false, false, extra);
    let loaded = load_volume(&path, &RawOptions::default()).expect("load");
    // y: 20 − 1.5 · (3 − 1); z: 30 − 2 · (2 − 1).
    assert_eq!(loaded.volume.meta.origin, Some(DVec3::new(10.0, 17.0, 28.0)));

    let ras = ramp(UVec3::new(4, 3, 2));
    let text = std::fs::read(write_nrrd(
        &dir,
        &ras,
        false,
        false,
        false,
        "space directions: (1,0,0) (0,1,0) (0,0,1)\nspace origin: (5,6,7)\n",
    ))
    .expect("read");
    let text = String::from_utf8_lossy(&text).replace("left-posterior-superior", "right-anterior-superior");
    let ras_path = dir.join("ras.nrrd");
    std::fs::write(&ras_path, text.as_bytes()).expect("write");
    let loaded = load_volume(&ras_path, &RawOptions::default()).expect("load");
    // LPS (−5, −6, 7); x and y run towards −LPS in the file: the lowest voxel is 3 and 2 away.
    assert_eq!(loaded.volume.meta.origin, Some(DVec3::new(-8.0, -8.0, 7.0)));
}

/// A segmentation saved on a cropped grid (as 3D Slicer saves a `.seg.nrrd`: only the extent
/// its segments cover) lands on its scan: the scan's voxel at the segmentation's origin maps to
/// the segmentation's first voxel. Before `space origin` was read both sat at 0 and the
/// segment drew 2 voxels off.
#[test]
fn a_segmentation_on_a_cropped_grid_lands_on_its_scan() {
    let dir = common::temp_dir("nrrd-cropped-seg");
    let mut scan = ramp(UVec3::splat(8));
    scan.name = "scan".into();
    let mut seg = ramp(UVec3::splat(4));
    seg.name = "seg".into();
    let directions = "space directions: (1,0,0) (0,1,0) (0,0,1)\n";
    let scan = load_volume(
        &write_nrrd(&dir, &scan, false, false, false, &format!("{directions}space origin: (-4,-4,-4)\n")),
        &RawOptions::default(),
    )
    .expect("scan")
    .volume;
    let seg = load_volume(
        &write_nrrd(&dir, &seg, false, false, false, &format!("{directions}space origin: (-2,-2,-2)\n")),
        &RawOptions::default(),
    )
    .expect("seg")
    .volume;
    let map = volgraph_accel::fusion::TextureMap::between(&scan, &seg).expect("one frame");
    // The scan's voxel (2, 2, 2) centre, in its texture space, is the segmentation's first.
    let at_scan = (DVec3::splat(2.0) + 0.5) / 8.0;
    let at_seg = map.apply(at_scan);
    assert!((at_seg - DVec3::splat(0.5 / 4.0)).abs().max_element() < 1e-12, "{at_seg}");
}
