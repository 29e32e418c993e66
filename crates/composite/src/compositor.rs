//! The buffers compositing keeps from frame to frame, and what both algorithms share: the
//! front-to-back combination of one piece's fragments, and the gather onto rank 0.
//!
//! A frame's compositing touches a few times the image's bytes, so every copy shows. Allocating
//! messages and pieces anew each frame made the kernel fault in and zero every page (2 ranks at
//! 1024²: 23 ms with fresh buffers, 5.6 with kept ones, under perf); a [`Compositor`] keeps its
//! messages. And the pieces are
//! composited in place, in the caller's own image: this process's pixels stay where they are,
//! messages in front of them are laid over them and messages behind under them (over is
//! associative), and rank 0's image becomes the final one when the others' pieces arrive.

use crate::exchange::{Exchange, ExchangeError};
use crate::image::{Layer, PixelRange};
use crate::spans;

/// The messages each piece is gathered in ([`Compositor::gather`]): 8 overlap rank 0's decoding
/// with the others' encoding (2 ranks at 1024²: 5.6 → 4.5 ms, A/B in bench/distributed.md; 16
/// were no better).
pub const GATHER_PARTS: usize = 8;

/// Compositing's state across frames: run [`Compositor::direct_send`] or
/// [`Compositor::radix_k`] on this process's image, then [`Compositor::gather`] for rank 0's.
#[derive(Default)]
pub struct Compositor {
    /// Messages out, `(to, bytes)`.
    pub(crate) outgoing: Vec<(usize, Vec<u8>)>,
    /// Messages in, `(from, bytes)`.
    pub(crate) incoming: Vec<(usize, Vec<u8>)>,
    /// The pixels of the image this process composited (its piece of the final image).
    pub(crate) piece: PixelRange,
    /// Bytes this process sent in the last gather.
    gathered_bytes: u64,
}

/// One fragment of a piece: this process's own pixels (in place), or a message.
pub(crate) enum Fragment<'a> {
    Own,
    Received(&'a [u8]),
}

/// Combines `fragments`, front to back, in `pixels` — the piece `range` of this process's own
/// image, which is the [`Fragment::Own`] one: the messages before it in the order are laid over
/// it (nearest last), the ones after it under it. Without an own fragment the piece starts
/// transparent.
pub(crate) fn composite_in_place<'a>(
    pixels: &mut [[f32; 4]],
    range: PixelRange,
    fragments: impl IntoIterator<Item = Fragment<'a>>,
) -> Result<(), ExchangeError> {
    let fragments: Vec<Fragment<'a>> = fragments.into_iter().collect();
    let own = fragments.iter().position(|f| matches!(f, Fragment::Own));
    if own.is_none() {
        pixels.fill([0.0; 4]);
    }
    let split = own.unwrap_or(0);
    for fragment in fragments[..split].iter().rev() {
        if let Fragment::Received(message) = fragment {
            spans::decode_in_front(message, pixels, range.start)?;
        }
    }
    for fragment in &fragments[split..] {
        if let Fragment::Received(message) = fragment {
            spans::decode_behind(message, pixels, range.start)?;
        }
    }
    Ok(())
}

impl Compositor {
    /// New, with no buffers yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// The pixels of this process's image that hold its piece of the final image (after
    /// [`Compositor::direct_send`] or [`Compositor::radix_k`]).
    pub fn piece(&self) -> PixelRange {
        self.piece
    }

    /// The bytes this process sent in the last [`Compositor::gather`].
    pub fn gathered_bytes(&self) -> u64 {
        self.gathered_bytes
    }

    /// Collects every process's piece into rank 0's `image` (the one it composited), which
    /// then holds the final image: returns true there, false elsewhere. Only non-empty spans
    /// travel. The pieces must cover the image once (both algorithms' do).
    ///
    /// Each piece travels in [`GATHER_PARTS`] messages, so that rank 0 receives and decodes one
    /// part while the others encode the next (one message each left rank 0 waiting for the whole
    /// encode, then the others waiting for the whole decode).
    pub fn gather<E: Exchange + ?Sized>(&mut self, ex: &mut E, image: &mut Layer) -> Result<bool, ExchangeError> {
        let piece = self.piece;
        if ex.rank() != 0 {
            self.outgoing.resize_with(1, Default::default);
            self.gathered_bytes = 0;
            for part in 0..GATHER_PARTS {
                let p = piece.part(part, GATHER_PARTS);
                let (to, message) = &mut self.outgoing[0];
                *to = 0;
                spans::encode_into(message, &image.pixels[p.start..p.end], p.start);
                self.gathered_bytes += message.len() as u64;
                ex.exchange_into(&[(0, message.as_slice())], &mut [])?;
            }
            return Ok(false);
        }
        self.gathered_bytes = 0;
        self.incoming.resize_with(ex.size() - 1, Default::default);
        for (i, (from, _)) in self.incoming.iter_mut().enumerate() {
            *from = i + 1;
        }
        let mut covered = vec![(piece.start, piece.end)];
        for _ in 0..GATHER_PARTS {
            ex.exchange_into(&[], &mut self.incoming)?;
            for (_, message) in &self.incoming {
                let (a, b) = spans::extent(message)?;
                if (a < piece.end && piece.start < b) || b > image.len() {
                    return Err(ExchangeError::Malformed(format!("a piece {a}..{b} over rank 0's or past the image")));
                }
                covered.push((a, b));
                spans::decode_replace(message, &mut image.pixels, 0)?;
            }
        }
        // A pixel no piece spoke for would keep this process's own value.
        covered.sort_unstable();
        let mut at = 0;
        for (a, b) in covered {
            if a != at {
                return Err(ExchangeError::Malformed(format!("the pieces leave pixels {at}..{a} uncovered")));
            }
            at = b;
        }
        if at != image.len() {
            return Err(ExchangeError::Malformed(format!("the pieces cover {at} of {} pixels", image.len())));
        }
        Ok(true)
    }
}
