//! One DICOM file's header, read up to the pixel data: what grouping into series, geometry and
//! value conversion need. Reading goes through dicom-rs (`dicom-object`); this module only picks
//! attributes out.

use std::path::{Path, PathBuf};

use dicom_core::Tag;
use dicom_dictionary_std::tags;
use dicom_object::{DefaultDicomObject, OpenFileOptions};
use glam::DVec3;

use super::geometry::SliceGeometry;
use crate::load::LoadError;

/// MediaStorageSOPClassUID of a DICOMDIR (Media Storage Directory Storage).
const DICOMDIR_CLASS: &str = "1.2.840.10008.1.3.10";

/// What a file turned out to be.
pub enum Probe {
    /// No DICOM preamble and magic: skipped with a count.
    NotDicom,
    /// A DICOMDIR: an index of other files, skipped with a note.
    Dicomdir,
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
    /// SamplesPerPixel (1 for grey images).
    pub samples_per_pixel: u16,
    /// BitsAllocated.
    pub bits_allocated: u16,
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

/// Reads `path`'s header. `Ok(Probe::NotDicom)` for a file without the `DICM` magic; an error
/// for a DICOM file that cannot be parsed (a corrupt or truncated slice).
pub fn probe(path: &Path) -> Result<Probe, LoadError> {
    // A FIFO or a device would block the read of the magic: refuse it by name.
    match crate::input_file::special_kind(path) {
        Ok(None) => {}
        Ok(Some(what)) => return Err(LoadError::NotAFile { path: path.to_path_buf(), what }),
        Err(source) => return Err(LoadError::Io { path: path.to_path_buf(), source }),
    }
    if !has_dicom_magic(path)? {
        return Ok(Probe::NotDicom);
    }
    let object = OpenFileOptions::new()
        .read_until(tags::PIXEL_DATA)
        .open_file(path)
        .map_err(|e| LoadError::DicomRead { path: path.to_path_buf(), reason: e.to_string() })?;
    if object.meta().media_storage_sop_class_uid().trim_end_matches('\0') == DICOMDIR_CLASS {
        return Ok(Probe::Dicomdir);
    }
    Ok(Probe::Image(Box::new(FileHeader::of(path, &object)?)))
}

/// True when `path` has the 128-byte preamble and `DICM` (PS3.10 §7.1).
fn has_dicom_magic(path: &Path) -> Result<bool, LoadError> {
    use std::io::Read;
    let mut head = [0u8; 132];
    let mut file = std::fs::File::open(path).map_err(|source| LoadError::Io { path: path.to_path_buf(), source })?;
    let mut read = 0;
    while read < head.len() {
        match file.read(&mut head[read..]) {
            Ok(0) => return Ok(false),
            Ok(n) => read += n,
            Err(source) => return Err(LoadError::Io { path: path.to_path_buf(), source }),
        }
    }
    Ok(&head[128..132] == b"DICM")
}

/// The text of `tag`, trimmed; `None` when absent or empty.
pub fn text(object: &DefaultDicomObject, tag: Tag) -> Option<String> {
    let value = object.get(tag)?.to_str().ok()?;
    let value = value.trim_matches(|c: char| c.is_whitespace() || c == '\0');
    (!value.is_empty()).then(|| value.to_string())
}

/// The numbers of `tag` (DS, IS, FD, US…).
pub fn numbers(object: &DefaultDicomObject, tag: Tag) -> Option<Vec<f64>> {
    object.get(tag)?.to_multi_float64().ok().filter(|v| !v.is_empty())
}

fn number(object: &DefaultDicomObject, tag: Tag) -> Option<f64> {
    numbers(object, tag).and_then(|v| v.first().copied()).filter(|v| v.is_finite())
}

fn vec3(v: Option<Vec<f64>>) -> Option<DVec3> {
    v.filter(|v| v.len() == 3).map(|v| DVec3::new(v[0], v[1], v[2]))
}

fn six(v: Option<Vec<f64>>) -> Option<[f64; 6]> {
    v.filter(|v| v.len() == 6).map(|v| [v[0], v[1], v[2], v[3], v[4], v[5]])
}

fn two(v: Option<Vec<f64>>) -> Option<[f64; 2]> {
    v.filter(|v| v.len() == 2).map(|v| [v[0], v[1]])
}

/// The first item of sequence `tag` in `object`'s item `items[index]`.
fn nested<'a>(
    items: &'a [dicom_object::InMemDicomObject],
    index: usize,
    tag: Tag,
) -> Option<&'a dicom_object::InMemDicomObject> {
    items.get(index)?.get(tag)?.items()?.first()
}

