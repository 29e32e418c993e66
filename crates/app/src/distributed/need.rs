//! What the view needs of the volume, so that each rank holds only that part of its box.
//!
//! The kd-tree balances the voxels the transfer function shows, but a rank that held its whole
//! box would hold the empty space around them too: on the engine with 4 ranks one rank held
//! 36 % of the bytes. A brick is *needed* when its neighbourhood — itself and its 26
//! neighbours, all that trilinear filtering, gradients and the stretch between two samples
//! blend into a sample inside it — holds a value in a bin the march can show: under the transfer
//! function a bin of non-zero opacity or beside one (as the kd-tree's weights count them), for
//! an isosurface the isovalue's bin or beside it. A brick that is not needed lies a whole brick
//! from anything shown: the samples a ray takes in it add nothing, so a rank holds and marches
//! only the bounding box of the needed bricks of its kd box ([`Needed::tight`]; the visibility
//! order stays the kd-tree's, since the tight box lies inside).

use glam::UVec3;
use volgraph_accel::kd_split::{BrickWeights, VoxelBox};

use super::survey::{BINS, Survey};

/// The bricks the view needs, over the survey's brick grid.
pub struct Needed {
    dims: UVec3,
    brick: u32,
    needed: Vec<bool>,
}

/// The histogram bins the march can show: the isovalue's (and its neighbours') for an
/// isosurface graph, else those the transfer function `lut` gives opacity (and their
/// neighbours, which linear filtering of the table blends in).
pub fn shown_bins(plan: &volgraph_core::Plan, lut: &[[f32; 4]]) -> Vec<bool> {
    let iso = plan
        .steps
        .iter()
        .find(|s| volgraph_passes::raycast_params::is_iso(&s.params))
        .map(|s| s.params.float("iso_value"));
    let marked: Vec<bool> = match iso {
        Some(value) => {
            let bin = ((value.clamp(0.0, 1.0) * BINS as f64) as usize).min(BINS - 1);
            (0..BINS).map(|b| b == bin).collect()
        }
        None => (0..BINS).map(|b| lut.get(b * lut.len() / BINS).is_some_and(|t| t[3] > 0.0)).collect(),
    };
    (0..BINS).map(|b| marked[b] || (b > 0 && marked[b - 1]) || marked.get(b + 1).copied().unwrap_or(false)).collect()
}

impl Needed {
    /// The needed bricks of the surveyed volume of `dims` for the bins `shown`.
    pub fn of(survey: &Survey, dims: UVec3, shown: &[bool]) -> Self {
        let brick = survey.brick;
        let n = BrickWeights::bricks(dims, brick);
        let count = (n.x * n.y * n.z) as usize;
        // Each brick's lowest and highest non-empty bin.
        let ranges: Vec<(usize, usize)> = (0..count)
            .map(|b| {
                let bins = &survey.bins[b * BINS..(b + 1) * BINS];
                let lo = bins.iter().position(|&c| c > 0).unwrap_or(BINS);
                let hi = bins.iter().rposition(|&c| c > 0).unwrap_or(0);
                (lo, hi)
            })
            .collect();
        // shown_before[i]: shown bins below i, so a range is tested in O(1).
        let mut shown_before = vec![0usize; BINS + 1];
        for b in 0..BINS {
            shown_before[b + 1] = shown_before[b] + usize::from(shown.get(b).copied().unwrap_or(false));
        }
        let index = |x: u32, y: u32, z: u32| (x + n.x * (y + n.y * z)) as usize;
        let mut needed = vec![false; count];
        for z in 0..n.z {
            for y in 0..n.y {
                for x in 0..n.x {
                    let (mut lo, mut hi) = (BINS, 0);
                    for nz in z.saturating_sub(1)..(z + 2).min(n.z) {
                        for ny in y.saturating_sub(1)..(y + 2).min(n.y) {
                            for nx in x.saturating_sub(1)..(x + 2).min(n.x) {
                                let (a, b) = ranges[index(nx, ny, nz)];
                                (lo, hi) = (lo.min(a), hi.max(b));
                            }
                        }
                    }
                    needed[index(x, y, z)] = lo <= hi && shown_before[hi + 1] > shown_before[lo];
                }
            }
        }
        Self { dims, brick, needed }
    }

    fn brick_box(&self, b: UVec3) -> VoxelBox {
        VoxelBox::new(b * self.brick, ((b + UVec3::ONE) * self.brick).min(self.dims))
    }

