//! The Chebyshev (L∞) distance transform of a 3D grid of cells: for every cell, the distance in
//! cells to the nearest marked one. A raycaster standing in an unmarked cell at distance `d`
//! may leap out of the cube of `2d − 1` cells around it (every cell in it is unmarked) — the
//! octree's empty nodes as one lookup: Ruijters & Vilanova 2006 §7's boxes rasterized into
//! leaves, their complement turned into leap distances (`raycast_bricks`), like the distance
//! map of Krüger & Westermann 2003 §2.3's empty blocks (`empty_distance`).
//!
//! Two chamfer sweeps with all 26 neighbours at weight 1 are exact for L∞: every shortest L∞
//! path can be taken as a monotone staircase of unit king moves, which the forward sweep (the
//! 13 neighbours before a cell in scan order) and the backward sweep (the 13 after) cover.

use glam::UVec3;

/// Distance, in cells, to the nearest cell with `marked[i]` set (x fastest in `dims`), capped at
/// `cap` (also the value everywhere when nothing is marked). Marked cells get 0.
pub fn chebyshev_distance(marked: &[bool], dims: UVec3, cap: u32) -> Vec<u32> {
    let (nx, ny, nz) = (dims.x as i64, dims.y as i64, dims.z as i64);
    let index = |x: i64, y: i64, z: i64| ((z * ny + y) * nx + x) as usize;
    let mut d: Vec<u32> = marked.iter().map(|m| if *m { 0 } else { cap }).collect();
    // The 13 neighbours before a cell in x-fastest scan order.
    let mut before = Vec::with_capacity(13);
    for dz in -1..=1i64 {
        for dy in -1..=1i64 {
            for dx in -1..=1i64 {
                if (dz, dy, dx) < (0, 0, 0) {
                    before.push((dx, dy, dz));
                }
            }
        }
    }
    let mut sweep = |forward: bool| {
        for zi in 0..nz {
            for yi in 0..ny {
                for xi in 0..nx {
                    let (x, y, z) = if forward { (xi, yi, zi) } else { (nx - 1 - xi, ny - 1 - yi, nz - 1 - zi) };
                    let mut best = d[index(x, y, z)];
                    if best == 0 {
                        continue;
                    }
                    for &(dx, dy, dz) in &before {
                        let (dx, dy, dz) = if forward { (dx, dy, dz) } else { (-dx, -dy, -dz) };
                        let (a, b, c) = (x + dx, y + dy, z + dz);
                        if a >= 0 && b >= 0 && c >= 0 && a < nx && b < ny && c < nz {
                            best = best.min(d[index(a, b, c)].saturating_add(1));
                        }
                    }
                    d[index(x, y, z)] = best.min(cap);
                }
            }
        }
    };
    sweep(true);
    sweep(false);
    d
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate::SplitMix64;

    /// Equals the brute-force minimum over marked cells on random grids of odd shapes.
    #[test]
    fn the_chamfer_sweeps_equal_brute_force() {
        let mut rng = SplitMix64(4);
        for dims in [UVec3::new(7, 5, 3), UVec3::new(1, 9, 4), UVec3::new(6, 6, 6)] {
            let n = (dims.x * dims.y * dims.z) as usize;
            for density in [3, 20, 200] {
                let marked: Vec<bool> = (0..n).map(|_| rng.next_u64() % 1000 < density).collect();
                let got = chebyshev_distance(&marked, dims, 255);
                for (i, got) in got.iter().enumerate() {
                    let p = UVec3::new(i as u32 % dims.x, (i as u32 / dims.x) % dims.y, i as u32 / (dims.x * dims.y));
                    let want = (0..n)
                        .filter(|j| marked[*j])
                        .map(|j| {
                            let q = UVec3::new(
                                j as u32 % dims.x,
                                (j as u32 / dims.x) % dims.y,
                                j as u32 / (dims.x * dims.y),
                            );
                            (p.as_ivec3() - q.as_ivec3()).abs().max_element() as u32
                        })
                        .min()
                        .unwrap_or(255);
                    assert_eq!(*got, want, "{dims:?} cell {p:?}");
                }
            }
        }
    }
}
