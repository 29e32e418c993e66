//! Sampling a label map without mixing label numbers (issue "several volumes", item 3): a
//! trilinear blend of label values invents labels (4 next to 2 reads as 3), so a label map is
//! sampled either
//! - [`LabelFilter::Nearest`]: the label of the voxel whose cell holds the point (voxel stairs at
//!   every boundary), or
//! - [`LabelFilter::Smooth`] (the default): each label's own indicator (1 inside it, 0 outside)
//!   interpolated trilinearly, and the label whose indicator is largest wins — a boundary
//!   between two labels lies where their indicators cross, so a sphere stays round at any zoom,
//!   and only labels of the 8 voxels around the point can win.
//!
//! Texture coordinates as everywhere: voxel centres at `(i + 0.5) / n`, clamp to edge
//! (`docs/rendering_model.md`). This is the f64 reference the GPU sampling will be held to.

use glam::DVec3;

use crate::volume::Volume;

/// How a label map is sampled between voxel centres.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LabelFilter {
    /// The nearest voxel's label.
    Nearest,
    /// The label whose trilinearly interpolated indicator is largest.
    #[default]
    Smooth,
}

/// The label value of voxel `i` (a label map holds whole numbers; `census` checks it).
fn label_at(volume: &Volume, i: usize) -> u32 {
    volume.raw_value(i).max(0.0) as u32
}

