//! Volume loading: headerless `.raw` (layout from the file name or [`RawOptions`]), NRRD
//! (`.nrrd` attached, `.nhdr` detached; raw or gzip encoding), MetaImage (`.mhd` detached,
//! `.mha` with `ElementDataFile = LOCAL`; optionally zlib-compressed), NIfTI-1/2 (`.nii`,
//! `.nii.gz`) and DICOM series (a folder of slices, a multi-frame file, a list of files).
//!
//! [`load_volumes`] is the one entry point ([`load_volume`] for one file with raw options); it
//! picks the format from the extension, or DICOM for folders and `.dcm` files. Scanner formats
//! put the box in the LPS patient frame and fill [`crate::volume_meta::VolumeMeta`]. Every loader
//! returns the volume in native byte order with `value_range` set as [`Volume::new`] documents,
//! and a [`LoadReport`] saying what was repaired:
//!
//! - float32 NaN values are replaced by the minimum finite value of the volume (so they normalize
//!   to 0 and never widen the range), `+Inf` by the maximum finite value and `-Inf` by the
//!   minimum; a volume with no finite value at all becomes all zeros with range (0, 0).
//!
//! - the spacing (the header's, or [`RawOptions::spacing`] where set) must be finite, positive
//!   and within [`MAX_SPACING_RATIO`] in every format; a constant volume gets its one value as
//!   its range (16-bit data) and a note.
//!
//! Parsers never panic on any input (`tests/load_fuzz.rs` and, for NIfTI, `tests/nifti_fuzz.rs`
//! check it with proptest).

pub mod dicom;
mod error;
mod metaimage;
pub mod nifti;
mod nrrd;
mod orientation;
mod raw;
mod region;

use std::io::Read;
use std::path::{Path, PathBuf};

use glam::{DVec3, UVec3};

pub use error::{LoadError, Location};
pub use orientation::AxisOrientation;
pub use raw::parse_raw_name;
pub use region::{RawBoxes, VolumeHeader};

use crate::volume::{Volume, VoxelData, VoxelType, finite_range};

/// Byte order of multi-byte voxels in a file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Endianness {
    /// Least significant byte first (x86, ARM; what almost every file uses).
    #[default]
    Little,
    /// Most significant byte first.
    Big,
}

/// How to read a headerless `.raw` file. Set fields override what the file name says
/// (`name_XxYxZ_dtype.raw`). For headered formats only `spacing` is used: when set it overrides
/// the header's spacing.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RawOptions {
    /// Voxels per axis.
    pub dims: Option<UVec3>,
    /// Voxel type.
    pub dtype: Option<VoxelType>,
    /// Byte order of 16- and 32-bit voxels (raw files only; default little endian).
    pub endianness: Endianness,
    /// Physical voxel size; default (1, 1, 1) for raw files, the header's value otherwise.
    pub spacing: Option<DVec3>,
}

/// The file format a volume came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VolumeFormat {
    /// Headerless `.raw`.
    Raw,
    /// NRRD, attached (`.nrrd`) or detached (`.nhdr`).
    Nrrd,
    /// MetaImage, `.mhd` or `.mha`.
    MetaImage,
    /// NIfTI-1 or NIfTI-2, `.nii` or `.nii.gz`.
    Nifti,
    /// A DICOM series.
    Dicom,
}

/// Everything that says how to read a volume: raw layout, the DICOM series, the NIfTI frame,
/// and who hears of progress.
#[derive(Clone, Default)]
pub struct LoadOptions<'a> {
    /// Layout of headerless raw files; `spacing` overrides any header.
    pub raw: RawOptions,
    /// The series to read from a folder holding several (`N`, UID or description).
    pub series: Option<String>,
    /// The volume of a 4D NIfTI file.
    pub frame: Option<u64>,
    /// Told `(done, total)` as a DICOM series' files are read.
    pub progress: Option<dicom::Progress<'a>>,
}

impl std::fmt::Debug for LoadOptions<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LoadOptions")
            .field("raw", &self.raw)
            .field("series", &self.series)
            .field("frame", &self.frame)
            .field("progress", &self.progress.is_some())
            .finish()
    }
}

