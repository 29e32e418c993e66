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
use super::checks;
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
        // The UID as the file spells it, on one line.
        uid: super::one_line(uid),
        name,
        supported: supported_transfer_syntaxes(),
    })
}

/// One frame's stored values, as the file holds them.
enum Stored {
    /// 1- to 16-bit samples and signed 32-bit ones.
    I32(Vec<i32>),
    /// Unsigned 32-bit samples (above 2³¹ too).
    U32(Vec<u32>),
    /// Float or Double Float Pixel Data (7FE0,0008 / 7FE0,0009), as float32.
    F32(Vec<f32>),
}

impl Stored {
    fn len(&self) -> usize {
        match self {
            Stored::I32(v) => v.len(),
            Stored::U32(v) => v.len(),
            Stored::F32(v) => v.len(),
        }
    }

    /// The smallest and largest stored value (NaN left out).
    fn range(&self) -> (f64, f64) {
        let fold = |it: &mut dyn Iterator<Item = f64>| {
            it.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)))
        };
        match self {
            Stored::I32(v) => fold(&mut v.iter().map(|&x| f64::from(x))),
            Stored::U32(v) => fold(&mut v.iter().map(|&x| f64::from(x))),
            Stored::F32(v) => fold(&mut v.iter().map(|&x| f64::from(x))),
        }
    }
}

/// One slice's stored values and its rescale.
struct Slice {
    stored: Stored,
    slope: f64,
    intercept: f64,
}

/// Reads the frames `ordered` (file index, frame) of `series` into voxels of `dims` (columns,
/// rows, slices), rescaled; with notes on what the conversion rounded.
pub fn read(
    series: &[FileHeader],
    ordered: &[(usize, usize)],
    dims: UVec3,
    progress: Option<Progress<'_>>,
) -> Result<(VoxelData, Vec<String>), LoadError> {
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
    let mut slices: Vec<&Slice> = Vec::with_capacity(ordered.len());
    for &(file, frame) in ordered {
        let slice = files[file].get(frame).ok_or_else(|| LoadError::DicomPixels {
            path: series[file].path.clone(),
            message: format!(
                "has no frame {frame}: the pixel data holds {} frame(s), fewer than NumberOfFrames (0028,0008); the file \
                 is truncated or its NumberOfFrames is wrong",
                files[file].len()
            ),
        })?;
        slices.push(slice);
    }

    let integral = slices
        .iter()
        .all(|s| s.slope.fract() == 0.0 && s.intercept.fract() == 0.0 && !matches!(s.stored, Stored::F32(_)));
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (s, &(file, _)) in slices.iter().zip(ordered) {
        let (a, b) = s.stored.range();
        if a > b {
            continue; // only NaN
        }
        for v in [a * s.slope + s.intercept, b * s.slope + s.intercept] {
            // Beyond float32 the values would be ±inf (a constant volume once normalized).
            if v.is_nan() || v.abs() > f64::from(f32::MAX) {
                return Err(LoadError::DicomPixels {
                    path: series[file].path.clone(),
                    message: format!(
                        "stored values {a} … {b} × RescaleSlope (0028,1053) {:e} + RescaleIntercept (0028,1052) {:e} \
                         reach {v:e}, beyond float32's ±3.4e38; the rescale is wrong: fix RescaleSlope/\
                         RescaleIntercept (e.g. with dcmodify) or remove the file",
                        s.slope, s.intercept
                    ),
                });
            }
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    let mut notes = Vec::new();
    let eight_bit = series.iter().all(|h| h.bits_allocated == 8);
    let out = if integral && eight_bit && lo >= 0.0 && hi <= 255.0 {
        VoxelData::U8(convert(&slices, |v| v as u8))
    } else if integral && lo >= -32768.0 && hi <= 32767.0 {
        VoxelData::I16(convert(&slices, |v| v as i16))
    } else if integral && lo >= 0.0 && hi <= 65535.0 {
        VoxelData::U16(convert(&slices, |v| v as u16))
    } else {
        if integral && lo.abs().max(hi.abs()) > 16_777_216.0 {
            notes.push(format!(
                "values {lo} … {hi} are stored as float32, which holds integers exactly only up to 2^24 = 16777216: \
                 larger ones are rounded to 24 significant bits"
            ));
        }
        VoxelData::F32(floats(&slices))
    };
    Ok((out, notes))
}

/// The rescaled values of `slices` as float32 (the caller checked their range).
fn floats(slices: &[&Slice]) -> Vec<f32> {
    let per: Vec<Vec<f32>> = slices
        .par_iter()
        .map(|s| {
            let f = |v: f64| (v * s.slope + s.intercept) as f32;
            match &s.stored {
                Stored::I32(v) => v.iter().map(|&x| f(f64::from(x))).collect(),
                Stored::U32(v) => v.iter().map(|&x| f(f64::from(x))).collect(),
                Stored::F32(v) => v.iter().map(|&x| f(f64::from(x))).collect(),
            }
        })
        .collect();
    per.concat()
}

/// The rescaled values of `slices`, in order, converted by `cast` (the caller checked that every
/// rescaled value is an integer in the target's range, and that no slice holds floats).
fn convert<T: Send + Copy>(slices: &[&Slice], cast: impl Fn(i64) -> T + Sync) -> Vec<T> {
    let per: Vec<Vec<T>> = slices
        .par_iter()
        .map(|s| {
            let (slope, intercept) = (s.slope as i64, s.intercept as i64);
            match &s.stored {
                Stored::I32(v) => v.iter().map(|&x| cast(i64::from(x) * slope + intercept)).collect(),
                Stored::U32(v) => v.iter().map(|&x| cast(i64::from(x) * slope + intercept)).collect(),
                Stored::F32(_) => Vec::new(),
            }
        })
        .collect();
    per.concat()
}

/// The stored values of one frame's native little-endian pixel bytes: `bits_allocated` per
/// sample (1-bit data comes one byte per pixel from the decoder), the low `bits_stored` of
/// them, sign-extended when `signed` (PS3.5 §8.1.1). Unsigned 32-bit values are kept whole.
fn stored_values(bytes: &[u8], bits_allocated: u16, bits_stored: u16, signed: bool) -> Option<Stored> {
    let stored = u32::from(bits_stored.clamp(1, bits_allocated.max(1)));
    let extend = |v: u32| -> i32 {
        let v = if stored < 32 { v & ((1u32 << stored) - 1) } else { v };
        if signed && stored < 32 && v >> (stored - 1) & 1 == 1 {
            (v | !((1u32 << stored) - 1)) as i32
        } else {
            v as i32
        }
    };
    let words = || bytes.chunks_exact(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]));
    Some(match bits_allocated {
        1 | 8 => Stored::I32(bytes.iter().map(|&b| extend(u32::from(b))).collect()),
        16 => Stored::I32(bytes.chunks_exact(2).map(|c| extend(u32::from(u16::from_le_bytes([c[0], c[1]])))).collect()),
        32 if signed => Stored::I32(words().map(extend).collect()),
        32 => Stored::U32(words().map(|v| if stored < 32 { v & ((1u32 << stored) - 1) } else { v }).collect()),
        _ => return None,
    })
}

