//! A volume as a resolution pyramid read box by box: what a ray-guided streaming raycaster
//! (`raycast_stream`, after Hadwiger et al. 2012 and Crassin et al. 2009) reads bricks from,
//! without the volume ever being in memory whole. An OME-Zarr store is one
//! (`volgraph_zarr::ZarrPyramid`); an in-memory [`Volume`] is another ([`InCorePyramid`]), so
//! every graph and test can stream any volume.
//!
//! Level 0 is the finest. Level `l` has `dims[l]` voxels, each `factor[l]` level-0 voxels wide per
//! axis (2ˡ for a pyramid of 2×2×2 means): a point at level-0 voxel coordinate `u` (0 at the
//! volume's face, voxel centres at `i + 0.5`) is at `u / factor` in level `l` — the convention the
//! writer's means follow (a coarse voxel's centre is the centre of the fine voxels it averages).
//! Voxels come back normalized to \[0, 1\] exactly as a whole volume's texture holds them.

use glam::{DVec3, IVec3, UVec3};

use crate::volume::{Volume, VoxelData};

/// One level of a pyramid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PyramidLevel {
    /// Voxels per axis.
    pub dims: UVec3,
    /// Level-0 voxels per voxel of this level, per axis (1 at level 0).
    pub factor: DVec3,
}

/// Voxels of a box, normalized as the GPU texture holds them (`docs/rendering_model.md`).
#[derive(Clone, Debug, PartialEq)]
pub enum BoxTexels {
    /// `v / 255`.
    Unorm8(Vec<u8>),
    /// `v / 65535`.
    Unorm16(Vec<u16>),
    /// The value itself.
    Float(Vec<f32>),
}

impl BoxTexels {
    /// Number of voxels.
    pub fn len(&self) -> usize {
        match self {
            BoxTexels::Unorm8(v) => v.len(),
            BoxTexels::Unorm16(v) => v.len(),
            BoxTexels::Float(v) => v.len(),
        }
    }

    /// True when no voxel is held.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Voxel `i` normalized.
    pub fn value(&self, i: usize) -> f32 {
        match self {
            BoxTexels::Unorm8(v) => f32::from(v[i]) / 255.0,
            BoxTexels::Unorm16(v) => f32::from(v[i]) / 65535.0,
            BoxTexels::Float(v) => v[i],
        }
    }

    /// The (min, max) of the normalized values; `None` when empty.
    pub fn range(&self) -> Option<(f32, f32)> {
        (0..self.len()).map(|i| self.value(i)).fold(None, |r, v| match r {
            None => Some((v, v)),
            Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
        })
    }
}

/// The kind of texels a pyramid's boxes hold (one for all its levels).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TexelKind {
    /// [`BoxTexels::Unorm8`].
    Unorm8,
    /// [`BoxTexels::Unorm16`].
    Unorm16,
    /// [`BoxTexels::Float`].
    Float,
}

/// A volume read box by box at any level. Reads may come from several threads at once.
pub trait PyramidSource: Send + Sync {
    /// A name for messages.
    fn name(&self) -> &str;
    /// The levels, finest first; never empty.
    fn levels(&self) -> &[PyramidLevel];
    /// The physical size of a level-0 voxel (its world box follows, as a [`Volume`]'s).
    fn spacing(&self) -> DVec3;
    /// What the boxes hold.
    fn texel_kind(&self) -> TexelKind;
    /// Voxels `lo .. lo + dims` of `level`, x fastest, indices clamped to the level per axis (a
    /// box past a face repeats the face: clamp-to-edge, as the sampler does). An error names what
    /// could not be read; the caller draws that box as empty.
    fn read_box(&self, level: usize, lo: IVec3, dims: UVec3) -> Result<BoxTexels, String>;
    /// The (min, max) normalized value within voxels `lo .. hi` of `level` (clamped to it) if
    /// the source knows it without reading voxels (an OME-Zarr store's chunk ranges); `None`:
    /// unknown until read.
    fn box_range(&self, level: usize, lo: IVec3, hi: IVec3) -> Option<(f32, f32)> {
        let _ = (level, lo, hi);
        None
    }
    /// What reading found since last asked (missing or undecodable chunks, one line each), for
    /// the application to print; the bricks concerned were drawn empty.
    fn notes(&self) -> Vec<String> {
        Vec::new()
    }
    /// The coarsest level as a whole volume of the same physical box (transfer-function fitting,
    /// a first image, `info`).
    fn coarsest(&self) -> Result<Volume, String>;
}

