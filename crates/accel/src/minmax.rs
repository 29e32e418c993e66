//! The min/max block grid of Krüger & Westermann 2003 §2.3: the volume is cut into disjoint
//! blocks of `block_size³` voxels and every block stores the minimum and maximum normalized
//! value that a trilinear sample inside it can take. A transfer function then decides per block,
//! in O(1) (see [`crate::classify`]), whether the block can be skipped.
//!
//! # Which positions a block covers
//! Texture space has voxel `i` centred at `u = (i + 0.5) / n` (`docs/rendering_model.md`); in
//! voxel coordinates `p = u·n − 0.5` voxel `i` sits at `p = i`. Block `b` (per axis) owns the
//! texel footprints of voxels `[b·B, e)` with `e = min((b+1)·B, n)`, i.e. the closed box
//! `u ∈ [b·B / n, e / n]` (`p ∈ [b·B − 0.5, e − 0.5]`); the block holding `u` is
//! `floor(u·n / B)`, clamped to the grid. A trilinear sample at such a `p` reads voxels
//! `floor(p)` and `floor(p) + 1`, which lie in `[b·B − 1, e]`: the block's own voxels plus a
//! one-voxel apron on each side, clamped to the volume (clamp-to-edge). The stored range is the
//! min/max over exactly that apron box, so every sample in the closed box (faces shared with a
//! neighbour included) lies in `[min, max]`. Positions outside `[0,1]` clamp to the border
//! voxels, so the outermost blocks also bound every sample beyond the volume's faces.
//!
//! Values are stored as `f32` rounded outward (min down, max up) from the exact `f64`
//! normalized value, so the bound holds for the f64 reference and the f32 GPU texture alike.

use glam::UVec3;
use rayon::prelude::*;

use crate::volume::{Volume, VoxelData};

/// Default block edge length in voxels: the 8³ blocks of Krüger & Westermann 2003 §2.3.
pub const DEFAULT_BLOCK_SIZE: u32 = 8;

/// Why a min/max grid, brick set or octree hierarchy could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GridError {
    /// A size parameter (block size, brick size, node size) was zero.
    #[error("{what} must be at least 1 voxel (got 0)")]
    ZeroSize {
        /// Which parameter, e.g. `"block_size"`.
        what: &'static str,
    },
    /// The volume has a zero dimension.
    #[error("volume \"{name}\" has no voxels (dims {dims}); load or generate a non-empty volume")]
    EmptyVolume {
        /// The volume's name.
        name: String,
        /// Its dims.
        dims: UVec3,
    },
    /// The voxel array does not match `dims`.
    #[error(
        "volume \"{name}\" holds {found} voxels but its dims {dims} need {expected}; \
         the loader or generator built an inconsistent volume"
    )]
    DataLength {
        /// The volume's name.
        name: String,
        /// Its dims.
        dims: UVec3,
        /// `nx*ny*nz`.
        expected: usize,
        /// The length of the voxel array.
        found: usize,
    },
    /// A brick overlap other than 1 (trilinear) or 2 (trilinear + central differences).
    #[error("brick overlap must be 1 (trilinear) or 2 (trilinear with on-the-fly gradients), got {overlap}")]
    UnsupportedOverlap {
        /// The overlap asked for.
        overlap: u32,
    },
    /// A structure was used with a volume of other dims than the one it was built for.
    #[error("{what} was built for a volume of dims {expected}, but the volume has dims {found}")]
    MismatchedVolume {
        /// What was used, e.g. `"brick layout"`.
        what: &'static str,
        /// Dims it was built for.
        expected: UVec3,
        /// Dims of the volume passed in.
        found: UVec3,
    },
}

/// Checks that `volume` is non-empty and its voxel array matches its dims.
pub(crate) fn check_volume(volume: &Volume) -> Result<(), GridError> {
    if volume.dims.min_element() == 0 {
        return Err(GridError::EmptyVolume { name: volume.name.clone(), dims: volume.dims });
    }
    let expected = volume.voxel_count();
    let found = volume.data.len();
    if expected != found {
        return Err(GridError::DataLength { name: volume.name.clone(), dims: volume.dims, expected, found });
    }
    Ok(())
}

/// `x` rounded to an `f32` that is `<= x`.
pub(crate) fn f32_down(x: f64) -> f32 {
    let f = x as f32;
    if f as f64 > x { f.next_down() } else { f }
}

/// `x` rounded to an `f32` that is `>= x`.
pub(crate) fn f32_up(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x { f.next_up() } else { f }
}

fn raw_box_minmax<T: Copy + PartialOrd>(data: &[T], dims: UVec3, lo: UVec3, hi: UVec3) -> (T, T) {
    let (nx, ny) = (dims.x as usize, dims.y as usize);
    let first = lo.x as usize + nx * (lo.y as usize + ny * lo.z as usize);
    let (mut mn, mut mx) = (data[first], data[first]);
    let row_len = (hi.x - lo.x) as usize + 1;
    for z in lo.z..=hi.z {
        for y in lo.y..=hi.y {
            let start = lo.x as usize + nx * (y as usize + ny * z as usize);
            for &v in &data[start..start + row_len] {
                if v < mn {
                    mn = v;
                }
                if v > mx {
                    mx = v;
                }
            }
        }
    }
    (mn, mx)
}

