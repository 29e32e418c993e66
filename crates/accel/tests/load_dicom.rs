//! Issue 21, item 1: DICOM series, written in-tree with dicom-rs from a CT phantom in the LPS
//! frame. Every good case loads back to exactly that phantom (its raw twin) — values in HU,
//! dims, spacing — whatever the file names, slice order, orientation, transfer syntax or
//! rescale; every bad case is a message naming the file or the slices.

mod scanner_support;

use std::path::PathBuf;

use glam::{DVec3, IVec3, UVec3};
use scanner_support::*;
use volgraph_accel::load::{LoadOptions, load_volumes};
use volgraph_accel::volume::{Volume, VoxelData};
use volgraph_accel::volume_meta::WorldFrame;

fn phantom() -> Volume {
    ct_phantom(UVec3::new(12, 10, 8), DVec3::new(0.7, 0.6, 2.5))
}

fn load(paths: &[PathBuf]) -> Result<volgraph_accel::load::LoadedVolume, String> {
    load_volumes(paths, &LoadOptions::default()).map_err(|e| e.to_string())
}

fn load_series(paths: &[PathBuf], series: &str) -> Result<volgraph_accel::load::LoadedVolume, String> {
    let options = LoadOptions { series: Some(series.to_string()), ..LoadOptions::default() };
    load_volumes(paths, &options).map_err(|e| e.to_string())
}

/// The loaded volume is the phantom: same world dims, spacing (to the header's decimal
/// precision) and every value.
fn assert_twin(loaded: &Volume, phantom: &Volume) {
    assert_eq!(loaded.dims, phantom.dims, "dims");
    assert!(
        (loaded.spacing - phantom.spacing).abs().max_element() < 1e-9,
        "spacing {} vs {}",
        loaded.spacing,
        phantom.spacing
    );
    let values: Vec<f64> = (0..loaded.voxel_count()).map(|i| loaded.raw_value(i)).collect();
    let want: Vec<f64> = (0..phantom.voxel_count()).map(|i| phantom.raw_value(i)).collect();
    let wrong = values.iter().zip(&want).filter(|(a, b)| (*a - *b).abs() > 1e-3).count();
    assert_eq!(wrong, 0, "{wrong} voxels differ from the phantom");
}

#[test]
fn every_transfer_syntax_loads_the_phantom_in_hounsfield_units() {
    let phantom = phantom();
    for (name, ts) in [("implicit", IMPLICIT_LE), ("explicit", EXPLICIT_LE), ("big", EXPLICIT_BE), ("rle", RLE)] {
        let dir = scratch(&format!("ts_{name}"));
        write_series(&dir, &phantom, &SeriesSpec { transfer_syntax: ts, ..SeriesSpec::default() });
        let loaded = load(&[dir]).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_twin(&loaded.volume, &phantom);
        // Stored unsigned with intercept −1024: kept as int16 in HU.
        assert!(matches!(loaded.volume.data, VoxelData::I16(_)), "{name}: {}", loaded.volume.data.type_name());
        let meta = &loaded.volume.meta;
        assert_eq!(meta.units.as_deref(), Some("HU"));
        assert_eq!(meta.modality.as_deref(), Some("CT"));
        assert_eq!(meta.frame, WorldFrame::Lps);
        assert_eq!(meta.window.map(|w| (w.center, w.width)), Some((40.0, 400.0)));
        // The value range is the data's, so a TF in HU gets the whole LUT.
        assert_eq!(loaded.volume.value_range, loaded.volume.data_min_max());
        assert_eq!(meta.origin, Some(SeriesSpec::default().origin));
    }
}

#[test]
fn shuffled_names_and_descending_positions_are_sorted_by_position() {
    let phantom = phantom();
    let dir = scratch("shuffled");
    // Column direction −y: the normal row × column is −z, so positions fall as slices go on,
    // and InstanceNumber runs against them too.
    let spec = SeriesSpec { row: IVec3::X, column: -IVec3::Y, shuffle_names: true, ..SeriesSpec::default() };
    write_series(&dir, &phantom, &spec);
    let loaded = load(&[dir]).expect("loads");
    assert_twin(&loaded.volume, &phantom);
    assert!(loaded.report.notes.iter().any(|n| n.contains("LPS")), "{:?}", loaded.report.notes);
}

