//! The CPU side of the brick raycaster (`raycast_bricks` in volgraph-passes) after Ruijters &
//! Vilanova 2006: what it computes from bricks and octrees before anything reaches the GPU.
//!
//! - §5 **bricks in one texture**: resident bricks sit in slots of a 3D atlas; a slot's
//!   position ([`slot_coord`]) and the word the march's batch table holds for it
//!   ([`slot_word`]), and how many bricks one staging buffer uploads at once
//!   ([`staging_bricks_per_chunk`]): the paper swaps bricks into texture memory, here a frame
//!   streams the ones it needs.
//! - §7 **octree leaves**: the octree's node-size limit makes leaves of `node_cells`³ cells
//!   ([`leaf_grid`]). On a TF change the boxes §7's ratio rule draws are rasterized into that
//!   grid ([`classify_leaves`]) and every leaf gets one word ([`leaf_word`]): the Chebyshev leap
//!   distance to the nearest drawn leaf ([`crate::chebyshev`]) where nothing is drawn, and how
//!   far the cube of drawn leaves around it reaches within its brick where something is. The
//!   march (`shaders/raycast_bricks.wgsl`) leaps over empty nodes and empty bricks alike and
//!   samples a drawn cube in one run.
//! - **sort-last ranks** (docs/scaling.md, not in the paper): which slab of the brick grid a
//!   rank draws ([`owns`]).

use glam::{DVec3, UVec3};

use crate::bricks::{BrickLayout, ViewPoint};
use crate::octree::{DrawBox, OctreeHierarchy, OctreeVisibility};

/// The row pitch alignment of a buffer-to-texture copy (`wgpu::COPY_BYTES_PER_ROW_ALIGNMENT`,
/// checked against it where the copies are recorded).
pub const COPY_ROW_ALIGNMENT: u64 = 256;

/// Leap distances are capped here: a leap out of a cube of 2·255 − 1 leaves is long enough that a
/// larger one would save little (the cap only shortens leaps, it never skips a drawn leaf).
pub const MAX_LEAP: u32 = 255;

/// Slots per atlas axis, at most: a slot word ([`slot_word`]) has 10 bits per axis. (A slot is
/// at least 4 voxels wide, so a 3D texture limit of 4096 or less never meets it.)
pub const SLOTS_PER_AXIS: u32 = 1 << 10;

/// Where slot `slot` lies in an atlas of `slots` slots per axis, in slots: x fastest.
pub fn slot_coord(slot: u32, slots: UVec3) -> UVec3 {
    UVec3::new(slot % slots.x, (slot / slots.x) % slots.y, slot / (slots.x * slots.y))
}

/// A drawn brick's word in the batch table (`raycast_bricks.wgsl`'s `table`): bit 31 set (0 is
/// "not in this batch") and its slot's coordinates, 10 bits per axis, x lowest — so the march
/// finds the slot's origin with a multiply instead of three integer divisions per brick entered,
/// which llvmpipe runs one lane at a time (2 % of the `bricks` graph's time on the engine,
/// bench/one-march-final.md "Brick runs").
pub fn slot_word(coord: UVec3) -> u32 {
    debug_assert!(coord.max_element() < SLOTS_PER_AXIS);
    1 << 31 | coord.x | coord.y << 10 | coord.z << 20
}

/// Bytes per staging row for `bricks` bricks of `brick_row` bytes side by side, padded to
/// [`COPY_ROW_ALIGNMENT`].
pub fn staging_row_bytes(brick_row: u64, bricks: usize) -> u64 {
    (brick_row * bricks as u64).div_ceil(COPY_ROW_ALIGNMENT) * COPY_ROW_ALIGNMENT
}

/// How many bricks (`rows` rows of `brick_row` bytes each) one staging buffer of at most
/// `limit` bytes holds (0: not even one). Row pitch stays within `u32`, as copies need.
pub fn staging_bricks_per_chunk(brick_row: u64, rows: u64, limit: u64) -> usize {
    let fits = |n: u64| {
        let row = staging_row_bytes(brick_row, n as usize);
        row <= u64::from(u32::MAX) && row * rows <= limit
    };
    if !fits(1) {
        return 0;
    }
    // The largest n that fits: rows grow monotonically with n.
    let (mut lo, mut hi) = (1u64, (limit / (brick_row * rows).max(1)).max(1) + 1);
    while lo + 1 < hi {
        let mid = lo + (hi - lo) / 2;
        if fits(mid) { lo = mid } else { hi = mid }
    }
    lo as usize
}

