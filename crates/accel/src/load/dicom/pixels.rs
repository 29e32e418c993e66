//! A series' pixels: decoded by `dicom-pixeldata` (native, RLE lossless and the JPEG family of
//! its pure-Rust codecs), rescaled by RescaleSlope/Intercept and stored in the narrowest type
//! that holds the rescaled values exactly.

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use dicom_encoding::transfer_syntax::TransferSyntaxIndex;
use dicom_pixeldata::PixelDecoder;
use dicom_transfer_syntax_registry::TransferSyntaxRegistry;
use glam::UVec3;
use rayon::prelude::*;

use super::Progress;
use super::header::FileHeader;
use crate::load::LoadError;
use crate::volume::VoxelData;

/// The transfer syntaxes whose pixel data this build decodes, by name.
pub fn supported_transfer_syntaxes() -> String {
    let mut names: Vec<String> = TransferSyntaxRegistry
        .iter()
        .filter(|ts| ts.can_decode_all())
        .map(|ts| format!("{} ({})", ts.name(), ts.uid().trim_end_matches('\0')))
        .collect();
    names.sort();
    names.join(", ")
}

/// Fails unless this build can decode `uid`'s pixel data.
pub fn check_transfer_syntax(path: &Path, uid: &str) -> Result<(), LoadError> {
    let uid = uid.trim_end_matches('\0');
    let name = match TransferSyntaxRegistry.get(uid) {
        Some(ts) if ts.can_decode_all() => return Ok(()),
        Some(ts) => ts.name().to_string(),
        None => "an unknown transfer syntax".to_string(),
    };
    Err(LoadError::DicomTransferSyntax {
        path: path.to_path_buf(),
        uid: uid.to_string(),
        name,
        supported: supported_transfer_syntaxes(),
    })
}

/// One slice's stored values and its rescale.
struct Slice {
    raw: Vec<i32>,
    slope: f64,
    intercept: f64,
}

