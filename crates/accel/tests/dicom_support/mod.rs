//! Hostile DICOM files for the round-three tests (issue 47) and the DICOM fuzzer, written with
//! dicom-rs: one small valid image whose attributes, pixel data and transfer syntax a test
//! replaces. Shared by `crates/accel/tests` and, through `#[path]`, `crates/app/tests`.

#![allow(dead_code)]

use std::path::{Path, PathBuf};

use dicom_core::value::{PixelFragmentSequence, PrimitiveValue, Value};
use dicom_core::{DataElement, Tag, VR};
use dicom_dictionary_std::tags;
use dicom_object::{FileMetaTableBuilder, InMemDicomObject};

pub const EXPLICIT_LE: &str = "1.2.840.10008.1.2.1";
pub const RLE: &str = "1.2.840.10008.1.2.5";
pub const JPEG2000: &str = "1.2.840.10008.1.2.4.91";
const CT: &str = "1.2.840.10008.5.1.4.1.1.2";

/// One image: `columns × rows` 16-bit pixels (or what `pixels` replaces), at z = `z` mm.
#[derive(Clone, Debug)]
pub struct Image {
    pub rows: u16,
    pub columns: u16,
    pub z: f64,
    pub series_uid: String,
    pub description: String,
    pub transfer_syntax: &'static str,
    /// Elements put after the defaults (replacing them): hostile values.
    pub replace: Vec<(Tag, VR, String)>,
    /// Elements removed.
    pub remove: Vec<Tag>,
    /// The pixel data element; `None`: native 16-bit pixels `value(x, y)`.
    pub pixels: Option<DataElement<InMemDicomObject>>,
}

impl Default for Image {
    fn default() -> Self {
        Image {
            rows: 6,
            columns: 5,
            z: 0.0,
            series_uid: "2.25.4701".into(),
            description: "axial".into(),
            transfer_syntax: EXPLICIT_LE,
            replace: Vec::new(),
            remove: Vec::new(),
            pixels: None,
        }
    }
}

/// The stored value of pixel (x, y) of a default image.
pub fn value(x: u16, y: u16) -> u16 {
    100 + 10 * y + x
}

fn text(v: &str) -> PrimitiveValue {
    PrimitiveValue::from(v)
}

impl Image {
    /// The file's bytes (preamble, meta group, data set).
    pub fn bytes(&self) -> Vec<u8> {
        let mut o = InMemDicomObject::from_element_iter([
            DataElement::new(tags::SOP_CLASS_UID, VR::UI, text(CT)),
            DataElement::new(
                tags::SOP_INSTANCE_UID,
                VR::UI,
                text(&format!("{}.{}", self.series_uid, self.z as i64 + 1000)),
            ),
            DataElement::new(tags::MODALITY, VR::CS, text("CT")),
            DataElement::new(tags::SERIES_DESCRIPTION, VR::LO, text(&self.description)),
            DataElement::new(tags::SERIES_INSTANCE_UID, VR::UI, text(&self.series_uid)),
            DataElement::new(tags::SERIES_NUMBER, VR::IS, text("1")),
            DataElement::new(tags::IMAGE_POSITION_PATIENT, VR::DS, text(&format!("0\\0\\{}", self.z))),
            DataElement::new(tags::IMAGE_ORIENTATION_PATIENT, VR::DS, text("1\\0\\0\\0\\1\\0")),
            DataElement::new(tags::SLICE_THICKNESS, VR::DS, text("2")),
            DataElement::new(tags::SAMPLES_PER_PIXEL, VR::US, PrimitiveValue::from(1u16)),
            DataElement::new(tags::PHOTOMETRIC_INTERPRETATION, VR::CS, text("MONOCHROME2")),
            DataElement::new(tags::ROWS, VR::US, PrimitiveValue::from(self.rows)),
            DataElement::new(tags::COLUMNS, VR::US, PrimitiveValue::from(self.columns)),
            DataElement::new(tags::PIXEL_SPACING, VR::DS, text("0.5\\0.5")),
            DataElement::new(tags::BITS_ALLOCATED, VR::US, PrimitiveValue::from(16u16)),
            DataElement::new(tags::BITS_STORED, VR::US, PrimitiveValue::from(16u16)),
            DataElement::new(tags::HIGH_BIT, VR::US, PrimitiveValue::from(15u16)),
            DataElement::new(tags::PIXEL_REPRESENTATION, VR::US, PrimitiveValue::from(0u16)),
            DataElement::new(tags::RESCALE_INTERCEPT, VR::DS, text("-1024")),
            DataElement::new(tags::RESCALE_SLOPE, VR::DS, text("1")),
        ]);
        for (tag, vr, v) in &self.replace {
            let value = match vr {
                VR::US => PrimitiveValue::from(v.parse::<u16>().unwrap_or(0)),
                VR::UL => PrimitiveValue::from(v.parse::<u32>().unwrap_or(0)),
                _ => text(v),
            };
            o.put(DataElement::new(*tag, *vr, value));
        }
        for tag in &self.remove {
            o.remove_element(*tag);
        }
        let pixels = self.pixels.clone().unwrap_or_else(|| {
            let mut values = Vec::new();
            for y in 0..self.rows {
                for x in 0..self.columns {
                    values.push(value(x, y));
                }
            }
            DataElement::new(tags::PIXEL_DATA, VR::OW, PrimitiveValue::U16(values.into()))
        });
        o.put(pixels);
        let file = o
            .with_meta(
                FileMetaTableBuilder::new()
                    .transfer_syntax(self.transfer_syntax)
                    .media_storage_sop_class_uid(CT)
                    .media_storage_sop_instance_uid("2.25.1"),
            )
            .expect("file meta");
        let mut bytes = Vec::new();
        file.write_all(&mut bytes).expect("written");
        bytes
    }