/// Normalized `[min, max]` (rounded outward to f32) over the voxel box `lo..=hi` (inclusive,
/// already clamped to the volume). The normalization mirrors [`Volume::normalized`], which is
/// monotone for every voxel type, so the raw min/max map to the normalized min/max.
pub(crate) fn voxel_box_range(volume: &Volume, lo: UVec3, hi: UVec3) -> [f32; 2] {
    let dims = volume.dims;
    let (a, b) = match &volume.data {
        VoxelData::U8(v) => {
            let (a, b) = raw_box_minmax(v, dims, lo, hi);
            (a as f64, b as f64)
        }
        VoxelData::U16(v) => {
            let (a, b) = raw_box_minmax(v, dims, lo, hi);
            (a as f64, b as f64)
        }
        VoxelData::I16(v) => {
            let (a, b) = raw_box_minmax(v, dims, lo, hi);
            (a as f64, b as f64)
        }
        VoxelData::F32(v) => {
            let (a, b) = raw_box_minmax(v, dims, lo, hi);
            (a as f64, b as f64)
        }
    };
    let (mn, mx) = (volume.normalize_value(a), volume.normalize_value(b));
    [f32_down(mn), f32_up(mx)]
}

/// The min/max block grid of Krüger & Westermann 2003 §2.3, conservative for trilinear
/// interpolation (see the module docs for the exact region each block covers).
#[derive(Clone, Debug, PartialEq)]
pub struct MinMaxGrid {
    volume_dims: UVec3,
    block_size: u32,
    dims: UVec3,
    ranges: Vec<[f32; 2]>,
}

impl MinMaxGrid {
    /// Builds the grid with blocks of `block_size³` voxels (the last block per axis is smaller
    /// when `block_size` does not divide the dims), in parallel over z-slabs of blocks.
    pub fn build(volume: &Volume, block_size: u32) -> Result<Self, GridError> {
        if block_size == 0 {
            return Err(GridError::ZeroSize { what: "block_size" });
        }
        check_volume(volume)?;
        let n = volume.dims;
        let dims = (n - 1) / block_size + 1; // ceil without overflow for huge block sizes
        let slab = (dims.x * dims.y) as usize;
        let mut ranges = vec![[0.0f32; 2]; slab * dims.z as usize];
        ranges.par_chunks_mut(slab).enumerate().for_each(|(bz, out)| {
            for by in 0..dims.y {
                for bx in 0..dims.x {
                    let block = UVec3::new(bx, by, bz as u32);
                    let (lo, hi) = apron_box(n, block_size, block);
                    out[(bx + dims.x * by) as usize] = voxel_box_range(volume, lo, hi);
                }
            }
        });
        Ok(Self { volume_dims: n, block_size, dims, ranges })
    }

    /// Blocks per axis: `ceil(volume_dims / block_size)`.
    pub fn dims(&self) -> UVec3 {
        self.dims
    }

    /// Block edge length in voxels.
    pub fn block_size(&self) -> u32 {
        self.block_size
    }

    /// Dims of the volume the grid was built from.
    pub fn volume_dims(&self) -> UVec3 {
        self.volume_dims
    }

    /// Number of blocks.
    pub fn block_count(&self) -> usize {
        self.ranges.len()
    }

    /// Linear index of block `b` (x fastest).
    pub fn block_index(&self, b: UVec3) -> usize {
        (b.x + self.dims.x * (b.y + self.dims.y * b.z)) as usize
    }

    /// `[min, max]` normalized of block `b`, apron included. Panics if `b` is outside the grid
    /// (an indexing bug in the caller, like slice indexing).
    pub fn range(&self, b: UVec3) -> [f32; 2] {
        self.ranges[self.block_index(b)]
    }

    /// All `[min, max]` pairs, x fastest.
    pub fn ranges(&self) -> &[[f32; 2]] {
        &self.ranges
    }

    /// The data of an `Rg32Float` 3D texture of size [`Self::dims`]: R = min, G = max, x
    /// fastest, as bytes ready for `queue.write_texture` (bytes per row = `8 * dims.x`).
    pub fn to_rg32float_bytes(&self) -> Vec<u8> {
        bytemuck::cast_slice::<[f32; 2], u8>(&self.ranges).to_vec()
    }

    /// The voxel box `lo..=hi` (inclusive) whose values block `b` bounds: its own voxels
    /// plus the one-voxel apron, clamped to the volume.
    pub fn block_voxel_box(&self, b: UVec3) -> (UVec3, UVec3) {
        apron_box(self.volume_dims, self.block_size, b)
    }

    /// The closed texture-space box `[lo, hi]` that block `b` covers: `b·B/n ..
    /// min((b+1)·B, n)/n` per axis (the texel footprints of its own voxels).
    pub fn block_texture_box(&self, b: UVec3) -> (glam::DVec3, glam::DVec3) {
        let n = self.volume_dims.as_dvec3();
        let lo = (b * self.block_size).as_dvec3() / n;
        let hi = (b + 1).saturating_mul(UVec3::splat(self.block_size)).min(self.volume_dims);
        let hi = hi.as_dvec3() / n;
        (lo, hi)
    }
}

/// Voxel box (inclusive) of block `b` plus a one-voxel apron, clamped to `[0, n-1]`.
fn apron_box(n: UVec3, block_size: u32, b: UVec3) -> (UVec3, UVec3) {
    let start = b * block_size;
    let end = (b + 1).saturating_mul(UVec3::splat(block_size)).min(n); // exclusive
    let lo = start.saturating_sub(UVec3::ONE);
    let hi = end.min(n - 1);
    (lo, hi)
}
