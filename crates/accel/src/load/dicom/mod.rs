//! DICOM series: a folder of slices (searched recursively), one multi-frame file, or a list of
//! files, read with dicom-rs (`dicom-object`, `dicom-pixeldata`). Slices are grouped by
//! SeriesInstanceUID; several series are an error listing them unless
//! [`DicomOptions::series`] picks one. Geometry ([`geometry`]): slices sorted by
//! ImagePositionPatient along the normal, flips and axis swaps honoured in the LPS patient
//! frame, oblique stacks rejected. Values: RescaleSlope/Intercept applied (CT in HU), kept as
//! int16/uint16/uint8 where the rescaled values are integers that fit, float32 otherwise.

mod checks;
mod geometry;
mod header;
mod lengths;
mod pixels;
pub mod seg;
mod write;

pub use write::{write_ct_series, write_segmentation};

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use self::header::{FileHeader, Probe};
use super::{AxisOrientation, LoadError, LoadReport, LoadedVolume, Location, VolumeFormat};
use crate::volume::Volume;
use crate::volume_meta::{VolumeMeta, Window, WorldFrame};

/// Progress of a long load: `(done, total)` files; called from worker threads.
pub type Progress<'a> = &'a (dyn Fn(usize, usize) + Sync);

/// Which series to load when a folder holds several.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DicomOptions {
    /// `N` (the position in the listing, from 1), a SeriesInstanceUID, or a SeriesDescription.
    pub series: Option<String>,
}

/// One series found, as listed in errors and by `volgraph info`.
#[derive(Clone, Debug, PartialEq)]
pub struct SeriesSummary {
    /// SeriesInstanceUID.
    pub uid: String,
    /// SeriesNumber.
    pub number: Option<i64>,
    /// SeriesDescription.
    pub description: String,
    /// Modality.
    pub modality: String,
    /// Slices (frames) in the series.
    pub slices: usize,
    /// Columns × rows of the first slice.
    pub size: (u32, u32),
}

impl SeriesSummary {
    fn line(&self, position: usize) -> String {
        let description = if self.description.is_empty() {
            "(no description)".to_string()
        } else {
            format!("\"{}\"", one_line(&self.description))
        };
        format!(
            "  {position}. series {} {description} {}: {} slice(s) of {}x{} (UID {})",
            self.number.map_or("-".to_string(), |n| n.to_string()),
            one_line(&self.modality),
            self.slices,
            self.size.0,
            self.size.1,
            one_line(&self.uid)
        )
    }
}