    /// The bytes of the needed bricks, at `voxel_bytes` a voxel: what the view needs.
    pub fn bytes(&self, voxel_bytes: u64) -> u64 {
        self.boxes_in(VoxelBox::new(UVec3::ZERO, self.dims)).map(|b| b.voxels()).sum::<u64>() * voxel_bytes
    }

    /// The needed bricks that meet `bx` (on brick faces), as boxes.
    fn boxes_in(&self, bx: VoxelBox) -> impl Iterator<Item = VoxelBox> + '_ {
        let n = BrickWeights::bricks(self.dims, self.brick);
        let (lo, hi) = (bx.lo / self.brick, ((bx.hi + UVec3::splat(self.brick - 1)) / self.brick).min(n));
        (lo.z..hi.z).flat_map(move |z| {
            (lo.y..hi.y).flat_map(move |y| {
                (lo.x..hi.x)
                    .filter(move |x| self.needed[(x + n.x * (y + n.y * z)) as usize])
                    .map(move |x| self.brick_box(UVec3::new(x, y, z)))
            })
        })
    }

    /// The weights that balance the needed bytes: each needed brick's voxels, 0 elsewhere.
    pub fn weights(&self) -> BrickWeights {
        let mut weights = BrickWeights::zeros(self.dims, self.brick);
        let n = BrickWeights::bricks(self.dims, self.brick);
        for (i, w) in weights.weight.iter_mut().enumerate() {
            if self.needed[i] {
                let i = i as u32;
                *w = self.brick_box(UVec3::new(i % n.x, i / n.x % n.y, i / (n.x * n.y))).voxels();
            }
        }
        weights
    }

    /// The bounding box of the needed bricks in `bx`, within `bx`; a one-voxel box at `bx`'s
    /// corner when it has none (the rank draws nothing, but takes part in compositing).
    pub fn tight(&self, bx: VoxelBox) -> VoxelBox {
        let bound = self.boxes_in(bx).reduce(|a, b| VoxelBox::new(a.lo.min(b.lo), a.hi.max(b.hi)));
        match bound {
            Some(b) => VoxelBox::new(b.lo.max(bx.lo), b.hi.min(bx.hi)),
            None => VoxelBox::new(bx.lo, (bx.lo + UVec3::ONE).min(bx.hi)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn survey_of(dims: UVec3, brick: u32, value_at: impl Fn(UVec3) -> usize) -> Survey {
        let n = BrickWeights::bricks(dims, brick);
        let weights = BrickWeights::zeros(dims, brick);
        let mut bins = vec![0u64; (n.x * n.y * n.z) as usize * BINS];
        for z in 0..dims.z {
            for y in 0..dims.y {
                for x in 0..dims.x {
                    let v = UVec3::new(x, y, z);
                    bins[weights.brick_of(v) * BINS + value_at(v)] += 1;
                }
            }
        }
        Survey::for_tests(brick, bins)
    }

    /// A shown ball in a corner of an empty volume: the needed bricks are the ball's and one
    /// brick around them; a box away from it holds one voxel.
    #[test]
    fn the_tight_box_is_the_shown_bricks_and_one_around() {
        let dims = UVec3::new(64, 64, 64);
        let survey = survey_of(dims, 8, |v| if v.as_vec3().distance(glam::Vec3::splat(12.0)) < 4.0 { 200 } else { 0 });
        let mut shown = vec![false; BINS];
        shown[200] = true;
        let needed = Needed::of(&survey, dims, &shown);
        let whole = VoxelBox::new(UVec3::ZERO, dims);
        // The ball spans voxels 9..=15 per axis, brick 1 (8..16); one brick around it.
        assert_eq!(needed.tight(whole), VoxelBox::new(UVec3::ZERO, UVec3::splat(24)));
        assert_eq!(needed.bytes(2), 27 * 512 * 2, "bricks 0..3 per axis, two bytes a voxel");
        let far = VoxelBox::new(UVec3::new(40, 0, 0), UVec3::new(64, 64, 64));
        assert_eq!(needed.tight(far), VoxelBox::new(UVec3::new(40, 0, 0), UVec3::new(41, 1, 1)));
        let nothing = Needed::of(&survey, dims, &vec![false; BINS]);
        assert_eq!(nothing.bytes(1), 0);
    }
}
