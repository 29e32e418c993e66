//! Where a label map holds one label (the GPU's `label_cubes`, `shaders/common/label_cubes.wgsl`):
//! the label-map analogue of Krüger & Westermann 2003 §2.3's empty-space distance map. Inside an
//! organ, a smooth sample's eight corners all hold its label and every read of them is wasted; a
//! march that knows a run of samples lies in one label's region reads the label once for the run.
//!
//! The map is cut into blocks of [`LABEL_BLOCK`]³ voxels. A block is *uniform* with label L when
//! every voxel of the block and of a one-voxel apron around it (clamped to the map) holds L, so
//! every sample whose point lies in the block's box — or up to half a voxel past its faces —
//! has all eight corners, and the nearest voxel, labelled L. Per block the map keeps its label
//! and the Chebyshev distance in blocks to the nearest block that is not uniform with the same
//! label (0 for a block that is not uniform itself): every block within distance − 1 is uniform
//! with L, so the cube of them is one box a ray's samples can be taken through without a read.

use glam::UVec3;
use rayon::prelude::*;

use crate::volume::Volume;

/// The edge of a block, in voxels.
pub const LABEL_BLOCK: u32 = 4;

/// Per block, x fastest: `[label, distance]` (see the module).
#[derive(Clone, Debug, PartialEq)]
pub struct LabelCubes {
    /// Blocks per axis: ⌈n / LABEL_BLOCK⌉.
    pub dims: UVec3,
    /// `[label, distance]` per block, x fastest.
    pub texels: Vec<[u32; 2]>,
}

impl LabelCubes {
    /// Of a label map.
    pub fn of(volume: &Volume) -> Self {
        let dims = (volume.dims + UVec3::splat(LABEL_BLOCK - 1)) / LABEL_BLOCK;
        let uniform = uniform_labels(volume, dims);
        let texels = chessboard_distances(&uniform, dims);
        Self { dims, texels }
    }

    /// The texel of block `b`.
    pub fn at(&self, b: UVec3) -> [u32; 2] {
        self.texels[(b.x + self.dims.x * (b.y + self.dims.y * b.z)) as usize]
    }
}

/// Per block, its label where it and its one-voxel apron hold one label.
fn uniform_labels(volume: &Volume, dims: UVec3) -> Vec<Option<u32>> {
    let n = volume.dims;
    let label = |x: u32, y: u32, z: u32| volume.raw_value(volume.index(x, y, z)).max(0.0) as u32;
    // The voxels of block b along an axis of n voxels, with the apron, clamped.
    let span = |b: u32, n: u32| (b * LABEL_BLOCK).saturating_sub(1)..=((b + 1) * LABEL_BLOCK).min(n - 1);
    (0..dims.z)
        .into_par_iter()
        .flat_map_iter(|bz| {
            (0..dims.y).flat_map(move |by| {
                (0..dims.x).map(move |bx| {
                    let first = label(bx * LABEL_BLOCK, by * LABEL_BLOCK, bz * LABEL_BLOCK);
                    let same =
                        span(bz, n.z).all(|z| span(by, n.y).all(|y| span(bx, n.x).all(|x| label(x, y, z) == first)));
                    same.then_some(first)
                })
            })
        })
        .collect()
}

