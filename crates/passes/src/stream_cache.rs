//! Which bricks of which level the streaming raycaster ([`crate::raycast_stream`]) holds, what
//! its rays asked for, and in what order they are read: ray-guided streaming after Hadwiger et
//! al. 2012 §5 (the rays report the bricks they needed and lacked; only those are read) and
//! Crassin et al. 2009 §5 (usage feedback drives a least-recently-used cache). Pure bookkeeping
//! with no GPU in it, tested on its own.
//!
//! Every brick of every level has one page-table word: 0 while nothing is known or it is not
//! resident, [`EMPTY_BRICK`] when its value range is transparent under the transfer function
//! (never read, leapt over), or its slot's word ([`slot_word`]) once resident. The coarsest
//! level is read first and pinned, so a ray always finds something to draw. After each frame
//! the feedback (per brick: wanted and missing, drawn) becomes the requests — coarse before
//! fine, near before far — and the slots drawn from are stamped with the frame, so eviction
//! takes the least recently drawn and never one the last frame drew.

use std::collections::HashSet;

use glam::{DVec3, IVec3, UVec3};
use volgraph_accel::brick_leaves::{slot_coord, slot_word};
use volgraph_accel::pyramid::PyramidLevel;

/// The page-table word of a brick that is transparent under the transfer function.
pub const EMPTY_BRICK: u32 = 0x4000_0000;
/// Feedback bit: a ray wanted this brick and it was not resident.
pub const WANTED: u32 = 1;
/// Feedback bit: a ray drew from this brick.
pub const DRAWN: u32 = 2;

/// The bricks of one level.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LevelBricks {
    /// Voxels per axis.
    pub dims: UVec3,
    /// Level-0 voxels per voxel of this level.
    pub factor: DVec3,
    /// Bricks per axis.
    pub grid: UVec3,
    /// Page-table index of brick (0, 0, 0).
    pub first: u32,
}

/// The bricks of every level and where each sits in the page table.
#[derive(Clone, Debug, PartialEq)]
pub struct StreamLayout {
    /// Voxels per brick side (its own; the slot adds the apron).
    pub brick_cells: u32,
    /// Finest first.
    pub levels: Vec<LevelBricks>,
    entries: u32,
}

/// The most page-table entries: the words leave bit 30 to [`EMPTY_BRICK`].
const MAX_ENTRIES: u64 = 1 << 28;

impl StreamLayout {
    /// The bricks of `levels` at `brick_cells` voxels per side; an error when they are too many
    /// for the page table.
    pub fn new(levels: &[PyramidLevel], brick_cells: u32) -> Result<Self, String> {
        let mut out = Vec::with_capacity(levels.len());
        let mut first = 0u64;
        for level in levels {
            let grid = (level.dims + brick_cells - 1) / brick_cells;
            out.push(LevelBricks { dims: level.dims, factor: level.factor, grid, first: first as u32 });
            first += grid.as_u64vec3().element_product();
            if first > MAX_ENTRIES {
                return Err(format!(
                    "{first} bricks of {brick_cells}³ voxels are more than the page table's {MAX_ENTRIES}; raise \
                     brick_cells"
                ));
            }
        }
        Ok(Self { brick_cells, levels: out, entries: first as u32 })
    }

    /// Bricks of all levels.
    pub fn entries(&self) -> u32 {
        self.entries
    }

    /// The level and brick of page-table entry `entry`.
    pub fn locate(&self, entry: u32) -> (usize, UVec3) {
        let l = self.levels.iter().rposition(|l| l.first <= entry).unwrap_or(0);
        let g = self.levels[l].grid;
        let i = entry - self.levels[l].first;
        (l, UVec3::new(i % g.x, (i / g.x) % g.y, i / (g.x * g.y)))
    }

    /// The entries of level `level`.
    pub fn level_entries(&self, level: usize) -> std::ops::Range<u32> {
        let l = &self.levels[level];
        l.first..l.first + l.grid.element_product()
    }

    /// The voxels a slot holds for a brick (of any level): its own and `apron` more on every
    /// side (a box past the level's faces; the source clamps it).
    pub fn slot_box(&self, brick: UVec3, apron: u32) -> (IVec3, UVec3) {
        let lo = (brick * self.brick_cells).as_ivec3() - IVec3::splat(apron as i32);
        (lo, UVec3::splat(self.brick_cells + 2 * apron))
    }

