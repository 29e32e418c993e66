//! Bricking after Ruijters & Vilanova 2006 §5: the volume is cut into bricks that each become a
//! small 3D texture holding the *raw* values (so a transfer-function change never rebuilds a
//! brick, only re-classifies its min/max), with an overlap so that interpolation at a brick's
//! faces reads the same voxels as in the whole volume.
//!
//! # Cells and the space a brick covers
//! Like §7 of the paper, bricks and octrees partition *cells*: cell `c` (per axis) is the box
//! between voxel centres `c` and `c + 1`, i.e. voxel coordinates `p ∈ [c, c+1]` or texture
//! coordinates `u ∈ [(c+0.5)/n, (c+1.5)/n]`, and a trilinear sample inside it reads only its
//! two corner voxels per axis. There are `m = max(n−1, 1)` cells per axis. To tile the whole
//! texture box `[0,1]`, the first cell extends down to `u = 0` and the last one up to `u = 1`:
//! in those half-voxel border slabs clamp-to-edge makes the sample constant along the axis and
//! equal to the value on the cell's face, so it still reads only the cell's corner voxels (for
//! `n = 1` the single "cell" has both corners at voxel 0). A cell's value range is therefore
//! exactly `[min, max]` of its corner voxels.
//!
//! A brick owns `brick_cells` cells per axis (fewer in the last brick when `brick_cells` does
//! not divide `m`: the paper's "rest-bricks"). It stores the corner voxels of its cells
//! (`brick_cells + 1` per axis: adjacent bricks share one voxel layer, the one-voxel overlap of
//! §5 for trilinear interpolation) and, with overlap 2, one more voxel on each side for on-the-fly
//! central-difference gradients, clamped to the volume. The §5 estimate of the memory overhead
//! is `3·overlap / brick_cells`; [`BrickSet::memory`] reports the measured one.

use glam::{DVec3, UVec3};
use rayon::prelude::*;

use crate::classify::OpacityClassifier;
use crate::minmax::{GridError, check_volume, voxel_box_range};
use crate::volume::{Volume, VoxelData};

/// Cells per axis of a volume with `n` voxels per axis: `max(n − 1, 1)`.
pub fn cell_dims(volume_dims: UVec3) -> UVec3 {
    volume_dims.saturating_sub(UVec3::ONE).max(UVec3::ONE)
}

/// Texture-space box `[lo, hi]` covered by cells `cells_lo..cells_hi` (exclusive) of a volume
/// with `volume_dims` voxels, border cells extended to the faces (module docs).
pub fn cells_texture_box(volume_dims: UVec3, cells_lo: UVec3, cells_hi: UVec3) -> (DVec3, DVec3) {
    let n = volume_dims.as_dvec3();
    let m = cell_dims(volume_dims);
    let lo = (cells_lo.as_dvec3() + 0.5) / n;
    let hi = (cells_hi.as_dvec3() + 0.5) / n;
    let lo = DVec3::select(cells_lo.cmpeq(UVec3::ZERO), DVec3::ZERO, lo);
    let hi = DVec3::select(cells_hi.cmpge(m), DVec3::ONE, hi);
    (lo, hi)
}

/// Inclusive voxel box of the corner voxels of cells `cells_lo..cells_hi` (exclusive).
pub(crate) fn cells_corner_voxels(volume_dims: UVec3, lo: UVec3, hi: UVec3) -> (UVec3, UVec3) {
    (lo, hi.min(volume_dims - 1))
}

/// Where the bricks of a volume are (Ruijters & Vilanova 2006 §5), without any voxel data:
/// shared by [`BrickSet`] and the per-brick octrees of [`crate::octree`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BrickLayout {
    volume_dims: UVec3,
    brick_cells: u32,
    overlap: u32,
    grid_dims: UVec3,
}

