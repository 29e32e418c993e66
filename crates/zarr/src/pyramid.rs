//! An OME-Zarr image as a [`PyramidSource`]: the streaming raycaster reads its bricks box by
//! box, chunk by chunk, never a level whole. Decoded chunks are kept in a cache bounded in bytes
//! (`--memory-mb`), since neighbouring bricks (and their aprons) share chunks; the chunk value
//! ranges `volgraph convert` writes answer [`PyramidSource::box_range`], so a brick the transfer
//! function leaves transparent is never read. A chunk missing where the writer saw data, or one
//! that cannot be decoded, is drawn as the fill value with a note naming it (as
//! [`OmeZarr::read_level`] does).

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use glam::{DVec3, IVec3, UVec3};
use volgraph_accel::pyramid::{BoxTexels, PyramidLevel, PyramidSource, TexelKind};
use volgraph_accel::volume::{Volume, VoxelType};
use zarrs::array::ElementOwned;

use crate::ZarrError;
use crate::ngff::AxisKind;
use crate::read::Pick;
use crate::store::{Level, OmeZarr};

/// The most bytes of voxels the coarsest level may hold: it is read whole (the first image, the
/// transfer function's fit), so a store without a small level is refused, not read into memory.
pub const COARSEST_LIMIT_BYTES: u64 = 256 << 20;

/// Chunk lines noted at most per kind (missing, undecodable); the rest are counted.
const NOTED_CHUNKS: usize = 8;

/// How stored values become the texels the GPU samples, as a whole volume's upload makes them
/// (`volgraph_core::runtime::upload_volume_texture`).
#[derive(Clone, Copy, Debug)]
struct Normalize {
    kind: TexelKind,
    lo: f64,
    hi: f64,
}

impl Normalize {
    fn unit(&self, v: f64) -> f64 {
        let span = self.hi - self.lo;
        if !v.is_finite() || !(span > 0.0) { 0.0 } else { ((v - self.lo) / span).clamp(0.0, 1.0) }
    }
}

/// A decoded chunk at the picked time point and channel, as texels, (z, y, x) of the chunk shape.
type Chunk = Arc<BoxTexels>;

#[derive(Default)]
struct ChunkCache {
    chunks: HashMap<(usize, [u64; 3]), (Chunk, u64)>,
    bytes: u64,
    clock: u64,
}

#[derive(Default)]
struct Noted {
    lines: Vec<String>,
    missing: usize,
    broken: usize,
    /// The chunks noted, by (level, z, y, x): two readers decoding one chunk at once, or a
    /// chunk decoded again after the cache let it go, are named once.
    chunks: std::collections::HashSet<(String, [u64; 3])>,
}

/// An OME-Zarr image read brick by brick.
pub struct ZarrPyramid {
    image: OmeZarr,
    pick: Pick,
    name: String,
    levels: Vec<PyramidLevel>,
    spacing: DVec3,
    normalize: Normalize,
    /// Per level: the writer's chunk value ranges ([gz, gy, gx, 2], stored values), if any.
    ranges: Vec<Option<Vec<f32>>>,
    cache: Mutex<ChunkCache>,
    cache_limit: u64,
    noted: Mutex<Noted>,
    coarsest: Volume,
}

impl ZarrPyramid {
    /// The volume `pick` of `image`, its chunks cached up to `cache_bytes`. Reads the coarsest
    /// level whole (for the value range, the transfer function's fit and a first image).
    pub fn new(image: OmeZarr, pick: Pick, cache_bytes: u64) -> Result<Self, ZarrError> {
        let last = image.levels.len() - 1;
        let level = &image.levels[last];
        let bytes = crate::read::level_bytes(level);
        if bytes > COARSEST_LIMIT_BYTES {
            return Err(ZarrError::Level {
                path: image.path.clone(),
                level: level.path.clone(),
                problem: format!(
                    "the coarsest level is {}×{}×{} ({} MiB); streaming reads the coarsest level whole, at most {} MiB: \
                     write the store with levels down to 64³ (`volgraph convert STORE OUT.ome.zarr`)",
                    level.dims.x,
                    level.dims.y,
                    level.dims.z,
                    bytes >> 20,
                    COARSEST_LIMIT_BYTES >> 20
                ),
            });
        }
        let coarsest = image.read_level(last, pick, COARSEST_LIMIT_BYTES)?.volume;
        let mm = image.millimetres_per_unit().unwrap_or(1.0);
        let fine = &image.levels[0];
        let levels: Vec<PyramidLevel> =
            image.levels.iter().map(|l| PyramidLevel { dims: l.dims, factor: l.spacing / fine.spacing }).collect();
        let (lo, hi) = coarsest.value_range;
        let kind = match fine.voxel_type {
            VoxelType::U8 => TexelKind::Unorm8,
            VoxelType::U16 | VoxelType::I16 => TexelKind::Unorm16,
            VoxelType::F32 => TexelKind::Float,
        };
        let ranges = image.levels.iter().map(|l| image.chunk_ranges(l)).collect();
        let name = image.path.file_name().map_or("ome-zarr".into(), |n| n.to_string_lossy().into_owned());
        Ok(Self {
            spacing: fine.spacing * mm,
            pick,
            name,
            levels,
            normalize: Normalize { kind, lo, hi },
            ranges,
            cache: Mutex::new(ChunkCache::default()),
            cache_limit: cache_bytes,
            noted: Mutex::new(Noted::default()),
            coarsest,
            image,
        })
    }