/// A [`Volume`] held in memory as a pyramid of 2×2×2 means (odd edges averaged with
/// themselves, integer types rounded to the nearest as `volgraph convert` writes them),
/// halving until every axis is at most `coarsest_edge`: the in-core twin of an OME-Zarr store
/// the converter wrote, texel for texel, so the streaming raycaster renders any volume and its
/// tests need no store.
pub struct InCorePyramid {
    volume: std::sync::Arc<Volume>,
    levels: Vec<PyramidLevel>,
    /// Levels 1.. as stored values (level 0 is the volume).
    coarse: Vec<Vec<f32>>,
    kind: TexelKind,
}

impl InCorePyramid {
    /// The pyramid of `volume`, halving until every axis is at most `coarsest_edge` (≥ 1).
    pub fn new(volume: std::sync::Arc<Volume>, coarsest_edge: u32) -> Self {
        let integer = !matches!(volume.data, VoxelData::F32(_));
        let levels = pyramid_levels(volume.dims, coarsest_edge);
        let mut coarse: Vec<Vec<f32>> = Vec::new();
        for fine in &levels[..levels.len() - 1] {
            let d = fine.dims;
            let index = |v: UVec3| ((v.z * d.y + v.y) * d.x + v.x) as usize;
            let half = (d + 1) / 2;
            let next = match coarse.last() {
                Some(values) => halve_box(|v| f64::from(values[index(v)]), d, UVec3::ZERO, half, integer),
                None => halve_box(|v| volume.raw_value(index(v)), d, UVec3::ZERO, half, integer),
            };
            coarse.push(next);
        }
        let kind = texel_kind_of(&volume);
        Self { volume, levels, coarse, kind }
    }

    /// Stored value of voxel `i` of `level`.
    fn raw(&self, level: usize, i: usize) -> f64 {
        match level {
            0 => self.volume.raw_value(i),
            l => f64::from(self.coarse[l - 1][i]),
        }
    }
}

/// The texel kind of `volume`'s type (one for every level of its pyramid).
pub fn texel_kind_of(volume: &Volume) -> TexelKind {
    match volume.data {
        VoxelData::U8(_) => TexelKind::Unorm8,
        VoxelData::U16(_) | VoxelData::I16(_) => TexelKind::Unorm16,
        VoxelData::F32(_) => TexelKind::Float,
    }
}

/// Stored values of a pyramid of `volume` (its type, value range) as the whole volume's texture
/// holds them (`upload_volume_texture`): bytes as stored, the 16-bit type range as stored,
/// anything else normalized over the value range. `volume` may hold no voxels: only its type
/// and range are read.
pub fn texels_of(volume: &Volume, kind: TexelKind, values: impl Iterator<Item = f64>) -> BoxTexels {
    match kind {
        TexelKind::Unorm8 => BoxTexels::Unorm8(values.map(|v| v as u8).collect()),
        TexelKind::Unorm16 if volume.value_range == (0.0, 65535.0) && matches!(volume.data, VoxelData::U16(_)) => {
            BoxTexels::Unorm16(values.map(|v| v as u16).collect())
        }
        TexelKind::Unorm16 => BoxTexels::Unorm16(
            values.map(|v| (volume.normalize_value(v).clamp(0.0, 1.0) * 65535.0).round() as u16).collect(),
        ),
        TexelKind::Float => BoxTexels::Float(values.map(|v| volume.normalize_value(v) as f32).collect()),
    }
}

/// The dims of each level of a pyramid of `dims` halving until every axis is at most `edge`,
/// finest first, with their factors.
pub fn pyramid_levels(dims: UVec3, edge: u32) -> Vec<PyramidLevel> {
    let edge = edge.max(1);
    let mut levels = vec![PyramidLevel { dims, factor: DVec3::ONE }];
    let mut at = dims;
    while at.max_element() > edge {
        at = (at + 1) / 2;
        let factor = levels.last().map_or(DVec3::ONE, |l| l.factor * 2.0);
        levels.push(PyramidLevel { dims: at, factor });
    }
    levels
}

/// Voxels `[a, b)` of the level above a level of `dims` voxels whose stored values `value`
/// gives (by level voxel): each the 2×2×2 mean of its children `2x` and `min(2x + 1, dims − 1)`
/// per axis (odd edges averaged with themselves), summed z, y, x outermost first — one order
/// for every caller, so the in-memory pyramid, a file's cascade and its bricks agree bit for
/// bit — and rounded to the nearest for integer types.
pub fn halve_box(value: impl Fn(UVec3) -> f64, dims: UVec3, a: UVec3, b: UVec3, integer: bool) -> Vec<f32> {
    let size = b.saturating_sub(a);
    let mut out = Vec::with_capacity(size.x as usize * size.y as usize * size.z as usize);
    for z in a.z..b.z {
        let zs = [2 * z, (2 * z + 1).min(dims.z - 1)];
        for y in a.y..b.y {
            let ys = [2 * y, (2 * y + 1).min(dims.y - 1)];
            for x in a.x..b.x {
                let xs = [2 * x, (2 * x + 1).min(dims.x - 1)];
                let mut sum = 0.0;
                for zz in zs {
                    for yy in ys {
                        for xx in xs {
                            sum += value(UVec3::new(xx, yy, zz));
                        }
                    }
                }
                let mean = sum / 8.0;
                out.push(if integer { mean.round() } else { mean } as f32);
            }
        }
    }
    out
}