/// Leaves of `node_cells`³ cells per axis over a volume of `volume_dims` voxels.
pub fn leaf_grid(volume_dims: UVec3, node_cells: u32) -> UVec3 {
    let cells = crate::bricks::cell_dims(volume_dims);
    UVec3::new(cells.x.div_ceil(node_cells), cells.y.div_ceil(node_cells), cells.z.div_ceil(node_cells))
}

/// The CPU work of a TF change after the octrees' visible counts are rebuilt: which bricks are
/// visible, and every leaf's word ([`leaf_words`]).
pub struct LeafClassification {
    /// Per brick: visible under the TF.
    pub visible: Vec<bool>,
    /// Per leaf of the volume (x fastest), what the march reads ([`leaf_word`]): where no box
    /// to draw covers it, the Chebyshev distance in leaves to the nearest such leaf (capped at
    /// 255); where one does, how far the drawn leaves around it reach within its brick.
    pub words: Vec<u32>,
    /// Fraction of the leaves drawn.
    pub drawn_fraction: f64,
}

/// Rasterizes every visible brick's boxes to draw (§7's ratio rule at `ratio`) into the leaf
/// grid and turns them into the march's words ([`leaf_words`]: leap distances, drawn cubes).
pub fn classify_leaves(
    octree: &OctreeHierarchy,
    visibility: &OctreeVisibility,
    layout: &BrickLayout,
    grid: UVec3,
    ratio: f32,
) -> LeafClassification {
    let count = layout.brick_count();
    let visible: Vec<bool> = (0..count).map(|b| visibility.brick_visible_cells(b) > 0).collect();
    let mut drawn = vec![false; (grid.x * grid.y * grid.z) as usize];
    let mut boxes: Vec<DrawBox> = Vec::new();
    let leaf = octree.min_node_cells();
    for b in (0..count).filter(|b| visible[*b]) {
        boxes.clear();
        octree.draw_boxes(visibility, b, ratio, ViewPoint::Direction(DVec3::Z), &mut boxes);
        for d in &boxes {
            let lo = d.cells_lo / leaf;
            let hi = UVec3::new(d.cells_hi.x.div_ceil(leaf), d.cells_hi.y.div_ceil(leaf), d.cells_hi.z.div_ceil(leaf))
                .min(grid);
            for z in lo.z..hi.z {
                for y in lo.y..hi.y {
                    for x in lo.x..hi.x {
                        drawn[(x + grid.x * (y + grid.y * z)) as usize] = true;
                    }
                }
            }
        }
    }
    let drawn_fraction = drawn.iter().filter(|d| **d).count() as f64 / drawn.len().max(1) as f64;
    let words = leaf_words(&drawn, grid, layout.brick_cells().div_ceil(leaf).max(1));
    LeafClassification { visible, words, drawn_fraction }
}

/// Every leaf's [`leaf_word`] for the drawn leaves `drawn` (x fastest in `grid`), in bricks of
/// `leaves_per_brick` leaves per side.
pub fn leaf_words(drawn: &[bool], grid: UVec3, leaves_per_brick: u32) -> Vec<u32> {
    let to_drawn = crate::chebyshev::chebyshev_distance(drawn, grid, MAX_LEAP);
    let not_drawn: Vec<bool> = drawn.iter().map(|d| !d).collect();
    let to_not_drawn = crate::chebyshev::chebyshev_distance(&not_drawn, grid, leaves_per_brick);
    let mut words = Vec::with_capacity(drawn.len());
    for z in 0..grid.z {
        for y in 0..grid.y {
            for x in 0..grid.x {
                let i = (x + grid.x * (y + grid.y * z)) as usize;
                let reach = to_not_drawn[i].min(reach_within_brick(UVec3::new(x, y, z), leaves_per_brick, grid));
                words.push(leaf_word(drawn[i], to_drawn[i], reach));
            }
        }
    }
    words
}

/// The word `raycast_bricks.wgsl` reads per leaf (`empty_region_at`): the leap distance
/// `to_drawn` (1..=255) of a leaf no box covers; `reach << 8` for a drawn one, whose cube of
/// `2·reach − 1` leaves around it is drawn and inside its brick, so one run of samples crosses it
/// (a dense brick in a few runs, not one per leaf).
pub fn leaf_word(drawn: bool, to_drawn: u32, reach: u32) -> u32 {
    if drawn { reach.clamp(1, 0x00ff_ffff) << 8 } else { to_drawn.clamp(1, MAX_LEAP) }
}

