//! DICOM Segmentation objects (issue "several volumes", item 3), written in-tree with dicom-rs
//! (`write_segmentation`: BINARY, one frame per segment and slice it reaches, bits packed across
//! frames) from the organ phantom's label map, beside its CT (`write_ct_series`): the SEG loads
//! back voxel for voxel onto the CT's grid and frame of reference, its SegmentSequence is the
//! map's label table, a SEG that reaches only some slices spans only those planes, and a corrupt
//! one is an error naming the file.

use std::path::{Path, PathBuf};

use dicom_core::value::PrimitiveValue;
use dicom_core::{DataElement, VR};
use dicom_dictionary_std::tags;
use volgraph_accel::labels::LabelTable;
use volgraph_accel::load::dicom::seg::cielab_to_srgb;
use volgraph_accel::load::dicom::{write_ct_series, write_segmentation};
use volgraph_accel::load::{LoadOptions, load_volumes};
use volgraph_accel::organs::{label_table, organs_ct, organs_labels};
use volgraph_accel::volume::{Volume, VoxelData};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("volgraph-seg-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch");
    dir
}

fn load(path: &Path) -> Result<volgraph_accel::load::LoadedVolume, String> {
    load_volumes(&[path.to_path_buf()], &LoadOptions::default()).map_err(|e| e.to_string())
}

/// The organ phantom's segments: (value, name, colour).
fn names() -> Vec<(u8, String, [u8; 3])> {
    label_table().labels.iter().map(|(v, l)| (*v as u8, l.name.clone(), l.rgb)).collect()
}

fn write_seg(path: &Path, labels: &Volume) {
    let names = names();
    let names: Vec<(u8, &str, [u8; 3])> = names.iter().map(|(v, n, c)| (*v, n.as_str(), *c)).collect();
    write_segmentation(path, labels, &names).expect("writes the SEG");
}

fn u8_values(v: &Volume) -> Vec<u8> {
    match &v.data {
        VoxelData::U8(values) => values.clone(),
        other => panic!("a u8 label map, not {}", other.type_name()),
    }
}

#[test]
fn a_seg_loads_back_as_its_label_map_on_its_cts_grid_and_frame() {
    let dir = scratch("roundtrip");
    let mut labels = organs_labels(32);
    labels.meta.frame_of_reference = Some("1.2.826.0.1.7".into());
    let mut ct = organs_ct(32);
    ct.meta.frame_of_reference = labels.meta.frame_of_reference.clone();
    write_ct_series(&dir.join("ct"), &ct).expect("CT series");
    write_seg(&dir.join("seg.dcm"), &labels);

    let seg = load(&dir.join("seg.dcm")).expect("the SEG loads").volume;
    let ct = load(&dir.join("ct")).expect("the CT loads").volume;
    // Every slice holds some organ, so the SEG's frames span the CT's grid exactly.
    assert_eq!(seg.dims, labels.dims);
    assert_eq!(seg.dims, ct.dims);
    assert!((seg.spacing - ct.spacing).abs().max_element() < 1e-9, "{} vs {}", seg.spacing, ct.spacing);
    assert_eq!(seg.meta.origin, ct.meta.origin);
    assert_eq!(seg.meta.frame_of_reference.as_deref(), Some("1.2.826.0.1.7"));
    assert_eq!(seg.meta.modality.as_deref(), Some("SEG"));
    assert_eq!(u8_values(&seg), u8_values(&labels), "voxel for voxel the map written");

    // Its SegmentSequence is the label table: names as written, colours through CIELab and
    // back within one step of 255 (DICOM stores colours as 16-bit CIELab).
    let (table, notes) = LabelTable::read(&dir.join("seg.dcm")).expect("the table");
    assert!(notes.is_empty(), "{notes:?}");
    assert!(table.source.starts_with("DICOM SEG "), "{}", table.source);
    for (value, name, rgb) in names() {
        let label = &table.labels[&u32::from(value)];
        assert_eq!(label.name, name);
        let off = label.rgb.iter().zip(rgb).map(|(a, b)| (i32::from(*a) - i32::from(b)).abs()).max();
        assert!(off <= Some(1), "{name}: {:?} written as {rgb:?}", label.rgb);
        assert!(label.visible && label.opacity == 1.0);
    }
    assert!(volgraph_accel::labels::names_its_labels(&dir.join("seg.dcm")));
    assert!(!volgraph_accel::labels::names_its_labels(&dir.join("ct").join("slice_0001.dcm")));
}

