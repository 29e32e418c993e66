//! DICOM Segmentation objects (SEG, PS3.3 A.51 and C.8.20): what PACS and segmentation tools
//! (highdicom, dcmqi, 3D Slicer) send beside a scan. One multi-frame file whose frames each hold
//! one segment's mask on one plane — `BINARY` (1 bit a pixel, packed across frames),
//! `FRACTIONAL` (8 bits, a share of MaximumFractionalValue), or the newer `LABELMAP` (the
//! segment number itself) — placed in the patient frame by per-frame ImagePositionPatient.
//!
//! [`load`] turns it into a label map (voxel = segment number, 0 outside every segment) on the
//! grid the frames lie on, in LPS axes like every loaded volume; [`segments`] reads the segments'
//! names and recommended colours (CIELab, PS3.3 C.10.7.1.1) as the map's label table. A SEG may
//! cover only the slices its segments reach: the grid spans the frames' planes, with empty slices
//! where a gap has none.

use std::path::Path;

use dicom_core::Tag;
use dicom_dictionary_std::tags;
use dicom_object::{DefaultDicomObject, InMemDicomObject};
use glam::DVec3;

use super::header::{FileHeader, numbers, text};
use crate::labels::{Label, LabelTable};
use crate::load::{AxisOrientation, LoadError, LoadReport, LoadedVolume, Location, VolumeFormat};
use crate::volume::{Volume, VoxelData};
use crate::volume_meta::{VolumeMeta, WorldFrame};

/// Segmentation Storage.
pub const SEGMENTATION_STORAGE: &str = "1.2.840.10008.5.1.4.1.1.66.4";
/// The native transfer syntaxes (the only ones whose 1-bit frames this reader unpacks).
const NATIVE: [&str; 3] = ["1.2.840.10008.1.2", "1.2.840.10008.1.2.1", "1.2.840.10008.1.2.2"];
/// Planes closer than this (mm) along the normal are one plane.
const SAME_PLANE_MM: f64 = 1e-3;
/// Slices a SEG's grid may span (between its first and last plane).
const MAX_SLICES: f64 = 65_535.0;
/// Voxels a SEG's label map may hold (2³¹: past any GPU's 3D texture).
const MAX_VOXELS: usize = 1 << 31;

/// One segment of a SEG: its number (the label value), name and display colour.
#[derive(Clone, Debug, PartialEq)]
pub struct Segment {
    /// SegmentNumber (0062,0004): 1, 2, …
    pub number: u32,
    /// SegmentLabel (0062,0005), else `Segment N`.
    pub name: String,
    /// RecommendedDisplayCIELabValue (0062,000D) as sRGB, when the file gives one.
    pub rgb: Option<[u8; 3]>,
}

/// Whether `header` is a segmentation (Modality SEG).
pub fn is_segmentation(header: &FileHeader) -> bool {
    header.modality.eq_ignore_ascii_case("SEG")
}

/// Whether `path` is a single DICOM SEG file (what names its own labels, like a `.seg.nrrd`).
pub fn is_seg_file(path: &Path) -> bool {
    path.is_file()
        && super::header::looks_like_dicom(path)
        && matches!(super::header::probe(path), Ok(super::header::Probe::Image(h)) if is_segmentation(&h))
}

fn pixels_error(path: &Path, message: String) -> LoadError {
    LoadError::DicomPixels { path: path.to_path_buf(), message }
}

/// Opens the whole object (the header was probed, so every length fits in the file).
fn open(path: &Path) -> Result<DefaultDicomObject, LoadError> {
    dicom_object::open_file(path)
        .map_err(|e| LoadError::DicomRead { path: path.to_path_buf(), reason: super::one_line(&e.to_string()) })
}

/// The segments `path` (a SEG) lists, in SegmentNumber order.
pub fn segments(path: &Path) -> Result<Vec<Segment>, LoadError> {
    segments_of(path, &open(path)?)
}

