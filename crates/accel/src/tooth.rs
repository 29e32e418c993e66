//! A generated CT of a molar, the stand-in for the classic tooth scan (256×256×161, 16-bit) that
//! Klein et al. 2005 and later papers show and that no dataset folder here holds: a crown of
//! enamel with four cusps over dentin, a pulp chamber running down two root canals, two tapered
//! roots, all with a voxel of partial-volume blur at every boundary and the scanner's noise in
//! the air around it. The noise is what makes it a hard case for reprojection: under a DVR
//! transfer function the first non-transparent sample of a ray through air lies at a random
//! depth, so last frame's hits scatter in depth from pixel to pixel
//! (`crates/passes/tests/klein_2005.rs`). Deterministic for a given edge.
//!
//! Values (16-bit, like the scan): air 60 ± 30 (uniform noise), pulp 420, dentin 1050, enamel
//! 1900, each material ± 25.

use glam::{DVec3, UVec3};
use rayon::prelude::*;

use crate::generate::SplitMix64;
use crate::volume::{Volume, VoxelData};

/// Mean values of the materials.
const AIR: f64 = 60.0;
const PULP: f64 = 420.0;
const DENTIN: f64 = 1050.0;
const ENAMEL: f64 = 1900.0;
/// Half the range of the air's uniform noise, and of every material's.
const AIR_NOISE: f64 = 30.0;
const MATERIAL_NOISE: f64 = 25.0;

/// Signed distance (normalized units, negative inside) to the tooth's outer surface, to its
/// dentin (inside the enamel), and to its pulp, at `p` in [-1, 1]³ (z up, crown at +z).
fn distances(p: DVec3) -> (f64, f64, f64) {
    // The crown: a flattened ellipsoid with four cusps on top.
    let crown_centre = DVec3::new(0.0, 0.0, 0.35);
    let q = (p - crown_centre) / DVec3::new(0.62, 0.55, 0.42);
    let cusps = [(-0.28, -0.25), (0.28, -0.25), (-0.28, 0.25), (0.28, 0.25)]
        .iter()
        .map(|&(cx, cy)| {
            let c = DVec3::new(cx, cy, 0.64);
            (p - c).length() - 0.18
        })
        .fold(f64::INFINITY, f64::min);
    let crown = smooth_min((q.length() - 1.0) * 0.45, cusps, 0.16);
    // Two roots: tapered capsules from the crown's base down and slightly outwards.
    let root = |x_top: f64, x_tip: f64| {
        let (a, b) = (DVec3::new(x_top, 0.0, 0.1), DVec3::new(x_tip, 0.05, -0.85));
        let (d, t) = segment_distance(p, a, b);
        d - (0.22 - 0.15 * t)
    };
    let roots = root(-0.25, -0.38).min(root(0.25, 0.36));
    let outer = smooth_min(crown, roots, 0.1);
    // Enamel: a shell 0.07 thick over the crown only (above z = 0.12).
    let enamel_depth = if p.z > 0.12 { 0.07 } else { 0.0 };
    let dentin = outer + enamel_depth;
    // The pulp: a chamber in the crown running down a canal in each root.
    let chamber = ((p - DVec3::new(0.0, 0.0, 0.3)) / DVec3::new(0.3, 0.22, 0.16)).length() - 1.0;
    let canal = |x_top: f64, x_tip: f64| {
        let (a, b) = (DVec3::new(x_top, 0.0, 0.25), DVec3::new(x_tip, 0.05, -0.8));
        segment_distance(p, a, b).0 - 0.045
    };
    let pulp = smooth_min(chamber * 0.12, canal(-0.25, -0.37).min(canal(0.25, 0.35)), 0.05);
    (outer, dentin, pulp)
}

/// Distance from `p` to the segment `a–b`, and where along it (0 at `a`, 1 at `b`) the nearest point lies.
fn segment_distance(p: DVec3, a: DVec3, b: DVec3) -> (f64, f64) {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    ((p - (a + ab * t)).length(), t)
}

/// A smooth minimum over a blend width `k` (polynomial): surfaces join without a crease.
fn smooth_min(a: f64, b: f64, k: f64) -> f64 {
    let h = (0.5 + 0.5 * (b - a) / k).clamp(0.0, 1.0);
    b + (a - b) * h - k * h * (1.0 - h)
}