/// A SEG reaching slices 4 and 8 only (of 16) spans planes 4..=8, the three between empty,
/// placed where those slices of the CT lie.
#[test]
fn a_seg_of_a_few_slices_spans_only_their_planes() {
    let dir = scratch("sparse");
    let full = organs_labels(32);
    let mut labels = full.clone();
    let per_slice = (full.dims.x * full.dims.y) as usize;
    let VoxelData::U8(values) = &mut labels.data else { panic!("u8") };
    for (i, v) in values.iter_mut().enumerate() {
        let z = i / per_slice;
        if z != 4 && z != 8 {
            *v = 0;
        }
    }
    write_seg(&dir.join("seg.dcm"), &labels);
    let seg = load(&dir.join("seg.dcm")).expect("loads").volume;
    assert_eq!(seg.dims, glam::UVec3::new(full.dims.x, full.dims.y, 5));
    let origin = seg.meta.origin.expect("an origin");
    assert!((origin.z - 4.0 * full.spacing.z).abs() < 1e-9, "origin {origin}");
    let got = u8_values(&seg);
    let want = u8_values(&full);
    assert_eq!(&got[..per_slice], &want[4 * per_slice..5 * per_slice]);
    assert!(got[per_slice..4 * per_slice].iter().all(|&v| v == 0));
    assert_eq!(&got[4 * per_slice..], &want[8 * per_slice..9 * per_slice]);
}

/// Rewrites `path` with `edit` applied to its data set.
fn edited(path: &Path, out: &Path, edit: impl FnOnce(&mut dicom_object::DefaultDicomObject)) {
    let mut object = dicom_object::open_file(path).expect("opens");
    edit(&mut object);
    object.write_to_file(out).expect("writes");
}

#[test]
fn a_corrupt_seg_is_an_error_naming_the_file_and_what_is_wrong() {
    let dir = scratch("corrupt");
    let labels = organs_labels(16);
    let good = dir.join("seg.dcm");
    write_seg(&good, &labels);

    type Edit = Box<dyn FnOnce(&mut dicom_object::DefaultDicomObject)>;
    let cases: Vec<(&str, Edit, &str)> = vec![
        (
            "truncated.dcm",
            Box::new(|o| {
                o.put(DataElement::new(tags::PIXEL_DATA, VR::OB, PrimitiveValue::U8(vec![0xff; 4].into())));
            }),
            "PixelData holds 4 bytes, but",
        ),
        (
            "no_segments.dcm",
            Box::new(|o| {
                o.remove_element(tags::SEGMENT_SEQUENCE);
            }),
            "without a SegmentSequence (0062,0002)",
        ),
        (
            "fractional_1bit.dcm",
            Box::new(|o| {
                o.put(DataElement::new(tags::SEGMENTATION_TYPE, VR::CS, PrimitiveValue::from("FRACTIONAL")));
            }),
            "SegmentationType (0062,0001) \"FRACTIONAL\" with BitsAllocated 1 is not a segmentation volgraph reads",
        ),
    ];
    for (name, edit, expected) in cases {
        let path = dir.join(name);
        edited(&good, &path, edit);
        let err = load(&path).expect_err(name);
        assert!(err.starts_with(&path.display().to_string()) && err.contains(expected), "{name}: {err}");
    }
}

/// DICOM's scaled CIELab of known colours (white, black, and sRGB red, whose L*a*b* is
/// 53.24, 80.09, 67.20) come back as those sRGB bytes.
#[test]
fn cielab_values_are_srgb_colours() {
    let scaled =
        |l: f64, a: f64, b: f64| [l / 100.0 * 65_535.0, (a + 128.0) / 255.0 * 65_535.0, (b + 128.0) / 255.0 * 65_535.0];
    assert_eq!(cielab_to_srgb(scaled(100.0, 0.0, 0.0)), [255, 255, 255]);
    assert_eq!(cielab_to_srgb(scaled(0.0, 0.0, 0.0)), [0, 0, 0]);
    let red = cielab_to_srgb(scaled(53.24, 80.09, 67.20));
    assert!(red[0] >= 254 && red[1] <= 1 && red[2] <= 1, "{red:?}");
}