/// `text` from a file's header made safe to show on one line: every control character (a
/// newline or CR that would forge a line of output, ESC, BEL, tab) and every bidirectional
/// override written as a visible escape (`\n`, `\u{1b}`, `\u{202e}`). The app's terminal escaping
/// (volgraph-compiler's `terminal`, which this crate cannot depend on: the compiler depends on
/// it) keeps newlines, as its messages have lines; a header string never does.
pub fn one_line(text: &str) -> String {
    let unsafe_char = |c: char| c.is_control() || matches!(c, '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}');
    text.chars().fold(String::with_capacity(text.len()), |mut out, c| {
        if unsafe_char(c) {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
        out
    })
}

/// The lines listing `series`, one per series.
pub fn series_list(series: &[SeriesSummary]) -> String {
    series.iter().enumerate().map(|(i, s)| s.line(i + 1)).collect::<Vec<_>>().join("\n")
}

/// True when `paths` should be read as DICOM: a directory, or files ending in `.dcm`/`.dicom`/
/// `.ima`, or without an extension (scanners often write bare numbers), holding the DICM magic.
pub fn is_dicom_input(paths: &[PathBuf]) -> bool {
    paths.iter().all(|p| {
        p.is_dir() || {
            let ext = p.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
            matches!(ext.as_deref(), Some("dcm" | "dicom" | "ima")) || (ext.is_none() && header::looks_like_dicom(p))
        }
    })
}

/// Every file under `paths` (folders searched recursively, in name order). Links are followed,
/// but each real folder is read once and each real file taken once (by canonical path): a link
/// to `.` or to a parent neither loops nor doubles the slices, and a file reached through two
/// links is one file.
fn collect_files(paths: &[PathBuf]) -> Result<Vec<PathBuf>, LoadError> {
    use std::collections::HashSet;
    let real = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    struct Walk {
        folders: HashSet<PathBuf>,
        files: HashSet<PathBuf>,
        out: Vec<PathBuf>,
    }
    fn walk(dir: &Path, w: &mut Walk, real: &dyn Fn(&Path) -> PathBuf) -> Result<(), LoadError> {
        if !w.folders.insert(real(dir)) {
            return Ok(());
        }
        let entries = std::fs::read_dir(dir).map_err(|source| LoadError::Io { path: dir.to_path_buf(), source })?;
        let mut paths: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
        paths.sort();
        for p in paths {
            if p.is_dir() {
                walk(&p, w, real)?;
            } else if p.is_file() && w.files.insert(real(&p)) {
                w.out.push(p);
            }
        }
        Ok(())
    }
    let mut w = Walk { folders: HashSet::new(), files: HashSet::new(), out: Vec::new() };
    for p in paths {
        if p.is_dir() {
            walk(p, &mut w, &real)?;
        } else if w.files.insert(real(p)) {
            w.out.push(p.clone());
        }
    }
    Ok(w.out)
}

/// The headers of the images among `paths`, grouped into series (in SeriesNumber, then UID,
/// order), with a note on what was skipped.
pub fn scan(paths: &[PathBuf]) -> Result<(Vec<Vec<FileHeader>>, Vec<String>), LoadError> {
    let files = collect_files(paths)?;
    let probes: Vec<Result<Probe, LoadError>> = files.par_iter().map(|f| header::probe(f)).collect();
    let (mut images, mut not_dicom, mut dicomdirs, mut no_image) = (Vec::new(), 0usize, 0usize, Vec::new());
    for (probe, file) in probes.into_iter().zip(&files) {
        match probe? {
            Probe::NotDicom => not_dicom += 1,
            Probe::Dicomdir => dicomdirs += 1,
            Probe::NoImage => no_image.push(file),
            Probe::Image(h) => images.push(*h),
        }
    }
    let place = paths.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ");
    if let (true, Some(first)) = (images.is_empty(), no_image.first()) {
        return Err(LoadError::DicomPixels {
            path: first.to_path_buf(),
            message: format!(
                "is a DICOM object without an image (no Rows or Columns: a report, plan, structure set or \
                 waveform){}; give the folder or files of the image slices",
                if no_image.len() > 1 {
                    format!(", as are {} other file(s) here", no_image.len() - 1)
                } else {
                    String::new()
                }
            ),
        });
    }
    if images.is_empty() {
        let what = if paths.len() == 1 && paths[0].is_dir() { "is a folder with" } else { "holds" };
        return Err(LoadError::NoDicomImages { place, what, files: files.len(), not_dicom, dicomdirs });
    }
    let mut notes = Vec::new();
    if not_dicom > 0 {
        notes.push(format!("skipped {not_dicom} file(s) that are not DICOM"));
    }
    if !no_image.is_empty() {
        notes.push(format!(
            "skipped {} DICOM file(s) without an image (no Rows or Columns: reports, presentation states)",
            no_image.len()
        ));
    }
    if dicomdirs > 0 {
        notes.push(format!("skipped {dicomdirs} DICOMDIR index file(s); the images were read from the folder itself"));
    }
    let mut groups: Vec<Vec<FileHeader>> = Vec::new();
    for h in images {
        match groups.iter_mut().find(|g| g[0].series_uid == h.series_uid) {
            Some(g) => g.push(h),
            None => groups.push(vec![h]),
        }
    }
    groups.sort_by(|a, b| (a[0].series_number, &a[0].series_uid).cmp(&(b[0].series_number, &b[0].series_uid)));
    Ok((groups, notes))
}

/// A summary of each series in `groups`.
pub fn summaries(groups: &[Vec<FileHeader>]) -> Vec<SeriesSummary> {
    groups
        .iter()
        .map(|g| {
            let first = &g[0];
            let geometry = &first.frame_geometry[0];
            SeriesSummary {
                uid: first.series_uid.clone(),
                number: first.series_number,
                description: first.description.clone(),
                modality: first.modality.clone(),
                slices: g.iter().map(|h| h.frame_geometry.len()).sum(),
                size: (geometry.columns, geometry.rows),
            }
        })
        .collect()
}

/// Lists the series under `paths` (what `volgraph info DIR` shows).
pub fn list_series(paths: &[PathBuf]) -> Result<Vec<SeriesSummary>, LoadError> {
    Ok(summaries(&scan(paths)?.0))
}

/// Picks the series `wanted` names (position from 1, UID or description), or the only one.
fn choose(place: &str, groups: Vec<Vec<FileHeader>>, wanted: Option<&str>) -> Result<Vec<FileHeader>, LoadError> {
    let list = series_list(&summaries(&groups));
    let Some(wanted) = wanted else {
        if groups.len() == 1 {
            return Ok(groups.into_iter().next().unwrap_or_default());
        }
        return Err(LoadError::SeveralSeries { place: place.to_string(), count: groups.len(), list });
    };
    let index = match wanted.parse::<usize>() {
        Ok(n) if (1..=groups.len()).contains(&n) => Some(n - 1),
        _ => match groups.iter().position(|g| g[0].series_uid == wanted) {
            Some(i) => Some(i),
            None => by_description(place, &groups, wanted)?,
        },
    };
    match index {
        Some(i) => Ok(groups.into_iter().nth(i).unwrap_or_default()),
        None => Err(LoadError::NoSuchSeries { place: place.to_string(), wanted: one_line(wanted), list }),
    }
}

/// The series whose description is `wanted`: the one spelled exactly so, else the one equal
/// ignoring case; two series that match equally well are an error listing them.
fn by_description(place: &str, groups: &[Vec<FileHeader>], wanted: &str) -> Result<Option<usize>, LoadError> {
    let matching = |same: &dyn Fn(&str) -> bool| -> Vec<usize> {
        groups.iter().enumerate().filter(|(_, g)| same(&g[0].description)).map(|(i, _)| i).collect()
    };
    let exact = matching(&|d| d == wanted);
    let candidates = if exact.is_empty() { matching(&|d| d.eq_ignore_ascii_case(wanted)) } else { exact };
    match candidates.as_slice() {
        [] => Ok(None),
        [only] => Ok(Some(*only)),
        several => {
            let all = summaries(groups);
            let list = several.iter().map(|&i| all[i].line(i + 1)).collect::<Vec<_>>().join("\n");
            Err(LoadError::DicomGeometry {
                series: format!("series \"{}\"", one_line(wanted)),
                message: format!(
                    "{} series under {place} have this description; choose one with --series N or --series UID:\n{list}",
                    several.len()
                ),
            })
        }
    }
}

/// Loads one DICOM series from `paths` (folders, files). `progress` hears of each slice file
/// read.
pub fn load(
    paths: &[PathBuf],
    options: &DicomOptions,
    progress: Option<Progress<'_>>,
) -> Result<LoadedVolume, LoadError> {
    let (series, notes) = pick_series(paths, options.series.as_deref())?;
    if seg::is_segmentation(&series[0]) {
        return seg::load(&series[0], notes);
    }
    let Stacked { series, ordered, stack, file_dims, mut notes } = stack_picked(series, notes)?;
    notes.extend(stack.notes.iter().cloned());
    let first = series[0].clone();
    let (voxels, pixel_notes) = pixels::read(&series, &ordered, file_dims, progress)?;
    notes.extend(pixel_notes);

    let at = Location::file(&first.path);
    let (orientation, spacing) = AxisOrientation::from_directions(stack.directions, &at, "ImageOrientationPatient")?;
    let mut report = LoadReport::new(VolumeFormat::Dicom, &first.path);
    report.notes = notes;
    if !orientation.is_identity() {
        report.notes.push(format!(
            "voxels reordered to the LPS patient frame ({}): the series' orientation is honoured",
            orientation.describe()
        ));
    }
    // The corner of the box nearest −∞ on every world axis: voxel (0,0,0) after reordering.
    let origin = (0..3).fold(stack.origin, |o, i| {
        if orientation.flipped[i] { o + stack.directions[i] * (file_dims[i] as f64 - 1.0) } else { o }
    });
    let data = orientation.reorder(file_dims, voxels);
    let name = series_label(paths, &first);
    let mut volume = Volume::new(name, orientation.world_dims(file_dims), spacing, data);
    volume.fit_range_to_data();
    volume.meta = series_meta(&first, origin);
    Ok(LoadedVolume { volume, report })
}

/// What a series' first file says of the volume besides its voxels; `origin` is the centre of
/// voxel (0, 0, 0) in the patient frame.
fn series_meta(first: &FileHeader, origin: glam::DVec3) -> VolumeMeta {
    let units = match (first.modality.as_str(), first.rescale_type.as_deref()) {
        (_, Some(t)) if !t.eq_ignore_ascii_case("US") => Some(t.to_string()),
        ("CT", _) => Some("HU".to_string()),
        _ => None,
    };
    VolumeMeta {
        modality: (!first.modality.is_empty()).then(|| first.modality.clone()),
        units,
        window: first.window.map(|(center, width)| Window { center, width }),
        frame: WorldFrame::Lps,
        origin: Some(origin),
        description: (!first.description.is_empty()).then(|| first.description.clone()),
        frame_of_reference: (!first.frame_of_reference.is_empty()).then(|| first.frame_of_reference.clone()),
    }
}

/// A series' frames in stack order.
struct Stacked {
    series: Vec<FileHeader>,
    /// (file, frame) per slice, in increasing position along the slice normal.
    ordered: Vec<(usize, usize)>,
    stack: geometry::Stack,
    /// Columns, rows, slices.
    file_dims: glam::UVec3,
    notes: Vec<String>,
}

/// Scans `paths` and picks the series (`wanted`, or the only one), with the scan's notes.
fn pick_series(paths: &[PathBuf], wanted: Option<&str>) -> Result<(Vec<FileHeader>, Vec<String>), LoadError> {
    let place = paths.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ");
    let (groups, notes) = scan(paths)?;
    Ok((choose(&place, groups, wanted)?, notes))
}

/// Checks the pixels of `series` can be read and orders its frames along the slice normal.
fn stack_picked(series: Vec<FileHeader>, mut notes: Vec<String>) -> Result<Stacked, LoadError> {
    let first = series[0].clone();
    let series_name = if first.description.is_empty() {
        format!("series {}", first.series_number.map_or(first.series_uid.clone(), |n| n.to_string()))
    } else {
        format!("series \"{}\"", one_line(&first.description))
    };
    for h in &series {
        if h.samples_per_pixel != 1 {
            return Err(LoadError::DicomPixels {
                path: h.path.clone(),
                message: format!(
                    "has {} samples per pixel (a colour image); volgraph renders scalar volumes: use a greyscale \
                     series (SamplesPerPixel 1)",
                    h.samples_per_pixel
                ),
            });
        }
        if h.photometric.eq_ignore_ascii_case("PALETTE COLOR") {
            return Err(LoadError::DicomPixels {
                path: h.path.clone(),
                message:
                    "PhotometricInterpretation (0028,0004) is PALETTE COLOR: its pixels are indices into a colour \
                          table, not measured values; volgraph renders scalar volumes: use a greyscale series \
                          (MONOCHROME1 or MONOCHROME2), or convert the images to greyscale first"
                        .to_string(),
            });
        }
        pixels::check_transfer_syntax(&h.path, &h.transfer_syntax)?;
    }
    // Every frame of every file, with where its pixels come from.
    let mut slices = Vec::new();
    let mut sources = Vec::new();
    for (file, h) in series.iter().enumerate() {
        for (frame, g) in h.frame_geometry.iter().enumerate() {
            slices.push(g.clone());
            sources.push((file, frame));
        }
    }
    // One image alone needs no position to be ordered by: it is placed at the origin.
    if let [only] = slices.as_mut_slice()
        && only.position.is_none()
    {
        only.position = Some(glam::DVec3::ZERO);
        notes.push("the image has no ImagePositionPatient; placed at the origin".to_string());
    }
    let stack = geometry::stack(&series_name, &slices, first.slice_thickness.or(first.spacing_between_slices))?;
    let ordered: Vec<(usize, usize)> = stack.order.iter().map(|&i| sources[i]).collect();
    let (rows, columns) = (first.frame_geometry[0].rows, first.frame_geometry[0].columns);
    let file_dims = glam::UVec3::new(columns, rows, ordered.len() as u32);
    Ok(Stacked { series, ordered, stack, file_dims, notes })
}

/// One DICOM series whose slices can be read a z-range at a time (sort-last rendering,
/// `load::VolumeHeader`): only the files holding those slices are opened.
#[derive(Clone, Debug)]
pub struct SeriesSlices {
    series: Vec<FileHeader>,
    ordered: Vec<(usize, usize)>,
    /// Voxels per axis (columns, rows, slices).
    pub dims: glam::UVec3,
    /// Voxel spacing (mm).
    pub spacing: glam::DVec3,
    /// The series' name.
    pub name: String,
    /// True when every file stores 8 bits per pixel (the whole volume normalizes over 0..=255
    /// then, as [`load`] gives it).
    pub eight_bit: bool,
    /// Modality, units (HU for CT), window and origin, as [`load`] gives them.
    pub meta: VolumeMeta,
}

impl SeriesSlices {
    /// The series in `paths` (`wanted`, or the only one; its slices along the patient axes).
    pub fn open(paths: &[PathBuf], wanted: Option<&str>) -> Result<Self, LoadError> {
        let (series, notes) = pick_series(paths, wanted)?;
        if seg::is_segmentation(&series[0]) {
            return Err(LoadError::NoBoxRead { path: series[0].path.clone(), format: "DICOM segmentation" });
        }
        let Stacked { series, ordered, stack, file_dims, .. } = stack_picked(series, notes)?;
        let first = &series[0];
        let at = Location::file(&first.path);
        let (orientation, spacing) =
            AxisOrientation::from_directions(stack.directions, &at, "ImageOrientationPatient")?;
        if !orientation.is_identity() {
            return Err(LoadError::NoBoxRead {
                path: first.path.clone(),
                format: "DICOM series with flipped or swapped axes",
            });
        }
        let name = series_label(paths, first);
        let eight_bit = series.iter().all(|h| h.bits_allocated == 8 && h.rescale == (1.0, 0.0));
        // The axes are the world's (checked above), so voxel (0, 0, 0) is the stack's origin.
        let meta = series_meta(first, stack.origin);
        Ok(Self { series, ordered, dims: file_dims, spacing, name, eight_bit, meta })
    }

    /// The rescaled values of slices `z` (whole slices, x fastest), reading only their files.
    pub fn read_slices(&self, z: std::ops::Range<u32>) -> Result<Vec<f32>, LoadError> {
        let wanted = &self.ordered[z.start as usize..z.end as usize];
        let mut files: Vec<usize> = wanted.iter().map(|&(f, _)| f).collect();
        files.sort_unstable();
        files.dedup();
        let subset: Vec<FileHeader> = files.iter().map(|&f| self.series[f].clone()).collect();
        let reindexed: Vec<(usize, usize)> =
            wanted.iter().map(|&(f, frame)| (files.binary_search(&f).unwrap_or(0), frame)).collect();
        let dims = glam::UVec3::new(self.dims.x, self.dims.y, wanted.len() as u32);
        let (voxels, _) = pixels::read(&subset, &reindexed, dims, None)?;
        Ok(match voxels {
            crate::volume::VoxelData::U8(v) => v.into_iter().map(f32::from).collect(),
            crate::volume::VoxelData::U16(v) => v.into_iter().map(f32::from).collect(),
            crate::volume::VoxelData::I16(v) => v.into_iter().map(f32::from).collect(),
            crate::volume::VoxelData::F32(v) => v,
        })
    }
}

/// The volume's name: the series' description on one line (it is shown in notes and titles;
/// the raw text stays in `VolumeMeta::description`), else the folder's or file's name.
fn series_label(paths: &[PathBuf], first: &FileHeader) -> String {
    if first.description.is_empty() { dicom_name(paths) } else { one_line(&first.description) }
}

/// A name for a series without a description: the folder's (or first file's) name.
fn dicom_name(paths: &[PathBuf]) -> String {
    paths
        .first()
        .and_then(|p| p.file_stem().or_else(|| p.file_name()))
        .map_or_else(|| "dicom".to_string(), |s| s.to_string_lossy().into_owned())
}
