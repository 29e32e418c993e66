//! NRRD (<https://teem.sourceforge.net/nrrd/format.html>): attached `.nrrd` and detached `.nhdr`
//! (`data file:`), raw or gzip encoding, 3D scalar volumes only.
//!
//! Read: `type`, `dimension`, `sizes`, `spacings` or `space directions` (spacing = length of each
//! direction vector; flips and axis swaps are honoured by reordering the voxels, rotated or oblique
//! directions are rejected: see [`super::AxisOrientation`]), `endian` (little when missing, noted in the report), `encoding`,
//! `data file`, `byte skip` (≥ 0, or -1 with raw encoding: data at the end of the file) and
//! `line skip: 0`, and `space`: an anatomical space (`right-anterior-superior`/`RAS`,
//! `left-anterior-superior`, `left-posterior-superior`, …) turns the directions and `space
//! origin` (the first voxel's centre) into the LPS patient frame as ITK does
//! (`docs/rendering_model.md`, "Patient frame"), so a segmentation saved on a cropped grid lands
//! on its scan; another space keeps its own axes. Ignored as harmless: comments, `key:=value`
//! pairs, `content`, `kinds`, `labels`, `units`, `centers` and the other per-axis or range
//! annotations. Any other field is an error rather than a silent misreading.

use std::path::Path;

use glam::DVec3;

use super::error::clip;
use super::{
    Endianness, Layout, LoadError, LoadReport, LoadedVolume, Location, VolumeFormat, byte_count, check_dims,
    check_spacing, finish, header_lines, inflate, read_data_file, read_file, stem,
};
use crate::volume::VoxelType;
use crate::volume_meta::WorldFrame;

const SUPPORTED_TYPES: &str = "uchar/uint8, ushort/uint16, short/int16, float";
const SUPPORTED_ENCODINGS: &str = "raw, gzip";
const HINT: &str =
    "check \"sizes\", \"type\", \"encoding\" and \"byte skip\" in the header, or whether the data is complete";

/// Fields that do not change how the voxels are read.
const IGNORED: &[&str] = &[
    "content",
    "space units",
    "space dimension",
    "labels",
    "units",
    "centers",
    "centerings",
    "thicknesses",
    "axis mins",
    "axismins",
    "axis maxs",
    "axismaxs",
    "min",
    "max",
    "old min",
    "oldmin",
    "old max",
    "oldmax",
    "sample units",
    "sampleunits",
    "measurement frame",
    "number",
];

fn voxel_type(name: &str) -> Option<VoxelType> {
    match name {
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => Some(VoxelType::U8),
        "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => Some(VoxelType::U16),
        "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => Some(VoxelType::I16),
        "float" => Some(VoxelType::F32),
        _ => None,
    }
}

#[derive(Clone, Copy, PartialEq)]
enum Encoding {
    Raw,
    Gzip,
}

pub(super) fn load(path: &Path) -> Result<LoadedVolume, LoadError> {
    let bytes = read_file(path)?;
    parse(path, &bytes)
}

/// What a NRRD header says: the layout and where and how the voxels are stored.
pub(super) struct Header {
    layout: Layout,
    encoding: Encoding,
    data_file: Option<(String, usize)>,
    byte_skip: i64,
    /// Where attached data starts (after the blank line), when the header ends in `bytes`.
    data_start: Option<usize>,
    notes: Vec<String>,
    frame: WorldFrame,
    oriented: bool,
    /// `space origin` in the frame's coordinates (LPS for an anatomical space).
    origin: Option<DVec3>,
}

pub(super) fn parse(path: &Path, bytes: &[u8]) -> Result<LoadedVolume, LoadError> {
    let Header { layout, encoding, data_file, byte_skip, data_start, notes, frame, oriented, origin } =
        parse_header(path, bytes)?;
    let world_origin = origin.map(|o| layout.orientation.world_origin(o, layout.dims, layout.spacing));
    let (dims, dtype) = (layout.dims, layout.dtype);
    let missing = |field, example| LoadError::MissingField { path: path.to_path_buf(), field, example };
    let (data_path, stored) = match &data_file {
        Some((name, line)) => read_data_file(path, Location::line(path, *line), "data file", name)?,
        None => match data_start {
            Some(start) => (path.to_path_buf(), bytes.get(start..).unwrap_or(&[]).to_vec()),
            None if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("nhdr")) => {
                return Err(missing("data file", "data file: volume.raw"));
            }
            None => {
                return Err(LoadError::UnterminatedHeader { path: path.to_path_buf() });
            }
        },
    };
    let expected = byte_count(dims, dtype).unwrap_or(u64::MAX);
    let skip = byte_skip.max(0) as u64;
    let decoded = match encoding {
        Encoding::Raw => stored,
        Encoding::Gzip => inflate(&data_path, &stored, false, expected.saturating_add(skip).saturating_add(1))?,
    };
    let data: &[u8] = if byte_skip == -1 {
        // Data at the end of the file: the last `expected` bytes (too few bytes fall through to
        // the size error below).
        let start = (decoded.len() as u64).saturating_sub(expected) as usize;
        &decoded[start..]
    } else {
        decoded.get(skip.min(decoded.len() as u64) as usize..).unwrap_or(&[])
    };
    let mut report = LoadReport::new(VolumeFormat::Nrrd, &data_path);
    report.notes = notes;
    let mut loaded = finish(layout, data, &data_path, report, HINT)?;
    loaded.volume.meta.frame = if oriented { frame } else { WorldFrame::IndexAxes };
    loaded.volume.meta.origin = world_origin.filter(|_| oriented);
    Ok(loaded)
}

