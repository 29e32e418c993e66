//! What is checked of a file's pixel data before a decoder sees it, and how a decoder runs.
//! Sizes are compared with the bytes present before anything is allocated from a header's
//! word: native PixelData must hold Rows × Columns × NumberOfFrames samples; RLE Lossless
//! (PS3.5 Annex G) must have one fragment per frame, a 64-byte header claiming 1 to 15 segments
//! (as many as the samples' bytes), offsets inside the fragment, and segments that decode to a
//! whole plane; a JPEG 2000 codestream's SIZ marker must declare Columns × Rows ×
//! SamplesPerPixel. The third-party decoders (dicom-rs's adapters, OpenJPEG) run under
//! `catch_unwind`: a panic in them becomes an error naming the file, never an abort.

use std::cell::RefCell;
use std::path::Path;
use std::sync::Once;

use dicom_core::value::{PrimitiveValue, Value};
use dicom_dictionary_std::tags;
use dicom_object::DefaultDicomObject;

use super::header::FileHeader;
use crate::load::LoadError;

/// RLE Lossless.
const RLE_LOSSLESS: &str = "1.2.840.10008.1.2.5";
/// Bytes of an RLE frame's header: the segment count and 15 offsets (PS3.5 G.5).
const RLE_HEADER_BYTES: usize = 64;

fn error(h: &FileHeader, message: String) -> LoadError {
    LoadError::DicomPixels { path: h.path.clone(), message }
}

thread_local! {
    /// Set while a decoder runs on this thread: its panic is reported as an error, not printed
    /// (the location, for the message, is kept here by the hook).
    static DECODING: RefCell<Option<Option<String>>> = const { RefCell::new(None) };
}

/// Installs, once, a panic hook that stays quiet for a panic inside [`guarded`] (keeping its
/// location for the error) and hands every other panic to the hook that was there before.
fn quiet_decoder_panics() {
    static HOOK: Once = Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let inside = DECODING.with(|d| {
                let mut d = d.borrow_mut();
                match d.as_mut() {
                    Some(location) => {
                        *location = info.location().map(|l| format!("{}:{}", l.file(), l.line()));
                        true
                    }
                    None => false,
                }
            });
            if !inside {
                previous(info);
            }
        }));
    });
}

/// Runs `decode` (a third-party decoder) on `path`'s pixel data; a panic in it becomes an error
/// naming the file, the panic's message and where in the decoder it happened.
pub fn guarded<T>(path: &Path, decode: impl FnOnce() -> T) -> Result<T, LoadError> {
    quiet_decoder_panics();
    DECODING.with(|d| *d.borrow_mut() = Some(None));
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(decode));
    let location = DECODING.with(|d| d.borrow_mut().take()).flatten();
    result.map_err(|payload| {
        let message = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .map_or_else(|| "(no message)".to_string(), |m| super::one_line(&m));
        LoadError::DicomPixels {
            path: path.to_path_buf(),
            message: format!(
                "the pixel decoder failed ({message}, at {}); the pixel data is corrupt: remove the file or copy it \
                 again",
                location.as_deref().unwrap_or("an unknown place")
            ),
        }
    })
}

/// Fails unless `object`'s PixelData holds what the header promises (see the module doc).
pub fn pixel_data(h: &FileHeader, object: &DefaultDicomObject, per_slice: usize) -> Result<(), LoadError> {
    let Some(element) = object.get(tags::PIXEL_DATA) else {
        return Err(error(
            h,
            "has no pixel data (no PixelData (7FE0,0010), Float Pixel Data (7FE0,0008) or Double Float Pixel Data \
             (7FE0,0009)); the file is not an image or was cut short: remove it or copy it again"
                .to_string(),
        ));
    };
    let frames = h.frames as usize;
    if let Some(fragments) = element.value().fragments() {
        if h.transfer_syntax == RLE_LOSSLESS {
            return rle(h, fragments, per_slice);
        }
        if fragments.is_empty() {
            return Err(error(
                h,
                "PixelData (7FE0,0010) holds no compressed fragment; the file is corrupt".to_string(),
            ));
        }
        if JPEG_2000.contains(&h.transfer_syntax.as_str()) {
            return jpeg2000(h, fragments);
        }
        return Ok(());
    }
    let bytes = element.to_bytes().map(|b| b.len()).unwrap_or(0) as u128;
    let bits = u128::from(h.bits_allocated);
    let needed = (per_slice as u128 * frames as u128 * bits).div_ceil(8);
    if bytes < needed {
        return Err(error(
            h,
            format!(
                "PixelData (7FE0,0010) holds {bytes} bytes, but Rows × Columns × NumberOfFrames ({per_slice} × {frames}) \
                 pixels of BitsAllocated {bits} need {needed}; the file is truncated (copy it again) or its Rows, \
                 Columns, NumberOfFrames or BitsAllocated are wrong"
            ),
        ));
    }
    Ok(())
}

