//! Direct-send compositing: process r owns tile r of the image (an equal range of pixels) and
//! receives every other process's non-empty spans in that tile; it composites the fragments in
//! visibility order. One round; N − 1 messages out of each process.

use crate::compositor::{Compositor, Fragment, composite_in_place};
use crate::exchange::{Exchange, ExchangeError};
use crate::image::{Layer, PixelRange};
use crate::{CompositeStats, spans};

impl Compositor {
    /// Composites `image` (this process's, premultiplied) with every other process's; `order`
    /// lists the ranks front to back (the same on every process). `rows` bounds the rows this
    /// process's image may be non-zero in (its box's screen rectangle; the whole image when
    /// unknown). Leaves this process's tile of the final image in place, in `image`'s pixels
    /// [`Compositor::piece`] (the rest of `image` is left as it was).
    pub fn direct_send<E: Exchange + ?Sized>(
        &mut self,
        ex: &mut E,
        image: &mut Layer,
        rows: std::ops::Range<u32>,
        order: &[usize],
    ) -> Result<CompositeStats, ExchangeError> {
        let (rank, size) = (ex.rank(), ex.size());
        let whole = PixelRange { start: 0, end: image.len() };
        let width = image.width as usize;
        let drawn =
            PixelRange { start: rows.start as usize * width, end: (rows.end as usize * width).min(image.len()) };
        let mut stats = CompositeStats { rounds: 1, ..Default::default() };
        let peers: Vec<usize> = (0..size).filter(|&r| r != rank).collect();
        self.outgoing.resize_with(peers.len(), Default::default);
        self.incoming.resize_with(peers.len(), Default::default);
        for ((out, inc), &r) in self.outgoing.iter_mut().zip(&mut self.incoming).zip(&peers) {
            let tile = whole.part(r, size);
            // The tile's drawn rows (none: an empty message at the tile's start).
            let a = tile.start.max(drawn.start).min(tile.end);
            let b = tile.end.min(drawn.end).max(a);
            out.0 = r;
            spans::encode_into(&mut out.1, &image.pixels[a..b], a);
            stats.bytes_sent += out.1.len() as u64;
            stats.messages += 1;
            inc.0 = r;
        }
        let sends: Vec<(usize, &[u8])> = self.outgoing.iter().map(|(r, m)| (*r, m.as_slice())).collect();
        ex.exchange_into(&sends, &mut self.incoming)?;
        let tile = whole.part(rank, size);
        let incoming = &self.incoming;
        let fragments = order.iter().filter_map(|&r| {
            if r == rank {
                Some(Fragment::Own)
            } else {
                incoming.iter().find(|(from, _)| *from == r).map(|(_, m)| Fragment::Received(m))
            }
        });
        composite_in_place(&mut image.pixels[tile.start..tile.end], tile, fragments)?;
        self.piece = tile;
        Ok(stats)
    }
}

#[cfg(test)]
mod tests {
    use crate::{Compositor, Layer, LocalGroup, over_front_to_back};

    /// Each rank drew only some rows (its box's screen rows), away from the other rank's tile:
    /// its message for that tile is empty and still lies in the tile.
    #[test]
    fn rows_outside_a_peers_tile_send_an_empty_message() {
        let (w, h) = (7u32, 10u32);
        let drawn = [0..3u32, 7..10u32];
        let layers: Vec<Layer> = drawn
            .iter()
            .enumerate()
            .map(|(r, rows)| {
                let mut l = Layer::transparent(w, h);
                for y in rows.clone() {
                    for x in 0..w {
                        let a = 0.1 + 0.05 * (x + r as u32) as f32;
                        l.pixels[(y * w + x) as usize] = [a * 0.5, a, 0.0, a];
                    }
                }
                l
            })
            .collect();
        let order = [1usize, 0];
        let images: Vec<Option<Layer>> = std::thread::scope(|s| {
            let handles: Vec<_> = LocalGroup::new(2)
                .into_iter()
                .zip(layers.iter().zip(&drawn))
                .map(|(mut ex, (layer, rows))| {
                    s.spawn(move || {
                        let mut image = layer.clone();
                        let mut compositor = Compositor::new();
                        compositor.direct_send(&mut ex, &mut image, rows.clone(), &order).expect("direct-send");
                        compositor.gather(&mut ex, &mut image).expect("gather").then_some(image)
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().expect("rank")).collect()
        });
        let image = images[0].as_ref().expect("rank 0 has the image");
        for (i, p) in image.pixels.iter().enumerate() {
            assert_eq!(*p, over_front_to_back(layers[1].pixels[i], layers[0].pixels[i]), "pixel {i}");
        }
    }
}