    /// The centre of `entry`'s brick in level-0 voxel coordinates (ordering requests near first).
    pub fn centre(&self, entry: u32) -> DVec3 {
        let (l, b) = self.locate(entry);
        let level = &self.levels[l];
        (b.as_dvec3() + 0.5) * f64::from(self.brick_cells) * level.factor
    }
}

/// What one frame's feedback and arrivals did (the pass's counters).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StreamCounts {
    /// Bricks requested this frame.
    pub requested: u64,
    /// Bricks that arrived and were placed this frame.
    pub placed: u64,
    /// Bricks that arrived transparent (marked empty, no slot).
    pub arrived_empty: u64,
    /// Bricks that found no slot: the pool holds what the last frame drew and no more.
    pub refused: u64,
}

/// Residency, requests and eviction.
#[derive(Clone, Debug)]
pub struct StreamCache {
    layout: StreamLayout,
    /// Page-table words, one per entry.
    table: Vec<u32>,
    /// Per entry: its value range (normalized, apron included) once known.
    ranges: Vec<Option<(f32, f32)>>,
    /// Per entry: its slot, if resident.
    slot_of: Vec<Option<u32>>,
    /// Per slot: the entry it holds.
    entry_in_slot: Vec<Option<u32>>,
    /// Per slot: the frame it was last drawn from (or filled).
    last_drawn: Vec<u64>,
    /// Per slot: never evicted (the coarsest level).
    pinned: Vec<bool>,
    /// Slots per atlas axis.
    atlas_slots: UVec3,
    /// Requested, not arrived.
    pending: HashSet<u32>,
    /// Refused for want of a slot; not asked for again until the view changes.
    refused: HashSet<u32>,
    frame: u64,
    dirty: bool,
    /// Bit l: the last feedback's frame drew from a brick of level l.
    drawn_levels: u32,
    /// Bricks the last feedback's frame wanted and lacked (pending ones included).
    missing: usize,
}

impl StreamCache {
    /// An empty cache of `slots` slots (laid out `atlas_slots` per axis) for `layout`.
    pub fn new(layout: StreamLayout, atlas_slots: UVec3) -> Self {
        let entries = layout.entries() as usize;
        let slots = atlas_slots.element_product() as usize;
        Self {
            layout,
            table: vec![0; entries],
            ranges: vec![None; entries],
            slot_of: vec![None; entries],
            entry_in_slot: vec![None; slots],
            last_drawn: vec![0; slots],
            pinned: vec![false; slots],
            atlas_slots,
            pending: HashSet::new(),
            refused: HashSet::new(),
            frame: 0,
            dirty: true,
            drawn_levels: 0,
            missing: 0,
        }
    }

    /// The layout.
    pub fn layout(&self) -> &StreamLayout {
        &self.layout
    }

    /// The page table; `take_dirty` says whether it changed since last asked.
    pub fn table(&self) -> &[u32] {
        &self.table
    }

    /// Whether the page table changed since the last call (then upload it).
    pub fn take_dirty(&mut self) -> bool {
        std::mem::replace(&mut self.dirty, false)
    }

    /// Slots in all.
    pub fn slots(&self) -> u32 {
        self.entry_in_slot.len() as u32
    }

    /// Bricks resident.
    pub fn resident(&self) -> usize {
        self.entry_in_slot.iter().filter(|e| e.is_some()).count()
    }

    /// Requested and not arrived.
    pub fn pending(&self) -> usize {
        self.pending.len()
    }

    /// Bricks known to be empty.
    pub fn empty(&self) -> usize {
        self.table.iter().filter(|w| **w == EMPTY_BRICK).count()
    }

    /// Bricks the frame of the last feedback wanted and lacked (drawn coarser), pending or not,
    /// but not those refused for want of a slot: 0 means that frame drew everything at the level
    /// it wanted, or as close as the pool allows.
    pub fn missing(&self) -> usize {
        self.missing
    }

    /// Bit l set: the frame of the last feedback drew from level l.
    pub fn drawn_levels(&self) -> u32 {
        self.drawn_levels
    }

    /// Refused for want of a slot since the view last changed.
    pub fn refused(&self) -> usize {
        self.refused.len()
    }