    /// Replaces the level-0 voxel size (`--spacing`); the coarser levels keep their factors.
    pub fn set_spacing(&mut self, spacing: DVec3) {
        let last = self.levels[self.levels.len() - 1];
        self.spacing = spacing;
        self.coarsest.spacing = spacing * last.factor;
    }

    /// The image.
    pub fn image(&self) -> &OmeZarr {
        &self.image
    }

    /// Chunk `c` (z, y, x) of level `l` as texels, from the cache or decoded now.
    fn chunk(&self, l: usize, c: [u64; 3]) -> Chunk {
        if let Some(hit) = self.with_cache(|cache| {
            cache.clock += 1;
            let clock = cache.clock;
            cache.chunks.get_mut(&(l, c)).map(|(chunk, used)| {
                *used = clock;
                chunk.clone()
            })
        }) {
            return hit;
        }
        let level = &self.image.levels[l];
        let chunk = Arc::new(match level.voxel_type {
            VoxelType::U8 => self.decode::<u8>(l, c),
            VoxelType::U16 => self.decode::<u16>(l, c),
            VoxelType::I16 => self.decode::<i16>(l, c),
            VoxelType::F32 => self.decode::<f32>(l, c),
        });
        let bytes = chunk.len() as u64 * texel_bytes(self.normalize.kind);
        self.with_cache(|cache| {
            cache.clock += 1;
            let clock = cache.clock;
            if cache.chunks.insert((l, c), (chunk.clone(), clock)).is_none() {
                cache.bytes += bytes;
            }
            while cache.bytes > self.cache_limit && cache.chunks.len() > 1 {
                let Some(oldest) = cache.chunks.iter().min_by_key(|(_, (_, used))| *used).map(|(k, _)| *k) else {
                    break;
                };
                if let Some((gone, _)) = cache.chunks.remove(&oldest) {
                    cache.bytes -= gone.len() as u64 * texel_bytes(self.normalize.kind);
                }
            }
        });
        chunk
    }

    fn with_cache<R>(&self, f: impl FnOnce(&mut ChunkCache) -> R) -> R {
        f(&mut self.cache.lock().unwrap_or_else(|e| e.into_inner()))
    }