#[test]
fn flips_and_axis_swaps_are_honoured() {
    let phantom = phantom();
    for (i, (row, column)) in
        [(-IVec3::X, IVec3::Y), (IVec3::Y, IVec3::X), (IVec3::Z, -IVec3::X), (-IVec3::Y, IVec3::Z)]
            .into_iter()
            .enumerate()
    {
        let dir = scratch(&format!("orient_{i}"));
        write_series(&dir, &phantom, &SeriesSpec { row, column, ..SeriesSpec::default() });
        let loaded = load(&[dir]).unwrap_or_else(|e| panic!("row {row} column {column}: {e}"));
        assert_twin(&loaded.volume, &phantom);
    }
}

#[test]
fn a_list_of_files_is_a_series() {
    let phantom = phantom();
    let dir = scratch("list");
    let files = write_series(&dir, &phantom, &SeriesSpec::default());
    std::fs::write(dir.join("notes.txt"), "not a slice").expect("write");
    let loaded = load(&files).expect("loads");
    assert_twin(&loaded.volume, &phantom);
    // The folder itself: the text file is skipped with a count.
    let loaded = load(&[dir]).expect("loads");
    assert!(
        loaded.report.notes.iter().any(|n| n.contains("skipped 1 file(s) that are not DICOM")),
        "{:?}",
        loaded.report.notes
    );
}

#[test]
fn mr_with_a_fractional_slope_is_float() {
    let mut phantom = phantom();
    // Values on a 0.5 grid, non-negative: stored unsigned with slope 0.5.
    if let VoxelData::I16(v) = &phantom.data {
        let halves: Vec<f32> = v.iter().map(|&x| (x as f32 + 1024.0) * 0.5).collect();
        phantom = Volume::new("mr", phantom.dims, phantom.spacing, VoxelData::F32(halves));
    }
    let dir = scratch("mr");
    let spec = SeriesSpec { modality: "MR".into(), slope: 0.5, intercept: 0.0, ..SeriesSpec::default() };
    write_series(&dir, &phantom, &spec);
    let loaded = load(&[dir]).expect("loads");
    assert!(matches!(loaded.volume.data, VoxelData::F32(_)));
    assert_twin(&loaded.volume, &phantom);
    assert_eq!(loaded.volume.meta.units, None, "MR values have no physical unit");
}

#[test]
fn two_series_are_listed_and_picked_by_number_uid_or_description() {
    let phantom = phantom();
    let dir = scratch("two");
    write_series(&dir.join("a"), &phantom, &SeriesSpec::default());
    let other = ct_phantom(UVec3::new(6, 5, 4), DVec3::ONE);
    let second = SeriesSpec {
        uid: "1.2.826.0.1.3680043.8.498.2".into(),
        number: 2,
        description: "COR small".into(),
        ..SeriesSpec::default()
    };
    write_series(&dir.join("b"), &other, &second);
    let e = load(std::slice::from_ref(&dir)).expect_err("two series");
    assert!(e.contains("holds 2 DICOM series"), "{e}");
    assert!(e.contains("1. series 1 \"AX test\" CT: 8 slice(s) of 12x10"), "{e}");
    assert!(e.contains("2. series 2 \"COR small\" CT: 4 slice(s) of 6x5"), "{e}");
    assert_twin(&load_series(std::slice::from_ref(&dir), "2").expect("by number").volume, &other);
    assert_twin(
        &load_series(std::slice::from_ref(&dir), "1.2.826.0.1.3680043.8.498.1").expect("by UID").volume,
        &phantom,
    );
    assert_twin(&load_series(std::slice::from_ref(&dir), "cor small").expect("by description").volume, &other);
    let e = load_series(&[dir], "sagittal").expect_err("no such series");
    assert!(e.contains("no DICOM series \"sagittal\"") && e.contains("2. series 2"), "{e}");
}

