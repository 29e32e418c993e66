//! One DICOM file's header, read up to the pixel data: what grouping into series, geometry and
//! value conversion need. Reading goes through dicom-rs (`dicom-object`); this module only picks
//! attributes out.

use std::path::{Path, PathBuf};

use dicom_core::Tag;
use dicom_dictionary_std::tags;
use dicom_object::{DefaultDicomObject, OpenFileOptions};
use glam::DVec3;

use super::geometry::SliceGeometry;
use crate::load::{LoadError, Location};

/// MediaStorageSOPClassUID of a DICOMDIR (Media Storage Directory Storage).
const DICOMDIR_CLASS: &str = "1.2.840.10008.1.3.10";

/// What a file turned out to be.
pub enum Probe {
    /// No DICOM preamble and magic: skipped with a count.
    NotDicom,
    /// A DICOMDIR: an index of other files, skipped with a note.
    Dicomdir,
    /// A DICOM object without an image (no Rows and no Columns: a report, a presentation
    /// state), skipped with a note.
    NoImage,
    /// An image.
    Image(Box<FileHeader>),
}

/// One file's header.
#[derive(Clone, Debug)]
pub struct FileHeader {
    /// The file.
    pub path: PathBuf,
    /// Transfer syntax UID (from the file meta group).
    pub transfer_syntax: String,
    /// SeriesInstanceUID ("" when absent).
    pub series_uid: String,
    /// SeriesNumber.
    pub series_number: Option<i64>,
    /// SeriesDescription.
    pub description: String,
    /// Modality.
    pub modality: String,
    /// FrameOfReferenceUID ("" when absent).
    pub frame_of_reference: String,
    /// SamplesPerPixel (1 for grey images).
    pub samples_per_pixel: u16,
    /// BitsAllocated.
    pub bits_allocated: u16,
    /// PhotometricInterpretation ("" when absent).
    pub photometric: String,
    /// NumberOfFrames (1 when absent).
    pub frames: u32,
    /// RescaleSlope, RescaleIntercept (1, 0 when absent).
    pub rescale: (f64, f64),
    /// RescaleType.
    pub rescale_type: Option<String>,
    /// First WindowCenter and WindowWidth.
    pub window: Option<(f64, f64)>,
    /// SliceThickness.
    pub slice_thickness: Option<f64>,
    /// SpacingBetweenSlices.
    pub spacing_between_slices: Option<f64>,
    /// The geometry of each frame (one for a single-frame file).
    pub frame_geometry: Vec<SliceGeometry>,
}

/// Reads `path`'s header. `Ok(Probe::NotDicom)` for a file without the `DICM` magic (after the
/// 128-byte preamble, or at the start of a file written without one); an error for a DICOM file
/// that cannot be parsed (a corrupt or truncated slice) or whose attributes are malformed.
pub fn probe(path: &Path) -> Result<Probe, LoadError> {
    // A FIFO or a device would block the read of the magic: refuse it by name.
    match crate::input_file::special_kind(path) {
        Ok(None) => {}
        Ok(Some(what)) => return Err(LoadError::NotAFile { path: path.to_path_buf(), what }),
        Err(source) => return Err(LoadError::Io { path: path.to_path_buf(), source }),
    }
    let Some(magic_at) = dicom_magic_at(path)? else {
        return Ok(Probe::NotDicom);
    };
    // Every length must fit in the file before dicom-rs sizes a buffer by it.
    super::lengths::check(path, magic_at)?;
    // Float and Double Float Pixel Data (7FE0,0008/0009) come just before PixelData: the
    // header stops at the first pixel element of any kind. The default preamble detection
    // reads files with and without the 128-byte preamble.
    let object = OpenFileOptions::new()
        .read_until(tags::FLOAT_PIXEL_DATA)
        .open_file(path)
        .map_err(|e| LoadError::DicomRead { path: path.to_path_buf(), reason: super::one_line(&e.to_string()) })?;
    if object.meta().media_storage_sop_class_uid().trim_end_matches('\0') == DICOMDIR_CLASS {
        return Ok(Probe::Dicomdir);
    }
    if object.get(tags::ROWS).is_none() && object.get(tags::COLUMNS).is_none() {
        return Ok(Probe::NoImage);
    }
    let file_len = std::fs::metadata(path).map_err(|source| LoadError::Io { path: path.to_path_buf(), source })?.len();
    Ok(Probe::Image(Box::new(FileHeader::of(path, &object, file_len)?)))
}