/// Where the voxels of NRRD `path` lie when a box of them can be read by seeking: the layout,
/// the data file and the offset of the first voxel. `bytes` holds at least the header. Raw
/// encoding and file axes along the world's only; anything else is [`LoadError::NoBoxRead`].
pub(super) fn raw_data(path: &Path, bytes: &[u8]) -> Result<(Layout, std::path::PathBuf, u64), LoadError> {
    let header = parse_header(path, bytes)?;
    let refuse = |format| LoadError::NoBoxRead { path: path.to_path_buf(), format };
    if header.encoding != Encoding::Raw {
        return Err(refuse("gzip-encoded NRRD"));
    }
    if !header.layout.orientation.is_identity() {
        return Err(refuse("NRRD with flipped or swapped axes"));
    }
    let expected = byte_count(header.layout.dims, header.layout.dtype).unwrap_or(u64::MAX);
    let (data_path, start) = match (&header.data_file, header.data_start) {
        (Some((name, _)), _) => (super::sibling(path, name), 0),
        (None, Some(start)) => (path.to_path_buf(), start as u64),
        (None, None) => return Err(LoadError::UnterminatedHeader { path: path.to_path_buf() }),
    };
    super::check_is_file(&data_path)?;
    let size = std::fs::metadata(&data_path).map_err(|source| LoadError::Io { path: data_path.clone(), source })?.len();
    let offset = if header.byte_skip == -1 { size.saturating_sub(expected) } else { start + header.byte_skip as u64 };
    super::check_data_extent(&data_path, offset, &header.layout, HINT)?;
    Ok((header.layout, data_path, offset))
}

