//! A generated abdominal CT and its segmentation, made from the same shapes (issue "several
//! volumes": a scan with its label map, which no dataset folder here holds): a body of soft
//! tissue and fat in air, a liver, two kidneys, a spleen, the aorta (contrast-filled) and a
//! vertebral body. `organs<N>` is the CT (i16, Hounsfield units, ± 10 HU of noise); `organs_labels<N>`
//! its label map (u8, the values of [`label_table`]), voxel for voxel the label of the shape the
//! CT's voxel centre lies in, so "the scan inside label L" can be checked against the scan with
//! every voxel outside L set to air. N × N × N/2 voxels of 1 × 1 × 2 (spacing in mm: an
//! anisotropic CT, its box about square), in the LPS patient frame. Deterministic for a given N.

use glam::{DVec3, UVec3};

use crate::generate::SplitMix64;
use crate::labels::{Label, LabelTable};
use crate::volume::{Volume, VoxelData};
use crate::volume_meta::WorldFrame;

/// The organs: label value, name, colour, mean HU.
pub const ORGANS: [(u8, &str, [u8; 3], f64); 6] = [
    (1, "liver", [221, 130, 101], 60.0),
    (2, "left kidney", [185, 102, 83], 30.0),
    (3, "right kidney", [185, 102, 83], 30.0),
    (4, "spleen", [157, 108, 162], 50.0),
    (5, "aorta", [224, 97, 76], 250.0),
    (6, "vertebra", [241, 214, 145], 700.0),
];

/// Air, fat and soft tissue outside the organs (HU).
const AIR: f64 = -1000.0;
const FAT: f64 = -100.0;
const TISSUE: f64 = 40.0;

/// The label (0: none) and the material's HU at `p` in the body's normalized frame: x, y in
/// [-1, 1] across the box, z in [-1, 1] along it (+x left, +y posterior, +z superior).
fn material(p: DVec3) -> (u8, f64) {
    let ellipsoid = |c: DVec3, r: DVec3| ((p - c) / r).length_squared() < 1.0;
    let inside = |label: u8| ORGANS.iter().find(|o| o.0 == label).map_or((0, TISSUE), |o| (label, o.3));
    // The body: an elliptic cylinder; a ring of fat under the skin.
    let body = (p.x / 0.9).powi(2) + (p.y / 0.7).powi(2);
    if body >= 1.0 {
        return (0, AIR);
    }
    if ellipsoid(DVec3::new(0.0, 0.35, 0.0), DVec3::new(0.12, 0.12, 2.0)) {
        return inside(6); // the vertebral body, a column along z
    }
    if ellipsoid(DVec3::new(0.12, 0.08, 0.0), DVec3::new(0.07, 0.07, 2.0)) {
        return inside(5); // the aorta, left of the midline in front of the spine
    }
    if ellipsoid(DVec3::new(-0.38, -0.05, 0.35), DVec3::new(0.38, 0.42, 0.5)) {
        return inside(1); // the liver, on the patient's right (-x)
    }
    if ellipsoid(DVec3::new(0.45, 0.25, 0.4), DVec3::new(0.17, 0.2, 0.3)) {
        return inside(4); // the spleen, left and posterior
    }
    if ellipsoid(DVec3::new(0.33, 0.3, -0.25), DVec3::new(0.12, 0.1, 0.3)) {
        return inside(2);
    }
    if ellipsoid(DVec3::new(-0.33, 0.3, -0.35), DVec3::new(0.12, 0.1, 0.3)) {
        return inside(3);
    }
    (0, if body > 0.85 { FAT } else { TISSUE })
}

/// Dimensions and the normalized position of voxel (x, y, z)'s centre.
fn grid(n: u32) -> (UVec3, impl Fn(u32, u32, u32) -> DVec3) {
    let n = n.max(2);
    let dims = UVec3::new(n, n, (n / 2).max(1));
    let centre = move |x: u32, y: u32, z: u32| {
        let c = |i: u32, m: u32| -1.0 + 2.0 * (i as f64 + 0.5) / m as f64;
        DVec3::new(c(x, dims.x), c(y, dims.y), c(z, dims.z))
    };
    (dims, centre)
}

fn physical(mut volume: Volume, modality: Option<&str>) -> Volume {
    volume.meta.frame = WorldFrame::Lps;
    volume.meta.modality = modality.map(str::to_string);
    volume
}

/// The CT at edge `n`: HU as i16, ± 10 HU of uniform noise.
pub fn organs_ct(n: u32) -> Volume {
    let (dims, centre) = grid(n);
    let mut rng = SplitMix64(0x0a6a_5000 + n as u64);
    let mut data = Vec::with_capacity((dims.x * dims.y * dims.z) as usize);
    for z in 0..dims.z {
        for y in 0..dims.y {
            for x in 0..dims.x {
                let noise = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * 20.0 - 10.0;
                data.push((material(centre(x, y, z)).1 + noise).round() as i16);
            }
        }
    }
    let mut ct = Volume::new(format!("organs_{n}"), dims, DVec3::new(1.0, 1.0, 2.0), VoxelData::I16(data));
    ct.fit_range_to_data();
    let mut ct = physical(ct, Some("CT"));
    ct.meta.units = Some("HU".to_string());
    ct
}

/// The label map at edge `n`, voxel for voxel the organ of [`organs_ct`]'s voxel.
pub fn organs_labels(n: u32) -> Volume {
    let (dims, centre) = grid(n);
    let mut data = Vec::with_capacity((dims.x * dims.y * dims.z) as usize);
    for z in 0..dims.z {
        for y in 0..dims.y {
            for x in 0..dims.x {
                data.push(material(centre(x, y, z)).0);
            }
        }
    }
    physical(Volume::new(format!("organs_labels_{n}"), dims, DVec3::new(1.0, 1.0, 2.0), VoxelData::U8(data)), None)
}

/// The organs' names and colours, as a label table would give them.
pub fn label_table() -> LabelTable {
    LabelTable {
        labels: ORGANS
            .iter()
            .map(|(v, name, rgb, _)| {
                (*v as u32, Label { name: name.to_string(), rgb: *rgb, opacity: 1.0, visible: true })
            })
            .collect(),
        source: "the organ phantom".to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::labels::census::census;

    #[test]
    fn every_organ_is_in_the_map_and_the_ct_agrees_with_it() {
        let (ct, labels) = (organs_ct(64), organs_labels(64));
        assert_eq!((ct.dims, labels.dims), (UVec3::new(64, 64, 32), UVec3::new(64, 64, 32)));
        let counts = census(&labels).expect("a label map");
        assert_eq!(counts.values(), [0, 1, 2, 3, 4, 5, 6], "every organ present");
        // Each organ's voxels hold its HU within the noise, and no voxel outside the organs does.
        for i in 0..ct.voxel_count() {
            let label = labels.raw_value(i) as u8;
            let hu = ct.raw_value(i);
            match ORGANS.iter().find(|o| o.0 == label) {
                Some(o) => assert!((hu - o.3).abs() <= 10.5, "voxel {i}: label {label} at {hu} HU"),
                None => assert!([AIR, FAT, TISSUE].iter().any(|m| (hu - m).abs() <= 10.5), "voxel {i}: {hu} HU"),
            }
        }
        assert_eq!(ct.meta.units.as_deref(), Some("HU"));
        assert_eq!(label_table().label(5).name, "aorta");
    }
}