    /// The chunk's voxels at the pick, (z, y, x) over the chunk shape, as texels; the fill
    /// value where it is missing or cannot be decoded (with a note).
    fn decode<T: ElementOwned + Copy + Default + Send + Sync + Into<f64>>(&self, l: usize, c: [u64; 3]) -> BoxTexels {
        let level = &self.image.levels[l];
        let [az, ay, ax] = self.image.multiscale.space_axes();
        let axes = self.image.multiscale.axes.len();
        let mut index = vec![0u64; axes];
        (index[az], index[ay], index[ax]) = (c[0], c[1], c[2]);
        let mut within = Vec::new();
        for (kind, value) in [(AxisKind::Time, self.pick.time), (AxisKind::Channel, self.pick.channel)] {
            if let Some(a) = self.image.multiscale.axis_of(&kind) {
                let size = level.array.chunk_shape(&index).map(|s| s[a].get()).unwrap_or(1);
                index[a] = value / size;
                within.push((a, value % size));
            }
        }
        let shape: Vec<u64> = match level.array.chunk_shape(&index) {
            Ok(s) => s.iter().map(|s| s.get()).collect(),
            Err(e) => return self.fill(c, Some(e.to_string()), level),
        };
        let file = self.image.path.join(level.array.chunk_key(&index).as_str());
        let read = crate::store::check_file(&file)
            .map_err(zarrs::array::ArrayError::Other)
            .and_then(|()| level.array.retrieve_chunk_if_exists::<Vec<T>>(&index));
        let elements = match read {
            Ok(Some(e)) => e,
            Ok(None) => {
                let had_data = self.ranges[l].as_ref().and_then(|r| {
                    let g = level.array.chunk_grid_shape();
                    let i = ((c[0] * g[ay] + c[1]) * g[ax] + c[2]) as usize;
                    r.get(2 * i..2 * i + 2).map(|r| r != [0.0, 0.0])
                });
                return self.fill(c, (had_data == Some(true)).then(String::new), level);
            }
            Err(e) => return self.fill(c, Some(e.to_string()), level),
        };
        // Strides of the chunk's C order, and the offset of the picked t/c.
        let n = shape.len();
        let mut strides = vec![1u64; n];
        for a in (0..n.saturating_sub(1)).rev() {
            strides[a] = strides[a + 1] * shape[a + 1];
        }
        let base: u64 = within.iter().map(|&(a, v)| v * strides[a]).sum();
        let (sz, sy, sx) = (shape[az], shape[ay], shape[ax]);
        let mut values = Vec::with_capacity((sz * sy * sx) as usize);
        for z in 0..sz {
            for y in 0..sy {
                let row = base + z * strides[az] + y * strides[ay];
                values.extend((0..sx).map(|x| elements[(row + x * strides[ax]) as usize].into()));
            }
        }
        self.texels(values.into_iter())
    }

    /// A chunk of the fill value (0), noting why: `problem` None for a chunk Zarr left out as
    /// all fill, empty for one missing where the writer saw data, else the decoding error.
    fn fill(&self, c: [u64; 3], problem: Option<String>, level: &Level) -> BoxTexels {
        if let Some(problem) = problem {
            let mut noted = self.noted.lock().unwrap_or_else(|e| e.into_inner());
            let first_time = noted.chunks.insert((level.path.clone(), c));
            let (count, line) = if !first_time {
                (usize::MAX, String::new())
            } else if problem.is_empty() {
                noted.missing += 1;
                (
                    noted.missing,
                    format!(
                        "warning: {}: level \"{}\", chunk (z, y, x) {}/{}/{} is missing; drawn as the fill value",
                        self.image.path.display(),
                        level.path,
                        c[0],
                        c[1],
                        c[2]
                    ),
                )
            } else {
                noted.broken += 1;
                let e =
                    ZarrError::Chunk { path: self.image.path.clone(), level: level.path.clone(), chunk: c, problem };
                (noted.broken, format!("error: {e}; drawn as the fill value"))
            };
            if count <= NOTED_CHUNKS {
                noted.lines.push(line);
            }
        }
        let shape = level.chunk;
        let count = shape.as_u64vec3().element_product() as usize;
        self.texels(std::iter::repeat_n(0.0, count))
    }

    fn texels(&self, values: impl Iterator<Item = f64>) -> BoxTexels {
        let n = self.normalize;
        match n.kind {
            // Bytes and the type's own 16-bit range are uploaded as they are stored, as a whole
            // volume's texture holds them (`upload_volume_texture`).
            TexelKind::Unorm8 => BoxTexels::Unorm8(values.map(|v| v as u8).collect()),
            TexelKind::Unorm16 if (n.lo, n.hi) == (0.0, 65535.0) => {
                BoxTexels::Unorm16(values.map(|v| v as u16).collect())
            }
            TexelKind::Unorm16 => BoxTexels::Unorm16(values.map(|v| (n.unit(v) * 65535.0).round() as u16).collect()),
            TexelKind::Float => BoxTexels::Float(values.map(|v| n.unit(v) as f32).collect()),
        }
    }
}

fn texel_bytes(kind: TexelKind) -> u64 {
    match kind {
        TexelKind::Unorm8 => 1,
        TexelKind::Unorm16 => 2,
        TexelKind::Float => 4,
    }
}

impl PyramidSource for ZarrPyramid {
    fn name(&self) -> &str {
        &self.name
    }

    fn levels(&self) -> &[PyramidLevel] {
        &self.levels
    }

    fn spacing(&self) -> DVec3 {
        self.spacing
    }