/// JPEG 2000 (lossless, lossy) and High-Throughput JPEG 2000 transfer syntaxes.
const JPEG_2000: [&str; 5] = [
    "1.2.840.10008.1.2.4.90",
    "1.2.840.10008.1.2.4.91",
    "1.2.840.10008.1.2.4.201",
    "1.2.840.10008.1.2.4.202",
    "1.2.840.10008.1.2.4.203",
];

/// The size every JPEG 2000 codestream among `fragments` declares in its SIZ marker (ITU-T
/// T.800 A.5.1: SOC, then SIZ with Xsiz, Ysiz, XOsiz, YOsiz … Csiz, big-endian) must be the
/// header's Columns × Rows × SamplesPerPixel: OpenJPEG decodes, and allocates, at the size the
/// codestream claims. A fragment that does not start a codestream (a frame's continuation) is
/// left to the decoder.
fn jpeg2000(h: &FileHeader, fragments: &[Vec<u8>]) -> Result<(), LoadError> {
    let Some(first) = h.frame_geometry.first() else { return Ok(()) };
    for (index, fragment) in fragments.iter().enumerate() {
        if !fragment.starts_with(&[0xFF, 0x4F, 0xFF, 0x51]) {
            continue;
        }
        let bad = |what: String| {
            error(
                h,
                format!(
                    "JPEG 2000 fragment {index}: {what}; the pixel data is corrupt: remove the file or copy it again"
                ),
            )
        };
        let Some(siz) = fragment.get(4..42) else {
            return Err(bad(format!("{} bytes, cut short inside its SIZ marker (42 bytes)", fragment.len())));
        };
        let word = |at: usize| u32::from_be_bytes([siz[at], siz[at + 1], siz[at + 2], siz[at + 3]]);
        let (xsiz, ysiz, x0, y0) = (word(4), word(8), word(12), word(16));
        let components = u16::from_be_bytes([siz[36], siz[37]]);
        let (Some(width), Some(height)) = (xsiz.checked_sub(x0), ysiz.checked_sub(y0)) else {
            return Err(bad(format!(
                "its SIZ marker puts the image origin ({x0}, {y0}) past its end ({xsiz}, {ysiz})"
            )));
        };
        if (width, height, components) != (first.columns, first.rows, h.samples_per_pixel) {
            return Err(bad(format!(
                "the codestream's SIZ marker says {width} × {height} pixels of {components} component(s), but Columns \
                 × Rows (0028,0011 × 0028,0010) are {} × {} of SamplesPerPixel {}",
                first.columns, first.rows, h.samples_per_pixel
            )));
        }
    }
    Ok(())
}

/// The checks of RLE Lossless `fragments` (one per frame) that keep dicom-rs's RLE adapter from
/// indexing past a short segment or allocating what a junk header claims.
fn rle(h: &FileHeader, fragments: &[Vec<u8>], per_slice: usize) -> Result<(), LoadError> {
    if fragments.len() != h.frames as usize {
        return Err(error(
            h,
            format!(
                "RLE pixel data holds {} fragment(s), but NumberOfFrames (0028,0008) is {}; RLE Lossless stores each \
                 frame in one fragment: the file is corrupt or truncated",
                fragments.len(),
                h.frames
            ),
        ));
    }
    let bytes_per_sample = usize::from(h.bits_allocated / 8);
    let expected = bytes_per_sample * usize::from(h.samples_per_pixel);
    for (frame, fragment) in fragments.iter().enumerate() {
        let bad = |what: String| {
            error(h, format!("RLE frame {frame}: {what}; the pixel data is corrupt: remove the file or copy it again"))
        };
        if fragment.len() < RLE_HEADER_BYTES {
            return Err(bad(format!("{} bytes, shorter than the 64-byte RLE header", fragment.len())));
        }
        let word = |i: usize| {
            u32::from_le_bytes([fragment[4 * i], fragment[4 * i + 1], fragment[4 * i + 2], fragment[4 * i + 3]])
        };
        let count = word(0) as usize;
        if !(1..=15).contains(&count) {
            return Err(bad(format!("the header claims {} segments; the standard allows 1 to 15", word(0))));
        }
        if count != expected {
            return Err(bad(format!(
                "the header has {count} segment(s), but BitsAllocated {} × SamplesPerPixel {} need {expected}",
                h.bits_allocated, h.samples_per_pixel
            )));
        }
        let mut offsets: Vec<usize> = (1..=count).map(|i| word(i) as usize).collect();
        if let Some((k, start)) =
            offsets.iter().enumerate().find(|(_, o)| !(RLE_HEADER_BYTES..=fragment.len()).contains(o))
        {
            return Err(bad(format!(
                "segment {k} starts at byte {start}, outside {RLE_HEADER_BYTES}..={} of the fragment",
                fragment.len()
            )));
        }
        offsets.push(fragment.len());
        for (k, pair) in offsets.windows(2).enumerate() {
            let (start, end) = (pair[0], pair[1]);
            if start > end {
                return Err(bad(format!("segment {k} starts at byte {start}, after segment {} at {end}", k + 1)));
            }
            let decoded = packbits_len(&fragment[start..end]);
            if decoded < per_slice {
                return Err(bad(format!(
                    "segment {k} decodes to {decoded} bytes, fewer than the {per_slice} pixels of Rows × Columns"
                )));
            }
        }
    }
    Ok(())
}