/// `e` and its sources, `outer: inner: innermost` (dicom-rs's outer message alone says only
/// "Could not decode pixel data").
fn causes(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        let next = s.to_string();
        if !text.ends_with(&next) {
            text.push_str(": ");
            text.push_str(&next);
        }
        source = s.source();
    }
    // dicom-rs quotes what it read (a transfer syntax UID, a value): one line, escaped.
    super::one_line(&text)
}

fn read_file(h: &FileHeader, per_slice: usize) -> Result<Vec<Slice>, LoadError> {
    let pixels_error = |message: String| LoadError::DicomPixels { path: h.path.clone(), message };
    let object = dicom_object::open_file(&h.path)
        .map_err(|e| LoadError::DicomRead { path: h.path.clone(), reason: super::one_line(&e.to_string()) })?;
    let slice = |stored: Stored| Slice { stored, slope: h.rescale.0, intercept: h.rescale.1 };
    if let Some(values) = checks::float_pixels(h, &object, per_slice)? {
        return Ok(values
            .chunks_exact(per_slice)
            .take(h.frames as usize)
            .map(|c| slice(Stored::F32(c.to_vec())))
            .collect());
    }
    checks::pixel_data(h, &object, per_slice)?;
    let decoded = checks::guarded(&h.path, || object.decode_pixel_data())?
        .map_err(|e| pixels_error(format!("cannot decode the pixel data: {}", causes(&e))))?;
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
            let bytes = decoded.frame_data(frame).map_err(|e| pixels_error(format!("frame {frame}: {}", causes(&e))))?;
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
            Ok(slice(raw))
        })
        .collect()
}