/// How far a cube around leaf `l` may reach and stay inside its brick (of `leaves_per_brick`
/// leaves per side, fewer in the last brick of an axis): 1 next to another brick. The volume's
/// faces do not bound it: the march clamps the cube to the leaf grid.
fn reach_within_brick(l: UVec3, leaves_per_brick: u32, grid: UVec3) -> u32 {
    let lo = l / leaves_per_brick * leaves_per_brick;
    let hi = (lo + leaves_per_brick).min(grid) - 1;
    let to_lo = UVec3::select(lo.cmpeq(UVec3::ZERO), UVec3::MAX, l - lo);
    let to_hi = UVec3::select(hi.cmpeq(grid - 1), UVec3::MAX, hi - l);
    to_lo.min(to_hi).min_element().saturating_add(1)
}

/// Whether rank `ranks.0` of `ranks.1` draws brick `brick`: the brick grid is cut into
/// `ranks.1` slabs along its longest axis (a one-level kd-tree; docs/scaling.md).
pub fn owns(layout: &BrickLayout, brick: u32, (rank, ranks): (u32, u32)) -> bool {
    if ranks <= 1 {
        return true;
    }
    let grid = layout.grid_dims();
    let axis = if grid.x >= grid.y && grid.x >= grid.z {
        0
    } else if grid.y >= grid.z {
        1
    } else {
        2
    };
    let c = layout.brick_coord(brick as usize)[axis] as u64;
    (c * ranks as u64 / grid[axis] as u64) as u32 == rank
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Chunks fill the limit without passing it; rows are padded to the copy alignment once per
    /// chunk, not once per brick.
    #[test]
    fn staging_chunks_fit_the_limit() {
        // 35-voxel u8 rows, 35·35 rows per brick.
        let (brick_row, rows) = (35u64, 35 * 35u64);
        for limit in [64 << 20, 512 << 10, 400_000, 256 * rows] {
            let n = staging_bricks_per_chunk(brick_row, rows, limit);
            assert!(n >= 1, "{limit}");
            assert!(staging_row_bytes(brick_row, n) * rows <= limit, "{limit}: {n} bricks");
            assert!(staging_row_bytes(brick_row, n + 1) * rows > limit, "{limit}: {n} is the most");
        }
        // Padding: 64 MiB holds ~1561 bricks of 42875 bytes, not the 214 a 256-byte row each allows.
        assert!(staging_bricks_per_chunk(brick_row, rows, 64 << 20) > 1500);
        assert_eq!(staging_bricks_per_chunk(brick_row, rows, 1000), 0, "not even one brick");
    }

    /// The words the march leaps and runs by, against brute force on random leaf masks: an
    /// empty leaf's distance is the Chebyshev distance to the nearest drawn leaf; a drawn leaf's
    /// reach is the largest cube around it that is all drawn and inside its brick (the last
    /// brick of an axis is thinner).
    #[test]
    fn leaf_words_are_leap_distances_and_drawn_cubes_within_a_brick() {
        let grid = UVec3::new(9, 8, 7);
        let per_brick = 4;
        let index = |l: UVec3| (l.x + grid.x * (l.y + grid.y * l.z)) as usize;
        let leaves = || {
            (0..grid.z).flat_map(move |z| (0..grid.y).flat_map(move |y| (0..grid.x).map(move |x| UVec3::new(x, y, z))))
        };
        let cube = |l: UVec3, r: u32| {
            let lo = l.saturating_sub(UVec3::splat(r));
            let hi = (l + r).min(grid - 1);
            leaves().filter(move |m| m.cmpge(lo).all() && m.cmple(hi).all())
        };
        let mut rng = crate::generate::SplitMix64(7);
        for density in [0.1, 0.6, 0.95, 1.0] {
            let drawn: Vec<bool> =
                (0..grid.element_product()).map(|_| (rng.next_u64() as f64 / u64::MAX as f64) < density).collect();
            let words = leaf_words(&drawn, grid, per_brick);
            for l in leaves() {
                let word = words[index(l)];
                if !drawn[index(l)] {
                    let want = leaves()
                        .filter(|m| drawn[index(*m)])
                        .map(|m| (m.as_ivec3() - l.as_ivec3()).abs().max_element() as u32)
                        .min();
                    assert_eq!(word, want.unwrap_or(MAX_LEAP).clamp(1, MAX_LEAP), "{density}: empty leaf {l}");
                    continue;
                }
                assert_eq!(word & 0xff, 0, "{density}: drawn leaf {l}");
                let fits = |r: u32| cube(l, r).all(|m| drawn[index(m)] && m / per_brick == l / per_brick);
                let reach = word >> 8;
                assert!(reach >= 1 && fits(reach - 1), "{density}: leaf {l} reach {reach}");
                assert!(
                    !fits(reach) || cube(l, reach).count() == cube(l, reach - 1).count(),
                    "{density}: leaf {l}: reach {reach} is the largest"
                );
            }
        }
    }
}
