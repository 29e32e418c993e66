//! Non-empty pixel spans: what travels between processes. A process's image is mostly empty
//! (its box covers a part of the screen, and rays that miss its box leave zeros), so each
//! message holds only runs of pixels with any non-zero channel:
//! `[run count, (start, length)…]` as u32 words, then the runs' pixels as f32.

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
    let mut words: Vec<u32> = Vec::with_capacity(1 + 2 * runs.len() + 4 * count);
    words.push(runs.len() as u32);
    for &(start, len) in &runs {
        words.extend([start, len]);
    }
    for &(start, len) in &runs {
        let from = start as usize - first;
        for p in &pixels[from..from + len as usize] {
            words.extend(p.map(f32::to_bits));
        }
    }
    bytemuck::cast_slice(&words).to_vec()
}

/// Applies every pixel of an encoded message to `image` (indexed by image pixel) with `apply`.
pub fn decode_into(
    message: &[u8],
    image: &mut [[f32; 4]],
    mut apply: impl FnMut(&mut [f32; 4], [f32; 4]),
) -> Result<(), ExchangeError> {
    let bad = |what: &str| ExchangeError::Malformed(what.to_string());
    if message.len() % 4 != 0 || message.len() < 4 {
        return Err(bad("not a whole number of words"));
    }
    let words: Vec<u32> = message.chunks_exact(4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
    let runs = words[0] as usize;
    let header = 1 + 2 * runs;
    if words.len() < header {
        return Err(bad("runs past the end"));
    }
    let mut at = header;
    for r in 0..runs {
        let (start, len) = (words[1 + 2 * r] as usize, words[2 + 2 * r] as usize);
        if start + len > image.len() || at + 4 * len > words.len() {
            return Err(bad("a run outside the image"));
        }
        for (i, dst) in image[start..start + len].iter_mut().enumerate() {
            let w = &words[at + 4 * i..at + 4 * i + 4];
            apply(dst, [f32::from_bits(w[0]), f32::from_bits(w[1]), f32::from_bits(w[2]), f32::from_bits(w[3])]);
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
        decode_into(&message, &mut image, |d, s| *d = s).expect("decodes");
        assert_eq!(&image[100..120], &pixels[..]);
        assert!(decode_into(&message[..8], &mut image, |d, s| *d = s).is_err());
    }
}
