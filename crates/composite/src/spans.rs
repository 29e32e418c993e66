//! Non-empty pixel spans: what travels between processes. A process's image is mostly empty
//! (its box covers a part of the screen, and rays that miss its box leave zeros), so each
//! message holds only runs of pixels with any non-zero channel:
//! `[run count, (start, length)…]` as u32 words, then the runs' pixels as f32, in the hosts'
//! byte order (the processes of one job share it).

use crate::exchange::ExchangeError;

fn is_empty(p: &[f32; 4]) -> bool {
    p[0] == 0.0 && p[1] == 0.0 && p[2] == 0.0 && p[3] == 0.0
}

/// The non-empty runs of `pixels`, whose first pixel is pixel `first` of the image.
pub fn encode(pixels: &[[f32; 4]], first: usize) -> Vec<u8> {
    let mut runs: Vec<(u32, u32)> = Vec::new();
    let mut i = 0;
    while i < pixels.len() {
        if is_empty(&pixels[i]) {
            i += 1;
            continue;
        }
        let start = i;
        while i < pixels.len() && !is_empty(&pixels[i]) {
            i += 1;
        }
        runs.push(((first + start) as u32, (i - start) as u32));
    }
    let count: usize = runs.iter().map(|r| r.1 as usize).sum();
    let mut bytes: Vec<u8> = Vec::with_capacity(4 * (1 + 2 * runs.len()) + 16 * count);
    bytes.extend_from_slice(&(runs.len() as u32).to_ne_bytes());
    for &(start, len) in &runs {
        bytes.extend_from_slice(&start.to_ne_bytes());
        bytes.extend_from_slice(&len.to_ne_bytes());
    }
    for &(start, len) in &runs {
        let from = start as usize - first;
        bytes.extend_from_slice(bytemuck::cast_slice(&pixels[from..from + len as usize]));
    }
    bytes
}

/// Applies every pixel of an encoded message to `image` (indexed by image pixel minus
/// `offset`, so a tile can be its own slice) with `apply`. Reads the message in place.
pub fn decode_into(
    message: &[u8],
    image: &mut [[f32; 4]],
    offset: usize,
    mut apply: impl FnMut(&mut [f32; 4], [f32; 4]),
) -> Result<(), ExchangeError> {
    let bad = |what: &str| ExchangeError::Malformed(what.to_string());
    if !message.len().is_multiple_of(4) || message.len() < 4 {
        return Err(bad("not a whole number of words"));
    }
    let word =
        |i: usize| u32::from_ne_bytes([message[4 * i], message[4 * i + 1], message[4 * i + 2], message[4 * i + 3]]);
    let words = message.len() / 4;
    let runs = word(0) as usize;
    let header = 1 + 2 * runs;
    if words < header {
        return Err(bad("runs past the end"));
    }
    let mut at = header;
    for r in 0..runs {
        let (start, len) = (word(1 + 2 * r) as usize, word(2 + 2 * r) as usize);
        if start < offset || start - offset + len > image.len() || at + 4 * len > words {
            return Err(bad("a run outside the image"));
        }
        let bytes = &message[4 * at..4 * (at + 4 * len)];
        for (dst, px) in image[start - offset..start - offset + len].iter_mut().zip(bytes.chunks_exact(16)) {
            let f = |c: usize| f32::from_ne_bytes([px[4 * c], px[4 * c + 1], px[4 * c + 2], px[4 * c + 3]]);
            apply(dst, [f(0), f(1), f(2), f(3)]);
        }
        at += 4 * len;
    }
    Ok(())
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
        assert_eq!(message.len(), 4 * (1 + 4 + 12), "two runs, three pixels");
        let mut image = vec![[0.0f32; 4]; 120];
        decode_into(&message, &mut image, 0, |d, s| *d = s).expect("decodes");
        assert_eq!(&image[100..120], &pixels[..]);
        assert!(decode_into(&message[..8], &mut image, 0, |d, s| *d = s).is_err());
        let mut tile = vec![[0.0f32; 4]; 20];
        decode_into(&message, &mut tile, 100, |d, s| *d = s).expect("decodes into a tile");
        assert_eq!(tile, pixels);
    }
}
