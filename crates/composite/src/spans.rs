//! Non-empty pixel spans: what travels between processes. A process's image is mostly empty
//! (its box covers a part of the screen, and rays that miss its box leave zeros), so each
//! message holds only runs of pixels with any non-zero channel: `[first, end, run count]` as
//! u32 words — the pixels `[first, end)` the message speaks for, zero outside its runs — then
//! the runs' pixels as f32, then the runs' `(start, length)` as u32 words, in the hosts' byte
//! order (the processes of one job share it). The table comes last so that one pass over the
//! image finds each run and copies it.
//!
//! Messages are written into a caller's buffer ([`encode_into`]) and read in place
//! ([`decode_behind`], [`decode_in_front`], [`decode_replace`]): a compositor that keeps its
//! buffers from frame to frame allocates (and page-faults) nothing after the first.

use crate::exchange::ExchangeError;
use crate::image::over_front_to_back;

const ZERO: [f32; 4] = [0.0; 4];

/// Every channel's bits zero (a `-0.0` counts as a value: it travels, harmlessly).
#[inline]
fn is_empty(p: &[f32; 4]) -> bool {
    (p[0].to_bits() | p[1].to_bits() | p[2].to_bits() | p[3].to_bits()) == 0
}

/// The non-empty runs of `pixels`, whose first pixel is pixel `first` of the image, written
/// over `out` (its capacity reused).
pub fn encode_into(out: &mut Vec<u8>, pixels: &[[f32; 4]], first: usize) {
    out.clear();
    out.extend_from_slice(bytemuck::cast_slice(&[first as u32, (first + pixels.len()) as u32, 0]));
    let mut table: Vec<u32> = Vec::new();
    let mut i = 0;
    while let Some(skip) = pixels[i..].iter().position(|p| !is_empty(p)) {
        let start = i + skip;
        let len = pixels[start..].iter().position(is_empty).unwrap_or(pixels.len() - start);
        out.extend_from_slice(bytemuck::cast_slice(&pixels[start..start + len]));
        table.extend([(first + start) as u32, len as u32]);
        i = start + len;
    }
    out[8..12].copy_from_slice(&((table.len() / 2) as u32).to_ne_bytes());
    out.extend_from_slice(bytemuck::cast_slice(&table));
}

/// The non-empty runs of `pixels` as a new message (see [`encode_into`]).
pub fn encode(pixels: &[[f32; 4]], first: usize) -> Vec<u8> {
    let mut out = Vec::new();
    encode_into(&mut out, pixels, first);
    out
}

fn word(message: &[u8], i: usize) -> u32 {
    u32::from_ne_bytes([message[4 * i], message[4 * i + 1], message[4 * i + 2], message[4 * i + 3]])
}

/// A checked view of a message: the pixels it speaks for and its runs.
struct Message<'a> {
    first: usize,
    end: usize,
    table: &'a [u8],
    pixels: &'a [u8],
}

impl<'a> Message<'a> {
    fn parse(message: &'a [u8]) -> Result<Self, ExchangeError> {
        let bad = |what: &str| ExchangeError::Malformed(what.to_string());
        if !message.len().is_multiple_of(4) || message.len() < 12 {
            return Err(bad("not a whole number of words"));
        }
        let (first, end, runs) = (word(message, 0) as usize, word(message, 1) as usize, word(message, 2) as usize);
        let table_bytes = runs.checked_mul(8).ok_or_else(|| bad("runs past the end"))?;
        if end < first || message.len() < 12 + table_bytes {
            return Err(bad("runs past the end"));
        }
        let table_start = message.len() - table_bytes;
        let (pixels, table) = (&message[12..table_start], &message[table_start..]);
        let mut previous_end = first;
        let mut count = 0usize;
        for run in table.chunks_exact(8) {
            let (start, len) = (word(run, 0) as usize, word(run, 1) as usize);
            if start < previous_end || start + len > end {
                return Err(bad("a run outside its pixels or out of order"));
            }
            previous_end = start + len;
            count += len;
        }
        if count.checked_mul(16) != Some(pixels.len()) {
            return Err(bad("the runs' pixels do not match the message's length"));
        }
        Ok(Self { first, end, table, pixels })
    }

