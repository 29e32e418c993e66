//! Headerless `.raw` volumes: the layout comes from the name `name_XxYxZ_dtype.raw` or from
//! [`RawOptions`].

use std::path::Path;

use glam::DVec3;

use super::{
    Layout, LoadError, LoadReport, LoadedVolume, Location, RawOptions, VolumeFormat, byte_count, check_dims, dims_text,
    finish, read_file,
};
use crate::volume::VoxelType;

const SUPPORTED: &str = "uint8, uint16, int16, float32 (or u8, u16, i16, f32)";

/// Splits a raw file name (or stem) of the form `name_XxYxZ_dtype[.raw]` into the dataset name,
/// the dimensions and the type token (not checked; see [`VoxelType::from_name`]). A name ending
/// in `_XxYxZ` without a type gives `None` for the token. `None` when no `_XxYxZ` part is there.
pub fn parse_raw_name(file_name: &str) -> Option<(String, [u64; 3], Option<String>)> {
    // The extension in any case (`.RAW` from Windows tools), as `load_volume` matches it.
    let stem = match file_name.len().checked_sub(4) {
        Some(cut) if file_name.is_char_boundary(cut) && file_name[cut..].eq_ignore_ascii_case(".raw") => {
            &file_name[..cut]
        }
        _ => file_name,
    };
    let parse_dims = |token: &str| -> Option<[u64; 3]> {
        let mut parts = token.split(['x', 'X']);
        let mut dims = [0u64; 3];
        for d in &mut dims {
            let part = parts.next()?;
            if part.is_empty() || !part.bytes().all(|b| b.is_ascii_digit()) {
                return None;
            }
            *d = part.parse().ok()?;
        }
        parts.next().is_none().then_some(dims)
    };
    let (head, last) = stem.rsplit_once('_')?;
    if let Some(dims) = parse_dims(last) {
        return Some((head.to_string(), dims, None));
    }
    let (name, dims_token) = head.rsplit_once('_')?;
    let dims = parse_dims(dims_token)?;
    Some((name.to_string(), dims, Some(last.to_string())))
}

pub(super) fn load(path: &Path, opts: &RawOptions) -> Result<LoadedVolume, LoadError> {
    let layout = layout(path, opts)?;
    let bytes = read_file(path)?;
    finish(layout, &bytes, path, LoadReport::new(VolumeFormat::Raw, path), HINT)
}

const HINT: &str = "check the dimensions and type in the file name (name_XxYxZ_dtype.raw), or give them with \
                    --dims XxYxZ --dtype TYPE (RawOptions::dims and ::dtype in code)";

/// The layout of raw file `path` from its name or `opts`, its size checked against it; reads
/// no voxels.
pub(super) fn layout(path: &Path, opts: &RawOptions) -> Result<Layout, LoadError> {
    let at = Location::file(path);
    let file_name = path.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let parsed = parse_raw_name(&file_name);
    let name = match &parsed {
        Some((name, _, _)) if !name.is_empty() => name.clone(),
        _ => super::stem(path),
    };
    let unknown = |what, field| LoadError::RawUnknownLayout { path: path.to_path_buf(), what, field };
    let dims = match (opts.dims, &parsed) {
        (Some(d), _) => [d.x as u64, d.y as u64, d.z as u64],
        (None, Some((_, dims, _))) => *dims,
        (None, None) => return Err(unknown("dimensions", "dims")),
    };
    let dtype =
        match (opts.dtype, &parsed) {
            (Some(t), _) => t,
            (None, Some((_, _, Some(token)))) => VoxelType::from_name(token).ok_or_else(|| {
                LoadError::UnsupportedType { at: at.clone(), found: token.clone(), supported: SUPPORTED }
            })?,
            (None, _) => return Err(unknown("type", "dtype")),
        };
    let dims = check_dims(&at, "dims", &format!("{}x{}x{}", dims[0], dims[1], dims[2]), dims)?;
    let expected = byte_count(dims, dtype).unwrap_or(u64::MAX);
    let hint = HINT;
    // Compare sizes before reading, so a wrong name never makes us read a huge file for nothing.
    let actual = std::fs::metadata(path).map_err(|source| LoadError::Io { path: path.to_path_buf(), source })?.len();
    if actual != expected {
        return Err(LoadError::DataSize {
            path: path.to_path_buf(),
            dims: dims_text(dims),
            dtype,
            expected,
            actual,
            hint,
        });
    }
    Ok(Layout { name, dims, dtype, order: opts.endianness, spacing: DVec3::ONE, orientation: Default::default() })
}