impl FileHeader {
    fn of(path: &Path, object: &DefaultDicomObject) -> Result<FileHeader, LoadError> {
        let rows = number(object, tags::ROWS).unwrap_or(0.0) as u32;
        let columns = number(object, tags::COLUMNS).unwrap_or(0.0) as u32;
        let frames = number(object, tags::NUMBER_OF_FRAMES).map_or(1, |n| n.max(1.0) as u32);
        let mut slice_thickness = number(object, tags::SLICE_THICKNESS);
        let spacing_between_slices = number(object, tags::SPACING_BETWEEN_SLICES);
        let top = SliceGeometry {
            path: path.to_path_buf(),
            position: vec3(numbers(object, tags::IMAGE_POSITION_PATIENT)),
            orientation: six(numbers(object, tags::IMAGE_ORIENTATION_PATIENT)),
            pixel_spacing: two(numbers(object, tags::PIXEL_SPACING)),
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
            let shared_orientation = shared
                .and_then(|s| nested(s, 0, tags::PLANE_ORIENTATION_SEQUENCE))
                .and_then(|o| six(o.get(tags::IMAGE_ORIENTATION_PATIENT)?.to_multi_float64().ok()));
            let measures = shared.and_then(|s| nested(s, 0, tags::PIXEL_MEASURES_SEQUENCE));
            let shared_spacing = measures.and_then(|m| two(m.get(tags::PIXEL_SPACING)?.to_multi_float64().ok()));
            if let Some(t) = measures.and_then(|m| m.get(tags::SLICE_THICKNESS)?.to_float64().ok()) {
                slice_thickness = Some(t);
            }
            let orientation = shared_orientation.or(top.orientation);
            let pixel_spacing = shared_spacing.or(top.pixel_spacing);
            (0..frames as usize)
                .map(|f| {
                    let position = per_frame
                        .and_then(|p| nested(p, f, tags::PLANE_POSITION_SEQUENCE))
                        .and_then(|p| vec3(p.get(tags::IMAGE_POSITION_PATIENT)?.to_multi_float64().ok()))
                        .or_else(|| {
                            // A legacy multi-frame file: frames stepped along the normal, by
                            // the grid's offsets or the slice spacing.
                            let (p0, o) = (top.position?, orientation?);
                            let normal =
                                DVec3::new(o[0], o[1], o[2]).cross(DVec3::new(o[3], o[4], o[5])).normalize_or_zero();
                            let offset = match &grid_offsets {
                                Some(offsets) => offsets[f],
                                None => spacing_between_slices.or(slice_thickness)? * f as f64,
                            };
                            Some(p0 + normal * offset)
                        });
                    SliceGeometry {
                        path: PathBuf::from(format!("{} frame {f}", path.display())),
                        position,
                        orientation,
                        pixel_spacing,
                        rows,
                        columns,
                    }
                })
                .collect()
        };
        let window = match (number(object, tags::WINDOW_CENTER), number(object, tags::WINDOW_WIDTH)) {
            (Some(c), Some(w)) if w > 0.0 => Some((c, w)),
            _ => None,
        };
        Ok(FileHeader {
            path: path.to_path_buf(),
            transfer_syntax: object.meta().transfer_syntax().trim_end_matches('\0').to_string(),
            series_uid: text(object, tags::SERIES_INSTANCE_UID).unwrap_or_default(),
            series_number: number(object, tags::SERIES_NUMBER).map(|n| n as i64),
            description: text(object, tags::SERIES_DESCRIPTION).unwrap_or_default(),
            modality: text(object, tags::MODALITY).unwrap_or_default(),
            samples_per_pixel: number(object, tags::SAMPLES_PER_PIXEL).map_or(1, |n| n as u16),
            bits_allocated: number(object, tags::BITS_ALLOCATED).map_or(16, |n| n as u16),
            frames,
            // RT Dose scales by DoseGridScaling (PS3.3 C.8.8.3) instead of a rescale.
            rescale: (
                number(object, tags::RESCALE_SLOPE).or(number(object, tags::DOSE_GRID_SCALING)).unwrap_or(1.0),
                number(object, tags::RESCALE_INTERCEPT).unwrap_or(0.0),
            ),
            rescale_type: text(object, tags::RESCALE_TYPE).or_else(|| text(object, tags::DOSE_UNITS)),
            window,
            slice_thickness,
            spacing_between_slices,
            frame_geometry,
        })
    }
}

/// True when `path` is a readable file with the DICOM preamble and magic.
pub fn looks_like_dicom(path: &Path) -> bool {
    // Never open a FIFO or a device to look: that could block.
    matches!(crate::input_file::special_kind(path), Ok(None)) && has_dicom_magic(path).unwrap_or(false)
}
