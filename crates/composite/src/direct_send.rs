//! Direct-send compositing: process r owns tile r of the image (an equal range of pixels) and
//! receives every other process's non-empty spans in that tile; it composites the fragments in
//! visibility order. One round; N − 1 messages out of each process.

use crate::exchange::{Exchange, ExchangeError};
use crate::image::{Layer, Piece, PixelRange, over_front_to_back};
use crate::{CompositeStats, spans};

/// Composites `image` (this process's, premultiplied) with every other process's; `order` lists
/// the ranks front to back (the same on every process). `rows` bounds the rows this process's
/// image may be non-zero in (its box's screen rectangle; the whole image when unknown). Returns
/// this process's tile of the final image.
pub fn direct_send<E: Exchange + ?Sized>(
    ex: &mut E,
    image: &Layer,
    rows: std::ops::Range<u32>,
    order: &[usize],
) -> Result<(Piece, CompositeStats), ExchangeError> {
    let (rank, size) = (ex.rank(), ex.size());
    let whole = PixelRange { start: 0, end: image.len() };
    let width = image.width as usize;
    let drawn = PixelRange { start: rows.start as usize * width, end: (rows.end as usize * width).min(image.len()) };
    let mut stats = CompositeStats { rounds: 1, ..Default::default() };
    let mut outgoing = Vec::with_capacity(size - 1);
    for r in (0..size).filter(|&r| r != rank) {
        let tile = whole.part(r, size);
        let (a, b) = (tile.start.max(drawn.start), tile.end.min(drawn.end).max(tile.start.max(drawn.start)));
        let message = spans::encode(&image.pixels[a..b], a);
        stats.bytes_sent += message.len() as u64;
        stats.messages += 1;
        outgoing.push((r, message));
    }
    let others: Vec<usize> = (0..size).filter(|&r| r != rank).collect();
    let received = ex.exchange(outgoing, &others)?;
    let tile = whole.part(rank, size);
    // Front to back: each fragment goes under what is there, on its spans only (elsewhere it
    // is transparent and changes nothing).
    let mut acc = vec![[0.0f32; 4]; tile.len()];
    for &r in order {
        if r == rank {
            for (a, p) in acc.iter_mut().zip(&image.pixels[tile.start..tile.end]) {
                *a = over_front_to_back(*a, *p);
            }
            continue;
        }
        let Some(i) = others.iter().position(|&o| o == r) else { continue };
        spans::decode_into(&received[i], &mut acc, tile.start, |a, p| *a = over_front_to_back(*a, p))?;
    }
    Ok((Piece { range: tile, pixels: acc }, stats))
}
