//! Which brick sits in which slot of the GPU brick pool, and in what batches a frame draws them
//! (Ruijters & Vilanova 2006 §5–6: bricks are drawn front to back; a volume that does not fit
//! in texture memory is streamed). Pure bookkeeping with no GPU in it, so it is tested on its
//! own; [`crate::raycast_bricks`] does the uploads and dispatches it plans.
//!
//! A frame's bricks (the non-empty ones, front to back) are cut into batches of at most the
//! pool's slot count. For each batch, bricks already resident are kept and the others take a
//! free slot or the least recently used one whose brick is not in the batch. When everything
//! fits there is one batch and, after the first frame, no upload at all; when it does not, the
//! pool thrashes — slower, never wrong, since every batch holds the bricks it draws.

/// One batch of a frame: the bricks drawn together and where they are.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Batch {
    /// `(brick, slot)` of every brick the batch draws, front to back.
    pub bricks: Vec<(u32, u32)>,
    /// `(brick, slot)` of those that must be uploaded before the batch runs.
    pub uploads: Vec<(u32, u32)>,
}

/// Slot assignment with least-recently-used eviction.
#[derive(Clone, Debug)]
pub struct BrickPool {
    /// Per slot: the brick it holds.
    brick_in_slot: Vec<Option<u32>>,
    /// Per slot: the batch clock when it was last drawn.
    last_used: Vec<u64>,
    /// Per brick: its slot, if resident.
    slot_of: Vec<Option<u32>>,
    clock: u64,
}

impl BrickPool {
    /// An empty pool of `slots` slots for a volume of `bricks` bricks.
    pub fn new(slots: u32, bricks: usize) -> Self {
        Self {
            brick_in_slot: vec![None; slots as usize],
            last_used: vec![0; slots as usize],
            slot_of: vec![None; bricks],
            clock: 0,
        }
    }

    /// Number of slots.
    pub fn slots(&self) -> u32 {
        self.brick_in_slot.len() as u32
    }

    /// Bricks resident now.
    pub fn resident(&self) -> usize {
        self.brick_in_slot.iter().filter(|b| b.is_some()).count()
    }

    /// Adds `more` slots (the pool grew: a transfer function made more bricks visible); what is
    /// resident stays where it is.
    pub fn grow(&mut self, more: u32) {
        self.brick_in_slot.extend(std::iter::repeat_n(None, more as usize));
        self.last_used.extend(std::iter::repeat_n(0, more as usize));
    }

    /// The batches that draw `order` (brick indices, front to back), assigning slots and noting
    /// the uploads. With no slots, nothing can be drawn: no batch.
    pub fn plan_frame(&mut self, order: &[u32]) -> Vec<Batch> {
        let capacity = self.slots() as usize;
        if capacity == 0 {
            return Vec::new();
        }
        let mut batches = Vec::with_capacity(order.len().div_ceil(capacity));
        for chunk in order.chunks(capacity) {
            self.clock += 1;
            // Keep what is resident: those slots are not victims for this batch.
            for &b in chunk {
                if let Some(s) = self.slot_of[b as usize] {
                    self.last_used[s as usize] = self.clock;
                }
            }
            let mut batch = Batch::default();
            for &b in chunk {
                let slot = match self.slot_of[b as usize] {
                    Some(s) => s,
                    None => {
                        let s = self.victim();
                        if let Some(old) = self.brick_in_slot[s as usize] {
                            self.slot_of[old as usize] = None;
                        }
                        self.brick_in_slot[s as usize] = Some(b);
                        self.slot_of[b as usize] = Some(s);
                        self.last_used[s as usize] = self.clock;
                        batch.uploads.push((b, s));
                        s
                    }
                };
                batch.bricks.push((b, slot));
            }
            batches.push(batch);
        }
        batches
    }

    /// A free slot, else the least recently used one not used by the current batch (one exists:
    /// a batch holds at most as many bricks as there are slots).
    fn victim(&self) -> u32 {
        if let Some(free) = self.brick_in_slot.iter().position(Option::is_none) {
            return free as u32;
        }
        let (slot, _) = self
            .last_used
            .iter()
            .enumerate()
            .filter(|(_, used)| **used < self.clock)
            .min_by_key(|(_, used)| **used)
            .expect("a batch never holds more bricks than slots");
        slot as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn everything_fits_one_batch_and_a_second_frame_uploads_nothing() {
        let mut pool = BrickPool::new(8, 20);
        let first = pool.plan_frame(&[3, 1, 7]);
        assert_eq!(first.len(), 1);
        assert_eq!(first[0].uploads.len(), 3);
        let second = pool.plan_frame(&[7, 3, 1]);
        assert_eq!(second.len(), 1);
        assert!(second[0].uploads.is_empty());
        assert_eq!(second[0].bricks.iter().map(|(b, _)| *b).collect::<Vec<_>>(), vec![7, 3, 1]);
    }

    /// A pool smaller than the frame: batches of at most `slots` bricks, each brick in exactly
    /// one batch, in order, and every batch's bricks in distinct slots holding them.
    #[test]
    fn a_small_pool_draws_every_brick_once_in_order_in_distinct_slots() {
        let mut pool = BrickPool::new(3, 10);
        let order: Vec<u32> = vec![9, 2, 5, 0, 7, 1, 4];
        for _frame in 0..3 {
            let batches = pool.plan_frame(&order);
            assert_eq!(batches.len(), 3);
            let drawn: Vec<u32> = batches.iter().flat_map(|b| b.bricks.iter().map(|(b, _)| *b)).collect();
            assert_eq!(drawn, order);
            for batch in &batches {
                let mut slots: Vec<u32> = batch.bricks.iter().map(|(_, s)| *s).collect();
                slots.sort_unstable();
                slots.dedup();
                assert_eq!(slots.len(), batch.bricks.len(), "distinct slots in {batch:?}");
                assert!(batch.bricks.len() <= 3);
            }
        }
    }

    /// LRU keeps what the next batch needs when it can: the last batch of a frame stays
    /// resident, so a frame that needs only those bricks uploads nothing.
    #[test]
    fn the_least_recently_used_slot_is_evicted() {
        let mut pool = BrickPool::new(2, 6);
        pool.plan_frame(&[0, 1, 2, 3]);
        let again = pool.plan_frame(&[2, 3]);
        assert!(again[0].uploads.is_empty(), "{again:?}");
        let next = pool.plan_frame(&[4]);
        assert_eq!(next[0].uploads.len(), 1);
        pool.grow(2);
        assert_eq!(pool.slots(), 4);
        assert_eq!(pool.resident(), 2);
    }
}