/// True when `path` has the 128-byte preamble and `DICM` (PS3.10 §7.1), or `DICM` at its start
/// (a file written without the preamble, which dicom-rs reads as well).
fn has_dicom_magic(path: &Path) -> Result<bool, LoadError> {
    Ok(dicom_magic_at(path)?.is_some())
}

/// Where `DICM` is in `path`: at byte 128 (after the preamble) or 0 (a file without it).
fn dicom_magic_at(path: &Path) -> Result<Option<u64>, LoadError> {
    use std::io::Read;
    let mut head = [0u8; 132];
    let mut file = std::fs::File::open(path).map_err(|source| LoadError::Io { path: path.to_path_buf(), source })?;
    let mut read = 0;
    while read < head.len() {
        match file.read(&mut head[read..]) {
            Ok(0) => break,
            Ok(n) => read += n,
            Err(source) => return Err(LoadError::Io { path: path.to_path_buf(), source }),
        }
    }
    Ok(if read >= 132 && &head[128..132] == b"DICM" {
        Some(128)
    } else if read >= 4 && &head[..4] == b"DICM" {
        Some(0)
    } else {
        None
    })
}

/// The text of `tag`, trimmed; `None` when absent or empty.
pub fn text(object: &DefaultDicomObject, tag: Tag) -> Option<String> {
    let e = object.get(tag)?;
    let value = match e.value() {
        // Text written with VR UN stays bytes in dicom-rs.
        dicom_core::value::Value::Primitive(dicom_core::value::PrimitiveValue::U8(bytes)) => {
            String::from_utf8_lossy(bytes).into_owned().into()
        }
        _ => e.to_str().ok()?,
    };
    let value = value.trim_matches(|c: char| c.is_whitespace() || c == '\0');
    (!value.is_empty()).then(|| value.to_string())
}

/// The numbers of `tag` (DS, IS, FD, US…).
pub fn numbers(object: &DefaultDicomObject, tag: Tag) -> Option<Vec<f64>> {
    let e = object.get(tag)?;
    un_numbers(e).or_else(|| e.to_multi_float64().ok()).filter(|v| !v.is_empty())
}

/// The first finite number of `tag`, where a malformed value only loses a label (SeriesNumber,
/// the display window).
fn number(object: &DefaultDicomObject, tag: Tag) -> Option<f64> {
    numbers(object, tag).and_then(|v| v.first().copied()).filter(|v| v.is_finite())
}

type Element = dicom_object::mem::InMemElement;

/// An attribute as messages name it: `RescaleSlope (0028,1053)`.
fn attribute(name: &str, tag: Tag) -> String {
    format!("{name} {tag}")
}

/// The error for `element` (attribute `name`, `tag`) of `path` holding a value that is not
/// `expected`; the value shown with its control characters escaped, cut to 80 characters.
fn bad(path: &Path, element: Option<&Element>, name: &str, tag: Tag, expected: &'static str) -> LoadError {
    let value = match element.map(|e| e.to_str()) {
        None => "(absent)".to_string(),
        Some(Ok(text)) => super::one_line(&text.chars().take(80).collect::<String>()),
        Some(Err(_)) => "(not a number)".to_string(),
    };
    LoadError::BadField { at: Location::file(path), field: attribute(name, tag), value, expected }
}

