//! MetaImage (ITK): `.mhd` with a detached `ElementDataFile`, `.mha` with
//! `ElementDataFile = LOCAL` (the data follows that line). 3D scalar volumes only.
//!
//! Read: `NDims`, `DimSize`, `ElementSpacing` (or `ElementSize` when there is no spacing),
//! `ElementType`, `ElementByteOrderMSB` / `BinaryDataByteOrderMSB`, `HeaderSize` (detached data
//! only; -1 = data at the end of the file), `CompressedData` (zlib), `BinaryData`,
//! `ElementNumberOfChannels` (must be 1), `TransformMatrix` (`Rotation`, `Orientation`: the
//! direction of each file axis; flips and axis swaps are honoured by reordering the voxels,
//! rotated or oblique directions are rejected, see [`super::AxisOrientation`]) and
//! `ElementDataFile`, which must be the last field, and `Offset` (`Position`, `Origin`: the first
//! voxel's centre, so two files on different grids — a scan and its segmentation, a PET on a
//! CT — lie where their headers put them). Every other key (`ObjectType`,
//! `AnatomicalOrientation`, …) is ignored: MetaImage headers carry free-form keys.

use std::path::Path;

use glam::DVec3;

use super::error::clip;
use super::{
    Endianness, Layout, LoadError, LoadReport, LoadedVolume, Location, VolumeFormat, byte_count, check_dims,
    check_spacing, finish, header_lines, inflate, read_data_file, read_file, stem,
};
use crate::volume::VoxelType;

const SUPPORTED_TYPES: &str = "MET_UCHAR, MET_USHORT, MET_SHORT, MET_FLOAT";
const HINT: &str =
    "check DimSize, ElementType, HeaderSize and CompressedData in the header, or whether the data is complete";

fn voxel_type(name: &str) -> Option<VoxelType> {
    match name {
        "MET_UCHAR" => Some(VoxelType::U8),
        "MET_USHORT" => Some(VoxelType::U16),
        "MET_SHORT" => Some(VoxelType::I16),
        "MET_FLOAT" => Some(VoxelType::F32),
        _ => None,
    }
}

pub(super) fn load(path: &Path) -> Result<LoadedVolume, LoadError> {
    let bytes = read_file(path)?;
    parse(path, &bytes)
}

/// What a MetaImage header says: the layout and where and how the voxels are stored.
struct Header {
    layout: Layout,
    /// `Offset`: the first voxel's centre, in file order's world coordinates.
    offset: Option<DVec3>,
    compressed: bool,
    header_size: i64,
    /// `ElementDataFile`: its value, where attached data starts, its line.
    data_name: String,
    data_start: usize,
    data_line: usize,
    notes: Vec<String>,
}

pub(super) fn parse(path: &Path, bytes: &[u8]) -> Result<LoadedVolume, LoadError> {
    let Header { layout, offset, compressed, header_size, data_name, data_start, data_line, mut notes } =
        parse_header(path, bytes)?;
    let origin = offset.map(|o| layout.orientation.world_origin(o, layout.dims, layout.spacing));
    let (dims, dtype) = (layout.dims, layout.dtype);
    let local = data_name.eq_ignore_ascii_case("LOCAL");
    let (data_path, stored) = if local {
        if header_size != 0 {
            notes.push(format!("HeaderSize = {header_size} ignored for LOCAL data"));
        }
        (path.to_path_buf(), bytes.get(data_start..).unwrap_or(&[]).to_vec())
    } else {
        read_data_file(path, Location::line(path, data_line), "ElementDataFile", &data_name)?
    };
    let expected = byte_count(dims, dtype).unwrap_or(u64::MAX);
    let data = if compressed {
        inflate(&data_path, &stored, true, expected.saturating_add(1))?
    } else if local || header_size == 0 {
        stored
    } else if header_size == -1 {
        let start = (stored.len() as u64).saturating_sub(expected) as usize;
        stored[start..].to_vec()
    } else {
        let skip = (header_size as u64).min(stored.len() as u64) as usize;
        stored[skip..].to_vec()
    };
    let mut report = LoadReport::new(VolumeFormat::MetaImage, &data_path);
    report.notes = notes;
    let mut loaded = finish(layout, &data, &data_path, report, HINT)?;
    loaded.volume.meta.origin = origin;
    Ok(loaded)
}