    /// Sets every brick's word for a new transfer function: resident bricks keep their slots;
    /// a brick whose range is known (read, or `known` from the source's metadata) is
    /// [`EMPTY_BRICK`] where `visible` says its range shows nothing, else 0 until read.
    pub fn classify(&mut self, visible: impl Fn(f32, f32) -> bool, known: impl Fn(u32) -> Option<(f32, f32)>) {
        for e in 0..self.table.len() {
            if self.slot_of[e].is_some() {
                continue;
            }
            if self.ranges[e].is_none() {
                self.ranges[e] = known(e as u32);
            }
            self.table[e] = match self.ranges[e] {
                Some((lo, hi)) if !visible(lo, hi) => EMPTY_BRICK,
                _ => 0,
            };
        }
        // A brick refused or pending under the old function may now be empty or wanted anew.
        self.refused.clear();
        self.dirty = true;
    }

    /// One frame's feedback (one word per entry, [`WANTED`] | [`DRAWN`]): stamps the slots drawn
    /// from and returns the bricks to read — wanted, not resident, not pending, not known empty,
    /// not refused — coarse before fine, then nearest `eye` (level-0 voxels) first.
    pub fn feedback(&mut self, flags: &[u32], eye: DVec3) -> Vec<u32> {
        self.frame += 1;
        let mut wanted = Vec::new();
        self.drawn_levels = 0;
        self.missing = 0;
        for (e, &f) in flags.iter().enumerate().take(self.table.len()) {
            // A brick refused for want of a slot stays coarser until the view changes: not missing.
            self.missing += usize::from(f & WANTED != 0 && !self.refused.contains(&(e as u32)));
            if f & DRAWN != 0
                && let Some(s) = self.slot_of[e]
            {
                self.last_drawn[s as usize] = self.frame;
                self.drawn_levels |= 1 << self.layout.locate(e as u32).0.min(31);
            }
            let e = e as u32;
            if f & WANTED != 0
                && self.table[e as usize] == 0
                && !self.pending.contains(&e)
                && !self.refused.contains(&e)
            {
                wanted.push(e);
            }
        }
        let layout = &self.layout;
        wanted.sort_by(|a, b| {
            let (la, lb) = (layout.locate(*a).0, layout.locate(*b).0);
            lb.cmp(&la).then_with(|| {
                let (da, db) = (layout.centre(*a).distance_squared(eye), layout.centre(*b).distance_squared(eye));
                da.total_cmp(&db)
            })
        });
        self.pending.extend(wanted.iter().copied());
        wanted
    }

    /// The view changed: bricks refused for want of a slot may fit now.
    pub fn view_changed(&mut self) {
        self.refused.clear();
    }

    /// A request dropped before it was read (the queue was cut): it may be asked for again.
    pub fn dropped(&mut self, entry: u32) {
        self.pending.remove(&entry);
    }

    /// Brick `entry` was read with value range `range` (`None`: it could not be read; drawn
    /// empty). Returns the slot to upload it to, or `None` when it needs none (transparent, or no
    /// slot is free of what the last frame drew: refused).
    pub fn arrived(
        &mut self,
        entry: u32,
        range: Option<(f32, f32)>,
        visible: bool,
        counts: &mut StreamCounts,
    ) -> Option<u32> {
        self.pending.remove(&entry);
        let e = entry as usize;
        self.ranges[e] = range;
        if self.slot_of[e].is_some() {
            return None;
        }
        if range.is_none() || !visible {
            self.table[e] = EMPTY_BRICK;
            self.dirty = true;
            counts.arrived_empty += 1;
            return None;
        }
        let pin = self.layout.locate(entry).0 + 1 == self.layout.levels.len();
        let Some(slot) = self.victim(pin) else {
            self.refused.insert(entry);
            counts.refused += 1;
            return None;
        };
        if let Some(old) = self.entry_in_slot[slot as usize].replace(entry) {
            self.slot_of[old as usize] = None;
            self.table[old as usize] = 0;
        }
        self.slot_of[e] = Some(slot);
        self.last_drawn[slot as usize] = self.frame;
        self.pinned[slot as usize] = pin;
        self.table[e] = slot_word(slot_coord(slot, self.atlas_slots));
        self.dirty = true;
        counts.placed += 1;
        Some(slot)
    }

