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
