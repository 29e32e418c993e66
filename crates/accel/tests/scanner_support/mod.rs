//! Test series written with dicom-rs and test NIfTI files, from a volume in the LPS patient
//! frame: the loaders must give that volume back whatever the file's orientation, slice order,
//! file names, transfer syntax or rescale.

#![allow(dead_code)]

use std::path::{Path, PathBuf};

use dicom_core::value::{PixelFragmentSequence, PrimitiveValue, Value};
use dicom_core::{DataElement, Tag, VR};
use dicom_dictionary_std::tags;
use dicom_object::{FileMetaTableBuilder, InMemDicomObject};
use glam::{DVec3, IVec3, UVec3};
use volgraph_accel::volume::{Volume, VoxelData};

pub const IMPLICIT_LE: &str = "1.2.840.10008.1.2";
pub const EXPLICIT_LE: &str = "1.2.840.10008.1.2.1";
pub const EXPLICIT_BE: &str = "1.2.840.10008.1.2.2";
pub const RLE: &str = "1.2.840.10008.1.2.5";

/// How one series is written.
#[derive(Clone, Debug)]
pub struct SeriesSpec {
    pub uid: String,
    pub number: i32,
    pub description: String,
    pub modality: String,
    pub transfer_syntax: &'static str,
    /// Rows run along `row` (the direction the column index grows), then `column`: signed unit
    /// world axes.
    pub row: IVec3,
    pub column: IVec3,
    /// Stored value = (value − intercept) / slope.
    pub slope: f64,
    pub intercept: f64,
    /// PixelRepresentation 0 (unsigned) or 1.
    pub unsigned: bool,
    /// File names in a shuffled order rather than by slice.
    pub shuffle_names: bool,
    /// Slices (in order along the normal) left out: a gap.
    pub skip: Vec<usize>,
    /// A slice written without ImagePositionPatient.
    pub drop_position: Option<usize>,
    /// ImageOrientationPatient written instead of row/column (an oblique series).
    pub orientation_override: Option<[f64; 6]>,
    /// Millimetres of the world origin (centre of voxel 0,0,0).
    pub origin: DVec3,
}

impl Default for SeriesSpec {
    fn default() -> Self {
        SeriesSpec {
            uid: "1.2.826.0.1.3680043.8.498.1".into(),
            number: 1,
            description: "AX test".into(),
            modality: "CT".into(),
            transfer_syntax: EXPLICIT_LE,
            row: IVec3::X,
            column: IVec3::Y,
            slope: 1.0,
            intercept: -1024.0,
            unsigned: true,
            shuffle_names: false,
            skip: Vec::new(),
            drop_position: None,
            orientation_override: None,
            origin: DVec3::new(-40.0, -30.0, 12.5),
        }
    }
}

fn strs(values: &[f64]) -> PrimitiveValue {
    PrimitiveValue::Strs(values.iter().map(|v| format!("{v}")).collect::<Vec<_>>().into())
}

fn text(value: &str) -> PrimitiveValue {
    PrimitiveValue::from(value)
}

/// The world index of file pixel (i, j) of slice k, and the file dims, for `volume` in world
/// order written with `row`/`column` directions.
pub struct Layout {
    pub row: IVec3,
    pub column: IVec3,
    pub normal: IVec3,
    pub file_dims: UVec3,
    base: IVec3,
}

impl Layout {
    pub fn new(world: UVec3, row: IVec3, column: IVec3) -> Layout {
        let normal = row.cross(column);
        let along = |d: IVec3| (0..3).find(|&a| d[a] != 0).expect("an axis");
        let file_dims = UVec3::new(world[along(row)], world[along(column)], world[along(normal)]);
        let mut base = IVec3::ZERO;
        for d in [row, column, normal] {
            let a = along(d);
            if d[a] < 0 {
                base[a] = world[a] as i32 - 1;
            }
        }
        Layout { row, column, normal, file_dims, base }
    }

    pub fn world_index(&self, i: u32, j: u32, k: u32) -> IVec3 {
        self.base + self.row * i as i32 + self.column * j as i32 + self.normal * k as i32
    }
}

/// The value of world voxel `w`.
pub fn value_at(volume: &Volume, w: IVec3) -> f64 {
    let i = volume.index(w.x as u32, w.y as u32, w.z as u32);
    volume.raw_value(i)
}