    /// A free slot, else the least recently drawn one not drawn by the last frame and not
    /// pinned; a pinned brick (the coarsest level) may take any unpinned slot.
    fn victim(&self, pin: bool) -> Option<u32> {
        if let Some(free) = self.entry_in_slot.iter().position(Option::is_none) {
            return Some(free as u32);
        }
        (0..self.entry_in_slot.len())
            .filter(|&s| !self.pinned[s] && (pin || self.last_drawn[s] < self.frame))
            .min_by_key(|&s| self.last_drawn[s])
            .map(|s| s as u32)
    }
}

/// Sub-blocks per brick axis: a brick's occupancy is 8×8×8 bits (`SUB_BLOCKS` in
/// shaders/raycast_stream.wgsl), [`SUB_WORDS`] words.
pub const SUB_BLOCKS: u32 = 8;
/// Occupancy words per slot.
pub const SUB_WORDS: usize = (SUB_BLOCKS * SUB_BLOCKS * SUB_BLOCKS / 32) as usize;

/// The (min, max) of each of a slot's [`SUB_BLOCKS`]³ sub-blocks (x fastest), each with the slot's apron
/// around it: `texels` holds `side`³ values (the brick's `brick_cells` and `apron` more on every
/// side), normalized. A sub-block whose range the transfer function leaves transparent is empty:
/// no filter tap of a sample inside it reads a voxel the range leaves out.
pub fn sub_block_ranges(value: impl Fn(usize) -> f32, brick_cells: u32, apron: u32) -> Vec<[f32; 2]> {
    let side = brick_cells + 2 * apron;
    let sub = f64::from(brick_cells) / f64::from(SUB_BLOCKS);
    let span = |i: u32| {
        let lo = (f64::from(i) * sub).floor() as u32;
        let hi = ((f64::from(i + 1) * sub).ceil() as u32 + 2 * apron).min(side);
        lo..hi
    };
    let mut out = Vec::with_capacity((SUB_BLOCKS * SUB_BLOCKS * SUB_BLOCKS) as usize);
    for bz in 0..SUB_BLOCKS {
        for by in 0..SUB_BLOCKS {
            for bx in 0..SUB_BLOCKS {
                let mut range = [f32::INFINITY, f32::NEG_INFINITY];
                for z in span(bz) {
                    for y in span(by) {
                        let row = ((z * side + y) * side) as usize;
                        for x in span(bx) {
                            let v = value(row + x as usize);
                            range = [range[0].min(v), range[1].max(v)];
                        }
                    }
                }
                out.push(range);
            }
        }
    }
    out
}

