//! Axis orientation from a header's direction vectors (NRRD `space directions`, MetaImage
//! `TransformMatrix`): which world axis each file axis runs along, and whether it runs backwards.
//!
//! volgraph renders axis-aligned grids whose x, y and z run along world +x, +y and +z
//! (`docs/rendering_model.md`). A header whose directions are axis vectors up to sign and order
//! (flips and permutations) is honoured by reordering the voxels into that frame; the world axes
//! are the axes of the header's own space (NRRD `space`, e.g. left-posterior-superior). Rotated
//! or oblique directions cannot be shown without resampling and are rejected with a message.

use glam::{DVec3, UVec3};

use super::{LoadError, Location};
use crate::volume::VoxelData;

/// Components below this fraction of a direction's length count as zero (headers written with
/// rounding noise such as `(1,1e-17,0)` stay axis-aligned).
const AXIS_TOLERANCE: f64 = 1e-6;

/// How the file's index axes lie in the world.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AxisOrientation {
    /// File axis i runs along world axis `world_axis[i]` (0 = x, 1 = y, 2 = z).
    pub world_axis: [usize; 3],
    /// File axis i runs towards −world.
    pub flipped: [bool; 3],
}

impl Default for AxisOrientation {
    fn default() -> Self {
        Self { world_axis: [0, 1, 2], flipped: [false; 3] }
    }
}

impl AxisOrientation {
    /// From the three direction vectors of file axes 0, 1, 2 (each the world step of one voxel
    /// along that axis), with the voxel spacing along world x, y, z. `at` and `field` name the
    /// header line in errors.
    pub fn from_directions(directions: [DVec3; 3], at: &Location, field: &str) -> Result<(Self, DVec3), LoadError> {
        // Shortest round-trip text, in scientific notation where that would run to hundreds of
        // digits (a header's 1e300).
        let short =
            |v: f64| if v != 0.0 && !(1e-4..1e9).contains(&v.abs()) { format!("{v:e}") } else { format!("{v}") };
        let text = directions
            .iter()
            .map(|d| format!("({},{},{})", short(d.x), short(d.y), short(d.z)))
            .collect::<Vec<_>>()
            .join(" ");
        let mut orientation = AxisOrientation::default();
        let mut spacing = DVec3::ONE;
        let mut taken = [false; 3];
        for (i, d) in directions.iter().enumerate() {
            let length = d.length();
            let a = d.abs();
            let axis = if a.x >= a.y && a.x >= a.z {
                0
            } else if a.y >= a.z {
                1
            } else {
                2
            };
            let off_axis = (0..3).filter(|&k| k != axis).map(|k| a[k]).fold(0.0, f64::max);
            if !(length.is_finite() && length > 0.0) {
                return Err(LoadError::BadSpacing { at: at.clone(), x: d.x, y: d.y, z: d.z });
            }
            if off_axis > AXIS_TOLERANCE * length {
                return Err(LoadError::ObliqueAxes { at: at.clone(), field: field.to_string(), value: text });
            }
            if std::mem::replace(&mut taken[axis], true) {
                return Err(LoadError::DegenerateAxes { at: at.clone(), field: field.to_string(), value: text });
            }
            orientation.world_axis[i] = axis;
            orientation.flipped[i] = d[axis] < 0.0;
            spacing[axis] = length;
        }
        Ok((orientation, spacing))
    }

    /// True when file axes are world axes in order, none flipped.
    pub fn is_identity(&self) -> bool {
        *self == AxisOrientation::default()
    }

    /// `"file axis 0 → −x, 1 → +z, 2 → +y"`, for load notes.
    pub fn describe(&self) -> String {
        let parts: Vec<String> = (0..3)
            .map(|i| {
                let sign = if self.flipped[i] { "−" } else { "+" };
                format!("{i} → {sign}{}", ["x", "y", "z"][self.world_axis[i]])
            })
            .collect();
        format!("file axis {}", parts.join(", "))
    }

    /// The dimensions in world order of a grid of `file_dims`.
    pub fn world_dims(&self, file_dims: UVec3) -> UVec3 {
        let mut w = UVec3::ZERO;
        for i in 0..3 {
            w[self.world_axis[i]] = file_dims[i];
        }
        w
    }