/// The numbers `element` holds: `Ok(None)` when it is absent or empty; an error naming `path`
/// and the attribute when its value is not `count` finite numbers (`NaN`, `abc`, one value of
/// a pair). Nothing is taken as a default in place of a malformed value.
fn checked(
    path: &Path,
    element: Option<&Element>,
    name: &str,
    tag: Tag,
    count: usize,
    expected: &'static str,
) -> Result<Option<Vec<f64>>, LoadError> {
    let Some(e) = element else { return Ok(None) };
    if e.to_str().is_ok_and(|t| t.trim_matches(|c: char| c.is_whitespace() || c == '\0').is_empty()) {
        return Ok(None);
    }
    match un_numbers(e).or_else(|| e.to_multi_float64().ok()) {
        Some(v) if v.len() == count && v.iter().all(|x| x.is_finite()) => Ok(Some(v)),
        _ => Err(bad(path, element, name, tag, expected)),
    }
}

/// The numbers of an element written with VR UN (unknown) whose bytes are a DS or IS text, as
/// some converters write them (pydicom's `rtdose_rle.dcm`).
fn un_numbers(e: &Element) -> Option<Vec<f64>> {
    // dicom-rs keeps such a value as bytes (whatever VR it then gives the element).
    let dicom_core::value::Value::Primitive(dicom_core::value::PrimitiveValue::U8(bytes)) = e.value() else {
        return None;
    };
    let text = std::str::from_utf8(bytes).ok()?;
    text.trim_matches(|c: char| c.is_whitespace() || c == '\0')
        .split('\\')
        .map(|v| v.trim().parse::<f64>().ok())
        .collect()
}

/// A whole number in `range` from `element`, `Ok(None)` when absent or empty.
fn whole(
    path: &Path,
    element: Option<&Element>,
    name: &str,
    tag: Tag,
    range: std::ops::RangeInclusive<f64>,
    expected: &'static str,
) -> Result<Option<u32>, LoadError> {
    match checked(path, element, name, tag, 1, expected)? {
        Some(v) if v[0].fract() == 0.0 && range.contains(&v[0]) => Ok(Some(v[0] as u32)),
        Some(_) => Err(bad(path, element, name, tag, expected)),
        None => Ok(None),
    }
}

const ROWS_EXPECTED: &str = "a whole number of pixels from 1 to 65535 (Rows is the image's height, Columns its \
                             width); the header is corrupt: remove the file or copy it again";
const FRAMES_EXPECTED: &str = "a whole number of frames, at least 1; the header is corrupt: remove the file or copy \
                               it again";
const SLOPE_EXPECTED: &str = "one finite, non-zero number (data value = stored value × slope + intercept, e.g. 1); \
                              fix the header (e.g. with dcmodify) or remove the file";
const INTERCEPT_EXPECTED: &str = "one finite number (data value = stored value × slope + intercept, e.g. -1024); \
                                  fix the header (e.g. with dcmodify) or remove the file";
const SPACING_EXPECTED: &str = "two positive numbers in mm, the row spacing then the column spacing (e.g. \
                                0.5\\0.5); fix the header (e.g. with dcmodify) or remove the file";
const ORIENTATION_EXPECTED: &str = "six finite numbers, the row direction then the column direction (e.g. \
                                    1\\0\\0\\0\\1\\0); fix the header (e.g. with dcmodify) or remove the file";
const POSITION_EXPECTED: &str = "three finite numbers in mm, the centre of the first pixel (e.g. -120\\-80\\35.5); \
                                 fix the header (e.g. with dcmodify) or remove the file";
const THICKNESS_EXPECTED: &str = "one finite number in mm (e.g. 1.25); fix the header (e.g. with dcmodify) or \
                                  remove the file";
const SAMPLES_EXPECTED: &str = "a whole number from 1 to 4 (1 for a greyscale image); the header is corrupt";
const BITS_EXPECTED: &str = "a whole number from 1 to 64 (8, 16 or 32 for greyscale images); the header is corrupt";

/// The first item of sequence `tag` in `object`'s item `items[index]`.
fn nested(items: &[dicom_object::InMemDicomObject], index: usize, tag: Tag) -> Option<&dicom_object::InMemDicomObject> {
    items.get(index)?.get(tag)?.items()?.first()
}

