//! Radix-k compositing (Peterka, Goodell, Ross, Shen & Thakur 2009, "A configurable algorithm
//! for parallel image-compositing applications"), as IceT implements it: N = k₁·k₂·…, and in
//! round i groups of kᵢ processes that share a part of the image split it into kᵢ pieces; each
//! member receives its piece from the other kᵢ − 1 and composites them. After the last round
//! each process holds 1/N of the image. k = 2 in every round is binary swap; one round of
//! k = N is direct-send.
//!
//! The groups follow the kd-tree of the decomposition (`volgraph_accel::kd_split`): round i
//! combines the children of one tree node, which are contiguous in every visibility order, so
//! compositing each group in its children's order gives the single-process image.

use crate::compositor::{Compositor, Fragment, composite_in_place};
use crate::exchange::{Exchange, ExchangeError};
use crate::image::{Layer, PixelRange};
use crate::{CompositeStats, spans};

impl Compositor {
    /// Composites `image` over `factors.len()` rounds. `factors[i]` is the group size of round
    /// i (bottom of the kd-tree first; their product is the number of processes, rank digits as
    /// in `kd_split::rank_digits`), and `orders[i]` the front-to-back order of this process's
    /// group's members in round i, as digits (the kd-tree node's children order for the eye).
    /// Leaves this process's piece of the final image in place, in `image`'s pixels
    /// [`Compositor::piece`]; each round's piece lies inside the round before's.
    pub fn radix_k<E: Exchange + ?Sized>(
        &mut self,
        ex: &mut E,
        image: &mut Layer,
        factors: &[usize],
        orders: &[Vec<usize>],
    ) -> Result<CompositeStats, ExchangeError> {
        let rank = ex.rank();
        // What this process holds of the image: all of it at first, then its piece of each
        // round.
        let mut range = PixelRange { start: 0, end: image.len() };
        let mut stats = CompositeStats::default();
        let mut stride = 1;
        for (round, &k) in factors.iter().enumerate() {
            if k == 1 {
                continue;
            }
            let digit = (rank / stride) % k;
            let base = rank - digit * stride;
            let member = |c: usize| base + c * stride;
            self.outgoing.resize_with(k - 1, Default::default);
            self.incoming.resize_with(k - 1, Default::default);
            let others = (0..k).filter(|&c| c != digit);
            for ((out, inc), c) in self.outgoing.iter_mut().zip(&mut self.incoming).zip(others) {
                let piece = range.part(c, k);
                out.0 = member(c);
                spans::encode_into(&mut out.1, &image.pixels[piece.start..piece.end], piece.start);
                stats.bytes_sent += out.1.len() as u64;
                stats.messages += 1;
                inc.0 = member(c);
            }
            let sends: Vec<(usize, &[u8])> = self.outgoing.iter().map(|(r, m)| (*r, m.as_slice())).collect();
            ex.exchange_into(&sends, &mut self.incoming)?;
            let mine = range.part(digit, k);
            let incoming = &self.incoming;
            let fragments = orders[round].iter().map(|&c| {
                if c == digit {
                    Fragment::Own
                } else {
                    Fragment::Received(&incoming[if c < digit { c } else { c - 1 }].1)
                }
            });
            composite_in_place(&mut image.pixels[mine.start..mine.end], mine, fragments)?;
            range = mine;
            stride *= k;
            stats.rounds += 1;
        }
        self.piece = range;
        Ok(stats)
    }
}

#[cfg(test)]
mod tests {
    use crate::image::over_front_to_back;
    use crate::{Compositor, Exchange, Layer, LocalGroup};

    /// N random layers composited by both algorithms equal the sequential front-to-back over.
    fn check(factors: &[usize], order_of: impl Fn(usize) -> Vec<usize> + Sync) {
        let n: usize = factors.iter().product();
        let (w, h) = (37u32, 23u32);
        let layers: Vec<Layer> = (0..n)
            .map(|r| {
                let mut l = Layer::transparent(w, h);
                for (i, p) in l.pixels.iter_mut().enumerate() {
                    let x = ((i * 7919 + r * 104729) % 1000) as f32 / 1000.0;
                    // Some empty pixels, so spans are exercised.
                    if (i + r) % 5 != 0 {
                        let a = x * 0.8;
                        *p = [a * 0.9, a * 0.5, a * (1.0 - x), a];
                    }
                }
                l
            })
            .collect();
        // The global front-to-back order implied by per-round digit orders.
        let order = order_of(0);
        let mut expected = Layer::transparent(w, h);
        for &r in &order {
            for (e, p) in expected.pixels.iter_mut().zip(&layers[r].pixels) {
                *e = over_front_to_back(*e, *p);
            }
        }
        for algorithm in ["direct", "radix"] {
            let images: Vec<Option<Layer>> = std::thread::scope(|s| {
                let handles: Vec<_> = LocalGroup::new(n)
                    .into_iter()
                    .zip(&layers)
                    .map(|(mut ex, layer)| {
                        let order = &order;
                        s.spawn(move || {
                            let mut compositor = Compositor::new();
                            let mut image = layer.clone();
                            // Twice: the second frame reuses the first one's buffers.
                            let mut whole = false;
                            for _ in 0..2 {
                                image.clone_from(layer);
                                if algorithm == "direct" {
                                    compositor.direct_send(&mut ex, &mut image, 0..h, order).expect("direct");
                                } else {
                                    let orders = round_orders(factors, order, ex.rank());
                                    compositor.radix_k(&mut ex, &mut image, factors, &orders).expect("radix");
                                }
                                whole = compositor.gather(&mut ex, &mut image).expect("gather");
                            }
                            whole.then_some(image)
                        })
                    })
                    .collect();
                handles.into_iter().map(|h| h.join().expect("thread")).collect()
            });
            let image = images[0].as_ref().expect("rank 0 has the image");
            for (i, (a, b)) in image.pixels.iter().zip(&expected.pixels).enumerate() {
                for c in 0..4 {
                    // Both orders of the same f32 additions: a few ulps.
                    assert!((a[c] - b[c]).abs() < 1e-5, "{algorithm} {factors:?} pixel {i}: {a:?} vs {b:?}");
                }
            }
            assert!(images[1..].iter().all(Option::is_none));
        }
    }

    /// The digit orders of each round that a global order over a tree of `factors` implies
    /// (the order must be tree-consistent: every subtree contiguous).
    fn round_orders(factors: &[usize], order: &[usize], rank: usize) -> Vec<Vec<usize>> {
        let mut stride = 1;
        let mut out = Vec::new();
        for &k in factors {
            // This group's members by digit, ordered by their first appearance in `order`.
            let block = stride * k;
            let group_base = rank / block * block;
            let mut digits: Vec<usize> = Vec::new();
            for &r in order {
                if r / block * block == group_base {
                    let c = (r / stride) % k;
                    if !digits.contains(&c) {
                        digits.push(c);
                    }
                }
            }
            out.push(digits);
            stride *= k;
        }
        out
    }

    #[test]
    fn binary_swap_of_four_equals_sequential_over() {
        check(&[2, 2], |_| vec![2, 3, 0, 1]);
    }

    #[test]
    fn radix_three_then_two_equals_sequential_over() {
        check(&[3, 2], |_| vec![4, 3, 5, 1, 0, 2]);
    }

    #[test]
    fn one_round_of_three_equals_sequential_over() {
        check(&[3], |_| vec![1, 2, 0]);
    }
}
