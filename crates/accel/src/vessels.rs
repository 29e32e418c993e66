//! A generated sparse volume like the angiography of Ruijters & Vilanova 2006 §8 (Table 1: a
//! 512³ dataset of which about 3 % is visible under its transfer function): a branching tree of
//! vessels, deterministic for a given size and seed, so tests and benchmarks need no download.
//!
//! The tree starts near the `z = 0` face with a trunk of radius `n/20` voxels and branches in
//! two at the end of every vessel (children turned 20–40° away from their parent, radius ×0.8,
//! length ×0.85), nine generations deep, so its shape does not depend on `n`. Each segment is a capsule whose value
//! is 220 in its core and falls linearly to the background over two voxels at its wall; the
//! background is a constant 24 ("soft tissue" that a vessel TF leaves transparent). With
//! [`vessel_tf_points`] about 3 % of the voxels are visible (the test below measures it).

use glam::{DVec3, UVec3};
use rayon::prelude::*;

use crate::generate::SplitMix64;
use crate::volume::{Volume, VoxelData};

/// Background value (transparent under the vessel TF).
pub const BACKGROUND: u8 = 24;
/// Value in a vessel's core.
pub const VESSEL: u8 = 220;

/// Generations of vessels: 2⁹ − 1 vessels of three pieces each.
const GENERATIONS: u32 = 9;

/// One straight piece of a vessel, in voxel coordinates.
#[derive(Clone, Copy, Debug)]
struct Segment {
    a: DVec3,
    b: DVec3,
    radius: f64,
}

fn unit_random(rng: &mut SplitMix64) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

/// A unit vector at `angle` radians from `dir`, turned about a random axis.
fn turn(dir: DVec3, angle: f64, rng: &mut SplitMix64) -> DVec3 {
    let helper = if dir.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let u = dir.cross(helper).normalize();
    let v = dir.cross(u);
    let phi = unit_random(rng) * std::f64::consts::TAU;
    let side = u * phi.cos() + v * phi.sin();
    (dir * angle.cos() + side * angle.sin()).normalize()
}

/// The segments of the tree for an `n³` volume.
fn tree(n: u32, seed: u64) -> Vec<Segment> {
    let n = n as f64;
    let mut rng = SplitMix64(seed);
    let mut out = Vec::new();
    // (start, direction, radius, length, generation)
    let mut stack = vec![(DVec3::new(0.5 * n, 0.5 * n, 0.04 * n), DVec3::Z, n / 20.0, 0.30 * n, 0)];
    while let Some((start, dir, radius, length, generation)) = stack.pop() {
        if generation >= GENERATIONS {
            continue;
        }
        // A slightly curved vessel: three straight pieces.
        let mut p = start;
        let mut d = dir;
        for _ in 0..3 {
            d = turn(d, 0.15 * unit_random(&mut rng), &mut rng);
            let q = p + d * (length / 3.0);
            out.push(Segment { a: p, b: q, radius });
            p = q;
        }
        // Keep children inside the volume: steer back towards the centre when near a face.
        let to_centre = (DVec3::splat(0.5 * n) - p).normalize_or_zero();
        let near_face = p.min_element() < 0.12 * n || p.max_element() > 0.88 * n;
        let base = if near_face { (d + to_centre).normalize_or(d) } else { d };
        for _ in 0..2 {
            let angle = (20.0 + 20.0 * unit_random(&mut rng)).to_radians();
            stack.push((p, turn(base, angle, &mut rng), radius * 0.8, length * 0.85, generation + 1));
        }
    }
    out
}

/// Distance from `p` to the segment `a–b`.
fn distance_to_segment(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared().max(1e-12)).clamp(0.0, 1.0);
    (p - (a + t * ab)).length()
}

/// The tree of an `n³` volume, to fill any of its planes: a volume far larger than memory is
/// made a slab at a time (`volgraph convert vessels4096 …` writes 64 GiB this way).
pub struct VesselTree {
    n: u32,
    seed: u64,
    segments: Vec<Segment>,
}