/// Writes `volume` (world order, LPS, data values) as a series in `dir`; returns the files.
pub fn write_series(dir: &Path, volume: &Volume, spec: &SeriesSpec) -> Vec<PathBuf> {
    std::fs::create_dir_all(dir).expect("series folder");
    let layout = Layout::new(volume.dims, spec.row, spec.column);
    let s = volume.spacing;
    let mm = |w: IVec3| spec.origin + w.as_dvec3() * s;
    let axis_spacing = |d: IVec3| s[(0..3).find(|&a| d[a] != 0).expect("axis")];
    let (dx, dy) = (axis_spacing(spec.row), axis_spacing(spec.column));
    let iop = spec.orientation_override.unwrap_or([
        spec.row.x as f64,
        spec.row.y as f64,
        spec.row.z as f64,
        spec.column.x as f64,
        spec.column.y as f64,
        spec.column.z as f64,
    ]);
    let slices: Vec<u32> = (0..layout.file_dims.z).filter(|k| !spec.skip.contains(&(*k as usize))).collect();
    let mut names: Vec<usize> = (0..slices.len()).collect();
    if spec.shuffle_names {
        // A fixed permutation: name order says nothing about position.
        names.sort_by_key(|&n| (n * 7919) % slices.len().max(1));
    }
    let mut files = Vec::new();
    for (n, &k) in slices.iter().enumerate() {
        let mut pixels = Vec::with_capacity((layout.file_dims.x * layout.file_dims.y) as usize);
        for j in 0..layout.file_dims.y {
            for i in 0..layout.file_dims.x {
                let v = value_at(volume, layout.world_index(i, j, k));
                let stored = ((v - spec.intercept) / spec.slope).round();
                pixels.push(if spec.unsigned { stored as u16 } else { stored as i16 as u16 });
            }
        }
        let position = mm(layout.world_index(0, 0, k));
        let sop_uid = format!("{}.{}", spec.uid, k + 1);
        let class = if spec.modality == "MR" { "1.2.840.10008.5.1.4.1.1.4" } else { "1.2.840.10008.5.1.4.1.1.2" };
        let mut object = InMemDicomObject::from_element_iter([
            DataElement::new(tags::SOP_CLASS_UID, VR::UI, text(class)),
            DataElement::new(tags::SOP_INSTANCE_UID, VR::UI, text(&sop_uid)),
            DataElement::new(tags::MODALITY, VR::CS, text(&spec.modality)),
            DataElement::new(tags::SERIES_DESCRIPTION, VR::LO, text(&spec.description)),
            DataElement::new(tags::STUDY_INSTANCE_UID, VR::UI, text("1.2.826.0.1.3680043.8.498.9")),
            DataElement::new(tags::SERIES_INSTANCE_UID, VR::UI, text(&spec.uid)),
            DataElement::new(tags::SERIES_NUMBER, VR::IS, text(&spec.number.to_string())),
            // InstanceNumber runs against the positions: ordering by it would be wrong.
            DataElement::new(tags::INSTANCE_NUMBER, VR::IS, text(&(layout.file_dims.z - k).to_string())),
            DataElement::new(tags::IMAGE_ORIENTATION_PATIENT, VR::DS, strs(&iop)),
            DataElement::new(tags::SLICE_THICKNESS, VR::DS, strs(&[axis_spacing(layout.normal)])),
            DataElement::new(tags::SAMPLES_PER_PIXEL, VR::US, PrimitiveValue::from(1u16)),
            DataElement::new(tags::PHOTOMETRIC_INTERPRETATION, VR::CS, text("MONOCHROME2")),
            DataElement::new(tags::ROWS, VR::US, PrimitiveValue::from(layout.file_dims.y as u16)),
            DataElement::new(tags::COLUMNS, VR::US, PrimitiveValue::from(layout.file_dims.x as u16)),
            // Row spacing (between rows, along the column direction), then column spacing.
            DataElement::new(tags::PIXEL_SPACING, VR::DS, strs(&[dy, dx])),
            DataElement::new(tags::BITS_ALLOCATED, VR::US, PrimitiveValue::from(16u16)),
            DataElement::new(tags::BITS_STORED, VR::US, PrimitiveValue::from(16u16)),
            DataElement::new(tags::HIGH_BIT, VR::US, PrimitiveValue::from(15u16)),
            DataElement::new(tags::PIXEL_REPRESENTATION, VR::US, PrimitiveValue::from(u16::from(!spec.unsigned))),
            DataElement::new(tags::WINDOW_CENTER, VR::DS, strs(&[40.0])),
            DataElement::new(tags::WINDOW_WIDTH, VR::DS, strs(&[400.0])),
            DataElement::new(tags::RESCALE_INTERCEPT, VR::DS, strs(&[spec.intercept])),
            DataElement::new(tags::RESCALE_SLOPE, VR::DS, strs(&[spec.slope])),
        ]);
        if spec.drop_position != Some(k as usize) {
            object.put(DataElement::new(tags::IMAGE_POSITION_PATIENT, VR::DS, strs(&position.to_array())));
        }
        let pixel_data = if spec.transfer_syntax == RLE {
            let fragment = rle_encode(&pixels, layout.file_dims.x as usize);
            DataElement::new(
                tags::PIXEL_DATA,
                VR::OB,
                Value::PixelSequence(PixelFragmentSequence::new(Vec::<u32>::new(), vec![fragment])),
            )
        } else {
            DataElement::new(tags::PIXEL_DATA, VR::OW, PrimitiveValue::U16(pixels.into()))
        };
        object.put(pixel_data);
        let file = object
            .with_meta(
                FileMetaTableBuilder::new()
                    .transfer_syntax(spec.transfer_syntax)
                    .media_storage_sop_class_uid(class)
                    .media_storage_sop_instance_uid(&sop_uid),
            )
            .expect("file meta");
        let path = dir.join(format!("IM{:04}", names[n] + 1));
        file.write_to_file(&path).expect("write slice");
        files.push(path);
    }
    files
}