/// The label at texture coordinate `u`, with its weight: 1 for nearest, the winning indicator's
/// interpolated value (in [1/8, 1]) for smooth — where two labels meet it falls to ½.
pub fn sample_label(volume: &Volume, u: DVec3, filter: LabelFilter) -> (u32, f64) {
    let n = volume.dims.as_dvec3();
    let p = u * n - 0.5;
    let clamp = |v: f64, n: u32| -> u32 { v.clamp(0.0, (n - 1) as f64) as u32 };
    if filter == LabelFilter::Nearest {
        let c = (p + 0.5).floor();
        let i = volume.index(clamp(c.x, volume.dims.x), clamp(c.y, volume.dims.y), clamp(c.z, volume.dims.z));
        return (label_at(volume, i), 1.0);
    }
    let base = p.floor();
    let f = p - base;
    // The 8 corners' labels and trilinear weights; labels gathered with their summed weights.
    let mut labels: [(u32, f64); 8] = [(0, 0.0); 8];
    let mut count = 0;
    for corner in 0..8u32 {
        let (dx, dy, dz) = (corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
        let x = clamp(base.x + dx as f64, volume.dims.x);
        let y = clamp(base.y + dy as f64, volume.dims.y);
        let z = clamp(base.z + dz as f64, volume.dims.z);
        let w = (if dx == 1 { f.x } else { 1.0 - f.x })
            * (if dy == 1 { f.y } else { 1.0 - f.y })
            * (if dz == 1 { f.z } else { 1.0 - f.z });
        let label = label_at(volume, volume.index(x, y, z));
        match labels[..count].iter_mut().find(|(l, _)| *l == label) {
            Some(entry) => entry.1 += w,
            None => {
                labels[count] = (label, w);
                count += 1;
            }
        }
    }
    // The largest indicator; a tie goes to the smaller label value (deterministic on both sides).
    labels[..count]
        .iter()
        .copied()
        .fold((u32::MAX, -1.0), |best, (l, w)| if w > best.1 || (w == best.1 && l < best.0) { (l, w) } else { best })
}

/// Per voxel (x, y, z), the labels of the 2 × 2 voxels (x, y), (x + 1, y), (x, y + 1),
/// (x + 1, y + 1) of its slice, clamped at the faces: a smooth sample's 8 corners are then two
/// reads, one per slice (the GPU's `label_quads`, `shaders/common/fusion.wgsl`) instead of eight.
/// The narrowest channels that hold the map's largest label: 4, 8 or 16 bytes a voxel.
#[derive(Clone, Debug, PartialEq)]
pub enum LabelQuads {
    /// Every label up to 255.
    U8(Vec<[u8; 4]>),
    /// Every label up to 65,535.
    U16(Vec<[u16; 4]>),
    /// Larger labels (a float map of whole numbers).
    U32(Vec<[u32; 4]>),
}

/// [`LabelQuads`] of a label map, x fastest, made in the narrowest width directly (a 512³ map's
/// quads are 0.5 GiB of bytes; a u32 copy on the way would be 2 GiB).
pub fn label_quads(volume: &Volume) -> LabelQuads {
    let largest = (0..volume.voxel_count()).map(|i| label_at(volume, i)).max().unwrap_or(0);
    if largest <= u32::from(u8::MAX) {
        LabelQuads::U8(quads_of(volume, |l| l as u8))
    } else if largest <= u32::from(u16::MAX) {
        LabelQuads::U16(quads_of(volume, |l| l as u16))
    } else {
        LabelQuads::U32(quads_of(volume, |l| l))
    }
}

fn quads_of<T: Copy>(volume: &Volume, narrow: impl Fn(u32) -> T) -> Vec<[T; 4]> {
    let n = volume.dims;
    let mut out = Vec::with_capacity(volume.voxel_count());
    for z in 0..n.z {
        for y in 0..n.y {
            let y1 = (y + 1).min(n.y - 1);
            for x in 0..n.x {
                let x1 = (x + 1).min(n.x - 1);
                out.push(
                    [(x, y), (x1, y), (x, y1), (x1, y1)].map(|(x, y)| narrow(label_at(volume, volume.index(x, y, z)))),
                );
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use glam::UVec3;

    use super::*;
    use crate::volume::VoxelData;

    /// A 32³ map: label 2 inside a sphere of radius 10 voxels about the centre, label 4 in a slab
    /// x ≥ 24 outside it, 0 elsewhere.
    fn map() -> Volume {
        let n = 32u32;
        let mut data = vec![0u8; (n * n * n) as usize];
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let c = DVec3::new(x as f64 + 0.5, y as f64 + 0.5, z as f64 + 0.5) - 16.0;
                    let i = (x + n * (y + n * z)) as usize;
                    data[i] = if c.length() < 10.0 {
                        2
                    } else if x >= 24 {
                        4
                    } else {
                        0
                    };
                }
            }
        }
        Volume::new("labels", UVec3::splat(n), DVec3::ONE, VoxelData::U8(data))
    }

    #[test]
    fn at_voxel_centres_both_filters_give_the_voxels_label() {
        let v = map();
        for (x, y, z) in [(16u32, 16u32, 16u32), (0, 0, 0), (30, 2, 2), (25, 16, 16), (5, 16, 16)] {
            let u = (DVec3::new(x as f64, y as f64, z as f64) + 0.5) / 32.0;
            let want = v.raw_value(v.index(x, y, z)) as u32;
            assert_eq!(sample_label(&v, u, LabelFilter::Nearest), (want, 1.0));
            assert_eq!(sample_label(&v, u, LabelFilter::Smooth), (want, 1.0), "({x}, {y}, {z})");
        }
    }

    #[test]
    fn smooth_sampling_never_invents_a_label_between_two_others() {
        // Between label 2 (the sphere) and label 4 (the slab), a trilinear blend of the values
        // reads 3; the indicators give 2 or 4 and nothing else, anywhere in the volume.
        let v = map();
        let mut seen = std::collections::BTreeSet::new();
        for k in 0..20_000u32 {
            // A low-discrepancy walk over the volume.
            let u = DVec3::new(
                (k as f64 * 0.754_877_666).fract(),
                (k as f64 * 0.569_840_291).fract(),
                (k as f64 * 0.362_425_6).fract(),
            );
            let (label, weight) = sample_label(&v, u, LabelFilter::Smooth);
            // At least one of 8 corners carries an eighth; sums round by an ulp or two.
            assert!((0.125 - 1e-12..=1.0 + 1e-12).contains(&weight), "{u}: weight {weight}");
            seen.insert(label);
        }
        assert_eq!(seen.into_iter().collect::<Vec<_>>(), [0, 2, 4]);
        // The blend of values would have invented 3 on the sphere's boundary with the slab.
        // Halfway between the centres of voxel 25 (label 2) and voxel 26 (label 4).
        let boundary = DVec3::new(26.0, 16.5, 16.5) / 32.0;
        assert!((v.sample_trilinear(boundary) * 255.0 - 3.0).abs() < 1.0);
        assert_ne!(sample_label(&v, boundary, LabelFilter::Smooth).0, 3);
    }

    #[test]
    fn a_smooth_boundary_is_round_where_nearest_is_a_staircase() {
        // Along a ray through the sphere's centre at an angle, the smooth boundary lies within a
        // small fraction of a voxel of the radius; nearest misses by up to half a voxel diagonal.
        let v = map();
        let direction = DVec3::new(1.0, 0.37, 0.21).normalize();
        let edge = |filter| {
            let mut t = 0.0;
            while sample_label(&v, (DVec3::splat(16.0) + direction * t) / 32.0, filter).0 == 2 {
                t += 0.001;
            }
            t
        };
        // The sphere holds the voxels whose centres are within 10: its surface as sampled lies
        // near 10 (9.5–10.5 for the stairs).
        let smooth = edge(LabelFilter::Smooth);
        let nearest = edge(LabelFilter::Nearest);
        // Measured 9.835 on this ray (the indicator's ½-crossing of the voxel staircase lies
        // 0.17 voxel inside the radius); 0.35 leaves room for the ray's angle while staying well
        // under the half voxel a nearest boundary can be off along an axis.
        assert!((smooth - 10.0).abs() < 0.35, "smooth boundary at {smooth}");
        assert!((9.0..11.0).contains(&nearest), "nearest boundary at {nearest}");
    }

    #[test]
    fn a_voxels_quad_holds_its_slices_two_by_two_neighbours_clamped_at_the_faces() {
        let v = map();
        let LabelQuads::U8(quads) = label_quads(&v) else { panic!("labels up to 4 fit a byte") };
        let label = |x: u32, y: u32, z: u32| v.raw_value(v.index(x.min(31), y.min(31), z)) as u8;
        for (x, y, z) in [(16u32, 16u32, 16u32), (0, 0, 0), (31, 31, 31), (25, 16, 16), (31, 5, 7), (6, 31, 2)] {
            let q = quads[v.index(x, y, z)];
            assert_eq!(
                q,
                [label(x, y, z), label(x + 1, y, z), label(x, y + 1, z), label(x + 1, y + 1, z)],
                "({x}, {y}, {z})"
            );
        }
        // Wider labels take wider channels.
        let mut wide = v.clone();
        wide.data = VoxelData::U16((0..32u16 * 32 * 32).map(|i| i % 1000).collect());
        assert!(matches!(label_quads(&wide), LabelQuads::U16(q) if q[0] == [0, 1, 32, 33]));
        wide.data = VoxelData::F32((0..32 * 32 * 32).map(|i| if i == 5 { 70_000.0 } else { 0.0 }).collect());
        assert!(matches!(label_quads(&wide), LabelQuads::U32(q) if q[4] == [0, 70_000, 0, 0]));
    }
}