#[test]
fn a_gap_names_the_positions_around_it() {
    let dir = scratch("gap");
    write_series(&dir, &phantom(), &SeriesSpec { skip: vec![4], ..SeriesSpec::default() });
    let e = load(&[dir]).expect_err("a gap");
    assert!(e.contains("a gap") && e.contains("5.000 mm between") && e.contains("at 20.000 mm and"), "{e}");
}

#[test]
fn an_oblique_series_is_rejected_with_what_to_do() {
    let dir = scratch("oblique");
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    write_series(
        &dir,
        &phantom(),
        &SeriesSpec { orientation_override: Some([c, s, 0.0, -s, c, 0.0]), ..SeriesSpec::default() },
    );
    let e = load(&[dir]).expect_err("oblique");
    assert!(
        e.contains("ImageOrientationPatient") && e.contains("not along the volume's axes") && e.contains("resample"),
        "{e}"
    );
}

#[test]
fn a_slice_without_position_is_named() {
    let dir = scratch("no_position");
    write_series(&dir, &phantom(), &SeriesSpec { drop_position: Some(3), ..SeriesSpec::default() });
    let e = load(&[dir]).expect_err("no position");
    assert!(e.contains("IM0004 has no ImagePositionPatient"), "{e}");
}

#[test]
fn bad_files_are_named_never_a_panic() {
    let phantom = phantom();
    // A corrupt slice: the magic, then garbage.
    let dir = scratch("corrupt");
    write_series(&dir, &phantom, &SeriesSpec::default());
    let mut bytes = vec![0u8; 128];
    bytes.extend_from_slice(b"DICM");
    bytes.extend((0..300u32).map(|i| (i * 37 % 251) as u8));
    std::fs::write(dir.join("IM0099"), &bytes).expect("write");
    let e = load(std::slice::from_ref(&dir)).expect_err("corrupt");
    assert!(e.contains("IM0099: cannot read the DICOM file"), "{e}");

    // A truncated slice: its pixel data cut short.
    let dir = scratch("truncated");
    let files = write_series(&dir, &phantom, &SeriesSpec::default());
    let whole = std::fs::read(&files[2]).expect("read");
    std::fs::write(&files[2], &whole[..whole.len() - 50]).expect("truncate");
    let e = load(std::slice::from_ref(&dir)).expect_err("truncated");
    assert!(e.contains(&files[2].display().to_string()), "{e}");

    // Slices of different sizes in one series.
    let dir = scratch("sizes");
    write_series(&dir, &phantom, &SeriesSpec::default());
    let small = ct_phantom(UVec3::new(6, 5, 1), DVec3::new(0.7, 0.6, 2.5));
    let odd = scratch("sizes_odd");
    let files =
        write_series(&odd, &small, &SeriesSpec { origin: DVec3::new(-40.0, -30.0, 40.0), ..SeriesSpec::default() });
    std::fs::copy(&files[0], dir.join("IM0050")).expect("copy");
    let e = load(std::slice::from_ref(&dir)).expect_err("sizes");
    assert!(e.contains("slices of different sizes") && e.contains("IM0050"), "{e}");

    // Only a DICOMDIR, or nothing DICOM at all.
    let dir = scratch("empty");
    std::fs::write(dir.join("readme.txt"), "hello").expect("write");
    let e = load(std::slice::from_ref(&dir)).expect_err("nothing");
    assert!(e.contains("is a folder with no DICOM images (1 file(s): 1 not DICOM"), "{e}");
}