    fn texel_kind(&self) -> TexelKind {
        self.normalize.kind
    }

    fn read_box(&self, level: usize, lo: IVec3, dims: UVec3) -> Result<BoxTexels, String> {
        let info = self.image.levels.get(level).ok_or_else(|| format!("no level {level}"))?;
        let n = info.dims.as_ivec3();
        let chunk = info.chunk;
        // Per axis: (chunk, offset in it) of every clamped index.
        let axis = |a: usize| -> Vec<(u64, usize)> {
            (0..dims[a] as i32)
                .map(|i| {
                    let v = (lo[a] + i).clamp(0, n[a] - 1) as u32;
                    (u64::from(v / chunk[a]), (v % chunk[a]) as usize)
                })
                .collect()
        };
        let (xs, ys, zs) = (axis(0), axis(1), axis(2));
        let first = UVec3::new(xs[0].0 as u32, ys[0].0 as u32, zs[0].0 as u32);
        let span = UVec3::new(
            xs.last().map_or(0, |c| c.0) as u32 - first.x + 1,
            ys.last().map_or(0, |c| c.0) as u32 - first.y + 1,
            zs.last().map_or(0, |c| c.0) as u32 - first.z + 1,
        );
        let mut chunks = Vec::with_capacity(span.element_product() as usize);
        for cz in 0..span.z {
            for cy in 0..span.y {
                for cx in 0..span.x {
                    let c = first + UVec3::new(cx, cy, cz);
                    chunks.push(self.chunk(level, [u64::from(c.z), u64::from(c.y), u64::from(c.x)]));
                }
            }
        }
        let (sx, sy) = (chunk.x as usize, chunk.y as usize);
        let at = |x: &(u64, usize), y: &(u64, usize), z: &(u64, usize)| {
            let local = ((z.0 as u32 - first.z) * span.y + (y.0 as u32 - first.y)) * span.x + (x.0 as u32 - first.x);
            (local as usize, (z.1 * sy + y.1) * sx + x.1)
        };
        let count = dims.element_product() as usize;
        macro_rules! gather {
            ($variant:ident) => {{
                let mut out = Vec::with_capacity(count);
                for z in &zs {
                    for y in &ys {
                        for x in &xs {
                            let (c, i) = at(x, y, z);
                            let BoxTexels::$variant(v) = chunks[c].as_ref() else { unreachable!() };
                            out.push(v[i]);
                        }
                    }
                }
                BoxTexels::$variant(out)
            }};
        }
        Ok(match self.normalize.kind {
            TexelKind::Unorm8 => gather!(Unorm8),
            TexelKind::Unorm16 => gather!(Unorm16),
            TexelKind::Float => gather!(Float),
        })
    }

    fn box_range(&self, level: usize, lo: IVec3, hi: IVec3) -> Option<(f32, f32)> {
        let ranges = self.ranges.get(level)?.as_ref()?;
        let info = &self.image.levels[level];
        let n = info.dims.as_ivec3();
        let c_lo = (lo.clamp(IVec3::ZERO, n - 1).as_uvec3()) / info.chunk;
        let c_hi = ((hi - 1).clamp(IVec3::ZERO, n - 1).as_uvec3()) / info.chunk;
        let grid = (info.dims + info.chunk - 1) / info.chunk;
        let (mut min, mut max) = (f64::INFINITY, f64::NEG_INFINITY);
        for cz in c_lo.z..=c_hi.z {
            for cy in c_lo.y..=c_hi.y {
                for cx in c_lo.x..=c_hi.x {
                    let i = 2 * ((cz * grid.y + cy) * grid.x + cx) as usize;
                    let r = ranges.get(i..i + 2)?;
                    min = min.min(f64::from(r[0]));
                    max = max.max(f64::from(r[1]));
                }
            }
        }
        let n = self.normalize;
        Some((n.unit(min) as f32, n.unit(max) as f32))
    }

    fn notes(&self) -> Vec<String> {
        let mut noted = self.noted.lock().unwrap_or_else(|e| e.into_inner());
        let mut lines = std::mem::take(&mut noted.lines);
        for (count, what) in [(noted.missing, "missing"), (noted.broken, "undecodable")] {
            if count > NOTED_CHUNKS {
                lines.push(format!("… and {} more {what} chunks", count - NOTED_CHUNKS));
            }
        }
        lines
    }

    fn coarsest(&self) -> Result<Volume, String> {
        Ok(self.coarsest.clone())
    }
}