/// Fails when the pixels `rows × columns × frames` claims cannot be in a file of `file_len`
/// bytes: before anything is allocated per frame, a 3 KB file claiming 10⁸ frames is refused.
/// Native pixels need their bytes; encapsulated frames at least one 8-byte item each; a
/// deflated data set at most deflate's 1032:1.
fn check_size(
    path: &Path,
    (transfer_syntax, photometric): (&str, &str),
    (rows, columns, frames, samples, bits): (u32, u32, u32, u32, u32),
    file_len: u64,
) -> Result<(), LoadError> {
    use dicom_encoding::transfer_syntax::TransferSyntaxIndex;
    // Half-samples per pixel: chroma subsampled YBR stores 2 (4:2:2) or 1.5 (4:2:0) samples.
    let half_samples = match photometric {
        p if p.ends_with("_422") => 4,
        p if p.ends_with("_420") => 3,
        _ => 2 * u128::from(samples),
    };
    let bits_per_frame = u128::from(rows) * u128::from(columns) * half_samples * u128::from(bits) / 2;
    let needed = (bits_per_frame * u128::from(frames)).div_ceil(8);
    let ts = dicom_transfer_syntax_registry::TransferSyntaxRegistry.get(transfer_syntax);
    let (limit, what) = match ts {
        Some(ts) if ts.is_encapsulated_pixel_data() => {
            if u64::from(frames) <= file_len / 8 {
                return Ok(());
            }
            return Err(LoadError::DicomPixels {
                path: path.to_path_buf(),
                message: format!(
                    "NumberOfFrames {} is {frames}, but the file has only {file_len} bytes, too few for {frames} \
                     compressed frames (each takes at least 8); NumberOfFrames is wrong or the file is truncated: \
                     remove the file or copy it again",
                    tags::NUMBER_OF_FRAMES
                ),
            });
        }
        Some(ts) if ts.is_codec_free() => (u128::from(file_len), "has only"),
        _ => (u128::from(file_len) * 1032, "can inflate to at most 1032 ×"),
    };
    if needed <= limit {
        return Ok(());
    }
    Err(LoadError::DicomPixels {
        path: path.to_path_buf(),
        message: format!(
            "Rows {} {rows} × Columns {} {columns} × NumberOfFrames {} {frames} × {samples} sample(s) of BitsAllocated \
             {} {bits} need {needed} bytes of pixel data, but the file {what} {file_len} bytes; one of those \
             attributes is wrong or the file is truncated: remove the file or copy it again",
            tags::ROWS,
            tags::COLUMNS,
            tags::NUMBER_OF_FRAMES,
            tags::BITS_ALLOCATED
        ),
    })
}