/// True when `path` names a NIfTI file (`.nii`, `.nii.gz`, any case).
pub fn is_nifti(path: &Path) -> bool {
    let name = path.file_name().map(|n| n.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    name.ends_with(".nii") || name.ends_with(".nii.gz")
}

/// Loads the volume at `paths`: one volume file, or DICOM (folders, `.dcm` files, a list of
/// slice files). See [`LoadOptions`].
pub fn load_volumes(paths: &[PathBuf], options: &LoadOptions<'_>) -> Result<LoadedVolume, LoadError> {
    let first = paths.first().cloned().unwrap_or_default();
    let mut loaded = if dicom::is_dicom_input(paths) && !paths.is_empty() {
        if options.frame.is_some() {
            return Err(LoadError::OptionDoesNotApply {
                path: first,
                option: "--frame",
                reason: "picks a volume of a 4D NIfTI file; a DICOM series is chosen with --series",
            });
        }
        check_no_raw_layout(&first, &options.raw)?;
        dicom::load(paths, &dicom::DicomOptions { series: options.series.clone() }, options.progress)?
    } else if paths.len() > 1 {
        return Err(LoadError::NotAFile {
            path: paths[1].clone(),
            what: "a second volume file (only DICOM slices come as a list)",
        });
    } else {
        if options.series.is_some() {
            return Err(LoadError::OptionDoesNotApply {
                path: first,
                option: "--series",
                reason: "picks a series of DICOM slices, but this is not DICOM",
            });
        }
        if is_nifti(&first) {
            if first.exists() {
                check_is_file(&first)?;
            }
            check_no_raw_layout(&first, &options.raw)?;
            nifti::load(&first, options.frame)?
        } else {
            if options.frame.is_some() {
                return Err(LoadError::OptionDoesNotApply {
                    path: first,
                    option: "--frame",
                    reason: "picks a volume of a 4D NIfTI file, but this is not NIfTI",
                });
            }
            load_file(&first, &options.raw)?
        }
    };
    finish_loaded(&first, options.raw.spacing, &mut loaded)?;
    Ok(loaded)
}

/// A volume handed over in memory (an array from Python, `volgraph_app::api`) read as a raw file
/// of the same voxels is: its size checked against `dims`, non-finite floats replaced, then what
/// every loaded volume passes ([`finish_loaded`]: the spacing checked, a constant volume's range
/// and note). `name` stands for the file in messages.
pub fn from_memory(name: &str, dims: UVec3, spacing: DVec3, data: VoxelData) -> Result<LoadedVolume, LoadError> {
    let path = PathBuf::from(name);
    let expected = dims.x as u64 * dims.y as u64 * dims.z as u64;
    if expected == 0 || data.len() as u64 != expected {
        return Err(LoadError::NotAFile {
            path,
            what: "an array whose voxel count is its dimensions' product, none of them 0",
        });
    }
    let mut volume = Volume::new(name, dims, spacing, data);
    let mut report = LoadReport::new(VolumeFormat::Raw, &path);
    (report.nan_replaced, report.pos_inf_replaced, report.neg_inf_replaced) = sanitize_volume(&mut volume);
    let mut loaded = LoadedVolume { volume, report };
    finish_loaded(&path, None, &mut loaded)?;
    Ok(loaded)
}

/// The largest ratio of the longest voxel side to the shortest: the box is scaled to its longest
/// side in f32, and beyond this the shortest side falls below f32's resolution and the volume
/// renders black. `--spacing` and every header's spacing are held to it.
pub const MAX_SPACING_RATIO: f64 = 1e4;

/// What every loaded volume passes through, whatever its format: `spacing` (`--spacing`),
/// checked, replaces the header's; a spacing whose sides differ by more than
/// [`MAX_SPACING_RATIO`] is refused; a constant volume gets its one value as its range (16-bit
/// data; 8-bit data keeps the type range its texture is normalized by) and a note.
fn finish_loaded(path: &Path, spacing: Option<DVec3>, loaded: &mut LoadedVolume) -> Result<(), LoadError> {
    loaded.volume.spacing = checked_spacing(path, spacing, loaded.volume.spacing)?;
    note_constant(loaded);
    Ok(())
}

/// The spacing a volume is drawn with: `option` (`--spacing`) where given, else the header's,
/// finite, positive and within [`MAX_SPACING_RATIO`]. [`region::VolumeHeader::read`] holds a
/// box read's header to it too.
fn checked_spacing(path: &Path, option: Option<DVec3>, header: DVec3) -> Result<DVec3, LoadError> {
    let at = Location::file(path);
    let (spacing, what) = match option {
        Some(s) => (s, "--spacing"),
        None => (header, "the header's voxel spacing"),
    };
    check_spacing(&at, spacing)?;
    let ratio = spacing.max_element() / spacing.min_element();
    if ratio > MAX_SPACING_RATIO {
        return Err(LoadError::SpacingRatio { at, what, x: spacing.x, y: spacing.y, z: spacing.z, ratio });
    }
    Ok(spacing)
}

/// A constant volume: its range is its value (as a constant float volume's is), with a note.
fn note_constant(loaded: &mut LoadedVolume) {
    let volume = &mut loaded.volume;
    if volume.voxel_count() == 0 {
        return;
    }
    let (lo, hi) = volume.data_min_max();
    if lo != hi {
        return;
    }
    if matches!(volume.data, VoxelData::U16(_) | VoxelData::I16(_)) {
        volume.value_range = (lo, lo);
    }
    loaded.report.notes.push(format!(
        "every voxel holds the value {lo}: the volume is constant, so a transfer function shows it as an empty or a \
         uniform box"
    ));
}

/// Raw layout options on a file with a header are an error.
fn check_no_raw_layout(path: &Path, opts: &RawOptions) -> Result<(), LoadError> {
    let mut given = Vec::new();
    if opts.dims.is_some() {
        given.push("--dims");
    }
    if opts.dtype.is_some() {
        given.push("--dtype");
    }
    if opts.endianness != Endianness::Little {
        given.push("--big-endian");
    }
    if given.is_empty() {
        Ok(())
    } else {
        Err(LoadError::RawOptionsOnHeader { path: path.to_path_buf(), options: given.join(", ") })
    }
}

/// What a loader did besides reading: repairs and ignored header content.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadReport {
    /// The format read.
    pub format: VolumeFormat,
    /// The file the voxels came from (the header itself when attached).
    pub data_path: PathBuf,
    /// NaN voxels replaced by the minimum finite value.
    pub nan_replaced: usize,
    /// `+Inf` voxels replaced by the maximum finite value.
    pub pos_inf_replaced: usize,
    /// `-Inf` voxels replaced by the minimum finite value.
    pub neg_inf_replaced: usize,
    /// Header content that was ignored or defaulted, one sentence each.
    pub notes: Vec<String>,
}