/// DICOM RLE Lossless (PS3.5 Annex G) of 16-bit pixels: two segments (high bytes, low bytes),
/// each row PackBits-coded on its own.
pub fn rle_encode(pixels: &[u16], row_len: usize) -> Vec<u8> {
    let segments: Vec<Vec<u8>> = [8u32, 0]
        .iter()
        .map(|&shift| {
            let bytes: Vec<u8> = pixels.iter().map(|p| (p >> shift) as u8).collect();
            let mut out = Vec::new();
            for row in bytes.chunks(row_len) {
                packbits(row, &mut out);
            }
            if out.len() % 2 == 1 {
                out.push(0);
            }
            out
        })
        .collect();
    let mut header = vec![0u32; 16];
    header[0] = segments.len() as u32;
    let mut offset = 64u32;
    for (i, s) in segments.iter().enumerate() {
        header[i + 1] = offset;
        offset += s.len() as u32;
    }
    let mut out: Vec<u8> = header.iter().flat_map(|h| h.to_le_bytes()).collect();
    for s in segments {
        out.extend(s);
    }
    out
}

fn packbits(row: &[u8], out: &mut Vec<u8>) {
    let mut i = 0;
    while i < row.len() {
        let run = row[i..].iter().take(128).take_while(|&&b| b == row[i]).count();
        if run >= 3 {
            out.push((257 - run) as u8);
            out.push(row[i]);
            i += run;
        } else {
            let mut end = i;
            while end < row.len() && end - i < 128 {
                let ahead = row[end..].iter().take(3).take_while(|&&b| b == row[end]).count();
                if ahead >= 3 {
                    break;
                }
                end += 1;
            }
            out.push((end - i - 1) as u8);
            out.extend_from_slice(&row[i..end]);
            i = end;
        }
    }
}

/// A small CT-like volume in HU: air (−1000 with noise), a soft-tissue body, a bone core; no
/// symmetry, so a flip shows.
pub fn ct_phantom(dims: UVec3, spacing: DVec3) -> Volume {
    let mut values = Vec::with_capacity((dims.x * dims.y * dims.z) as usize);
    let n = dims.as_dvec3();
    for z in 0..dims.z {
        for y in 0..dims.y {
            for x in 0..dims.x {
                let p = (DVec3::new(x as f64, y as f64, z as f64) + 0.5) / n - 0.5;
                let body = (p * DVec3::new(1.0, 1.3, 1.1)).length() < 0.42;
                let bone = (p - DVec3::new(0.12, -0.05, 0.08)).length() < 0.15;
                let noise = ((x * 31 + y * 17 + z * 7) % 13) as i32 - 6;
                let hu = if bone {
                    700 + 10 * x as i32
                } else if body {
                    40 + noise + y as i32
                } else {
                    -1000 + noise
                };
                values.push(hu as i16);
            }
        }
    }
    let mut v = Volume::new("phantom", dims, spacing, VoxelData::I16(values));
    v.fit_range_to_data();
    v
}

/// A fresh empty folder under the target directory for one test.
pub fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("scanner").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

/// The value of the first element `tag` in a written file, for checks.
pub fn tag_text(path: &Path, tag: Tag) -> Option<String> {
    let o = dicom_object::open_file(path).ok()?;
    Some(o.element(tag).ok()?.to_str().ok()?.into_owned())
}
