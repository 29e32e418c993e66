//! Writes a volume as an axial DICOM series (one CT slice per file, explicit VR little endian,
//! LPS axes as they are), through dicom-rs: what `volgraph bench load` times the loader on, and
//! a way to hand generated data to DICOM tools.

use std::path::{Path, PathBuf};

use dicom_core::value::PrimitiveValue;
use dicom_core::{DataElement, VR};
use dicom_dictionary_std::tags;
use dicom_object::{FileMetaTableBuilder, InMemDicomObject};

use crate::load::LoadError;
use crate::volume::{Volume, VoxelData};

const CT_IMAGE_STORAGE: &str = "1.2.840.10008.5.1.4.1.1.2";
const EXPLICIT_VR_LITTLE_ENDIAN: &str = "1.2.840.10008.1.2.1";

fn ds(values: &[f64]) -> PrimitiveValue {
    PrimitiveValue::Strs(values.iter().map(|v| format!("{v}")).collect::<Vec<_>>().into())
}

/// Writes int16 `volume` (values in HU) as `dir/slice_NNNN.dcm`, slice z at z·spacing mm;
/// returns the files.
pub fn write_ct_series(dir: &Path, volume: &Volume) -> Result<Vec<PathBuf>, LoadError> {
    let VoxelData::I16(values) = &volume.data else {
        return Err(LoadError::DicomPixels {
            path: dir.to_path_buf(),
            message: format!("write_ct_series takes int16 volumes, not {}", volume.data.type_name()),
        });
    };
    std::fs::create_dir_all(dir).map_err(|source| LoadError::Io { path: dir.to_path_buf(), source })?;
    let (nx, ny) = (volume.dims.x as usize, volume.dims.y as usize);
    let s = volume.spacing;
    let series_uid = "2.25.316470861183412903012545620470592143071";
    // The volume's frame of reference where it has one (tests write series in two frames).
    let frame_uid = volume.meta.frame_of_reference.clone().unwrap_or_else(|| format!("{series_uid}.0"));
    (0..volume.dims.z as usize)
        .map(|z| {
            let pixels: Vec<i16> = values[z * nx * ny..(z + 1) * nx * ny].to_vec();
            let sop_uid = format!("{series_uid}.{}", z + 1);
            let text = PrimitiveValue::from;
            let object = InMemDicomObject::from_element_iter([
                DataElement::new(tags::SOP_CLASS_UID, VR::UI, text(CT_IMAGE_STORAGE)),
                DataElement::new(tags::SOP_INSTANCE_UID, VR::UI, text(sop_uid.as_str())),
                DataElement::new(tags::MODALITY, VR::CS, text("CT")),
                DataElement::new(tags::SERIES_DESCRIPTION, VR::LO, text(volume.name.as_str())),
                DataElement::new(tags::SERIES_INSTANCE_UID, VR::UI, text(series_uid)),
                DataElement::new(tags::SERIES_NUMBER, VR::IS, text("1")),
                DataElement::new(tags::FRAME_OF_REFERENCE_UID, VR::UI, text(frame_uid.as_str())),
                DataElement::new(tags::INSTANCE_NUMBER, VR::IS, text((z + 1).to_string().as_str())),
                DataElement::new(tags::IMAGE_POSITION_PATIENT, VR::DS, ds(&[0.0, 0.0, z as f64 * s.z])),
                DataElement::new(tags::IMAGE_ORIENTATION_PATIENT, VR::DS, ds(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0])),
                DataElement::new(tags::SLICE_THICKNESS, VR::DS, ds(&[s.z])),
                DataElement::new(tags::SAMPLES_PER_PIXEL, VR::US, PrimitiveValue::from(1u16)),
                DataElement::new(tags::PHOTOMETRIC_INTERPRETATION, VR::CS, text("MONOCHROME2")),
                DataElement::new(tags::ROWS, VR::US, PrimitiveValue::from(ny as u16)),
                DataElement::new(tags::COLUMNS, VR::US, PrimitiveValue::from(nx as u16)),
                DataElement::new(tags::PIXEL_SPACING, VR::DS, ds(&[s.y, s.x])),
                DataElement::new(tags::BITS_ALLOCATED, VR::US, PrimitiveValue::from(16u16)),
                DataElement::new(tags::BITS_STORED, VR::US, PrimitiveValue::from(16u16)),
                DataElement::new(tags::HIGH_BIT, VR::US, PrimitiveValue::from(15u16)),
                DataElement::new(tags::PIXEL_REPRESENTATION, VR::US, PrimitiveValue::from(1u16)),
                DataElement::new(tags::RESCALE_INTERCEPT, VR::DS, ds(&[0.0])),
                DataElement::new(tags::RESCALE_SLOPE, VR::DS, ds(&[1.0])),
                DataElement::new(tags::PIXEL_DATA, VR::OW, PrimitiveValue::I16(pixels.into())),
            ]);
            let path = dir.join(format!("slice_{:04}.dcm", z + 1));
            let write_error = |reason: String| LoadError::DicomRead { path: path.clone(), reason };
            object
                .with_meta(
                    FileMetaTableBuilder::new()
                        .transfer_syntax(EXPLICIT_VR_LITTLE_ENDIAN)
                        .media_storage_sop_class_uid(CT_IMAGE_STORAGE)
                        .media_storage_sop_instance_uid(sop_uid.as_str()),
                )
                .map_err(|e| write_error(e.to_string()))?
                .write_to_file(&path)
                .map_err(|e| write_error(e.to_string()))?;
            Ok(path)
        })
        .collect()
}