impl LoadReport {
    fn new(format: VolumeFormat, data_path: &Path) -> LoadReport {
        LoadReport {
            format,
            data_path: data_path.to_path_buf(),
            nan_replaced: 0,
            pos_inf_replaced: 0,
            neg_inf_replaced: 0,
            notes: Vec::new(),
        }
    }

    /// Total number of non-finite voxels replaced.
    pub fn non_finite_replaced(&self) -> usize {
        self.nan_replaced + self.pos_inf_replaced + self.neg_inf_replaced
    }
}

/// A loaded volume and what the loader did to it.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedVolume {
    /// The volume, native byte order, NaN/Inf replaced.
    pub volume: Volume,
    /// Repairs and ignored header content.
    pub report: LoadReport,
}

/// Loads one volume file, choosing the format by extension (case-insensitive): `.raw`, `.nrrd`,
/// `.nhdr`, `.mhd`, `.mha`, `.nii`, `.nii.gz`. `opts` describes raw files; see [`RawOptions`].
/// A folder or a `.dcm` file is read as DICOM ([`load_volumes`] also takes a list of slices,
/// a series choice and a NIfTI frame).
pub fn load_volume(path: &Path, opts: &RawOptions) -> Result<LoadedVolume, LoadError> {
    load_volumes(&[path.to_path_buf()], &LoadOptions { raw: opts.clone(), ..LoadOptions::default() })
}