    /// The patient-frame centre of the reordered volume's voxel (0, 0, 0) — the world-lowest
    /// corner voxel — from the centre of the file's first voxel, `file_origin` (a header's
    /// `space origin` or `Offset`), for a grid of `file_dims` at `spacing` (world order): a file
    /// axis stored towards −world starts at the other end.
    pub fn world_origin(&self, file_origin: DVec3, file_dims: UVec3, spacing: DVec3) -> DVec3 {
        let mut origin = file_origin;
        for i in 0..3 {
            if self.flipped[i] {
                let a = self.world_axis[i];
                origin[a] -= spacing[a] * (file_dims[i].max(1) - 1) as f64;
            }
        }
        origin
    }

    /// Reorders voxels stored in file order (`file_dims`, file axis 0 fastest) into world order
    /// (x fastest, every axis ascending).
    pub fn reorder(&self, file_dims: UVec3, data: VoxelData) -> VoxelData {
        if self.is_identity() {
            return data;
        }
        match data {
            VoxelData::U8(v) => VoxelData::U8(self.reorder_values(file_dims, &v)),
            VoxelData::U16(v) => VoxelData::U16(self.reorder_values(file_dims, &v)),
            VoxelData::I16(v) => VoxelData::I16(self.reorder_values(file_dims, &v)),
            VoxelData::F32(v) => VoxelData::F32(self.reorder_values(file_dims, &v)),
        }
    }

    fn reorder_values<T: Copy>(&self, file_dims: UVec3, values: &[T]) -> Vec<T> {
        let world = self.world_dims(file_dims);
        let fd = [file_dims.x as usize, file_dims.y as usize, file_dims.z as usize];
        let file_stride = [1, fd[0], fd[0] * fd[1]];
        // For each world axis: the file axis along it, its stride and whether it runs backwards.
        let mut along = [(0usize, false, 0usize); 3];
        for i in 0..3 {
            along[self.world_axis[i]] = (file_stride[i], self.flipped[i], fd[i]);
        }
        let index = |axis: usize, w: usize| {
            let (stride, flipped, n) = along[axis];
            stride * if flipped { n - 1 - w } else { w }
        };
        let mut out = Vec::with_capacity(values.len());
        for z in 0..world.z as usize {
            let iz = index(2, z);
            for y in 0..world.y as usize {
                let iy = iz + index(1, y);
                for x in 0..world.x as usize {
                    out.push(values[iy + index(0, x)]);
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at() -> Location {
        Location::line(std::path::Path::new("h.nhdr"), 3)
    }

    #[test]
    fn flip_and_swap_reorder_voxels_into_world_order() {
        // File axis 0 runs along −y, file axis 1 along +x, file axis 2 along +z.
        let dirs = [DVec3::new(0.0, -2.0, 0.0), DVec3::new(1.0, 0.0, 0.0), DVec3::new(0.0, 0.0, 3.0)];
        let (o, spacing) = AxisOrientation::from_directions(dirs, &at(), "space directions").expect("axis-aligned");
        assert_eq!(spacing, DVec3::new(1.0, 2.0, 3.0));
        let file_dims = UVec3::new(2, 3, 1);
        // value = 10·i0 + i1
        let values: Vec<u8> = (0..3).flat_map(|i1| (0..2).map(move |i0| 10 * i0 + i1)).collect();
        let VoxelData::U8(out) = o.reorder(file_dims, VoxelData::U8(values)) else { unreachable!() };
        assert_eq!(o.world_dims(file_dims), UVec3::new(3, 2, 1));
        // World (x, y): x = i1, y runs backwards along i0.
        for y in 0..2u8 {
            for x in 0..3u8 {
                assert_eq!(out[(y * 3 + x) as usize], 10 * (1 - y) + x);
            }
        }
    }

    #[test]
    fn oblique_directions_are_rejected() {
        let dirs = [DVec3::new(0.7, 0.7, 0.0), DVec3::new(-0.7, 0.7, 0.0), DVec3::Z];
        let e = AxisOrientation::from_directions(dirs, &at(), "space directions").expect_err("oblique");
        assert!(e.to_string().contains("not along the volume's axes"), "{e}");
    }
}