    /// Writes the file as `dir/name`; returns its path.
    pub fn write(&self, dir: &Path, name: &str) -> PathBuf {
        std::fs::create_dir_all(dir).expect("folder");
        let path = dir.join(name);
        std::fs::write(&path, self.bytes()).expect("written");
        path
    }

    /// This image with `tag` set to `value` (as text, or a number for US/UL).
    pub fn with(mut self, tag: Tag, vr: VR, value: &str) -> Self {
        self.replace.push((tag, vr, value.to_string()));
        self
    }
}

/// Encapsulated pixel data of `fragments` (one per frame), no offset table.
pub fn encapsulated(fragments: Vec<Vec<u8>>) -> DataElement<InMemDicomObject> {
    DataElement::new(
        tags::PIXEL_DATA,
        VR::OB,
        Value::PixelSequence(PixelFragmentSequence::new(Vec::<u32>::new(), fragments)),
    )
}

/// An RLE Lossless frame: the 64-byte header with `count` segments at `offsets`, then `body`.
pub fn rle_frame(count: u32, offsets: &[u32], body: &[u8]) -> Vec<u8> {
    let mut header = [0u32; 16];
    header[0] = count;
    for (i, &o) in offsets.iter().enumerate().take(15) {
        header[i + 1] = o;
    }
    let mut out: Vec<u8> = header.iter().flat_map(|h| h.to_le_bytes()).collect();
    out.extend_from_slice(body);
    if out.len() % 2 == 1 {
        out.push(0);
    }
    out
}

/// A valid RLE frame of `n` 16-bit pixels all equal to `v`: two segments of PackBits runs.
pub fn rle_constant(n: usize, v: u16) -> Vec<u8> {
    let segment = |byte: u8| {
        let mut s = Vec::new();
        let mut left = n;
        while left > 0 {
            let run = left.min(128);
            s.push((257 - run) as u8);
            s.push(byte);
            left -= run;
        }
        s
    };
    let (high, low) = (segment((v >> 8) as u8), segment(v as u8));
    let mut body = high.clone();
    body.extend(&low);
    rle_frame(2, &[64, 64 + high.len() as u32], &body)
}

/// A fresh empty folder under `root` for one test.
pub fn fresh(root: &Path, name: &str) -> PathBuf {
    let dir = root.join("round_three_dicom").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("folder");
    dir
}

/// A series of `slices` default images 2 mm apart in `dir`.
pub fn series(dir: &Path, slices: usize, base: &Image) -> Vec<PathBuf> {
    (0..slices).map(|k| Image { z: 2.0 * k as f64, ..base.clone() }.write(dir, &format!("IM{k:04}"))).collect()
}