fn segments_of(path: &Path, object: &DefaultDicomObject) -> Result<Vec<Segment>, LoadError> {
    let items = object.get(tags::SEGMENT_SEQUENCE).and_then(|e| e.items()).unwrap_or_default();
    if items.is_empty() {
        return Err(pixels_error(
            path,
            format!(
                "is a segmentation (Modality SEG) without a SegmentSequence {}: nothing says what its frames are; \
                 the file is incomplete — export it again",
                tags::SEGMENT_SEQUENCE
            ),
        ));
    }
    let mut out: Vec<Segment> = Vec::with_capacity(items.len());
    for (i, item) in items.iter().enumerate() {
        let number = item_number(item, tags::SEGMENT_NUMBER).filter(|n| (1..=65_535).contains(n)).ok_or_else(|| {
            pixels_error(
                path,
                format!(
                    "item {} of SegmentSequence {} has no SegmentNumber {} from 1 to 65535; the file is corrupt",
                    i + 1,
                    tags::SEGMENT_SEQUENCE,
                    tags::SEGMENT_NUMBER
                ),
            )
        })?;
        if out.iter().any(|s| s.number == number) {
            return Err(pixels_error(
                path,
                format!("SegmentSequence {} lists segment {number} twice; the file is corrupt", tags::SEGMENT_SEQUENCE),
            ));
        }
        let name = item_text(item, tags::SEGMENT_LABEL).unwrap_or_else(|| format!("Segment {number}"));
        let rgb = item_numbers(item, tags::RECOMMENDED_DISPLAY_CIE_LAB_VALUE)
            .filter(|v| v.len() == 3 && v.iter().all(|x| (0.0..=65_535.0).contains(x)))
            .map(|v| cielab_to_srgb([v[0], v[1], v[2]]));
        out.push(Segment { number, name: super::one_line(&name), rgb });
    }
    out.sort_by_key(|s| s.number);
    Ok(out)
}

/// The segments as a label table (`source` names the file): their names and colours, opaque
/// and shown; a segment without a colour takes the default palette's.
pub fn table(path: &Path, segments: &[Segment]) -> LabelTable {
    let labels = segments
        .iter()
        .map(|s| {
            let default = crate::labels::default_label(s.number);
            let label = Label { name: s.name.clone(), rgb: s.rgb.unwrap_or(default.rgb), ..default };
            (s.number, label)
        })
        .collect();
    LabelTable { labels, source: format!("DICOM SEG {}", path.display()) }
}

/// DICOM's scaled CIELab (L* 0..100, a* and b* −128..127, each to 0..65535; D65) as sRGB bytes.
pub fn cielab_to_srgb(lab: [f64; 3]) -> [u8; 3] {
    let l = lab[0] / 65_535.0 * 100.0;
    let a = lab[1] / 65_535.0 * 255.0 - 128.0;
    let b = lab[2] / 65_535.0 * 255.0 - 128.0;
    // CIE 1976 L*a*b* to XYZ, D65 white.
    let fy = (l + 16.0) / 116.0;
    let (fx, fz) = (fy + a / 500.0, fy - b / 200.0);
    let inverse = |t: f64| if t > 6.0 / 29.0 { t * t * t } else { 3.0 * (6.0f64 / 29.0).powi(2) * (t - 4.0 / 29.0) };
    let (x, y, z) = (0.950_47 * inverse(fx), inverse(fy), 1.088_83 * inverse(fz));
    // XYZ to linear sRGB (IEC 61966-2-1), then its transfer curve.
    let linear = [
        3.240_6 * x - 1.537_2 * y - 0.498_6 * z,
        -0.968_9 * x + 1.875_8 * y + 0.041_5 * z,
        0.055_7 * x - 0.204_0 * y + 1.057_0 * z,
    ];
    linear.map(|c| {
        let c = c.clamp(0.0, 1.0);
        let v = if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
        (v * 255.0).round() as u8
    })
}