fn parse_header(path: &Path, bytes: &[u8]) -> Result<Header, LoadError> {
    let mut lines = header_lines(bytes);
    let magic = lines.next().map(|(_, text, _)| text).unwrap_or_default();
    let version_ok = magic.len() == 8 && magic.starts_with("NRRD000") && matches!(magic.as_bytes()[7], b'1'..=b'5');
    if !version_ok {
        return Err(LoadError::NotNrrd { path: path.to_path_buf(), found: clip(&magic) });
    }

    let mut dtype = None;
    let mut dimension_seen = false;
    let mut sizes: Option<(usize, [u64; 3], String)> = None;
    let mut spacing: Option<(usize, DVec3)> = None;
    let mut directions: Option<(Location, [DVec3; 3])> = None;
    let mut space: Option<String> = None;
    let mut space_origin: Option<DVec3> = None;
    let mut order = None;
    let mut encoding = None;
    let mut data_file: Option<(String, usize)> = None;
    let mut byte_skip: i64 = 0;
    let mut data_start = None;
    let mut notes = Vec::new();

    for (number, text, end) in lines {
        if text.is_empty() {
            data_start = Some(end);
            break;
        }
        if text.starts_with('#') {
            continue;
        }
        let at = Location::line(path, number);
        let malformed = || LoadError::MalformedLine {
            at: at.clone(),
            text: clip(&text),
            expected: "`field: value`, `key:=value` or a `#` comment",
        };
        let (key, value) = text.split_once(':').ok_or_else(malformed)?;
        if value.starts_with('=') {
            continue; // A key/value pair: free-form metadata.
        }
        let value = value.strip_prefix(' ').ok_or_else(malformed)?.trim();
        let field = key.trim().to_ascii_lowercase();
        let bad = |expected: &'static str| LoadError::BadField {
            at: at.clone(),
            field: field.clone(),
            value: clip(value),
            expected,
        };
        match field.as_str() {
            // Each axis must be a spatial one: a colour or vector axis (RGB-color, 3-vector,
            // list, ...) makes the voxels vectors, which read as a scalar volume would be the
            // components interleaved along that axis.
            "kinds" => {
                let spatial = ["domain", "space", "time", "none", "???"];
                if value.split_whitespace().any(|k| !spatial.contains(&k.to_ascii_lowercase().as_str())) {
                    return Err(bad(
                        "one spatial kind per axis (domain, space, time, none or ???); this file's voxels are \
                         vectors or colours, and volgraph renders scalar volumes: extract one component first \
                         (e.g. `unu slice -a 0 -p 0`)",
                    ));
                }
            }
            "type" => {
                let t = voxel_type(&value.to_ascii_lowercase()).ok_or_else(|| LoadError::UnsupportedType {
                    at: at.clone(),
                    found: clip(value),
                    supported: SUPPORTED_TYPES,
                })?;
                dtype = Some(t);
            }
            "dimension" => {
                if value != "3" {
                    return Err(LoadError::NotThreeD { at: at.clone(), field: "dimension", found: clip(value) });
                }
                dimension_seen = true;
            }
            "sizes" => {
                let parsed: Option<Vec<u64>> = value.split_whitespace().map(|s| s.parse().ok()).collect();
                match parsed.as_deref() {
                    Some(&[x, y, z]) => sizes = Some((number, [x, y, z], value.to_string())),
                    _ => return Err(bad("three whole numbers, e.g. `sizes: 64 64 32`")),
                }
            }
            "spacings" => {
                let parsed: Option<Vec<f64>> = value.split_whitespace().map(|s| s.parse().ok()).collect();
                match parsed.as_deref() {
                    Some(&[x, y, z]) => spacing = Some((number, DVec3::new(x, y, z))),
                    _ => return Err(bad("three numbers, e.g. `spacings: 1 1 1.5`")),
                }
            }
            "space directions" => {
                let parsed = parse_directions(value)
                    .ok_or_else(|| bad("three vectors, e.g. `space directions: (1,0,0) (0,1,0) (0,0,1.5)`"))?;
                // Checked here so a bad vector names its line; oriented once `space` is known.
                let (_, lengths) = super::AxisOrientation::from_directions(parsed, &at, "space directions")?;
                directions = Some((at.clone(), parsed));
                spacing = Some((number, lengths));
            }
            "endian" => {
                order = Some(match value.to_ascii_lowercase().as_str() {
                    "little" => Endianness::Little,
                    "big" => Endianness::Big,
                    _ => return Err(bad("`little` or `big`")),
                });
            }
            "encoding" => {
                encoding = Some(match value.to_ascii_lowercase().as_str() {
                    "raw" => Encoding::Raw,
                    "gzip" | "gz" => Encoding::Gzip,
                    _ => {
                        return Err(LoadError::UnsupportedEncoding {
                            at: at.clone(),
                            found: clip(value),
                            supported: SUPPORTED_ENCODINGS,
                        });
                    }
                });
            }
            "data file" | "datafile" => {
                if value.starts_with("LIST") || value.contains('%') || value.contains(' ') {
                    return Err(LoadError::UnsupportedField {
                        at: at.clone(),
                        field: field.clone(),
                        value: clip(value),
                        hint: "only a single data file is supported; join the slices into one file",
                    });
                }
                data_file = Some((value.to_string(), number));
            }
            "byte skip" | "byteskip" => {
                byte_skip = value
                    .parse::<i64>()
                    .ok()
                    .filter(|&n| n >= -1)
                    .ok_or_else(|| bad("a whole number ≥ 0, or -1 for data at the end of the file"))?;
            }
            "line skip" | "lineskip" => {
                if value != "0" {
                    return Err(LoadError::UnsupportedField {
                        at: at.clone(),
                        field: field.clone(),
                        value: clip(value),
                        hint: "skipping text lines before the data is not supported; use `byte skip` or remove the lines",
                    });
                }
            }
            "block size" | "blocksize" => {}
            "space" => space = Some(value.to_string()),
            "space origin" => {
                let parsed = parse_vector(value)
                    .filter(|o| o.is_finite())
                    .ok_or_else(|| bad("one vector of three finite numbers, e.g. `space origin: (-120.5,-98,40)`"))?;
                space_origin = Some(parsed);
            }
            f if IGNORED.contains(&f) => {}
            _ => {
                return Err(LoadError::UnsupportedField {
                    at: at.clone(),
                    field: field.clone(),
                    value: clip(value),
                    hint: "it is not a NRRD field volgraph knows; remove it or turn it into a `key:=value` pair",
                });
            }
        }
    }

    let missing = |field, example| LoadError::MissingField { path: path.to_path_buf(), field, example };
    let dtype = dtype.ok_or_else(|| missing("type", "type: uchar"))?;
    if !dimension_seen {
        return Err(missing("dimension", "dimension: 3"));
    }
    let (sizes_line, sizes, sizes_text) = sizes.ok_or_else(|| missing("sizes", "sizes: 64 64 64"))?;
    let encoding = encoding.ok_or_else(|| missing("encoding", "encoding: raw"))?;
    let dims = check_dims(&Location::line(path, sizes_line), "sizes", &sizes_text, sizes)?;
    let spacing = match spacing {
        Some((line, s)) => {
            check_spacing(&Location::line(path, line), s)?;
            s
        }
        None => DVec3::ONE,
    };
    let order = order.unwrap_or_else(|| {
        if dtype.size_bytes() > 1 {
            notes.push("no \"endian\" field; read as little endian".to_string());
        }
        Endianness::Little
    });
    if byte_skip == -1 && encoding != Encoding::Raw {
        return Err(LoadError::UnsupportedField {
            at: Location::file(path),
            field: "byte skip".to_string(),
            value: "-1".to_string(),
            hint: "-1 (data at the end) only works with raw encoding; give the skip in bytes",
        });
    }

    let (frame, lps) = space.as_deref().map_or((WorldFrame::IndexAxes, None), anatomical_space);
    let origin = space_origin.map(|o| lps.map_or(o, |flip| o * flip));
    let oriented = directions.is_some();
    let orientation = match directions {
        Some((at, d)) => {
            let d = match lps {
                Some(flip) => d.map(|v| v * flip),
                None => d,
            };
            super::AxisOrientation::from_directions(d, &at, "space directions")?.0
        }
        None => super::AxisOrientation::default(),
    };
    let layout = Layout { name: stem(path), dims, dtype, order, spacing, orientation };
    Ok(Header { layout, encoding, data_file, byte_skip, data_start, notes, frame, oriented, origin })
}