    /// Each run as (first image pixel, its pixels' bytes), in order.
    fn runs(&self) -> impl Iterator<Item = (usize, &'a [u8])> + '_ {
        let mut at = 0;
        self.table.chunks_exact(8).map(move |run| {
            let (start, len) = (word(run, 0) as usize, word(run, 1) as usize);
            let bytes = &self.pixels[at..at + 16 * len];
            at += 16 * len;
            (start, bytes)
        })
    }

    /// Checks the message's pixels lie in `image`, whose first pixel is image pixel `offset`.
    fn check_fits(&self, image_len: usize, offset: usize) -> Result<(), ExchangeError> {
        if self.first < offset || self.end - offset > image_len {
            return Err(ExchangeError::Malformed("a message's pixels outside the receiver's part".into()));
        }
        Ok(())
    }
}

fn pixel(bytes: &[u8]) -> [f32; 4] {
    let f = |c: usize| f32::from_ne_bytes([bytes[4 * c], bytes[4 * c + 1], bytes[4 * c + 2], bytes[4 * c + 3]]);
    [f(0), f(1), f(2), f(3)]
}

/// Lays a message's pixels behind what `image` holds (`image` over the message), `image`
/// indexed by image pixel minus `offset` so a piece can be its own slice. Outside the runs the
/// message is transparent and nothing changes.
pub fn decode_behind(message: &[u8], image: &mut [[f32; 4]], offset: usize) -> Result<(), ExchangeError> {
    decode_with(message, image, offset, over_front_to_back)
}

/// Lays a message's pixels in front of what `image` holds (the message over `image`), indexed
/// as in [`decode_behind`].
pub fn decode_in_front(message: &[u8], image: &mut [[f32; 4]], offset: usize) -> Result<(), ExchangeError> {
    decode_with(message, image, offset, |a, p| over_front_to_back(p, a))
}

fn decode_with(
    message: &[u8],
    image: &mut [[f32; 4]],
    offset: usize,
    combine: impl Fn([f32; 4], [f32; 4]) -> [f32; 4],
) -> Result<(), ExchangeError> {
    let m = Message::parse(message)?;
    m.check_fits(image.len(), offset)?;
    for (start, bytes) in m.runs() {
        let dst = &mut image[start - offset..start - offset + bytes.len() / 16];
        match bytemuck::try_cast_slice::<u8, [f32; 4]>(bytes) {
            Ok(src) => {
                for (a, p) in dst.iter_mut().zip(src) {
                    *a = combine(*a, *p);
                }
            }
            Err(_) => {
                for (a, px) in dst.iter_mut().zip(bytes.chunks_exact(16)) {
                    *a = combine(*a, pixel(px));
                }
            }
        }
    }
    Ok(())
}

/// Writes every pixel the message speaks for into `image` (indexed as in [`decode_behind`]): its
/// runs, and zero between them.
pub fn decode_replace(message: &[u8], image: &mut [[f32; 4]], offset: usize) -> Result<(), ExchangeError> {
    let m = Message::parse(message)?;
    m.check_fits(image.len(), offset)?;
    let mut at = m.first;
    for (start, bytes) in m.runs() {
        image[at - offset..start - offset].fill(ZERO);
        let dst = &mut image[start - offset..start - offset + bytes.len() / 16];
        bytemuck::cast_slice_mut::<[f32; 4], u8>(dst).copy_from_slice(bytes);
        at = start + bytes.len() / 16;
    }
    image[at - offset..m.end - offset].fill(ZERO);
    Ok(())
}

/// The pixels `[first, end)` a message speaks for.
pub fn extent(message: &[u8]) -> Result<(usize, usize), ExchangeError> {
    Message::parse(message).map(|m| (m.first, m.end))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spans_round_trip_and_skip_empty_pixels() {
        let mut pixels = vec![[0.0f32; 4]; 20];
        pixels[3] = [0.1, 0.2, 0.3, 0.4];
        pixels[4] = [0.0, 0.0, 0.0, 0.5];
        pixels[19] = [1.0, 0.0, 0.0, 1.0];
        let message = encode(&pixels, 100);
        assert_eq!(message.len(), 4 * (3 + 4 + 12), "two runs, three pixels");
        assert_eq!(extent(&message), Ok((100, 120)));
        let mut image = vec![[0.0f32; 4]; 120];
        decode_behind(&message, &mut image, 0).expect("decodes");
        assert_eq!(&image[100..120], &pixels[..]);
        assert!(decode_behind(&message[..8], &mut image, 0).is_err());
        assert!(decode_behind(&message[..message.len() - 16], &mut image, 0).is_err(), "a pixel short");
        let mut half = vec![[0.0, 0.0, 0.5, 0.5]; 120];
        decode_in_front(&message, &mut half, 0).expect("decodes");
        assert_eq!(half[103], over_front_to_back(pixels[3], [0.0, 0.0, 0.5, 0.5]), "the message in front");
        assert_eq!(half[105], [0.0, 0.0, 0.5, 0.5], "untouched between runs");
        let mut tile = vec![[7.0f32; 4]; 20];
        decode_replace(&message, &mut tile, 100).expect("decodes into a tile");
        assert_eq!(tile, pixels, "replace writes zeros between the runs");
        assert!(decode_replace(&message, &mut tile, 101).is_err(), "a message outside the tile");
    }

    #[test]
    fn a_buffer_is_reused_and_an_empty_image_is_a_header() {
        let mut buffer = encode(&[[1.0, 1.0, 1.0, 1.0]; 64], 0);
        let capacity = buffer.capacity();
        encode_into(&mut buffer, &[[0.0; 4]; 64], 64);
        assert_eq!(buffer.len(), 12);
        assert_eq!(buffer.capacity(), capacity);
        let mut image = vec![[2.0f32; 4]; 128];
        decode_replace(&buffer, &mut image, 0).expect("decodes");
        assert!(image[..64].iter().all(|p| *p == [2.0; 4]) && image[64..].iter().all(|p| *p == [0.0; 4]));
    }
}