/// Per block `[label, distance]`: the chessboard distance to the nearest block whose uniform
/// label differs (or that is not uniform), by the two raster passes of the 3 × 3 × 3 chamfer,
/// exact for this metric. A shortest path to the nearest such block runs through blocks of the
/// same label only (a block on it with another would be nearer), so each block's distance
/// follows from its same-labelled neighbours'. Blocks past the map's faces bound nothing: a
/// cube is clamped to the map where it is used.
fn chessboard_distances(uniform: &[Option<u32>], dims: UVec3) -> Vec<[u32; 2]> {
    let far = dims.max_element() + 1;
    let mut distance: Vec<u32> = uniform.iter().map(|u| if u.is_some() { far } else { 0 }).collect();
    let index = |x: i64, y: i64, z: i64| (x + dims.x as i64 * (y + dims.y as i64 * z)) as usize;
    let d = dims.as_i64vec3();
    let mut relax = |x: i64, y: i64, z: i64, behind: bool| {
        let i = index(x, y, z);
        let Some(own) = uniform[i] else { return };
        let mut best = distance[i];
        for dz in -1..=1i64 {
            for dy in -1..=1i64 {
                for dx in -1..=1i64 {
                    // The neighbours already visited by this pass: before in raster order, or
                    // after for the backward pass.
                    let order = dz * 9 + dy * 3 + dx;
                    if order == 0 || (order < 0) != behind {
                        continue;
                    }
                    let (nx, ny, nz) = (x + dx, y + dy, z + dz);
                    if nx < 0 || ny < 0 || nz < 0 || nx >= d.x || ny >= d.y || nz >= d.z {
                        continue;
                    }
                    let j = index(nx, ny, nz);
                    let through = if uniform[j] == Some(own) { distance[j] + 1 } else { 1 };
                    best = best.min(through);
                }
            }
        }
        distance[i] = best;
    };
    for z in 0..d.z {
        for y in 0..d.y {
            for x in 0..d.x {
                relax(x, y, z, true);
            }
        }
    }
    for z in (0..d.z).rev() {
        for y in (0..d.y).rev() {
            for x in (0..d.x).rev() {
                relax(x, y, z, false);
            }
        }
    }
    uniform.iter().zip(distance).map(|(u, d)| [u.unwrap_or(0), d]).collect()
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::labels::sample::{LabelFilter, sample_label};
    use crate::volume::VoxelData;

    /// A 40 × 36 × 28 map: label 3 in a ball of radius 9 voxels, label 7 for x ≥ 30, 0 elsewhere.
    fn map() -> Volume {
        let n = UVec3::new(40, 36, 28);
        let mut data = vec![0u16; (n.x * n.y * n.z) as usize];
        for z in 0..n.z {
            for y in 0..n.y {
                for x in 0..n.x {
                    let c = DVec3::new(x as f64, y as f64, z as f64) - DVec3::new(16.0, 18.0, 14.0);
                    data[(x + n.x * (y + n.y * z)) as usize] = if c.length() < 9.0 {
                        3
                    } else if x >= 30 {
                        7
                    } else {
                        0
                    };
                }
            }
        }
        Volume::new("labels", n, DVec3::ONE, VoxelData::U16(data))
    }

    #[test]
    fn distances_are_the_brute_force_chessboard_distances() {
        let v = map();
        let cubes = LabelCubes::of(&v);
        assert_eq!(cubes.dims, UVec3::new(10, 9, 7));
        let uniform = uniform_labels(&v, cubes.dims);
        let d = cubes.dims.as_ivec3();
        let mut uniform_blocks = 0;
        for (i, texel) in cubes.texels.iter().enumerate() {
            let b = glam::IVec3::new(i as i32 % d.x, (i as i32 / d.x) % d.y, i as i32 / (d.x * d.y));
            let nearest = (0..uniform.len())
                .filter(|&j| uniform[j].is_none() || uniform[j] != uniform[i])
                .map(|j| {
                    let o = glam::IVec3::new(j as i32 % d.x, (j as i32 / d.x) % d.y, j as i32 / (d.x * d.y));
                    (o - b).abs().max_element() as u32
                })
                .min()
                .unwrap_or(d.max_element() as u32 + 1);
            assert_eq!(texel[1], nearest, "block {b}");
            if let Some(label) = uniform[i] {
                assert_eq!(texel[0], label);
                uniform_blocks += 1;
            }
        }
        // The ball's inside, the slab and the background all have uniform blocks.
        assert!(uniform_blocks > 100, "{uniform_blocks}");
        assert!(cubes.texels.iter().any(|t| t[0] == 3 && t[1] >= 1));
        assert!(cubes.texels.iter().any(|t| t[0] == 7 && t[1] >= 2));
    }

    #[test]
    fn every_sample_in_a_cube_or_half_a_voxel_past_it_has_the_cubes_label() {
        // What the GPU relies on: samples anywhere in the box of the cube of blocks around a
        // block (within distance − 1), up to half a voxel past it, sample to the cube's label by
        // either filter.
        let v = map();
        let cubes = LabelCubes::of(&v);
        let n = v.dims.as_dvec3();
        let mut checked = 0;
        for bz in 0..cubes.dims.z {
            for by in 0..cubes.dims.y {
                for bx in 0..cubes.dims.x {
                    let b = UVec3::new(bx, by, bz);
                    let [label, distance] = cubes.at(b);
                    if distance == 0 {
                        continue;
                    }
                    let reach = distance - 1;
                    let lo = b.saturating_sub(UVec3::splat(reach));
                    let hi = (b + UVec3::splat(reach)).min(cubes.dims - 1);
                    let box_lo = (lo * LABEL_BLOCK).as_dvec3() - 0.5;
                    let box_hi = (((hi + 1) * LABEL_BLOCK).as_dvec3()).min(n) + 0.5;
                    for k in 0..64u32 {
                        let t = DVec3::new(
                            (k as f64 * 0.754_877_666).fract(),
                            (k as f64 * 0.569_840_291).fract(),
                            (k as f64 * 0.362_425_6).fract(),
                        );
                        // In voxel units, then texture coordinates; past the map's own box a
                        // sample is outside the label map (the GPU's in_box), not checked here.
                        let u = (box_lo + t * (box_hi - box_lo)) / n;
                        if u.min_element() < 0.0 || u.cmpgt(DVec3::ONE).any() {
                            continue;
                        }
                        for filter in [LabelFilter::Smooth, LabelFilter::Nearest] {
                            assert_eq!(sample_label(&v, u, filter).0, label, "block {b}, {u}, {filter:?}");
                        }
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 5_000, "{checked}");
    }

    #[test]
    fn a_map_smaller_than_a_block_and_a_constant_map() {
        let one = Volume::new("one", UVec3::ONE, DVec3::ONE, VoxelData::U8(vec![5]));
        assert_eq!(LabelCubes::of(&one), LabelCubes { dims: UVec3::ONE, texels: vec![[5, 2]] });
        let constant = Volume::new("c", UVec3::new(9, 5, 4), DVec3::ONE, VoxelData::U8(vec![2; 180]));
        let cubes = LabelCubes::of(&constant);
        assert_eq!(cubes.dims, UVec3::new(3, 2, 1));
        // Every block is uniform and nothing differs: the distance reaches past the map.
        assert!(cubes.texels.iter().all(|&[l, d]| l == 2 && d == 4), "{:?}", cubes.texels);
    }
}