/// Where the voxels of MetaImage `path` lie when a box of them can be read by seeking: the
/// layout, the data file and the offset of the first voxel. `bytes` holds at least the header.
/// Uncompressed data along the world's axes only; anything else is [`LoadError::NoBoxRead`].
pub(super) fn raw_data(path: &Path, bytes: &[u8]) -> Result<(Layout, std::path::PathBuf, u64), LoadError> {
    let h = parse_header(path, bytes)?;
    let refuse = |format| LoadError::NoBoxRead { path: path.to_path_buf(), format };
    if h.compressed {
        return Err(refuse("compressed MetaImage"));
    }
    if !h.layout.orientation.is_identity() {
        return Err(refuse("MetaImage with flipped or swapped axes"));
    }
    let expected = byte_count(h.layout.dims, h.layout.dtype).unwrap_or(u64::MAX);
    let local = h.data_name.eq_ignore_ascii_case("LOCAL");
    let data_path = if local { path.to_path_buf() } else { super::sibling(path, &h.data_name) };
    super::check_is_file(&data_path)?;
    let size = std::fs::metadata(&data_path).map_err(|source| LoadError::Io { path: data_path.clone(), source })?.len();
    let offset = match (local, h.header_size) {
        (true, _) => h.data_start as u64,
        (false, -1) => size.saturating_sub(expected),
        (false, skip) => skip.max(0) as u64,
    };
    super::check_data_extent(&data_path, offset, &h.layout, HINT)?;
    Ok((h.layout, data_path, offset))
}