fn item_text(item: &InMemDicomObject, tag: Tag) -> Option<String> {
    let value = item.get(tag)?.to_str().ok()?;
    let value = value.trim_matches(|c: char| c.is_whitespace() || c == '\0');
    (!value.is_empty()).then(|| value.to_string())
}

fn item_numbers(item: &InMemDicomObject, tag: Tag) -> Option<Vec<f64>> {
    item.get(tag)?.to_multi_float64().ok().filter(|v| !v.is_empty())
}

fn item_number(item: &InMemDicomObject, tag: Tag) -> Option<u32> {
    let v = *item_numbers(item, tag)?.first()?;
    (v.fract() == 0.0 && v >= 0.0 && v <= f64::from(u32::MAX)).then_some(v as u32)
}

/// How a frame's pixels say "inside".
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    /// 1 bit a pixel, packed across frames.
    Binary,
    /// 8 bits, inside where the value is at least half of this maximum.
    Fractional(u32),
    /// 8 or 16 bits, the segment number itself.
    Labelmap,
}

/// Loads the SEG `header` (one file of a chosen series) as a label map; `notes` come from the
/// folder scan.
pub fn load(header: &FileHeader, mut notes: Vec<String>) -> Result<LoadedVolume, LoadError> {
    let path = header.path.as_path();
    let ts = header.transfer_syntax.trim_end_matches('\0');
    if !NATIVE.contains(&ts) {
        return Err(pixels_error(
            path,
            format!(
                "is a segmentation whose pixel data is compressed (transfer syntax {}); volgraph reads segmentations \
                 stored uncompressed: convert it (e.g. `dcmconv +te` or `gdcmconv --raw`)",
                super::one_line(ts)
            ),
        ));
    }
    let object = open(path)?;
    let segments = segments_of(path, &object)?;
    let kind = match (text(&object, tags::SEGMENTATION_TYPE).as_deref(), header.bits_allocated) {
        (Some("BINARY"), 1) => Kind::Binary,
        (Some("FRACTIONAL"), 8) => {
            let max = numbers(&object, tags::MAXIMUM_FRACTIONAL_VALUE).and_then(|v| v.first().copied());
            Kind::Fractional(max.filter(|m| m.fract() == 0.0 && (1.0..=255.0).contains(m)).unwrap_or(255.0) as u32)
        }
        (Some("LABELMAP"), 8 | 16) => Kind::Labelmap,
        (kind, bits) => {
            return Err(pixels_error(
                path,
                format!(
                    "SegmentationType {} {} with BitsAllocated {bits} is not a segmentation volgraph reads (BINARY \
                     with 1 bit, FRACTIONAL with 8, LABELMAP with 8 or 16); the file is corrupt",
                    tags::SEGMENTATION_TYPE,
                    kind.map_or("(absent)".to_string(), |k| format!("\"{}\"", super::one_line(k)))
                ),
            ));
        }
    };
    let frames = header.frame_geometry.len();
    let frame_segment = frame_segments(path, &object, kind, frames, &segments)?;
    let grid = Grid::of(path, header, &object)?;
    let (rows, columns) = (header.frame_geometry[0].rows as usize, header.frame_geometry[0].columns as usize);
    let per_frame = rows * columns;
    let bytes = object
        .get(tags::PIXEL_DATA)
        .map(|e| e.to_bytes())
        .transpose()
        .map_err(|e| pixels_error(path, format!("cannot read PixelData: {e}")))?
        .ok_or_else(|| pixels_error(path, format!("has no PixelData {}", tags::PIXEL_DATA)))?;
    let bits = match kind {
        Kind::Binary => 1,
        Kind::Fractional(_) => 8,
        Kind::Labelmap => usize::from(header.bits_allocated),
    };
    let needed = (per_frame * frames * bits).div_ceil(8);
    if bytes.len() < needed {
        return Err(pixels_error(
            path,
            format!(
                "PixelData holds {} bytes, but {frames} frame(s) of {columns}x{rows} pixels at {bits} bit(s) need \
                 {needed}; the file is truncated: copy it again",
                bytes.len()
            ),
        ));
    }
    let largest = segments.iter().map(|s| s.number).max().unwrap_or(0);
    let voxels = per_frame.saturating_mul(grid.slices);
    let mut labels = Vec::new();
    if voxels > MAX_VOXELS || labels.try_reserve_exact(voxels).is_err() {
        return Err(pixels_error(
            path,
            format!(
                "its frames span {} slice(s) of {columns}x{rows} pixels, {voxels} voxels: too many to hold (at most                  {MAX_VOXELS}); a frame's position or the pixel size is wrong",
                grid.slices
            ),
        ));
    }
    labels.resize(voxels, 0u16);
    let mut overlapping = 0usize;
    for (f, slot) in grid.slot.iter().enumerate() {
        let plane = &mut labels[slot * per_frame..(slot + 1) * per_frame];
        for (i, voxel) in plane.iter_mut().enumerate() {
            let k = f * per_frame + i;
            let value = match kind {
                Kind::Binary => u16::from(bytes[k / 8] >> (k % 8) & 1) * frame_segment[f],
                Kind::Fractional(max) => {
                    if u32::from(bytes[k]) * 2 >= max {
                        frame_segment[f]
                    } else {
                        0
                    }
                }
                Kind::Labelmap if bits == 8 => u16::from(bytes[k]),
                Kind::Labelmap => u16::from_le_bytes([bytes[2 * k], bytes[2 * k + 1]]),
            };
            if value != 0 {
                if *voxel != 0 && *voxel != value {
                    overlapping += 1;
                }
                // Overlapping segments: the higher number shows (a label map holds one).
                *voxel = (*voxel).max(value);
            }
        }
    }
    if kind == Kind::Labelmap
        && let Some(v) = labels.iter().find(|&&v| v != 0 && segments.iter().all(|s| s.number != u32::from(v)))
    {
        return Err(pixels_error(
            path,
            format!("a LABELMAP pixel holds {v}, which SegmentSequence does not list; the file is corrupt"),
        ));
    }
    if overlapping > 0 {
        notes.push(format!(
            "{overlapping} voxel(s) lie in several segments; a label map holds one, so each shows the highest segment \
             number there"
        ));
    }
    if let Kind::Fractional(max) = kind {
        notes.push(format!("FRACTIONAL segments taken as inside where the value is at least half of {max}"));
    }
    let file_dims = glam::UVec3::new(columns as u32, rows as u32, grid.slices as u32);
    let data = if largest <= 255 {
        VoxelData::U8(labels.into_iter().map(|v| v as u8).collect())
    } else {
        VoxelData::U16(labels)
    };
    let at = Location::file(path);
    let (orientation, spacing) = AxisOrientation::from_directions(grid.directions, &at, "ImageOrientationPatient")?;
    let origin = (0..3).fold(grid.origin, |o, i| {
        if orientation.flipped[i] { o + grid.directions[i] * (file_dims[i] as f64 - 1.0) } else { o }
    });
    let data = orientation.reorder(file_dims, data);
    let name = if header.description.is_empty() {
        path.file_stem().map_or_else(|| "segmentation".to_string(), |s| s.to_string_lossy().into_owned())
    } else {
        super::one_line(&header.description)
    };
    let mut volume = Volume::new(name, orientation.world_dims(file_dims), spacing, data);
    volume.fit_range_to_data();
    volume.meta = VolumeMeta {
        modality: Some("SEG".to_string()),
        units: None,
        window: None,
        frame: WorldFrame::Lps,
        origin: Some(origin),
        description: (!header.description.is_empty()).then(|| header.description.clone()),
        frame_of_reference: (!header.frame_of_reference.is_empty()).then(|| header.frame_of_reference.clone()),
    };
    let mut report = LoadReport::new(VolumeFormat::Dicom, path);
    notes.push(format!(
        "a DICOM segmentation: {} segment(s) ({}) as a label map of {} frame(s) on {} slice(s)",
        segments.len(),
        segments.iter().take(6).map(|s| format!("{} {}", s.number, s.name)).collect::<Vec<_>>().join(", ")
            + if segments.len() > 6 { ", …" } else { "" },
        frames,
        grid.slices
    ));
    report.notes = notes;
    Ok(LoadedVolume { volume, report })
}