/// How many bytes PackBits `data` decodes to (PS3.5 G.3.1), counted without decoding.
fn packbits_len(data: &[u8]) -> usize {
    let (mut at, mut out) = (0usize, 0usize);
    while at < data.len() {
        let header = data[at] as i8;
        at += 1;
        if header >= 0 {
            let literal = header as usize + 1;
            out += literal.min(data.len() - at);
            at += literal;
        } else if header != -128 {
            if at < data.len() {
                out += (1 - isize::from(header)) as usize;
            }
            at += 1;
        }
    }
    out
}

/// The values of Float Pixel Data (7FE0,0008) or Double Float Pixel Data (7FE0,0009), as
/// float32, all frames in order; `None` when the file has neither.
pub fn float_pixels(
    h: &FileHeader,
    object: &DefaultDicomObject,
    per_slice: usize,
) -> Result<Option<Vec<f32>>, LoadError> {
    let (element, name, width) = match (object.get(tags::FLOAT_PIXEL_DATA), object.get(tags::DOUBLE_FLOAT_PIXEL_DATA)) {
        (Some(e), _) => (e, "Float Pixel Data (7FE0,0008)", 4),
        (None, Some(e)) => (e, "Double Float Pixel Data (7FE0,0009)", 8),
        (None, None) => return Ok(None),
    };
    let values: Vec<f32> = match element.value() {
        Value::Primitive(PrimitiveValue::F32(v)) => v.to_vec(),
        Value::Primitive(PrimitiveValue::F64(v)) => v.iter().map(|&x| x as f32).collect(),
        Value::Primitive(PrimitiveValue::U8(b)) if width == 4 => {
            b.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect()
        }
        Value::Primitive(PrimitiveValue::U8(b)) => b
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]) as f32)
            .collect(),
        _ => return Err(error(h, format!("{name} does not hold floating-point values; the file is corrupt"))),
    };
    let needed = per_slice as u128 * u128::from(h.frames);
    if (values.len() as u128) < needed {
        return Err(error(
            h,
            format!(
                "{name} holds {} values, but Rows × Columns × NumberOfFrames ({per_slice} × {}) need {needed}; the file \
                 is truncated (copy it again) or its Rows, Columns or NumberOfFrames are wrong",
                values.len(),
                h.frames
            ),
        ));
    }
    Ok(Some(values))
}

#[cfg(test)]
mod tests {
    use super::{guarded, packbits_len};

    #[test]
    fn a_panic_in_a_decoder_is_an_error_naming_the_file_and_where() {
        let path = std::path::Path::new("scan/IM0001");
        let e = guarded(path, || -> u8 { panic!("index out of bounds") }).expect_err("an error").to_string();
        assert!(e.starts_with("scan/IM0001: the pixel decoder failed (index out of bounds, at "), "{e}");
        assert!(e.contains("checks.rs:"), "the panic's place: {e}");
        assert_eq!(guarded(path, || 7).expect("no panic"), 7);
    }

    #[test]
    fn packbits_counts_runs_and_literals() {
        // A run of 3 (0xFE = -2), a literal of 2, a no-op, a cut literal (claims 4, has 1).
        assert_eq!(packbits_len(&[0xFE, 7, 0x01, 1, 2, 0x80, 0x03, 9]), 3 + 2 + 1);
        assert_eq!(packbits_len(&[0xFE]), 0, "a run without its byte decodes to nothing");
    }
}