#[test]
fn a_dicomdir_beside_the_slices_is_skipped() {
    let phantom = phantom();
    let dir = scratch("dicomdir");
    write_series(&dir, &phantom, &SeriesSpec::default());
    let object = dicom_object::InMemDicomObject::from_element_iter([dicom_core::DataElement::new(
        dicom_dictionary_std::tags::FILE_SET_ID,
        dicom_core::VR::CS,
        dicom_core::value::PrimitiveValue::from("TEST"),
    )]);
    object
        .with_meta(
            dicom_object::FileMetaTableBuilder::new()
                .transfer_syntax(EXPLICIT_LE)
                .media_storage_sop_class_uid("1.2.840.10008.1.3.10")
                .media_storage_sop_instance_uid("1.2.3.4"),
        )
        .expect("meta")
        .write_to_file(dir.join("DICOMDIR"))
        .expect("write");
    let loaded = load(std::slice::from_ref(&dir)).expect("loads");
    assert_twin(&loaded.volume, &phantom);
    assert!(loaded.report.notes.iter().any(|n| n.contains("DICOMDIR")), "{:?}", loaded.report.notes);
    let e = load(&[dir.join("DICOMDIR")]).expect_err("an index only");
    assert!(e.contains("1 DICOMDIR index"), "{e}");
}

/// Rewrites every element of `path` through `edit` (a test's way to make odd files from good
/// ones).
fn rewrite(path: &std::path::Path, edit: impl FnOnce(&mut dicom_object::DefaultDicomObject)) {
    let mut object = dicom_object::open_file(path).expect("slice");
    edit(&mut object);
    object.write_to_file(path).expect("rewrite");
}

fn element(
    tag: dicom_core::Tag,
    vr: dicom_core::VR,
    value: dicom_core::value::PrimitiveValue,
) -> dicom_object::mem::InMemElement {
    dicom_core::DataElement::new(tag, vr, value)
}

#[test]
fn a_colour_slice_is_refused_by_name() {
    use dicom_core::VR;
    use dicom_core::value::PrimitiveValue;
    use dicom_dictionary_std::tags;
    let dir = scratch("rgb");
    let files = write_series(&dir, &phantom(), &SeriesSpec::default());
    rewrite(&files[1], |o| {
        o.put(element(tags::SAMPLES_PER_PIXEL, VR::US, PrimitiveValue::from(3u16)));
        o.put(element(tags::PHOTOMETRIC_INTERPRETATION, VR::CS, PrimitiveValue::from("RGB")));
        o.put(element(tags::BITS_ALLOCATED, VR::US, PrimitiveValue::from(8u16)));
        o.put(element(tags::BITS_STORED, VR::US, PrimitiveValue::from(8u16)));
        o.put(element(tags::HIGH_BIT, VR::US, PrimitiveValue::from(7u16)));
        o.put(element(tags::PLANAR_CONFIGURATION, VR::US, PrimitiveValue::from(0u16)));
        o.put(element(tags::PIXEL_DATA, VR::OB, PrimitiveValue::U8(vec![128u8; 12 * 10 * 3].into())));
    });
    let e = load(&[dir]).expect_err("RGB");
    assert!(e.contains(&format!("{}: has 3 samples per pixel (a colour image)", files[1].display())), "{e}");
}

#[test]
fn a_single_multi_frame_file_is_a_volume() {
    use dicom_core::VR;
    use dicom_core::value::PrimitiveValue;
    use dicom_dictionary_std::tags;
    let phantom = phantom();
    let dir = scratch("multiframe");
    let files = write_series(&dir, &phantom, &SeriesSpec::default());
    // Every slice's pixels, in order, in the first file; frames stepped by SpacingBetweenSlices.
    let mut pixels: Vec<u16> = Vec::new();
    for f in &files {
        let o = dicom_object::open_file(f).expect("slice");
        pixels.extend(o.element(tags::PIXEL_DATA).expect("pixels").to_multi_int::<u16>().expect("words"));
    }
    let single = scratch("multiframe_one").join("volume.dcm");
    std::fs::copy(&files[0], &single).expect("copy");
    rewrite(&single, |o| {
        o.put(element(tags::NUMBER_OF_FRAMES, VR::IS, PrimitiveValue::from(files.len().to_string())));
        o.put(element(tags::SPACING_BETWEEN_SLICES, VR::DS, PrimitiveValue::from("2.5")));
        o.put(element(tags::PIXEL_DATA, VR::OW, PrimitiveValue::U16(pixels.into())));
    });
    let loaded = load(&[single]).expect("a multi-frame file");
    assert_twin(&loaded.volume, &phantom);
}