/// One volume file by extension (`opts.spacing` is applied by the caller).
fn load_file(path: &Path, opts: &RawOptions) -> Result<LoadedVolume, LoadError> {
    // A directory or FIFO is named as such before its (missing) extension is; a path that does
    // not exist gets the extension check first and the read error after.
    if path.exists() {
        check_is_file(path)?;
    }
    let extension = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    if matches!(extension.as_str(), "nrrd" | "nhdr" | "mhd" | "mha") || is_nifti(path) {
        check_no_raw_layout(path, opts)?;
    }
    match extension.as_str() {
        "raw" => raw::load(path, opts),
        "nrrd" | "nhdr" => nrrd::load(path),
        "mhd" | "mha" => metaimage::load(path),
        _ if is_nifti(path) => nifti::load(path, None),
        _ => Err(LoadError::UnknownFormat { path: path.to_path_buf(), extension }),
    }
}

/// Parses a NRRD header and data held in memory; `path` is used for messages and to find a
/// detached data file. Never panics.
pub fn parse_nrrd(path: &Path, bytes: &[u8]) -> Result<LoadedVolume, LoadError> {
    nrrd::parse(path, bytes)
}

/// Parses a MetaImage header (and `LOCAL` data) held in memory; `path` is used for messages and
/// to find a detached data file. Never panics.
pub fn parse_metaimage(path: &Path, bytes: &[u8]) -> Result<LoadedVolume, LoadError> {
    metaimage::parse(path, bytes)
}

/// Checks that every dimension of `volume` fits a 3D texture of at most `max_dim` texels per
/// side (`wgpu::Limits::max_texture_dimension_3d`). A volume that does not fit can still be
/// rendered in bricks.
pub fn check_texture_limit(volume: &Volume, max_dim: u32) -> Result<(), LoadError> {
    for (axis, size) in [("x", volume.dims.x), ("y", volume.dims.y), ("z", volume.dims.z)] {
        if size > max_dim {
            return Err(LoadError::TextureTooLarge { name: volume.name.clone(), axis, size, max_dim });
        }
    }
    Ok(())
}

/// Replaces NaN/Inf in float data as the module documentation says, sets `value_range` to the
/// finite (min, max), and returns the counts `(nan, +inf, -inf)`. Integer volumes are untouched
/// and give zeros.
pub fn sanitize_volume(volume: &mut Volume) -> (usize, usize, usize) {
    let VoxelData::F32(values) = &mut volume.data else {
        return (0, 0, 0);
    };
    let (lo, hi) = finite_range(values).unwrap_or((0.0, 0.0));
    let (mut nan, mut pos, mut neg) = (0, 0, 0);
    for v in values.iter_mut() {
        if v.is_nan() {
            *v = lo as f32;
            nan += 1;
        } else if *v == f32::INFINITY {
            *v = hi as f32;
            pos += 1;
        } else if *v == f32::NEG_INFINITY {
            *v = lo as f32;
            neg += 1;
        }
    }
    volume.value_range = (lo, hi);
    (nan, pos, neg)
}

/// Fails unless `path` is a regular file (or a link to one): a directory or a FIFO would
/// otherwise surface as a puzzling size error, or block.
/// Checks that `data_path` holds the voxels of `layout` from byte `offset` (a box read seeks
/// there), and that it is a regular file (a FIFO or device would block or never end).
fn check_data_extent(data_path: &Path, offset: u64, layout: &Layout, hint: &'static str) -> Result<(), LoadError> {
    check_is_file(data_path)?;
    let size =
        std::fs::metadata(data_path).map_err(|source| LoadError::Io { path: data_path.to_path_buf(), source })?.len();
    let expected = byte_count(layout.dims, layout.dtype).unwrap_or(u64::MAX);
    if size < offset.saturating_add(expected) {
        return Err(LoadError::DataSize {
            path: data_path.to_path_buf(),
            dims: dims_text(layout.dims),
            dtype: layout.dtype,
            expected,
            actual: size.saturating_sub(offset),
            hint,
        });
    }
    Ok(())
}

fn check_is_file(path: &Path) -> Result<(), LoadError> {
    match crate::input_file::special_kind(path) {
        Ok(None) => Ok(()),
        Ok(Some(what)) => Err(LoadError::NotAFile { path: path.to_path_buf(), what }),
        Err(source) => Err(LoadError::Io { path: path.to_path_buf(), source }),
    }
}