/// The segment number of each frame (0 for a LABELMAP, whose pixels carry it).
fn frame_segments(
    path: &Path,
    object: &DefaultDicomObject,
    kind: Kind,
    frames: usize,
    segments: &[Segment],
) -> Result<Vec<u16>, LoadError> {
    if kind == Kind::Labelmap {
        return Ok(vec![0; frames]);
    }
    let per_frame = object.get(tags::PER_FRAME_FUNCTIONAL_GROUPS_SEQUENCE).and_then(|e| e.items()).unwrap_or_default();
    let shared = object.get(tags::SHARED_FUNCTIONAL_GROUPS_SEQUENCE).and_then(|e| e.items()).unwrap_or_default();
    let referenced = |items: &[InMemDicomObject], i: usize| {
        items
            .get(i)?
            .get(tags::SEGMENT_IDENTIFICATION_SEQUENCE)?
            .items()?
            .first()
            .and_then(|s| item_number(s, tags::REFERENCED_SEGMENT_NUMBER))
    };
    (0..frames)
        .map(|f| {
            let number = referenced(per_frame, f).or_else(|| referenced(shared, 0)).ok_or_else(|| {
                pixels_error(
                    path,
                    format!(
                        "frame {} names no segment (no ReferencedSegmentNumber {} in its SegmentIdentificationSequence); \
                         the file is corrupt",
                        f + 1,
                        tags::REFERENCED_SEGMENT_NUMBER
                    ),
                )
            })?;
            if !segments.iter().any(|s| s.number == number) {
                return Err(pixels_error(
                    path,
                    format!(
                        "frame {} is of segment {number}, which SegmentSequence does not list (it lists {}); the file \
                         is corrupt",
                        f + 1,
                        segments.iter().map(|s| s.number.to_string()).collect::<Vec<_>>().join(", ")
                    ),
                ));
            }
            Ok(number as u16)
        })
        .collect()
}