impl FileHeader {
    fn of(path: &Path, object: &DefaultDicomObject, file_len: u64) -> Result<FileHeader, LoadError> {
        let get = |tag: Tag| object.get(tag);
        // A whole number in `range`, when the file has the attribute.
        let count = |tag: Tag, name: &str, range: std::ops::RangeInclusive<f64>, expected| {
            whole(path, get(tag), name, tag, range, expected)
        };
        let size = |tag: Tag, name: &str| -> Result<u32, LoadError> {
            count(tag, name, 1.0..=65535.0, ROWS_EXPECTED)?.ok_or_else(|| bad(path, None, name, tag, ROWS_EXPECTED))
        };
        let rows = size(tags::ROWS, "Rows")?;
        let columns = size(tags::COLUMNS, "Columns")?;
        let frames = count(tags::NUMBER_OF_FRAMES, "NumberOfFrames", 1.0..=4.0e9, FRAMES_EXPECTED)?.unwrap_or(1);
        let samples_per_pixel =
            count(tags::SAMPLES_PER_PIXEL, "SamplesPerPixel", 1.0..=4.0, SAMPLES_EXPECTED)?.unwrap_or(1);
        let bits_allocated = count(tags::BITS_ALLOCATED, "BitsAllocated", 1.0..=64.0, BITS_EXPECTED)?.unwrap_or(16);
        let transfer_syntax = object.meta().transfer_syntax().trim_end_matches('\0').to_string();
        let photometric = text(object, tags::PHOTOMETRIC_INTERPRETATION).unwrap_or_default();
        check_size(
            path,
            (&transfer_syntax, &photometric),
            (rows, columns, frames, samples_per_pixel, bits_allocated),
            file_len,
        )?;

        let one = |tag: Tag, name: &str, expected| -> Result<Option<f64>, LoadError> {
            Ok(checked(path, get(tag), name, tag, 1, expected)?.map(|v| v[0]))
        };
        let mut slice_thickness = one(tags::SLICE_THICKNESS, "SliceThickness", THICKNESS_EXPECTED)?;
        let spacing_between_slices = one(tags::SPACING_BETWEEN_SLICES, "SpacingBetweenSlices", THICKNESS_EXPECTED)?;
        let position = |e: Option<&Element>| -> Result<Option<DVec3>, LoadError> {
            let v = checked(path, e, "ImagePositionPatient", tags::IMAGE_POSITION_PATIENT, 3, POSITION_EXPECTED)?;
            Ok(v.map(|v| DVec3::new(v[0], v[1], v[2])))
        };
        let orientation = |e: Option<&Element>| -> Result<Option<[f64; 6]>, LoadError> {
            let v =
                checked(path, e, "ImageOrientationPatient", tags::IMAGE_ORIENTATION_PATIENT, 6, ORIENTATION_EXPECTED)?;
            Ok(v.map(|v| [v[0], v[1], v[2], v[3], v[4], v[5]]))
        };
        let pixel_spacing = |e: Option<&Element>| -> Result<Option<[f64; 2]>, LoadError> {
            let v = checked(path, e, "PixelSpacing", tags::PIXEL_SPACING, 2, SPACING_EXPECTED)?;
            match v {
                Some(v) if v[0] > 0.0 && v[1] > 0.0 => Ok(Some([v[0], v[1]])),
                Some(_) => Err(bad(path, e, "PixelSpacing", tags::PIXEL_SPACING, SPACING_EXPECTED)),
                None => Ok(None),
            }
        };
        let top = SliceGeometry {
            path: path.to_path_buf(),
            position: position(get(tags::IMAGE_POSITION_PATIENT))?,
            orientation: orientation(get(tags::IMAGE_ORIENTATION_PATIENT))?,
            pixel_spacing: pixel_spacing(get(tags::PIXEL_SPACING))?,
            rows,
            columns,
        };
        let enhanced = object.get(tags::PER_FRAME_FUNCTIONAL_GROUPS_SEQUENCE).is_some();
        // RT Dose and other multi-frame grids: frame offsets along the normal (PS3.3 C.8.8.3.2).
        let grid_offsets = numbers(object, tags::GRID_FRAME_OFFSET_VECTOR).filter(|v| v.len() == frames as usize);
        let frame_geometry = if frames <= 1 && !enhanced {
            vec![top]
        } else {
            // Enhanced multi-frame objects keep geometry in functional groups (PS3.3 C.7.6.16):
            // orientation and pixel measures shared, one plane position per frame.
            let shared = object.get(tags::SHARED_FUNCTIONAL_GROUPS_SEQUENCE).and_then(|e| e.items());
            let per_frame = object.get(tags::PER_FRAME_FUNCTIONAL_GROUPS_SEQUENCE).and_then(|e| e.items());
            let shared_orientation = orientation(
                shared
                    .and_then(|s| nested(s, 0, tags::PLANE_ORIENTATION_SEQUENCE))
                    .and_then(|o| o.get(tags::IMAGE_ORIENTATION_PATIENT)),
            )?;
            let measures = shared.and_then(|s| nested(s, 0, tags::PIXEL_MEASURES_SEQUENCE));
            let shared_spacing = pixel_spacing(measures.and_then(|m| m.get(tags::PIXEL_SPACING)))?;
            if let Some(t) = checked(
                path,
                measures.and_then(|m| m.get(tags::SLICE_THICKNESS)),
                "SliceThickness",
                tags::SLICE_THICKNESS,
                1,
                THICKNESS_EXPECTED,
            )? {
                slice_thickness = Some(t[0]);
            }
            let orientation = shared_orientation.or(top.orientation);
            let pixel_spacing = shared_spacing.or(top.pixel_spacing);
            (0..frames as usize)
                .map(|f| {
                    let own = position(
                        per_frame
                            .and_then(|p| nested(p, f, tags::PLANE_POSITION_SEQUENCE))
                            .and_then(|p| p.get(tags::IMAGE_POSITION_PATIENT)),
                    )?;
                    let position = own.or_else(|| {
                        // A legacy multi-frame file: frames stepped along the normal, by the
                        // grid's offsets or the slice spacing.
                        let (p0, o) = (top.position?, orientation?);
                        let normal =
                            DVec3::new(o[0], o[1], o[2]).cross(DVec3::new(o[3], o[4], o[5])).normalize_or_zero();
                        let offset = match &grid_offsets {
                            Some(offsets) => offsets[f],
                            None => spacing_between_slices.or(slice_thickness)? * f as f64,
                        };
                        Some(p0 + normal * offset)
                    });
                    Ok(SliceGeometry {
                        path: PathBuf::from(format!("{} frame {f}", path.display())),
                        position,
                        orientation,
                        pixel_spacing,
                        rows,
                        columns,
                    })
                })
                .collect::<Result<Vec<_>, LoadError>>()?
        };
        let window = match (number(object, tags::WINDOW_CENTER), number(object, tags::WINDOW_WIDTH)) {
            (Some(c), Some(w)) if w > 0.0 => Some((c, w)),
            _ => None,
        };
        // RT Dose scales by DoseGridScaling (PS3.3 C.8.8.3) instead of a rescale.
        let slope = match one(tags::RESCALE_SLOPE, "RescaleSlope", SLOPE_EXPECTED)? {
            Some(s) => Some((s, "RescaleSlope", tags::RESCALE_SLOPE)),
            None => one(tags::DOSE_GRID_SCALING, "DoseGridScaling", SLOPE_EXPECTED)?
                .map(|s| (s, "DoseGridScaling", tags::DOSE_GRID_SCALING)),
        };
        if let Some((s, name, tag)) = slope
            && s == 0.0
        {
            return Err(bad(path, get(tag), name, tag, SLOPE_EXPECTED));
        }
        let intercept = one(tags::RESCALE_INTERCEPT, "RescaleIntercept", INTERCEPT_EXPECTED)?;
        Ok(FileHeader {
            path: path.to_path_buf(),
            transfer_syntax,
            series_uid: text(object, tags::SERIES_INSTANCE_UID).unwrap_or_default(),
            series_number: number(object, tags::SERIES_NUMBER).map(|n| n as i64),
            description: text(object, tags::SERIES_DESCRIPTION).unwrap_or_default(),
            modality: text(object, tags::MODALITY).unwrap_or_default(),
            frame_of_reference: text(object, tags::FRAME_OF_REFERENCE_UID).unwrap_or_default(),
            samples_per_pixel: samples_per_pixel as u16,
            bits_allocated: bits_allocated as u16,
            photometric,
            frames,
            rescale: (slope.map_or(1.0, |s| s.0), intercept.unwrap_or(0.0)),
            rescale_type: text(object, tags::RESCALE_TYPE).or_else(|| text(object, tags::DOSE_UNITS)),
            window,
            slice_thickness,
            spacing_between_slices,
            frame_geometry,
        })
    }
}

/// True when `path` is a readable file with the DICOM magic (with or without the preamble).
pub fn looks_like_dicom(path: &Path) -> bool {
    // Never open a FIFO or a device to look: that could block.
    matches!(crate::input_file::special_kind(path), Ok(None)) && has_dicom_magic(path).unwrap_or(false)
}