/// Reads a whole file, mapping the error to [`LoadError::Io`].
fn read_file(path: &Path) -> Result<Vec<u8>, LoadError> {
    check_is_file(path)?;
    std::fs::read(path).map_err(|source| LoadError::Io { path: path.to_path_buf(), source })
}

/// Reads the detached data file `name` that header line `at` names (`field`).
fn read_data_file(
    header: &Path,
    at: Location,
    field: &'static str,
    name: &str,
) -> Result<(PathBuf, Vec<u8>), LoadError> {
    let path = sibling(header, name);
    let as_data_file_error = |e: LoadError| match e {
        LoadError::Io { path, source } => {
            LoadError::DataFile { at: at.clone(), field, name: name.to_string(), path, source }
        }
        other => other,
    };
    let bytes = read_file(&path).map_err(as_data_file_error)?;
    Ok((path, bytes))
}

/// The checked dimensions of a header (`field = value` at `at`): no zero axis, each at most
/// `u32::MAX`.
fn check_dims(at: &Location, field: &str, value: &str, dims: [u64; 3]) -> Result<UVec3, LoadError> {
    let [x, y, z] = dims;
    if x == 0 || y == 0 || z == 0 {
        return Err(LoadError::ZeroDimension { at: at.clone(), x, y, z });
    }
    let fit = |n: u64| u32::try_from(n).ok();
    match (fit(x), fit(y), fit(z)) {
        (Some(x), Some(y), Some(z)) => Ok(UVec3::new(x, y, z)),
        _ => Err(LoadError::BadField {
            at: at.clone(),
            field: field.to_string(),
            value: error::clip(value),
            expected: "three sizes of at most 4294967295 voxels",
        }),
    }
}

fn check_spacing(at: &Location, s: DVec3) -> Result<(), LoadError> {
    if s.is_finite() && s.min_element() > 0.0 {
        Ok(())
    } else {
        Err(LoadError::BadSpacing { at: at.clone(), x: s.x, y: s.y, z: s.z })
    }
}

/// Bytes needed by `dims` voxels of `dtype`; `None` on overflow.
fn byte_count(dims: UVec3, dtype: VoxelType) -> Option<u64> {
    (dims.x as u64).checked_mul(dims.y as u64)?.checked_mul(dims.z as u64)?.checked_mul(dtype.size_bytes() as u64)
}

fn dims_text(dims: UVec3) -> String {
    format!("{}x{}x{}", dims.x, dims.y, dims.z)
}

/// Inflates gzip (`zlib = false`) or zlib data, reading at most `limit` bytes so that a header
/// claiming little data cannot make a small file expand without bound.
fn inflate(path: &Path, data: &[u8], zlib: bool, limit: u64) -> Result<Vec<u8>, LoadError> {
    let mut out = Vec::new();
    let result = if zlib {
        flate2::read::ZlibDecoder::new(data).take(limit).read_to_end(&mut out)
    } else {
        flate2::read::MultiGzDecoder::new(data).take(limit).read_to_end(&mut out)
    };
    result.map_err(|source| LoadError::Decompress {
        path: path.to_path_buf(),
        codec: if zlib { "zlib" } else { "gzip" },
        source,
    })?;
    Ok(out)
}

/// Decodes exactly `dims × dtype` bytes (the caller checked the length) into voxels.
fn decode(bytes: &[u8], dtype: VoxelType, order: Endianness) -> VoxelData {
    let big = order == Endianness::Big;
    match dtype {
        VoxelType::U8 => VoxelData::U8(bytes.to_vec()),
        VoxelType::U16 => VoxelData::U16(
            bytes
                .chunks_exact(2)
                .map(|c| {
                    let b = [c[0], c[1]];
                    if big { u16::from_be_bytes(b) } else { u16::from_le_bytes(b) }
                })
                .collect(),
        ),
        VoxelType::I16 => VoxelData::I16(
            bytes
                .chunks_exact(2)
                .map(|c| {
                    let b = [c[0], c[1]];
                    if big { i16::from_be_bytes(b) } else { i16::from_le_bytes(b) }
                })
                .collect(),
        ),
        VoxelType::F32 => VoxelData::F32(
            bytes
                .chunks_exact(4)
                .map(|c| {
                    let b = [c[0], c[1], c[2], c[3]];
                    if big { f32::from_be_bytes(b) } else { f32::from_le_bytes(b) }
                })
                .collect(),
        ),
    }
}