fn parse_header(path: &Path, bytes: &[u8]) -> Result<Header, LoadError> {
    let mut ndims_seen = false;
    let mut sizes: Option<(usize, [u64; 3], String)> = None;
    let mut spacing: Option<(usize, DVec3)> = None;
    let mut element_size: Option<(usize, DVec3)> = None;
    let mut dtype = None;
    let mut order = Endianness::Little;
    let mut header_size: i64 = 0;
    let mut compressed = false;
    let mut data_file: Option<(String, usize, usize)> = None;
    let mut directions: Option<(usize, [DVec3; 3])> = None;
    let mut offset: Option<DVec3> = None;
    let notes = Vec::new();

    for (number, text, end) in header_lines(bytes) {
        if text.trim().is_empty() {
            continue;
        }
        let at = Location::line(path, number);
        let (key, value) = text.split_once('=').ok_or_else(|| LoadError::MalformedLine {
            at: at.clone(),
            text: clip(&text),
            expected: "`Key = Value`",
        })?;
        let (key, value) = (key.trim(), value.trim());
        let bad = |expected: &'static str| LoadError::BadField {
            at: at.clone(),
            field: key.to_string(),
            value: clip(value),
            expected,
        };
        let boolean = |v: &str| match v.to_ascii_lowercase().as_str() {
            "true" | "1" => Some(true),
            "false" | "0" => Some(false),
            _ => None,
        };
        let three = |v: &str| -> Option<[f64; 3]> {
            let parsed: Option<Vec<f64>> = v.split_whitespace().map(|s| s.parse().ok()).collect();
            match parsed.as_deref() {
                Some(&[x, y, z]) => Some([x, y, z]),
                _ => None,
            }
        };
        match key.to_ascii_lowercase().as_str() {
            "ndims" => {
                if value != "3" {
                    return Err(LoadError::NotThreeD { at, field: "NDims", found: clip(value) });
                }
                ndims_seen = true;
            }
            "dimsize" => {
                let parsed: Option<Vec<u64>> = value.split_whitespace().map(|s| s.parse().ok()).collect();
                match parsed.as_deref() {
                    Some(&[x, y, z]) => sizes = Some((number, [x, y, z], value.to_string())),
                    _ => return Err(bad("three whole numbers, e.g. `DimSize = 64 64 32`")),
                }
            }
            "elementspacing" => {
                let s = three(value).ok_or_else(|| bad("three numbers, e.g. `ElementSpacing = 1 1 1.5`"))?;
                spacing = Some((number, DVec3::from_array(s)));
            }
            "elementsize" => {
                let s = three(value).ok_or_else(|| bad("three numbers, e.g. `ElementSize = 1 1 1.5`"))?;
                element_size = Some((number, DVec3::from_array(s)));
            }
            "elementtype" => {
                dtype = Some(voxel_type(&value.to_ascii_uppercase()).ok_or_else(|| LoadError::UnsupportedType {
                    at: at.clone(),
                    found: clip(value),
                    supported: SUPPORTED_TYPES,
                })?);
            }
            "elementbyteordermsb" | "binarydatabyteordermsb" => {
                let msb = boolean(value).ok_or_else(|| bad("`True` or `False`"))?;
                order = if msb { Endianness::Big } else { Endianness::Little };
            }
            "headersize" => {
                header_size = value
                    .parse::<i64>()
                    .ok()
                    .filter(|&n| n >= -1)
                    .ok_or_else(|| bad("a whole number ≥ 0, or -1 for data at the end of the file"))?;
            }
            "transformmatrix" | "rotation" | "orientation" => {
                let parsed: Option<Vec<f64>> = value.split_whitespace().map(|s| s.parse().ok()).collect();
                match parsed.as_deref() {
                    Some(m @ &[a, b, c, d, e, f, g, h, i])
                        if m.iter().all(|v| v.is_finite())
                            && [[a, b, c], [d, e, f], [g, h, i]].iter().all(|r| r.iter().any(|v| *v != 0.0)) =>
                    {
                        // Row k is the world direction of file axis k (ITK's MetaImageIO).
                        directions = Some((number, [DVec3::new(a, b, c), DVec3::new(d, e, f), DVec3::new(g, h, i)]));
                    }
                    _ => {
                        return Err(bad(
                            "nine finite numbers, each row of three not all zero, e.g. `TransformMatrix = 1 0 0 0 1 0 0 0 1`",
                        ));
                    }
                }
            }
            "offset" | "position" | "origin" => {
                offset = Some(
                    three(value)
                        .filter(|o| o.iter().all(|v| v.is_finite()))
                        .map(DVec3::from_array)
                        .ok_or_else(|| bad("three finite numbers, e.g. `Offset = -120.5 -98 40`"))?,
                );
            }
            "compresseddata" => {
                compressed = boolean(value).ok_or_else(|| bad("`True` or `False`"))?;
            }
            "binarydata" if boolean(value) != Some(true) => {
                return Err(LoadError::UnsupportedField {
                    at,
                    field: key.to_string(),
                    value: clip(value),
                    hint: "only binary data is supported; save the image with `BinaryData = True`",
                });
            }
            "elementnumberofchannels" if value != "1" => {
                return Err(LoadError::UnsupportedField {
                    at,
                    field: key.to_string(),
                    value: clip(value),
                    hint: "only scalar volumes (1 channel) are supported; extract one channel first",
                });
            }
            "elementdatafile" => {
                if value.is_empty() || value.eq_ignore_ascii_case("LIST") || value.contains('%') || value.contains(' ')
                {
                    return Err(LoadError::UnsupportedField {
                        at,
                        field: key.to_string(),
                        value: clip(value),
                        hint: "use `LOCAL` or a single data file name; join slice files into one",
                    });
                }
                data_file = Some((value.to_string(), end, number));
                break; // ElementDataFile ends the header.
            }
            _ => {}
        }
    }

    // ElementDataFile ends the header: a field written after it is data, not a field.
    let data_file_line = data_file.as_ref().map(|(_, _, line)| *line);
    let missing = |field, example| match data_file_line {
        Some(line) => LoadError::FieldAfterDataFile { at: Location::line(path, line), field },
        None => LoadError::MissingField { path: path.to_path_buf(), field, example },
    };
    if !ndims_seen {
        return Err(missing("NDims", "NDims = 3"));
    }
    let (sizes_line, sizes, sizes_text) = sizes.ok_or_else(|| missing("DimSize", "DimSize = 64 64 64"))?;
    let dtype = dtype.ok_or_else(|| missing("ElementType", "ElementType = MET_UCHAR"))?;
    let (data_name, data_start, data_line) =
        data_file.ok_or_else(|| missing("ElementDataFile", "ElementDataFile = LOCAL"))?;
    let dims = check_dims(&Location::line(path, sizes_line), "DimSize", &sizes_text, sizes)?;
    let file_spacing = match spacing.or(element_size) {
        Some((line, s)) => {
            check_spacing(&Location::line(path, line), s)?;
            s
        }
        None => DVec3::ONE,
    };
    // The matrix gives directions; the spacing stays ElementSpacing's, moved to world axes.
    let (orientation, spacing) = match directions {
        Some((line, d)) => {
            let unit = d.map(|v| v.normalize_or_zero());
            let (o, _) = super::AxisOrientation::from_directions(unit, &Location::line(path, line), "TransformMatrix")?;
            let mut world = DVec3::ONE;
            for i in 0..3 {
                world[o.world_axis[i]] = file_spacing[i];
            }
            (o, world)
        }
        None => (super::AxisOrientation::default(), file_spacing),
    };

    let layout = Layout { name: stem(path), dims, dtype, order, spacing, orientation };
    Ok(Header { layout, offset, compressed, header_size, data_name, data_start, data_line, notes })
}