/// The occupancy words of a slot: bit i set when sub-block i's range is visible.
pub fn occupancy_words(ranges: &[[f32; 2]], visible: impl Fn(f32, f32) -> bool) -> [u32; SUB_WORDS] {
    let mut words = [0u32; SUB_WORDS];
    for (i, r) in ranges.iter().enumerate().take(32 * SUB_WORDS) {
        if visible(r[0], r[1]) {
            words[i / 32] |= 1 << (i % 32);
        }
    }
    words
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layout() -> StreamLayout {
        let levels = [
            PyramidLevel { dims: UVec3::splat(32), factor: DVec3::ONE },
            PyramidLevel { dims: UVec3::splat(16), factor: DVec3::splat(2.0) },
            PyramidLevel { dims: UVec3::splat(8), factor: DVec3::splat(4.0) },
        ];
        StreamLayout::new(&levels, 8).unwrap()
    }

    /// One bright voxel lights the sub-block holding it and, through the apron, its neighbours
    /// within reach; the far ones stay empty.
    #[test]
    fn a_voxel_lights_its_sub_block_and_those_its_apron_reaches() {
        let (cells, apron) = (16u32, 1u32);
        let side = cells + 2 * apron;
        // Brick voxel (0, 0, 0) is slot texel (1, 1, 1): sub-block 0, and the apron reaches it
        // from no other (sub-block 1 starts at brick voxel 2, its apron at slot texel 2).
        let lit = ((side + 1) * side + 1) as usize;
        let ranges = sub_block_ranges(|i| if i == lit { 1.0 } else { 0.0 }, cells, apron);
        let words = occupancy_words(&ranges, |_, hi| hi > 0.5);
        assert_eq!(words[0], 1);
        assert!(words[1..].iter().all(|w| *w == 0));
        // Brick voxel (2, 0, 0) (slot texel 3): sub-block 1's own, and within sub-block 0's apron.
        let edge = ((side + 1) * side + 3) as usize;
        let ranges = sub_block_ranges(|i| if i == edge { 1.0 } else { 0.0 }, cells, apron);
        let words = occupancy_words(&ranges, |_, hi| hi > 0.5);
        assert_eq!(words[0], 0b11);
        assert!(words[1..].iter().all(|w| *w == 0));
    }

    #[test]
    fn entries_count_every_level_and_locate_inverts_them() {
        let l = layout();
        assert_eq!(l.entries(), 64 + 8 + 1);
        assert_eq!(l.locate(0), (0, UVec3::ZERO));
        assert_eq!(l.locate(63), (0, UVec3::splat(3)));
        assert_eq!(l.locate(64 + 5), (1, UVec3::new(1, 0, 1)));
        assert_eq!(l.locate(72), (2, UVec3::ZERO));
        assert_eq!(l.slot_box(UVec3::new(1, 0, 0), 1), (IVec3::new(7, -1, -1), UVec3::splat(10)));
    }

    /// Requests go coarse first, then near first; a brick pending or known empty is not asked
    /// for twice, and one that arrives transparent takes no slot.
    #[test]
    fn requests_are_coarse_first_then_near_and_never_repeated() {
        let mut cache = StreamCache::new(layout(), UVec3::new(2, 2, 1));
        cache.classify(|_, hi| hi > 0.5, |e| (e == 3).then_some((0.0, 0.1)));
        let mut flags = vec![0u32; 73];
        for e in [0, 3, 63, 64, 72] {
            flags[e] = WANTED;
        }
        let asked = cache.feedback(&flags, DVec3::ZERO);
        assert_eq!(asked, vec![72, 64, 0, 63], "brick 3 is known empty");
        assert!(cache.feedback(&flags, DVec3::ZERO).is_empty(), "pending bricks are not asked again");
        let mut counts = StreamCounts::default();
        assert_eq!(cache.arrived(72, Some((0.0, 1.0)), true, &mut counts), Some(0));
        assert_eq!(cache.arrived(64, Some((0.0, 0.0)), false, &mut counts), None);
        assert_eq!(cache.table()[64], EMPTY_BRICK);
        assert_eq!(cache.table()[72], slot_word(UVec3::ZERO));
        assert_eq!(cache.pending(), 2);
    }

    /// The least recently drawn slot is evicted, never one the last frame drew nor a pinned
    /// (coarsest) one; with none left, the brick is refused until the view changes.
    #[test]
    fn eviction_takes_the_least_recently_drawn_and_spares_the_last_frame() {
        let mut cache = StreamCache::new(layout(), UVec3::new(3, 1, 1));
        let mut counts = StreamCounts::default();
        let mut flags = vec![0u32; 73];
        for e in [72, 0, 1, 2] {
            flags[e] = WANTED;
        }
        cache.feedback(&flags, DVec3::ZERO);
        assert_eq!(cache.arrived(72, Some((0.0, 1.0)), true, &mut counts), Some(0), "the coarsest, pinned");
        assert_eq!(cache.arrived(0, Some((0.0, 1.0)), true, &mut counts), Some(1));
        assert_eq!(cache.arrived(1, Some((0.0, 1.0)), true, &mut counts), Some(2));
        // A frame draws from brick 1 only: brick 0 is the least recently drawn.
        let mut drawn = vec![0u32; 73];
        drawn[1] = DRAWN;
        drawn[72] = DRAWN;
        cache.feedback(&drawn, DVec3::ZERO);
        cache.feedback(&drawn, DVec3::ZERO);
        assert_eq!(cache.arrived(2, Some((0.0, 1.0)), true, &mut counts), Some(1), "brick 0's slot");
        assert_eq!(cache.table()[0], 0, "evicted: not resident");
        // Now every unpinned slot was drawn by the last frame: refused.
        let mut both = vec![0u32; 73];
        both[1] = DRAWN;
        both[2] = DRAWN;
        both[3] = WANTED;
        assert_eq!(cache.feedback(&both, DVec3::ZERO), vec![3]);
        assert_eq!(cache.arrived(3, Some((0.0, 1.0)), true, &mut counts), None);
        assert_eq!((counts.refused, cache.refused()), (1, 1));
        cache.view_changed();
        assert_eq!(cache.refused(), 0);
    }
}