impl VesselTree {
    /// The tree of an `n³` volume with `seed`.
    pub fn new(n: u32, seed: u64) -> Self {
        Self { n, seed, segments: tree(n, seed) }
    }

    /// Voxels per axis.
    pub fn dims(&self) -> UVec3 {
        UVec3::splat(self.n)
    }

    /// The volume's name, `vessels_<n>_seed<seed>`.
    pub fn name(&self) -> String {
        format!("vessels_{}_seed{}", self.n, self.seed)
    }

    /// The planes `z` of the volume, x fastest (each plane on its own rayon task).
    pub fn planes(&self, z: std::ops::Range<u32>) -> Vec<u8> {
        let slice = self.n as usize * self.n as usize;
        let mut data = vec![BACKGROUND; slice * z.len()];
        data.par_chunks_mut(slice.max(1)).enumerate().for_each(|(i, plane)| self.fill_plane(z.start + i as u32, plane));
        data
    }

    /// Plane `z`: the segments whose (wall-padded) bounding box meets it.
    fn fill_plane(&self, z: u32, plane: &mut [u8]) {
        let n = self.n;
        let zc = z as f64;
        for s in &self.segments {
            let pad = s.radius + 1.0;
            let lo = s.a.min(s.b) - DVec3::splat(pad);
            let hi = s.a.max(s.b) + DVec3::splat(pad);
            if zc < lo.z || zc > hi.z {
                continue;
            }
            let x0 = lo.x.max(0.0).floor() as u32;
            let x1 = (hi.x.ceil() as i64).clamp(0, n as i64 - 1) as u32;
            let y0 = lo.y.max(0.0).floor() as u32;
            let y1 = (hi.y.ceil() as i64).clamp(0, n as i64 - 1) as u32;
            if hi.x < 0.0 || hi.y < 0.0 {
                continue;
            }
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let d = distance_to_segment(DVec3::new(x as f64, y as f64, zc), s.a, s.b);
                    // 1 inside the wall, 0 two voxels outside it.
                    let w = ((s.radius + 1.0 - d) / 2.0).clamp(0.0, 1.0);
                    let v = (BACKGROUND as f64 + w * (VESSEL - BACKGROUND) as f64).round() as u8;
                    let cell = &mut plane[y as usize * n as usize + x as usize];
                    *cell = (*cell).max(v);
                }
            }
        }
    }
}

/// A branching vessel tree in an `n³` `uint8` volume (module docs), named
/// `vessels_<n>_seed<seed>`. The same `(n, seed)` gives the same volume on every platform.
pub fn vessel_tree(n: u32, seed: u64) -> Volume {
    let tree = VesselTree::new(n, seed);
    Volume::new(tree.name(), tree.dims(), DVec3::ONE, VoxelData::U8(tree.planes(0..n)))
}

/// Control points `(value, rgb, alpha)` of the vessel transfer function on the 0..255 domain:
/// transparent up to 100 (the background and the outer wall ramp), red to white above.
pub fn vessel_tf_points() -> Vec<(f64, [f64; 3], f64)> {
    vec![
        (0.0, [0.0, 0.0, 0.0], 0.0),
        (100.0, [0.6, 0.05, 0.05], 0.0),
        (160.0, [0.9, 0.2, 0.15], 0.35),
        (255.0, [1.0, 0.9, 0.8], 0.9),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic, branching, and sparse like the paper's angiography: a few percent of the
    /// voxels are above the TF's transparent range.
    #[test]
    fn the_vessel_tree_is_deterministic_and_about_three_percent_visible() {
        let a = vessel_tree(96, 7);
        let b = vessel_tree(96, 7);
        assert_eq!(a.data, b.data, "same size and seed, same volume");
        let VoxelData::U8(v) = &a.data else { panic!("uint8") };
        let visible = v.iter().filter(|x| **x > 100).count() as f64 / v.len() as f64;
        assert!((0.01..0.06).contains(&visible), "visible fraction {visible}");
        assert!(tree(96, 7).len() > 30, "it branches");
        assert_ne!(vessel_tree(96, 8).data, a.data, "the seed matters");
    }
}