/// The fraction (0..1) of a voxel of width `voxel` (normalized units) inside a surface at signed
/// distance `d`: a linear ramp over one voxel, the partial-volume effect of a CT.
fn inside(d: f64, voxel: f64) -> f64 {
    (0.5 - d / voxel).clamp(0.0, 1.0)
}

/// The molar CT at edge `n` (n × n × ⌈0.63 n⌉ voxels, like the scan's 256×256×161), u16,
/// voxel spacing 1, its value range fitted to the data (as a scanner loader's).
pub fn tooth(n: u32) -> Volume {
    let n = n.max(1);
    let dims = UVec3::new(n, n, (n as f64 * 0.63).ceil() as u32);
    // Normalized units per voxel: the longest side spans [-1, 1].
    let voxel = 2.0 / n as f64;
    let slice = (dims.x * dims.y) as usize;
    let data: Vec<u16> = (0..dims.z)
        .into_par_iter()
        .flat_map_iter(|z| {
            let mut rng = SplitMix64(0x7007_0000 + z as u64);
            let mut out = Vec::with_capacity(slice);
            for y in 0..dims.y {
                for x in 0..dims.x {
                    let p = DVec3::new(
                        (x as f64 + 0.5) * voxel - 1.0,
                        (y as f64 + 0.5) * voxel - 1.0,
                        (z as f64 + 0.5 - 0.5 * dims.z as f64) * voxel / 0.63,
                    );
                    let (outer, dentin, pulp) = distances(p);
                    let (o, d, c) = (inside(outer, voxel), inside(dentin, voxel), inside(pulp, voxel));
                    // Air → enamel at the outer surface, → dentin under the enamel, → pulp.
                    let tissue = ENAMEL + (DENTIN - ENAMEL) * d;
                    let value = AIR + (tissue - AIR) * o + (PULP - DENTIN) * c * o;
                    let unit = 2.0 * ((rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64) - 1.0;
                    let noise = if o > 0.0 { MATERIAL_NOISE } else { AIR_NOISE };
                    out.push((value + noise * unit).round().clamp(0.0, u16::MAX as f64) as u16);
                }
            }
            out
        })
        .collect();
    // Like a scanner's loader: the values it holds span the LUT, not the type's range.
    let mut volume = Volume::new(format!("tooth{n}"), dims, DVec3::ONE, VoxelData::U16(data));
    volume.fit_range_to_data();
    volume
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The materials are where a tooth has them: enamel on the crown, dentin below it, pulp in
    /// the middle of the crown, air in the corners; the air is noisy, not constant.
    #[test]
    fn materials_lie_where_a_molar_has_them() {
        let v = tooth(64);
        let VoxelData::U16(data) = &v.data else { panic!("u16") };
        let at = |x: u32, y: u32, z: u32| data[((z * v.dims.y + y) * v.dims.x + x) as usize] as f64;
        let (cx, cy) = (v.dims.x / 2, v.dims.y / 2);
        // The top of the crown's side (enamel) and the pulp chamber at its centre.
        let z_chamber = (0.5 * v.dims.z as f64 + 0.3 * 0.63 * 32.0) as u32;
        assert!((at(cx, cy, z_chamber) - PULP).abs() < 150.0, "pulp {}", at(cx, cy, z_chamber));
        let enamel_side = (1..cx).map(|x| at(cx - x, cy, z_chamber + 4)).fold(0.0, f64::max);
        assert!(enamel_side > ENAMEL - 150.0, "enamel {enamel_side}");
        let corners = [at(0, 0, 0), at(v.dims.x - 1, 0, v.dims.z - 1), at(0, v.dims.y - 1, v.dims.z / 2)];
        for c in corners {
            assert!((c - AIR).abs() <= AIR_NOISE + 0.5, "air {c}");
        }
        let air: Vec<f64> = (0..16).map(|x| at(x, 0, 0)).collect();
        assert!(air.iter().any(|&a| a != air[0]), "the air carries noise");
        assert_eq!(tooth(64).data, v.data, "deterministic");
    }
}
