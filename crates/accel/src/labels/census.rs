//! The labels a label map holds: each value present, its voxels and its physical volume. A label
//! map is whole numbers ≥ 0 (u8, u16, i16 or f32 holding integers); anything else is an error
//! naming the first voxel that is not a label, never a silent rounding.

use std::collections::BTreeMap;

use crate::volume::{Volume, VoxelData};

/// One label value present in a map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LabelCount {
    /// The value.
    pub value: u32,
    /// Voxels holding it.
    pub voxels: u64,
}

/// The labels of a map, by value, and the volume of one voxel.
#[derive(Clone, Debug, PartialEq)]
pub struct Census {
    /// Each value present (background 0 included), ascending.
    pub counts: Vec<LabelCount>,
    /// The volume of one voxel in the spacing's units cubed (mm³ for DICOM and NIfTI).
    pub voxel_volume: f64,
}

impl Census {
    /// The values present, ascending.
    pub fn values(&self) -> Vec<u32> {
        self.counts.iter().map(|c| c.value).collect()
    }

    /// The volume of `voxels` voxels in millilitres, the spacing taken in millimetres.
    pub fn millilitres(&self, voxels: u64) -> f64 {
        voxels as f64 * self.voxel_volume / 1000.0
    }
}

/// A volume that is no label map: the first voxel (x, y, z) that holds no label, and its value.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error(
    "{name} is not a label map: voxel ({x}, {y}, {z}) holds {value}, and labels are whole numbers 0 or more; give \
     the segmentation (an integer volume), not the scan"
)]
pub struct NotALabelMap {
    /// The volume's name.
    pub name: String,
    /// The voxel.
    pub x: u32,
    /// The voxel.
    pub y: u32,
    /// The voxel.
    pub z: u32,
    /// What it holds.
    pub value: f64,
}

/// Counts the labels of `volume`.
pub fn census(volume: &Volume) -> Result<Census, NotALabelMap> {
    let not_a_label = |i: usize, value: f64| {
        let (nx, ny) = (volume.dims.x as usize, volume.dims.y as usize);
        NotALabelMap {
            name: volume.name.clone(),
            x: (i % nx) as u32,
            y: ((i / nx) % ny) as u32,
            z: (i / (nx * ny)) as u32,
            value,
        }
    };
    let dense = |values: &mut dyn Iterator<Item = usize>, size: usize| {
        let mut counts = vec![0u64; size];
        for v in values {
            counts[v] += 1;
        }
        counts
            .iter()
            .enumerate()
            .filter(|(_, n)| **n > 0)
            .map(|(v, n)| LabelCount { value: v as u32, voxels: *n })
            .collect::<Vec<_>>()
    };
    let counts = match &volume.data {
        VoxelData::U8(v) => dense(&mut v.iter().map(|x| *x as usize), 1 << 8),
        VoxelData::U16(v) => dense(&mut v.iter().map(|x| *x as usize), 1 << 16),
        VoxelData::I16(v) => {
            if let Some(i) = v.iter().position(|x| *x < 0) {
                return Err(not_a_label(i, f64::from(v[i])));
            }
            dense(&mut v.iter().map(|x| *x as usize), 1 << 15)
        }
        VoxelData::F32(v) => {
            let mut counts: BTreeMap<u32, u64> = BTreeMap::new();
            for (i, x) in v.iter().enumerate() {
                if !(*x >= 0.0 && x.fract() == 0.0 && *x <= u32::MAX as f32) {
                    return Err(not_a_label(i, f64::from(*x)));
                }
                *counts.entry(*x as u32).or_default() += 1;
            }
            counts.into_iter().map(|(value, voxels)| LabelCount { value, voxels }).collect()
        }
    };
    Ok(Census { counts, voxel_volume: volume.spacing.x * volume.spacing.y * volume.spacing.z })
}

#[cfg(test)]
mod tests {
    use glam::{DVec3, UVec3};

    use super::*;

    fn map(data: VoxelData, dims: UVec3, spacing: DVec3) -> Volume {
        Volume::new("labels", dims, spacing, data)
    }

    #[test]
    fn every_label_is_counted_with_its_volume() {
        // 4×4×4 at 0.5 × 0.5 × 2 mm (0.5 mm³ a voxel): 8 voxels of label 3, 2 of label 65535.
        let mut data = vec![0u16; 64];
        data[..8].fill(3);
        data[62] = 65_535;
        data[63] = 65_535;
        let census = census(&map(VoxelData::U16(data), UVec3::splat(4), DVec3::new(0.5, 0.5, 2.0))).expect("labels");
        assert_eq!(census.values(), [0, 3, 65_535]);
        assert_eq!(census.counts[1], LabelCount { value: 3, voxels: 8 });
        assert_eq!(census.counts[0].voxels, 54);
        assert!((census.millilitres(8) - 0.004).abs() < 1e-12);
    }

    #[test]
    fn sixty_five_thousand_labels_are_counted() {
        // Every u16 value once: 65,535 labels and the background (issue 43, item 7).
        let data: Vec<u16> = (0..=u16::MAX).collect();
        let counts = census(&map(VoxelData::U16(data), UVec3::new(256, 256, 1), DVec3::ONE)).expect("labels");
        assert_eq!(counts.counts.len(), 65_536);
        assert!(counts.counts.iter().all(|c| c.voxels == 1));
        assert_eq!(counts.counts.last().map(|c| c.value), Some(65_535));
    }

    #[test]
    fn a_volume_of_non_labels_is_an_error_naming_a_voxel() {
        let mut data = vec![1.0f32; 8];
        data[5] = 2.5;
        let err = census(&map(VoxelData::F32(data), UVec3::splat(2), DVec3::ONE)).expect_err("2.5");
        assert_eq!((err.x, err.y, err.z, err.value), (1, 0, 1, 2.5));
        assert!(err.to_string().contains("voxel (1, 0, 1) holds 2.5"), "{err}");
        let negative = census(&map(VoxelData::I16(vec![0, -1, 0, 0, 0, 0, 0, 0]), UVec3::splat(2), DVec3::ONE));
        assert_eq!(negative.expect_err("-1").value, -1.0);
        let whole =
            census(&map(VoxelData::F32(vec![0.0, 7.0, 7.0, 1.0e6, 0.0, 0.0, 0.0, 0.0]), UVec3::splat(2), DVec3::ONE));
        assert_eq!(whole.expect("whole numbers").values(), [0, 7, 1_000_000]);
    }
}