impl BrickLayout {
    /// A layout of bricks with `brick_cells` cells per axis and `overlap` 1 (trilinear) or 2
    /// (trilinear with on-the-fly central-difference gradients).
    pub fn new(volume_dims: UVec3, brick_cells: u32, overlap: u32) -> Result<Self, GridError> {
        if brick_cells == 0 {
            return Err(GridError::ZeroSize { what: "brick_cells" });
        }
        if !(1..=2).contains(&overlap) {
            return Err(GridError::UnsupportedOverlap { overlap });
        }
        if volume_dims.min_element() == 0 {
            return Err(GridError::EmptyVolume { name: "(layout)".into(), dims: volume_dims });
        }
        let grid_dims = (cell_dims(volume_dims) - 1) / brick_cells + 1;
        Ok(Self { volume_dims, brick_cells, overlap, grid_dims })
    }

    /// Dims of the volume.
    pub fn volume_dims(&self) -> UVec3 {
        self.volume_dims
    }

    /// Cells per brick and axis (the last brick per axis may have fewer).
    pub fn brick_cells(&self) -> u32 {
        self.brick_cells
    }

    /// The overlap, 1 or 2.
    pub fn overlap(&self) -> u32 {
        self.overlap
    }

    /// Bricks per axis.
    pub fn grid_dims(&self) -> UVec3 {
        self.grid_dims
    }

    /// Number of bricks.
    pub fn brick_count(&self) -> usize {
        (self.grid_dims.x * self.grid_dims.y * self.grid_dims.z) as usize
    }

    /// Grid coordinate of brick `index` (x fastest).
    pub fn brick_coord(&self, index: usize) -> UVec3 {
        let g = self.grid_dims;
        let i = index as u32;
        UVec3::new(i % g.x, (i / g.x) % g.y, i / (g.x * g.y))
    }

    /// The cells a brick owns: `lo..hi` (exclusive).
    pub fn brick_cells_box(&self, coord: UVec3) -> (UVec3, UVec3) {
        let lo = coord * self.brick_cells;
        let hi = (coord + 1).saturating_mul(UVec3::splat(self.brick_cells));
        (lo, hi.min(cell_dims(self.volume_dims)))
    }

    /// The voxels a brick stores: `origin` and `dims`; the corner voxels of its cells plus
    /// `overlap − 1` voxels per side, clamped to the volume.
    pub fn brick_stored_box(&self, coord: UVec3) -> (UVec3, UVec3) {
        let (lo, hi) = self.brick_cells_box(coord);
        let extra = self.overlap - 1;
        let origin = lo.saturating_sub(UVec3::splat(extra));
        let end = (hi + 1 + extra).min(self.volume_dims);
        (origin, end - origin)
    }

    /// Texture-space box the brick covers (module docs).
    pub fn brick_texture_box(&self, coord: UVec3) -> (DVec3, DVec3) {
        let (lo, hi) = self.brick_cells_box(coord);
        cells_texture_box(self.volume_dims, lo, hi)
    }

    /// Brick indices in a front-to-back order for a view (Ruijters & Vilanova 2006 §7 needs the
    /// bricks drawn front to back). The key of a brick is its grid distance from the eye summed
    /// over axes; a brick that occludes another is nearer on every axis where they differ, so
    /// it has a smaller key and comes first.
    pub fn front_to_back(&self, view: ViewPoint) -> Vec<u32> {
        let g = self.grid_dims;
        let key = |c: UVec3| -> u32 {
            let mut k = 0;
            for a in 0..3 {
                k += match view {
                    ViewPoint::Direction(d) if d[a] < 0.0 => g[a] - 1 - c[a],
                    ViewPoint::Direction(_) => c[a],
                    ViewPoint::Eye(eye) => {
                        // Grid distance from the brick holding the eye (clamped to the grid).
                        let m = cell_dims(self.volume_dims)[a] as f64;
                        let cell = (eye[a] * self.volume_dims[a] as f64 - 0.5).clamp(0.0, m - 1.0);
                        c[a].abs_diff(cell as u32 / self.brick_cells)
                    }
                };
            }
            k
        };
        let mut order: Vec<u32> = (0..self.brick_count() as u32).collect();
        order.sort_by_key(|i| key(self.brick_coord(*i as usize)));
        order
    }
}