/// The vector of a `space origin` value such as `(-120.5, -98, 40)`.
fn parse_vector(value: &str) -> Option<DVec3> {
    let compact: String = value.chars().filter(|c| !c.is_whitespace()).collect();
    let components: Option<Vec<f64>> =
        compact.strip_prefix('(')?.strip_suffix(')')?.split(',').map(|c| c.parse().ok()).collect();
    match components.as_deref() {
        Some(&[x, y, z]) => Some(DVec3::new(x, y, z)),
        _ => None,
    }
}

/// The frame of NRRD `space` value `name`, and for an anatomical space the per-axis signs that
/// take its coordinates to LPS (`right-anterior-superior` → (−1, −1, 1)).
fn anatomical_space(name: &str) -> (WorldFrame, Option<DVec3>) {
    let lower = name.trim().to_ascii_lowercase();
    let words: Vec<&str> = match lower.as_str() {
        "ras" => vec!["right", "anterior", "superior"],
        "las" => vec!["left", "anterior", "superior"],
        "lps" => vec!["left", "posterior", "superior"],
        "rps" => vec!["right", "posterior", "superior"],
        other => other.split('-').collect(),
    };
    let sign = |word: &str, towards: &str, away: &str| match word {
        w if w == towards => Some(1.0),
        w if w == away => Some(-1.0),
        _ => None,
    };
    match words.as_slice() {
        [x, y, z] => {
            match (sign(x, "left", "right"), sign(y, "posterior", "anterior"), sign(z, "superior", "inferior")) {
                (Some(a), Some(b), Some(c)) => (WorldFrame::Lps, Some(DVec3::new(a, b, c))),
                _ => (WorldFrame::Named(name.trim().to_string()), None),
            }
        }
        _ => (WorldFrame::Named(name.trim().to_string()), None),
    }
}

/// The three vectors of a `space directions` value such as `(1,0,0) (0,1,0) (0,0,2)`.
fn parse_directions(value: &str) -> Option<[DVec3; 3]> {
    let compact: String = value.chars().filter(|c| !c.is_whitespace()).collect();
    let inner = compact.strip_prefix('(')?.strip_suffix(')')?;
    let vectors: Option<Vec<DVec3>> = inner
        .split(")(")
        .map(|vector| {
            let components: Option<Vec<f64>> = vector.split(',').map(|c| c.parse().ok()).collect();
            match components.as_deref() {
                Some(&[x, y, z]) => Some(DVec3::new(x, y, z)),
                _ => None,
            }
        })
        .collect();
    match vectors.as_deref() {
        Some(&[a, b, c]) => Some([a, b, c]),
        _ => None,
    }
}