/// What every headered loader does once the header is parsed: check the data length, decode,
/// sanitize floats and build the volume and report.
struct Layout {
    name: String,
    /// Voxels per file axis.
    dims: UVec3,
    dtype: VoxelType,
    order: Endianness,
    /// Spacing along world x, y, z.
    spacing: DVec3,
    /// How file axes lie in the world (headers with direction vectors).
    orientation: AxisOrientation,
}

fn finish(
    layout: Layout,
    data: &[u8],
    data_path: &Path,
    mut report: LoadReport,
    hint: &'static str,
) -> Result<LoadedVolume, LoadError> {
    let expected = byte_count(layout.dims, layout.dtype).unwrap_or(u64::MAX);
    if data.len() as u64 != expected {
        return Err(LoadError::DataSize {
            path: data_path.to_path_buf(),
            dims: dims_text(layout.dims),
            dtype: layout.dtype,
            expected,
            actual: data.len() as u64,
            hint,
        });
    }
    let voxels = layout.orientation.reorder(layout.dims, decode(data, layout.dtype, layout.order));
    if !layout.orientation.is_identity() {
        report.notes.push(format!(
            "voxels reordered to world axes ({}): flips and axis swaps in the header are honoured",
            layout.orientation.describe()
        ));
    }
    let dims = layout.orientation.world_dims(layout.dims);
    let mut volume = Volume::new(layout.name, dims, layout.spacing, voxels);
    let (nan, pos, neg) = sanitize_volume(&mut volume);
    report.nan_replaced = nan;
    report.pos_inf_replaced = pos;
    report.neg_inf_replaced = neg;
    Ok(LoadedVolume { volume, report })
}

/// The file stem, used as the volume name.
fn stem(path: &Path) -> String {
    path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
}

/// Resolves a detached data file name relative to the header's folder.
fn sibling(header: &Path, name: &str) -> PathBuf {
    let name = Path::new(name);
    if name.is_absolute() { name.to_path_buf() } else { header.parent().unwrap_or(Path::new("")).join(name) }
}

/// The `key:=value` pairs of a NRRD header (free-form metadata: 3D Slicer writes a
/// segmentation's names and colours there), as `(line, key, value)`, from the header of the file
/// at `path` (its first 4 MiB at most; the header ends at the first empty line).
pub fn nrrd_key_values(path: &Path) -> Result<Vec<(usize, String, String)>, LoadError> {
    use std::io::Read as _;
    check_is_file(path)?;
    let file = std::fs::File::open(path).map_err(|source| LoadError::Io { path: path.to_path_buf(), source })?;
    let mut bytes = Vec::new();
    file.take(4 << 20).read_to_end(&mut bytes).map_err(|source| LoadError::Io { path: path.to_path_buf(), source })?;
    let mut pairs = Vec::new();
    for (number, text, _) in header_lines(&bytes) {
        if text.is_empty() {
            break;
        }
        if let Some((key, value)) = text.split_once(":=") {
            pairs.push((number, key.trim().to_string(), value.to_string()));
        }
    }
    Ok(pairs)
}

/// Splits `bytes` into header lines: `(1-based line number, text without the line end, byte
/// offset just past the line end)`. Lines are decoded lossily; the caller decides where the
/// header stops.
fn header_lines(bytes: &[u8]) -> impl Iterator<Item = (usize, String, usize)> + '_ {
    // A UTF-8 byte-order mark (editors on Windows write one) is not part of the first line.
    let mut start = if bytes.starts_with(&[0xEF, 0xBB, 0xBF]) { 3 } else { 0 };
    let mut number = 0usize;
    std::iter::from_fn(move || {
        if start >= bytes.len() {
            return None;
        }
        let rest = &bytes[start..];
        let (line, consumed) = match rest.iter().position(|&b| b == b'\n') {
            Some(i) => (&rest[..i], i + 1),
            None => (rest, rest.len()),
        };
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        start += consumed;
        number += 1;
        Some((number, String::from_utf8_lossy(line).into_owned(), start))
    })
}