/// Where the viewer is, for front-to-back orders.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ViewPoint {
    /// An orthographic view along this texture-space direction (from the eye into the scene).
    Direction(DVec3),
    /// A perspective eye at this texture-space position (may be outside `[0,1]³`).
    Eye(DVec3),
}

/// One brick: a copy of its stored voxels (overlap included) and its value range.
#[derive(Clone, Debug, PartialEq)]
pub struct Brick {
    /// Grid coordinate of the brick.
    pub coord: UVec3,
    /// Volume voxel index of the brick's voxel `(0,0,0)`.
    pub origin: UVec3,
    /// Stored voxels per axis.
    pub dims: UVec3,
    /// The stored voxels, x fastest, same type as the volume's.
    pub data: VoxelData,
    /// `[min, max]` normalized over the brick's cells (their corner voxels), rounded outward:
    /// every trilinear sample in [`BrickLayout::brick_texture_box`] lies in it. The gradient
    /// overlap does not enter: it never changes a sample's value.
    pub range: [f32; 2],
}

/// Memory of the bricks against the plain volume (Ruijters & Vilanova 2006 §5).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct BrickMemory {
    /// Bytes of the plain volume.
    pub volume_bytes: u64,
    /// Bytes of all bricks' voxels together.
    pub brick_bytes: u64,
    /// `brick_bytes − volume_bytes`.
    pub overhead_bytes: i64,
    /// `brick_bytes / volume_bytes`.
    pub ratio: f64,
}

/// A bricked copy of a volume (Ruijters & Vilanova 2006 §5).
#[derive(Clone, Debug, PartialEq)]
pub struct BrickSet {
    layout: BrickLayout,
    bricks: Vec<Brick>,
    name: String,
    spacing: DVec3,
    value_range: (f64, f64),
}

impl BrickSet {
    /// Copies `volume` into bricks of `brick_cells` cells per axis with `overlap` 1 or 2, in
    /// parallel over bricks.
    pub fn build(volume: &Volume, brick_cells: u32, overlap: u32) -> Result<Self, GridError> {
        check_volume(volume)?;
        let layout = BrickLayout::new(volume.dims, brick_cells, overlap)?;
        let bricks = (0..layout.brick_count())
            .into_par_iter()
            .map(|i| {
                let coord = layout.brick_coord(i);
                let (origin, dims) = layout.brick_stored_box(coord);
                let (cl, ch) = layout.brick_cells_box(coord);
                let (lo, hi) = cells_corner_voxels(volume.dims, cl, ch);
                Brick {
                    coord,
                    origin,
                    dims,
                    data: copy_box(&volume.data, volume.dims, origin, dims),
                    range: voxel_box_range(volume, lo, hi),
                }
            })
            .collect();
        Ok(Self { layout, bricks, name: volume.name.clone(), spacing: volume.spacing, value_range: volume.value_range })
    }

    /// The layout.
    pub fn layout(&self) -> &BrickLayout {
        &self.layout
    }

    /// The bricks, in layout order (x fastest).
    pub fn bricks(&self) -> &[Brick] {
        &self.bricks
    }

    /// Measured memory of the bricks against the plain volume.
    pub fn memory(&self) -> BrickMemory {
        let bytes_per_voxel = |d: &VoxelData| match d {
            VoxelData::U8(_) => 1u64,
            VoxelData::U16(_) | VoxelData::I16(_) => 2,
            VoxelData::F32(_) => 4,
        };
        let n = self.layout.volume_dims.as_u64vec3();
        let per = self.bricks.first().map_or(1, |b| bytes_per_voxel(&b.data));
        let volume_bytes = n.x * n.y * n.z * per;
        let brick_bytes: u64 = self.bricks.iter().map(|b| b.data.len() as u64 * per).sum();
        BrickMemory {
            volume_bytes,
            brick_bytes,
            overhead_bytes: brick_bytes as i64 - volume_bytes as i64,
            ratio: brick_bytes as f64 / volume_bytes as f64,
        }
    }

