//! Where a NIfTI file's voxels lie: the header's sizes, datatype, frame and `vox_offset`
//! checked, and the byte range of the one frame read (checked arithmetic: a header may claim
//! anything).

use std::path::Path;

use glam::UVec3;

use super::header::{self, Header, ReadValue};
use super::read_error;
use crate::load::{LoadError, Location};

/// The datatypes read, as a message lists them.
const SUPPORTED: &str = "uint8, int8, int16, uint16, int32, uint32, int64, uint64, float32, float64 (scalar)";

/// Where the wanted voxels lie in the file and how to read them.
pub(super) struct Layout {
    /// Voxels along the file's axes i, j, k (`dim[1..=3]`).
    pub(super) file_dims: UVec3,
    /// Volumes in the file (`dim[4]`) and the one read.
    pub(super) frames: u64,
    pub(super) frame: u64,
    /// The datatype's name, bytes per voxel and reader.
    pub(super) type_name: &'static str,
    pub(super) size: usize,
    pub(super) read: ReadValue,
    /// Byte range of the frame in the (inflated) file.
    pub(super) start: u64,
    pub(super) frame_bytes: u64,
    pub(super) end: u64,
    /// What was defaulted, for the report.
    pub(super) notes: Vec<String>,
}

/// The error for a file that holds fewer bytes than the header asks for; `found` says how many
/// it holds.
pub(super) fn size_error(path: &Path, l: &Layout, found: &str) -> LoadError {
    let d = l.file_dims;
    let frame = if l.frames > 1 { format!(" of frame {} (of {})", l.frame, l.frames) } else { String::new() };
    read_error(
        path,
        format!(
            "{}x{}x{} {} voxels{frame} need {} bytes from byte {} (to byte {}), but {found}; the file is truncated (copy \
             it again) or its header (dim, datatype, vox_offset) is wrong",
            d.x, d.y, d.z, l.type_name, l.frame_bytes, l.start, l.end
        ),
    )
}

/// Checks the header's sizes, type, frame and offset, and where the voxels lie.
pub(super) fn layout(path: &Path, h: &Header, frame: Option<u64>) -> Result<Layout, LoadError> {
    let ndim = h.dim[0];
    if !(2..=7).contains(&ndim) {
        return Err(LoadError::NotThreeD { at: Location::file(path), field: "dim[0]", found: ndim.to_string() });
    }
    let n = ndim as usize;
    let text = h.dim[1..=n].iter().map(i64::to_string).collect::<Vec<_>>().join(" × ");
    if let Some(i) = (1..=n).find(|&i| h.dim[i] < 1) {
        return Err(read_error(
            path,
            format!("dim[{i}] is {} (dim = {text}); every axis needs at least one voxel", h.dim[i]),
        ));
    }
    if let Some(i) = (5..=n).find(|&i| h.dim[i] > 1) {
        return Err(read_error(
            path,
            format!(
                "dim = {text}: dim[{i}] = {} makes this vector or higher-dimensional data; volgraph reads scalar 3D \
                 volumes and 4D series of them",
                h.dim[i]
            ),
        ));
    }
    let axis = |i: usize| if i <= n { h.dim[i] as u64 } else { 1 };
    let frames = axis(4);
    let frame = match frame {
        None if frames > 1 => {
            return Err(LoadError::NiftiFrame {
                path: path.to_path_buf(),
                frames,
                what: "no --frame was given".into(),
            });
        }
        None | Some(0) => 0,
        Some(_) if frames == 1 => {
            return Err(LoadError::OptionDoesNotApply {
                path: path.to_path_buf(),
                option: "--frame",
                reason: "picks a volume of a 4D NIfTI file, but this file holds a single 3D volume: there are no \
                         frames to pick",
            });
        }
        Some(f) if f >= frames => {
            return Err(LoadError::NiftiFrame {
                path: path.to_path_buf(),
                frames,
                what: format!("--frame {f} is past the end"),
            });
        }
        Some(f) => f,
    };
    let file_dims = crate::load::check_dims(&Location::file(path), "dim", &text, [axis(1), axis(2), axis(3)])?;
    let type_name = header::datatype_name(h.datatype);
    let (size, read) = header::element(h.datatype).ok_or_else(|| LoadError::UnsupportedType {
        at: Location::file(path),
        found: match type_name {
            Some(name) => format!("NIfTI datatype {} ({name})", h.datatype),
            None => format!("NIfTI datatype {}", h.datatype),
        },
        supported: SUPPORTED,
    })?;
    let mut notes = Vec::new();
    let first = if h.version == 1 { 352 } else { 544 };
    if !(h.vox_offset.is_finite() && h.vox_offset >= 0.0) {
        return Err(read_error(
            path,
            format!(
                "vox_offset is {}; it must be the byte offset of the voxels, at least {first} in a .nii file",
                h.vox_offset
            ),
        ));
    }
    // `as` saturates: an offset past any file is caught by the length check.
    let mut offset = h.vox_offset as u64;
    if offset < first {
        notes.push(format!(
            "vox_offset {} lies inside the header; the voxels are read from byte {first}, right after it",
            h.vox_offset
        ));
        offset = first;
    }
    let voxels = (file_dims.x as u64).checked_mul(file_dims.y as u64).and_then(|v| v.checked_mul(file_dims.z as u64));
    let frame_bytes = voxels.and_then(|v| v.checked_mul(size as u64));
    let start = frame_bytes.and_then(|b| b.checked_mul(frame)).and_then(|b| b.checked_add(offset));
    let (Some(frame_bytes), Some(start)) = (frame_bytes, start) else {
        return Err(read_error(
            path,
            format!(
                "dim = {text} of {} voxels from byte {offset}: more bytes than any file holds; the header is corrupt",
                type_name.unwrap_or("?")
            ),
        ));
    };
    let Some(end) = start.checked_add(frame_bytes) else {
        return Err(read_error(path, format!("vox_offset {offset}: past the end of any file; the header is corrupt")));
    };
    Ok(Layout {
        file_dims,
        frames,
        frame,
        type_name: type_name.unwrap_or("?"),
        size,
        read,
        start,
        frame_bytes,
        end,
        notes,
    })
}