/// The linear indices of voxels `lo .. lo + dims` of a `level_dims` grid, clamped per axis.
pub fn clamped_indices(level_dims: UVec3, lo: IVec3, dims: UVec3) -> impl Iterator<Item = usize> {
    let n = level_dims.as_ivec3();
    (0..dims.z as i32).flat_map(move |z| {
        let zz = (lo.z + z).clamp(0, n.z - 1) as usize;
        (0..dims.y as i32).flat_map(move |y| {
            let yy = (lo.y + y).clamp(0, n.y - 1) as usize;
            let row = (zz * n.y as usize + yy) * n.x as usize;
            (0..dims.x as i32).map(move |x| row + (lo.x + x).clamp(0, n.x - 1) as usize)
        })
    })
}

impl PyramidSource for InCorePyramid {
    fn name(&self) -> &str {
        &self.volume.name
    }

    fn levels(&self) -> &[PyramidLevel] {
        &self.levels
    }

    fn spacing(&self) -> DVec3 {
        self.volume.spacing
    }

    fn texel_kind(&self) -> TexelKind {
        self.kind
    }

    fn read_box(&self, level: usize, lo: IVec3, dims: UVec3) -> Result<BoxTexels, String> {
        let level_dims = self.levels.get(level).ok_or_else(|| format!("no level {level}"))?.dims;
        let indices = clamped_indices(level_dims, lo, dims);
        Ok(texels_of(&self.volume, self.kind, indices.map(|i| self.raw(level, i))))
    }

    fn coarsest(&self) -> Result<Volume, String> {
        let last = self.levels.len() - 1;
        if last == 0 {
            return Ok((*self.volume).clone());
        }
        let level = self.levels[last];
        let data = VoxelData::F32(self.coarse[last - 1].clone());
        let mut v = Volume::new(self.volume.name.clone(), level.dims, self.volume.spacing * level.factor, data);
        v.value_range = self.volume.value_range;
        v.meta = self.volume.meta.clone();
        Ok(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    fn ramp(dims: UVec3) -> Volume {
        let data = (0..dims.element_product()).map(|i| (i % 251) as u8).collect();
        Volume::new("ramp", dims, DVec3::ONE, VoxelData::U8(data))
    }

    #[test]
    fn levels_halve_to_the_coarsest_edge_and_factors_double() {
        let p = InCorePyramid::new(Arc::new(ramp(UVec3::new(37, 20, 9))), 8);
        let dims: Vec<UVec3> = p.levels().iter().map(|l| l.dims).collect();
        assert_eq!(dims, vec![UVec3::new(37, 20, 9), UVec3::new(19, 10, 5), UVec3::new(10, 5, 3), UVec3::new(5, 3, 2)]);
        assert_eq!(p.levels()[3].factor, DVec3::splat(8.0));
    }

    /// Level 0 reads back the volume's own voxels (clamped past the faces); a coarse voxel is
    /// the mean of the eight below it, rounded as the converter rounds a byte's.
    #[test]
    fn boxes_read_back_the_voxels_and_the_means_clamped_at_faces() {
        let v = ramp(UVec3::new(8, 6, 4));
        let p = InCorePyramid::new(Arc::new(v.clone()), 2);
        let BoxTexels::Unorm8(b) = p.read_box(0, IVec3::new(-1, 2, 3), UVec3::new(3, 1, 2)).unwrap() else {
            panic!("u8 volume reads u8 texels")
        };
        let VoxelData::U8(src) = &v.data else { unreachable!() };
        let at = |x: usize, y: usize, z: usize| src[x + 8 * (y + 6 * z)];
        assert_eq!(b, vec![at(0, 2, 3), at(0, 2, 3), at(1, 2, 3), at(0, 2, 3), at(0, 2, 3), at(1, 2, 3)]);
        let coarse = p.read_box(1, IVec3::ZERO, UVec3::ONE).unwrap();
        let mean: f64 = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0), (0, 0, 1), (1, 0, 1), (0, 1, 1), (1, 1, 1)]
            .iter()
            .map(|&(x, y, z)| f64::from(at(x, y, z)))
            .sum::<f64>()
            / 8.0;
        assert_eq!(coarse, BoxTexels::Unorm8(vec![mean.round() as u8]));
        assert_eq!(p.coarsest().unwrap().dims, p.levels().last().unwrap().dims);
    }
}