    /// Per brick: true when the brick is empty under the classifier (all of its samples are
    /// transparent). Only re-classifies the stored ranges; the bricks stay as they are.
    pub fn empty_bricks(&self, classifier: &OpacityClassifier) -> Vec<bool> {
        self.bricks.iter().map(|b| !classifier.is_range_visible(b.range)).collect()
    }

    /// The volume again, from the bricks' voxels (every voxel lies in at least one brick).
    pub fn reassemble(&self) -> Volume {
        let n = self.layout.volume_dims;
        let count = (n.x * n.y * n.z) as usize;
        let mut data = match self.bricks.first().map(|b| &b.data) {
            Some(VoxelData::U16(_)) => VoxelData::U16(vec![0; count]),
            Some(VoxelData::I16(_)) => VoxelData::I16(vec![0; count]),
            Some(VoxelData::F32(_)) => VoxelData::F32(vec![0.0; count]),
            _ => VoxelData::U8(vec![0; count]),
        };
        for b in &self.bricks {
            paste_box(&mut data, n, b.origin, b.dims, &b.data);
        }
        Volume {
            dims: n,
            spacing: self.spacing,
            data,
            name: self.name.clone(),
            value_range: self.value_range,
            meta: Default::default(),
        }
    }
}

fn copy_typed<T: Copy>(src: &[T], n: UVec3, origin: UVec3, dims: UVec3) -> Vec<T> {
    let mut out = Vec::with_capacity((dims.x * dims.y * dims.z) as usize);
    for z in origin.z..origin.z + dims.z {
        for y in origin.y..origin.y + dims.y {
            let start = (origin.x + n.x * (y + n.y * z)) as usize;
            out.extend_from_slice(&src[start..start + dims.x as usize]);
        }
    }
    out
}

fn paste_typed<T: Copy>(dst: &mut [T], n: UVec3, origin: UVec3, dims: UVec3, src: &[T]) {
    for (row, chunk) in src.chunks_exact(dims.x as usize).enumerate() {
        let (y, z) = (row as u32 % dims.y, row as u32 / dims.y);
        let start = (origin.x + n.x * (origin.y + y + n.y * (origin.z + z))) as usize;
        dst[start..start + dims.x as usize].copy_from_slice(chunk);
    }
}

/// The voxels `origin..origin+dims` of `data` (dims `n`), x fastest.
fn copy_box(data: &VoxelData, n: UVec3, origin: UVec3, dims: UVec3) -> VoxelData {
    match data {
        VoxelData::U8(v) => VoxelData::U8(copy_typed(v, n, origin, dims)),
        VoxelData::U16(v) => VoxelData::U16(copy_typed(v, n, origin, dims)),
        VoxelData::I16(v) => VoxelData::I16(copy_typed(v, n, origin, dims)),
        VoxelData::F32(v) => VoxelData::F32(copy_typed(v, n, origin, dims)),
    }
}

fn paste_box(dst: &mut VoxelData, n: UVec3, origin: UVec3, dims: UVec3, src: &VoxelData) {
    match (dst, src) {
        (VoxelData::U8(d), VoxelData::U8(s)) => paste_typed(d, n, origin, dims, s),
        (VoxelData::U16(d), VoxelData::U16(s)) => paste_typed(d, n, origin, dims, s),
        (VoxelData::I16(d), VoxelData::I16(s)) => paste_typed(d, n, origin, dims, s),
        (VoxelData::F32(d), VoxelData::F32(s)) => paste_typed(d, n, origin, dims, s),
        // Every brick is copied from the same volume, so the types always agree.
        _ => unreachable!("bricks of one set share the volume's voxel type"),
    }
}
