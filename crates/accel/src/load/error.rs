//! The one error type of the volume loaders. Every message names the file (with the header line
//! where one is to blame), says what is wrong and how to fix it; tests compare them word for word.

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in the input an error was found: a file, and a 1-based header line when one is to blame.
/// Displays as `path` or `path:line`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    /// The file.
    pub path: PathBuf,
    /// The 1-based header line, when a header line is to blame.
    pub line: Option<usize>,
}

impl Location {
    /// The whole file.
    pub fn file(path: &Path) -> Location {
        Location { path: path.to_path_buf(), line: None }
    }

    /// One header line (1-based) of `path`.
    pub fn line(path: &Path, line: usize) -> Location {
        Location { path: path.to_path_buf(), line: Some(line) }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}:{line}", self.path.display()),
            None => write!(f, "{}", self.path.display()),
        }
    }
}

/// Why a volume could not be loaded (or, for [`LoadError::TextureTooLarge`], uploaded whole).
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file (or a detached data file) could not be read.
    #[error("{}: cannot read the file: {source}", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },

    /// A format whose boxes cannot be read on their own (sort-last rendering reads each
    /// process's box of the file).
    #[error("{}: {format} files cannot be read a box at a time yet; `render --distributed` reads raw files (name_XxYxZ_dtype.raw), raw-encoded NRRD, uncompressed MetaImage and DICOM series along the world's axes: write the voxels out as one of those", .path.display())]
    NoBoxRead {
        /// The file.
        path: PathBuf,
        /// Its format.
        format: &'static str,
    },

    /// A box of a chunked store (an OME-Zarr image) could not be read.
    #[error("{}: {problem}", .path.display())]
    StoreBox {
        /// The store.
        path: PathBuf,
        /// What went wrong, naming the level or chunk.
        problem: String,
    },

    /// The path is a directory, a FIFO, a socket or a device rather than a file.
    #[error("{}: is {what}, not a volume file; give the path of a .raw, .nrrd, .nhdr, .mhd, .mha, .nii or .nii.gz file, or a folder of DICOM slices", .path.display())]
    NotAFile {
        /// The path.
        path: PathBuf,
        /// `"a directory"`, `"a FIFO (named pipe)"`, ...
        what: &'static str,
    },

    /// A MetaImage header sets a required field only after `ElementDataFile`, which ends the
    /// header.
    #[error(
        "{at}: ElementDataFile must be the last field of a MetaImage header (what follows it is data), but {field} is not set before it; move {field} above ElementDataFile"
    )]
    FieldAfterDataFile {
        /// The ElementDataFile line.
        at: Location,
        /// The field not set before it.
        field: &'static str,
    },

    /// A detached data file named in the header cannot be read.
    #[error("{at}: the header's {field} \"{name}\" points to {}, which cannot be read: {source}", .path.display())]
    DataFile {
        /// The header file and the line naming the data file.
        at: Location,
        /// `data file` or `ElementDataFile`.
        field: &'static str,
        /// The name as written in the header.
        name: String,
        /// The resolved path.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },

    /// Raw layout options given for a file whose header describes the layout.
    #[error(
        "{}: {options} describe headerless .raw files, but this file has a header that gives the layout; \
         remove {options} (--spacing alone may override a header)",
        .path.display()
    )]
    RawOptionsOnHeader {
        /// The file.
        path: PathBuf,
        /// The options given, as the command line spells them (`--dims, --dtype`).
        options: String,
    },

    /// Direction vectors that are rotated or oblique to the grid axes.
    #[error(
        "{at}: {field} {value} are not along the volume's axes; volgraph renders axis-aligned grids \
         (flips and axis swaps are honoured): resample the volume onto an axis-aligned grid (e.g. 3D Slicer's \
         \"Resample Scalar Volume\") or write axis vectors such as (1,0,0) (0,-1,0) (0,0,2)"
    )]
    ObliqueAxes {
        /// The header line.
        at: Location,
        /// `space directions` or `TransformMatrix`.
        field: String,
        /// The directions, as read.
        value: String,
    },

    /// Two direction vectors along the same axis.
    #[error("{at}: {field} {value} put two file axes along the same world axis; each axis needs its own direction")]
    DegenerateAxes {
        /// The header line.
        at: Location,
        /// `space directions` or `TransformMatrix`.
        field: String,
        /// The directions, as read.
        value: String,
    },

    /// The extension is not one of the supported formats.
    #[error(
        "{}: unknown volume format \"{extension}\"; use .raw, .nrrd, .nhdr, .mhd, .mha, .nii, .nii.gz, or DICOM (a folder of slices, .dcm files)",
        .path.display()
    )]
    UnknownFormat {
        /// The file.
        path: PathBuf,
        /// The extension found (empty when there is none).
        extension: String,
    },

    /// A `.raw` file whose dimensions or type are known neither from its name nor from
    /// [`super::RawOptions`].
    #[error(
        "{}: cannot tell the voxel {what} of a raw file; name the file like \
         `name_256x256x128_uint8.raw` (types: uint8, uint16, int16, float32) or give it with --{field} \
         (RawOptions::{field} in code)",
        .path.display()
    )]
    RawUnknownLayout {
        /// The file.
        path: PathBuf,
        /// `"dimensions"` or `"type"`.
        what: &'static str,
        /// The [`super::RawOptions`] field to set: `"dims"` or `"dtype"`.
        field: &'static str,
    },

    /// A voxel type volgraph does not store.
    #[error("{at}: unsupported voxel type \"{found}\"; supported: {supported} (convert the data to one of them)")]
    UnsupportedType {
        /// The file and header line.
        at: Location,
        /// The type as written in the file.
        found: String,
        /// The supported types, spelled as this format spells them.
        supported: &'static str,
    },

    /// A data encoding volgraph cannot decode.
    #[error("{at}: unsupported encoding \"{found}\"; supported: {supported} (re-save the file with one of them)")]
    UnsupportedEncoding {
        /// The file and header line.
        at: Location,
        /// The encoding as written in the file.
        found: String,
        /// The supported encodings.
        supported: &'static str,
    },

    /// A header field (or field value) that changes how the data is read and is not supported.
    #[error("{at}: unsupported header field \"{field}\" = \"{value}\"; {hint}")]
    UnsupportedField {
        /// The file and header line.
        at: Location,
        /// The field name.
        field: String,
        /// Its value.
        value: String,
        /// How to get a loadable file.
        hint: &'static str,
    },

    /// Not a 3D volume.
    #[error("{at}: {field} is {found}, but only 3D scalar volumes can be loaded (set it to 3 with three sizes)")]
    NotThreeD {
        /// The file and header line.
        at: Location,
        /// The field name (`dimension`, `NDims`).
        field: &'static str,
        /// The value found.
        found: String,
    },

    /// A required header field is missing.
    #[error("{}: the header has no \"{field}\" field; add a line like `{example}`", .path.display())]
    MissingField {
        /// The header file.
        path: PathBuf,
        /// The missing field.
        field: &'static str,
        /// An example line to add.
        example: &'static str,
    },

    /// A header field's value cannot be parsed or is out of range.
    #[error("{at}: cannot use {field} = \"{value}\"; expected {expected}")]
    BadField {
        /// The file and header line.
        at: Location,
        /// The field name.
        field: String,
        /// The value found (cut to 80 characters).
        value: String,
        /// What a valid value looks like.
        expected: &'static str,
    },

    /// A header line that is not of the form the format requires.
    #[error("{at}: cannot parse header line \"{text}\"; expected {expected}")]
    MalformedLine {
        /// The file and header line.
        at: Location,
        /// The line (cut to 80 characters).
        text: String,
        /// The line syntax of the format.
        expected: &'static str,
    },

    /// A NRRD file that does not start with the NRRD magic.
    #[error("{}: not a NRRD file: the first line is \"{found}\", expected \"NRRD0001\" to \"NRRD0005\"", .path.display())]
    NotNrrd {
        /// The file.
        path: PathBuf,
        /// The first line (cut to 80 characters).
        found: String,
    },

    /// An attached NRRD header not ended by an empty line.
    #[error("{}: the NRRD header does not end with an empty line before the data; the file is truncated or not a NRRD file", .path.display())]
    UnterminatedHeader {
        /// The file.
        path: PathBuf,
    },

    /// An axis has zero voxels.
    #[error("{at}: dimensions {x}x{y}x{z} contain a zero; every axis needs at least one voxel")]
    ZeroDimension {
        /// The file (and header line of the sizes).
        at: Location,
        /// Voxels along x.
        x: u64,
        /// Voxels along y.
        y: u64,
        /// Voxels along z.
        z: u64,
    },

    /// The spacing is not finite and positive.
    #[error("{at}: spacing ({x}, {y}, {z}) must be finite and positive on every axis")]
    BadSpacing {
        /// The file (and header line).
        at: Location,
        /// Spacing along x.
        x: f64,
        /// Spacing along y.
        y: f64,
        /// Spacing along z.
        z: f64,
    },

    /// Voxel sides so unequal that the box cannot be drawn (see
    /// [`super::MAX_SPACING_RATIO`]).
    #[error(
        "{at}: {what} ({x}, {y}, {z}): the longest voxel side is {ratio:.1e} times the shortest; at most 1e4, or the \
         volume renders black (give the spacing in one unit, e.g. mm for every axis: fix the header, or override it \
         with --spacing X,Y,Z)"
    )]
    SpacingRatio {
        /// The file.
        at: Location,
        /// `the header's voxel spacing` or `--spacing`.
        what: &'static str,
        /// Spacing along x.
        x: f64,
        /// Spacing along y.
        y: f64,
        /// Spacing along z.
        z: f64,
        /// Longest over shortest.
        ratio: f64,
    },

    /// The amount of voxel data differs from what the dimensions and type need.
    #[error(
        "{}: {dims} {dtype} voxels need {expected} bytes, but the data has {actual} bytes; {hint}",
        .path.display()
    )]
    DataSize {
        /// The file holding the data.
        path: PathBuf,
        /// The dimensions, as `XxYxZ`.
        dims: String,
        /// The voxel type.
        dtype: crate::volume::VoxelType,
        /// Bytes needed.
        expected: u64,
        /// Bytes found.
        actual: u64,
        /// How to fix it.
        hint: &'static str,
    },

    /// The compressed data could not be inflated.
    #[error("{}: cannot decompress the {codec} data: {source}; the file is truncated or not compressed as its header says", .path.display())]
    Decompress {
        /// The file holding the data.
        path: PathBuf,
        /// `gzip` or `zlib`.
        codec: &'static str,
        /// The decoder's error.
        source: std::io::Error,
    },

    /// A DICOM file that cannot be parsed (corrupt or truncated).
    #[error("{}: cannot read the DICOM file: {reason}; the file is corrupt or truncated (remove it, or copy it again)", .path.display())]
    DicomRead {
        /// The file.
        path: PathBuf,
        /// dicom-rs's message.
        reason: String,
    },

    /// No DICOM image where one was expected.
    #[error(
        "{place}: {what} no DICOM images ({files} file(s): {not_dicom} not DICOM, {dicomdirs} DICOMDIR index); \
         give the folder holding the slices, a slice file, or a volume file (.raw, .nrrd, .nhdr, .mhd, .mha, .nii, .nii.gz)"
    )]
    NoDicomImages {
        /// The paths given.
        place: String,
        /// `is a folder with` or `holds`.
        what: &'static str,
        /// Files looked at.
        files: usize,
        /// Files without the DICOM magic.
        not_dicom: usize,
        /// DICOMDIR files.
        dicomdirs: usize,
    },

    /// Several series where one was expected.
    #[error(
        "{place}: holds {count} DICOM series; choose one with --series N, --series UID or --series DESCRIPTION:\n{list}"
    )]
    SeveralSeries {
        /// The paths given.
        place: String,
        /// How many.
        count: usize,
        /// One line per series.
        list: String,
    },

    /// `--series` names no series that is there.
    #[error("{place}: no DICOM series \"{wanted}\"; give its number in this list, its UID or its description:\n{list}")]
    NoSuchSeries {
        /// The paths given.
        place: String,
        /// What was asked for.
        wanted: String,
        /// One line per series.
        list: String,
    },

    /// Slices that do not make a regular grid.
    #[error("DICOM {series}: {message}")]
    DicomGeometry {
        /// The series (description or number).
        series: String,
        /// What is wrong, naming slices and positions, and what to do.
        message: String,
    },

    /// Pixel data this build cannot decode.
    #[error(
        "{}: pixel data in {name} (transfer syntax {uid}) cannot be decoded; supported: {supported}; convert the series \
         (e.g. `gdcmconv --raw` or `dcmdjpeg`) to one of them",
        .path.display()
    )]
    DicomTransferSyntax {
        /// The file.
        path: PathBuf,
        /// The transfer syntax UID.
        uid: String,
        /// Its name.
        name: String,
        /// The decodable ones.
        supported: String,
    },

    /// Pixel data that is not a scalar image or fails to decode.
    #[error("{}: {message}", .path.display())]
    DicomPixels {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },

    /// A NIfTI file that cannot be read.
    #[error("{}: cannot read the NIfTI file: {reason}", .path.display())]
    NiftiRead {
        /// The file.
        path: PathBuf,
        /// What failed.
        reason: String,
    },

    /// A 4D NIfTI file without `--frame`, or a frame past its end.
    #[error(
        "{}: holds {frames} volumes (a 4D series); {what}: pick one with --frame N (0..={last})",
        .path.display(), last = .frames.saturating_sub(1)
    )]
    NiftiFrame {
        /// The file.
        path: PathBuf,
        /// Volumes in the file.
        frames: u64,
        /// `no --frame was given` or `--frame 9 is past the end`.
        what: String,
    },

    /// An option that does not apply to the file given.
    #[error("{}: {option} {reason}; remove {option}", .path.display())]
    OptionDoesNotApply {
        /// The file.
        path: PathBuf,
        /// `--series`, `--frame`.
        option: &'static str,
        /// Why.
        reason: &'static str,
    },

    /// A dimension exceeds the device's 3D texture limit (see [`super::check_texture_limit`]).
    #[error(
        "volume \"{name}\": {axis} size {size} exceeds the device's 3D texture limit of {max_dim}; \
         split it into bricks (volgraph_accel::bricks), which lifts this limit, or downsample it"
    )]
    TextureTooLarge {
        /// The volume's name (file stem).
        name: String,
        /// `"x"`, `"y"` or `"z"`.
        axis: &'static str,
        /// The voxels along that axis.
        size: u32,
        /// The device limit.
        max_dim: u32,
    },
}

/// Cuts `text` to at most 80 characters for messages (never inside a character).
pub(crate) fn clip(text: &str) -> String {
    const MAX_CHARS: usize = 80;
    if text.chars().count() <= MAX_CHARS {
        text.to_string()
    } else {
        let mut s: String = text.chars().take(MAX_CHARS).collect();
        s.push('…');
        s
    }
}