/// Reads the frames `ordered` (file index, frame) of `series` into voxels of `dims` (columns,
/// rows, slices), rescaled.
pub fn read(
    series: &[FileHeader],
    ordered: &[(usize, usize)],
    dims: UVec3,
    progress: Option<Progress<'_>>,
) -> Result<VoxelData, LoadError> {
    let per_slice = dims.x as usize * dims.y as usize;
    let done = AtomicUsize::new(0);
    // Each file is opened once, all its frames taken.
    let files: Vec<Result<Vec<Slice>, LoadError>> = series
        .par_iter()
        .map(|h| {
            let slices = read_file(h, per_slice);
            if let Some(report) = progress {
                report(done.fetch_add(1, Ordering::Relaxed) + 1, series.len());
            }
            slices
        })
        .collect();
    let files: Vec<Vec<Slice>> = files.into_iter().collect::<Result<_, _>>()?;
    let slices: Vec<&Slice> = ordered.iter().map(|&(file, frame)| &files[file][frame]).collect();

    let integral = slices.iter().all(|s| s.slope.fract() == 0.0 && s.intercept.fract() == 0.0);
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for s in &slices {
        let (a, b) = s.raw.iter().fold((i32::MAX, i32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
        for v in [a as f64 * s.slope + s.intercept, b as f64 * s.slope + s.intercept] {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    let eight_bit = series.iter().all(|h| h.bits_allocated == 8);
    let gather = |f: &(dyn Fn(f64) -> f64 + Sync)| -> Vec<f64> {
        // Only for the float path; integer paths convert directly below.
        slices.iter().flat_map(|s| s.raw.iter().map(move |&v| f(v as f64 * s.slope + s.intercept))).collect()
    };
    let out = if integral && eight_bit && lo >= 0.0 && hi <= 255.0 {
        VoxelData::U8(convert(&slices, |v| v as u8))
    } else if integral && lo >= -32768.0 && hi <= 32767.0 {
        VoxelData::I16(convert(&slices, |v| v as i16))
    } else if integral && lo >= 0.0 && hi <= 65535.0 {
        VoxelData::U16(convert(&slices, |v| v as u16))
    } else {
        VoxelData::F32(gather(&|v| v).into_iter().map(|v| v as f32).collect())
    };
    Ok(out)
}

/// The rescaled values of `slices`, in order, converted by `cast` (the caller checked that every
/// rescaled value is an integer in the target's range).
fn convert<T: Send + Copy>(slices: &[&Slice], cast: impl Fn(i64) -> T + Sync) -> Vec<T> {
    let per: Vec<Vec<T>> = slices
        .par_iter()
        .map(|s| {
            let (slope, intercept) = (s.slope as i64, s.intercept as i64);
            s.raw.iter().map(|&v| cast(v as i64 * slope + intercept)).collect()
        })
        .collect();
    per.concat()
}

/// The stored values of one frame's native little-endian pixel bytes: `bits_allocated` per
/// sample (1-bit data comes one byte per pixel from the decoder), the low `bits_stored` of
/// them, sign-extended when `signed` (PS3.5 §8.1.1). 32-bit values beyond `i32` are clamped.
fn stored_values(bytes: &[u8], bits_allocated: u16, bits_stored: u16, signed: bool) -> Option<Vec<i32>> {
    let stored = u32::from(bits_stored.clamp(1, bits_allocated.max(1)));
    let extend = |v: u32| -> i32 {
        let v = if stored < 32 { v & ((1u32 << stored) - 1) } else { v };
        if signed && stored < 32 && v >> (stored - 1) & 1 == 1 {
            (v | !((1u32 << stored) - 1)) as i32
        } else if signed {
            v as i32
        } else {
            v.min(i32::MAX as u32) as i32
        }
    };
    Some(match bits_allocated {
        1 | 8 => bytes.iter().map(|&b| extend(u32::from(b))).collect(),
        16 => bytes.chunks_exact(2).map(|c| extend(u32::from(u16::from_le_bytes([c[0], c[1]])))).collect(),
        32 => bytes.chunks_exact(4).map(|c| extend(u32::from_le_bytes([c[0], c[1], c[2], c[3]]))).collect(),
        _ => return None,
    })
}

fn read_file(h: &FileHeader, per_slice: usize) -> Result<Vec<Slice>, LoadError> {
    let pixels_error = |message: String| LoadError::DicomPixels { path: h.path.clone(), message };
    let object = dicom_object::open_file(&h.path)
        .map_err(|e| LoadError::DicomRead { path: h.path.clone(), reason: e.to_string() })?;
    let decoded = object.decode_pixel_data().map_err(|e| pixels_error(format!("cannot decode the pixel data: {e}")))?;
    if decoded.samples_per_pixel() != 1 {
        return Err(pixels_error(format!(
            "has {} samples per pixel (a colour image); volgraph renders scalar volumes",
            decoded.samples_per_pixel()
        )));
    }
    let (bits, stored) = (decoded.bits_allocated(), decoded.bits_stored());
    let signed = decoded.pixel_representation() == dicom_pixeldata::PixelRepresentation::Signed;
    (0..h.frames)
        .map(|frame| {
            let bytes = decoded.frame_data(frame).map_err(|e| pixels_error(format!("frame {frame}: {e}")))?;
            let raw = stored_values(bytes, bits, stored, signed).ok_or_else(|| {
                pixels_error(format!(
                    "BitsAllocated {bits} is not supported; volgraph reads 1-, 8-, 16- and 32-bit greyscale pixels"
                ))
            })?;
            if raw.len() != per_slice {
                return Err(pixels_error(format!(
                    "frame {frame} holds {} pixels, but Rows × Columns is {per_slice}; the file is truncated or corrupt",
                    raw.len()
                )));
            }
            Ok(Slice { raw, slope: h.rescale.0, intercept: h.rescale.1 })
        })
        .collect()
}