/// Writes u8 label map `labels` (on the grid [`write_ct_series`] writes: LPS axes, slice z at
/// z·spacing mm, frame of reference `volume.meta`'s or the CT's default) as one BINARY DICOM
/// Segmentation at `path`: one frame per segment and slice that segment reaches (PS3.3 C.8.20),
/// 1 bit a pixel packed across frames, each segment named by `names` (value, name, sRGB).
pub fn write_segmentation(path: &Path, labels: &Volume, names: &[(u8, &str, [u8; 3])]) -> Result<(), LoadError> {
    let VoxelData::U8(values) = &labels.data else {
        return Err(LoadError::DicomPixels {
            path: path.to_path_buf(),
            message: format!("write_segmentation takes u8 label maps, not {}", labels.data.type_name()),
        });
    };
    let (nx, ny, nz) = (labels.dims.x as usize, labels.dims.y as usize, labels.dims.z as usize);
    let per_slice = nx * ny;
    let s = labels.spacing;
    let series_uid = "2.25.316470861183412903012545620470592143072";
    let frame_uid = labels
        .meta
        .frame_of_reference
        .clone()
        .unwrap_or_else(|| "2.25.316470861183412903012545620470592143071.0".into());
    let text = PrimitiveValue::from;
    let item = |elements: Vec<DataElement<InMemDicomObject>>| InMemDicomObject::from_element_iter(elements);
    let sequence = |tag, items: Vec<InMemDicomObject>| {
        DataElement::new(tag, VR::SQ, dicom_core::value::DataSetSequence::from(items))
    };
    let mut segment_items = Vec::new();
    for &(value, name, rgb) in names {
        let lab = srgb_to_cielab(rgb);
        segment_items.push(item(vec![
            DataElement::new(tags::SEGMENT_NUMBER, VR::US, PrimitiveValue::from(u16::from(value))),
            DataElement::new(tags::SEGMENT_LABEL, VR::LO, text(name)),
            DataElement::new(tags::SEGMENT_ALGORITHM_TYPE, VR::CS, text("MANUAL")),
            DataElement::new(tags::RECOMMENDED_DISPLAY_CIE_LAB_VALUE, VR::US, PrimitiveValue::U16(lab.to_vec().into())),
        ]));
    }
    // One frame per (segment, slice it reaches), bits packed across frames.
    let mut frames = Vec::new();
    let mut bits: Vec<u8> = Vec::new();
    let mut count = 0usize;
    for &(value, _, _) in names {
        for z in 0..nz {
            let slice = &values[z * per_slice..(z + 1) * per_slice];
            if !slice.contains(&value) {
                continue;
            }
            for &v in slice {
                if count.is_multiple_of(8) {
                    bits.push(0);
                }
                if v == value {
                    *bits.last_mut().expect("pushed") |= 1 << (count % 8);
                }
                count += 1;
            }
            frames.push(item(vec![
                sequence(
                    tags::SEGMENT_IDENTIFICATION_SEQUENCE,
                    vec![item(vec![DataElement::new(
                        tags::REFERENCED_SEGMENT_NUMBER,
                        VR::US,
                        PrimitiveValue::from(u16::from(value)),
                    )])],
                ),
                sequence(
                    tags::PLANE_POSITION_SEQUENCE,
                    vec![item(vec![DataElement::new(
                        tags::IMAGE_POSITION_PATIENT,
                        VR::DS,
                        ds(&[0.0, 0.0, z as f64 * s.z]),
                    )])],
                ),
            ]));
        }
    }
    if bits.len() % 2 == 1 {
        bits.push(0);
    }
    let shared = item(vec![
        sequence(
            tags::PLANE_ORIENTATION_SEQUENCE,
            vec![item(vec![DataElement::new(
                tags::IMAGE_ORIENTATION_PATIENT,
                VR::DS,
                ds(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
            )])],
        ),
        sequence(
            tags::PIXEL_MEASURES_SEQUENCE,
            vec![item(vec![
                DataElement::new(tags::PIXEL_SPACING, VR::DS, ds(&[s.y, s.x])),
                DataElement::new(tags::SLICE_THICKNESS, VR::DS, ds(&[s.z])),
                DataElement::new(tags::SPACING_BETWEEN_SLICES, VR::DS, ds(&[s.z])),
            ])],
        ),
    ]);
    let sop_uid = format!("{series_uid}.1");
    let object = InMemDicomObject::from_element_iter([
        DataElement::new(tags::SOP_CLASS_UID, VR::UI, text(super::seg::SEGMENTATION_STORAGE)),
        DataElement::new(tags::SOP_INSTANCE_UID, VR::UI, text(sop_uid.as_str())),
        DataElement::new(tags::MODALITY, VR::CS, text("SEG")),
        DataElement::new(tags::SERIES_DESCRIPTION, VR::LO, text(labels.name.as_str())),
        DataElement::new(tags::SERIES_INSTANCE_UID, VR::UI, text(series_uid)),
        DataElement::new(tags::SERIES_NUMBER, VR::IS, text("2")),
        DataElement::new(tags::FRAME_OF_REFERENCE_UID, VR::UI, text(frame_uid.as_str())),
        sequence(tags::SHARED_FUNCTIONAL_GROUPS_SEQUENCE, vec![shared]),
        DataElement::new(tags::NUMBER_OF_FRAMES, VR::IS, text(frames.len().to_string().as_str())),
        sequence(tags::PER_FRAME_FUNCTIONAL_GROUPS_SEQUENCE, frames),
        DataElement::new(tags::SAMPLES_PER_PIXEL, VR::US, PrimitiveValue::from(1u16)),
        DataElement::new(tags::PHOTOMETRIC_INTERPRETATION, VR::CS, text("MONOCHROME2")),
        DataElement::new(tags::ROWS, VR::US, PrimitiveValue::from(ny as u16)),
        DataElement::new(tags::COLUMNS, VR::US, PrimitiveValue::from(nx as u16)),
        DataElement::new(tags::BITS_ALLOCATED, VR::US, PrimitiveValue::from(1u16)),
        DataElement::new(tags::BITS_STORED, VR::US, PrimitiveValue::from(1u16)),
        DataElement::new(tags::HIGH_BIT, VR::US, PrimitiveValue::from(0u16)),
        DataElement::new(tags::PIXEL_REPRESENTATION, VR::US, PrimitiveValue::from(0u16)),
        DataElement::new(tags::SEGMENTATION_TYPE, VR::CS, text("BINARY")),
        sequence(tags::SEGMENT_SEQUENCE, segment_items),
        DataElement::new(tags::PIXEL_DATA, VR::OB, PrimitiveValue::U8(bits.into())),
    ]);
    let write_error = |reason: String| LoadError::DicomRead { path: path.to_path_buf(), reason };
    object
        .with_meta(
            FileMetaTableBuilder::new()
                .transfer_syntax(EXPLICIT_VR_LITTLE_ENDIAN)
                .media_storage_sop_class_uid(super::seg::SEGMENTATION_STORAGE)
                .media_storage_sop_instance_uid(sop_uid.as_str()),
        )
        .map_err(|e| write_error(e.to_string()))?
        .write_to_file(path)
        .map_err(|e| write_error(e.to_string()))
}

/// sRGB bytes as DICOM's scaled CIELab (the inverse of [`super::seg::cielab_to_srgb`]).
fn srgb_to_cielab(rgb: [u8; 3]) -> [u16; 3] {
    let linear = rgb.map(|c| {
        let v = f64::from(c) / 255.0;
        if v <= 0.040_45 { v / 12.92 } else { ((v + 0.055) / 1.055).powf(2.4) }
    });
    let [r, g, b] = linear;
    let x = (0.412_4 * r + 0.357_6 * g + 0.180_5 * b) / 0.950_47;
    let y = 0.212_6 * r + 0.715_2 * g + 0.072_2 * b;
    let z = (0.019_3 * r + 0.119_2 * g + 0.950_5 * b) / 1.088_83;
    let f =
        |t: f64| if t > (6.0f64 / 29.0).powi(3) { t.cbrt() } else { t / (3.0 * (6.0f64 / 29.0).powi(2)) + 4.0 / 29.0 };
    let (fx, fy, fz) = (f(x), f(y), f(z));
    let (l, a, b) = (116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz));
    [l / 100.0, (a + 128.0) / 255.0, (b + 128.0) / 255.0].map(|v| (v.clamp(0.0, 1.0) * 65_535.0).round() as u16)
}