/// The grid the frames lie on: each frame's slice, the step per file axis, the first voxel.
struct Grid {
    slot: Vec<usize>,
    slices: usize,
    directions: [DVec3; 3],
    origin: DVec3,
}

impl Grid {
    fn of(path: &Path, header: &FileHeader, object: &DefaultDicomObject) -> Result<Self, LoadError> {
        let geometry =
            |message: String| LoadError::DicomGeometry { series: format!("segmentation {}", path.display()), message };
        let first = &header.frame_geometry[0];
        let o = first.orientation.ok_or_else(|| {
            geometry(format!(
                "has no ImageOrientationPatient {} (in the shared PlaneOrientationSequence): the frames cannot be placed",
                tags::IMAGE_ORIENTATION_PATIENT
            ))
        })?;
        let [row_spacing, column_spacing] = first.pixel_spacing.ok_or_else(|| {
            geometry(format!(
                "has no PixelSpacing {} (in the shared PixelMeasuresSequence): the frames cannot be placed",
                tags::PIXEL_SPACING
            ))
        })?;
        let (row, column) = (DVec3::new(o[0], o[1], o[2]), DVec3::new(o[3], o[4], o[5]));
        let normal = row.cross(column);
        if !((row.length() - 1.0).abs() < 1e-2 && (column.length() - 1.0).abs() < 1e-2 && row.dot(column).abs() < 1e-2)
        {
            return Err(geometry(format!(
                "ImageOrientationPatient {} is not two perpendicular unit vectors; the file is corrupt",
                tags::IMAGE_ORIENTATION_PATIENT
            )));
        }
        let (row, column, normal) = (row.normalize(), column.normalize(), normal.normalize());
        let mut positions = Vec::with_capacity(header.frame_geometry.len());
        for (f, g) in header.frame_geometry.iter().enumerate() {
            if g.orientation.is_some_and(|go| go.iter().zip(&o).any(|(a, b)| (a - b).abs() > 1e-4)) {
                return Err(geometry(format!("frame {} has another ImageOrientationPatient than frame 1", f + 1)));
            }
            match g.position {
                Some(p) if p.is_finite() && p.abs().max_element() < 1e9 => positions.push(p),
                _ => {
                    return Err(geometry(format!(
                        "frame {} has no ImagePositionPatient {} (in its PlanePositionSequence): it cannot be placed; \
                         the file is corrupt",
                        f + 1,
                        tags::IMAGE_POSITION_PATIENT
                    )));
                }
            }
        }
        let along: Vec<f64> = positions.iter().map(|p| p.dot(normal)).collect();
        let lowest = (0..along.len()).min_by(|&a, &b| along[a].total_cmp(&along[b])).unwrap_or(0);
        let (low, high) = (along[lowest], along.iter().copied().fold(f64::NEG_INFINITY, f64::max));
        // In-plane, every frame starts where the lowest does (no shear).
        for (f, p) in positions.iter().enumerate() {
            let offset = *p - positions[lowest];
            let lateral = offset - normal * offset.dot(normal);
            if lateral.length() > 0.01 * row_spacing.min(column_spacing) {
                return Err(geometry(format!(
                    "frame {} is shifted {:.3} mm sideways from frame {}: the frames are not stacked along their \
                     normal; volgraph renders axis-aligned grids",
                    f + 1,
                    lateral.length(),
                    lowest + 1
                )));
            }
        }
        // The step between planes: SpacingBetweenSlices of the shared pixel measures, else the
        // smallest step between the frames' planes, else the slice thickness.
        let measures = object
            .get(tags::SHARED_FUNCTIONAL_GROUPS_SEQUENCE)
            .and_then(|e| e.items())
            .and_then(|s| s.first())
            .and_then(|s| s.get(tags::PIXEL_MEASURES_SEQUENCE))
            .and_then(|e| e.items())
            .and_then(|m| m.first());
        let declared = measures
            .and_then(|m| item_numbers(m, tags::SPACING_BETWEEN_SLICES))
            .and_then(|v| v.first().copied())
            .or(header.spacing_between_slices)
            .filter(|s| s.is_finite() && *s > 0.0);
        let mut planes = along.clone();
        planes.sort_by(f64::total_cmp);
        planes.dedup_by(|a, b| (*a - *b).abs() < SAME_PLANE_MM);
        let smallest = planes.windows(2).map(|w| w[1] - w[0]).fold(f64::INFINITY, f64::min);
        let step = declared
            .or((smallest.is_finite()).then_some(smallest))
            .or(header.slice_thickness.filter(|t| t.is_finite() && *t > 0.0))
            .unwrap_or(row_spacing.min(column_spacing));
        let span = (high - low) / step;
        if !(span.is_finite() && span < MAX_SLICES) {
            return Err(geometry(format!(
                "its frames' planes span {:.3} mm at a step of {step:.3} mm: more than {MAX_SLICES} slices; \
                 SpacingBetweenSlices or a frame's position is wrong",
                high - low
            )));
        }
        let mut slot = Vec::with_capacity(along.len());
        for (f, d) in along.iter().enumerate() {
            let k = (d - low) / step;
            if (k - k.round()).abs() > 0.05 {
                return Err(geometry(format!(
                    "frame {} lies {:.3} mm along the normal, between the planes of a {step:.3} mm grid starting at \
                     {low:.3} mm; the frames are not on one grid",
                    f + 1,
                    d
                )));
            }
            slot.push(k.round() as usize);
        }
        let slices = span.round() as usize + 1;
        // The lowest plane's first pixel.
        let origin = positions[lowest];
        Ok(Grid { slot, slices, directions: [row * column_spacing, column * row_spacing, normal * step], origin })
    }
}
