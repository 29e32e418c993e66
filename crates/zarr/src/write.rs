//! Writing a pyramid (`volgraph convert`): level 0 from a [`SlabSource`] a slab of one chunk's
//! depth at a time, each coarser level from the one above as its slabs are finished (2×2×2
//! means), so the writer holds about one slab per level — never the volume. Every chunk's value
//! range is written beside the level (`chunk_ranges/<level>`, float32 [gz, gy, gx, 2]), for a
//! renderer to skip empty chunks without reading them. NGFF 0.5 (Zarr v3, zstd).

use std::ops::Range;
use std::path::Path;
use std::sync::Arc;

use glam::{DVec3, UVec3};
use rayon::prelude::*;
use serde_json::json;
use volgraph_accel::volume::{Volume, VoxelData, VoxelType};
use volgraph_accel::volume_meta::{VolumeMeta, WorldFrame};
use zarrs::array::codec::ZstdCodec;
use zarrs::array::{Array, ArrayBuilder};
use zarrs::filesystem::FilesystemStore;

use crate::ZarrError;
use crate::sample::{Sample, halve};

/// Where `convert` reads its voxels: slabs of whole z planes, x fastest.
pub trait SlabSource {
    /// Voxels per axis (x, y, z).
    fn dims(&self) -> UVec3;
    /// The voxel type.
    fn voxel_type(&self) -> VoxelType;
    /// Voxel size (x, y, z) in millimetres (or the volume's unit).
    fn spacing(&self) -> DVec3;
    /// Position of voxel (0, 0, 0)'s centre, where known.
    fn origin(&self) -> DVec3;
    /// The planes `z` (x fastest).
    fn read_slab(&mut self, z: Range<u32>) -> Result<VoxelData, String>;
    /// What the source's file says of it (modality, units, window, patient frame).
    fn meta(&self) -> VolumeMeta {
        VolumeMeta::default()
    }
    /// The data values that map to 0 and 1 on the GPU ([`Volume::value_range`]).
    fn value_range(&self) -> (f64, f64);
}

/// A volume in memory as a source.
pub struct InMemory(pub Volume);

impl SlabSource for InMemory {
    fn dims(&self) -> UVec3 {
        self.0.dims
    }
    fn voxel_type(&self) -> VoxelType {
        self.0.data.voxel_type()
    }
    fn spacing(&self) -> DVec3 {
        self.0.spacing
    }
    fn origin(&self) -> DVec3 {
        self.0.meta.origin.unwrap_or_default()
    }
    fn meta(&self) -> VolumeMeta {
        self.0.meta.clone()
    }
    fn value_range(&self) -> (f64, f64) {
        self.0.value_range
    }
    fn read_slab(&mut self, z: Range<u32>) -> Result<VoxelData, String> {
        let plane = self.0.dims.x as usize * self.0.dims.y as usize;
        let r = z.start as usize * plane..z.end as usize * plane;
        Ok(match &self.0.data {
            VoxelData::U8(v) => VoxelData::U8(v[r].to_vec()),
            VoxelData::U16(v) => VoxelData::U16(v[r].to_vec()),
            VoxelData::I16(v) => VoxelData::I16(v[r].to_vec()),
            VoxelData::F32(v) => VoxelData::F32(v[r].to_vec()),
        })
    }
}

/// How to write.
#[derive(Clone, Copy, Debug)]
pub struct WriteOptions {
    /// Chunk side in voxels (a cube; an even number ≥ 2).
    pub chunk: u32,
    /// Levels halve until every axis is at most this.
    pub coarsest: u32,
    /// The zstd level.
    pub zstd_level: i32,
}

impl Default for WriteOptions {
    fn default() -> Self {
        Self { chunk: 64, coarsest: 64, zstd_level: 3 }
    }
}

/// What was written.
#[derive(Clone, Debug, PartialEq)]
pub struct WriteReport {
    /// Each level's dims (x, y, z), finest first.
    pub levels: Vec<UVec3>,
    /// Chunks written (those all of the fill value are left out, as Zarr allows).
    pub chunks_written: u64,
    /// Chunks of the fill value alone, not written.
    pub chunks_empty: u64,
}

/// The dims of each level: halving (rounding up) until every axis is ≤ `coarsest`.
pub fn level_dims(dims: UVec3, coarsest: u32) -> Vec<UVec3> {
    let mut out = vec![dims];
    while out.last().is_some_and(|d| d.max_element() > coarsest.max(1)) {
        let d = *out.last().unwrap_or(&dims);
        out.push(UVec3::new(d.x.div_ceil(2), d.y.div_ceil(2), d.z.div_ceil(2)));
    }
    out
}

/// Chunks in a pyramid of `dims` (for a progress bar's total).
pub fn chunk_count(dims: UVec3, options: &WriteOptions) -> u64 {
    let c = options.chunk.max(1);
    level_dims(dims, options.coarsest)
        .iter()
        .map(|d| d.x.div_ceil(c) as u64 * d.y.div_ceil(c) as u64 * d.z.div_ceil(c) as u64)
        .sum()
}

/// One level being written: its array, the range array, and the planes not yet written.
struct LevelWriter<T> {
    path: String,
    array: Array<FilesystemStore>,
    ranges: Array<FilesystemStore>,
    dims: UVec3,
    chunk: u32,
    /// Planes received and not yet written, from plane `z0`.
    pending: Vec<T>,
    z0: u32,
}

impl<T: Sample> LevelWriter<T> {
    fn plane(&self) -> usize {
        self.dims.x as usize * self.dims.y as usize
    }

    fn pending_planes(&self) -> u32 {
        (self.pending.len() / self.plane().max(1)) as u32
    }

    /// Writes the chunks of the first `n` pending planes (one chunk row in z) and returns them.
    fn write_row(&mut self, n: u32, out: &Path) -> Result<(Vec<T>, u64, u64), ZarrError> {
        let c = self.chunk;
        let (nx, ny) = (self.dims.x, self.dims.y);
        let slab: Vec<T> = self.pending.drain(..n as usize * self.plane()).collect();
        let cz = (self.z0 / c) as u64;
        let (gx, gy) = (nx.div_ceil(c), ny.div_ceil(c));
        let cells: Vec<(u32, u32)> = (0..gy).flat_map(|cy| (0..gx).map(move |cx| (cy, cx))).collect();
        let results: Vec<Result<(f32, f32, bool), ZarrError>> = cells
            .par_iter()
            .map(|&(cy, cx)| {
                let mut chunk = vec![T::default(); (c * c * c) as usize];
                let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
                let mut any = false;
                for z in 0..n {
                    for y in cy * c..((cy + 1) * c).min(ny) {
                        let x0 = cx * c;
                        let x1 = ((cx + 1) * c).min(nx);
                        let src = ((z * ny + y) * nx + x0) as usize;
                        let dst = ((z * c + (y - cy * c)) * c) as usize;
                        let row = &slab[src..src + (x1 - x0) as usize];
                        chunk[dst..dst + row.len()].copy_from_slice(row);
                        for v in row {
                            let f = v.to_f64();
                            lo = lo.min(f);
                            hi = hi.max(f);
                            any |= *v != T::default();
                        }
                    }
                }
                if any {
                    self.array.store_chunk(&[cz, cy as u64, cx as u64], chunk.as_slice()).map_err(|e| {
                        ZarrError::Chunk {
                            path: out.to_path_buf(),
                            level: self.path.clone(),
                            chunk: [cz, cy as u64, cx as u64],
                            problem: e.to_string(),
                        }
                    })?;
                }
                Ok((lo as f32, hi as f32, any))
            })
            .collect();
        let mut ranges = Vec::with_capacity(cells.len() * 2);
        let (mut written, mut empty) = (0, 0);
        for r in results {
            let (lo, hi, any) = r?;
            ranges.extend([lo, hi]);
            if any { written += 1 } else { empty += 1 }
        }
        let subset = zarrs::array::ArraySubset::new_with_ranges(&[cz..cz + 1, 0..gy as u64, 0..gx as u64, 0..2]);
        self.ranges.store_array_subset(&subset, ranges.as_slice()).map_err(|e| ZarrError::Write {
            path: out.to_path_buf(),
            problem: format!("chunk_ranges/{}: {e}", self.path),
        })?;
        self.z0 += n;
        Ok((slab, written, empty))
    }
}

/// Writes `source` as an OME-Zarr pyramid at `out` (a new folder); `progress(done, total)`
/// counts chunks.
pub fn write_pyramid(
    source: &mut dyn SlabSource,
    out: &Path,
    options: &WriteOptions,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<WriteReport, ZarrError> {
    match source.voxel_type() {
        VoxelType::U8 => write_typed::<u8>(source, out, options, progress),
        VoxelType::U16 => write_typed::<u16>(source, out, options, progress),
        VoxelType::I16 => write_typed::<i16>(source, out, options, progress),
        VoxelType::F32 => write_typed::<f32>(source, out, options, progress),
    }
}

fn write_typed<T: Sample>(
    source: &mut dyn SlabSource,
    out: &Path,
    options: &WriteOptions,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<WriteReport, ZarrError> {
    let failed = |problem: String| ZarrError::Write { path: out.to_path_buf(), problem };
    if options.chunk < 2 || !options.chunk.is_multiple_of(2) || options.chunk > 1024 {
        return Err(failed(format!("chunk {}: an even side from 2 to 1024 voxels (64 is usual)", options.chunk)));
    }
    if out.exists() && std::fs::read_dir(out).map_or(true, |mut d| d.next().is_some()) {
        return Err(failed("exists and is not an empty folder; remove it or write to a new path".to_string()));
    }
    let store = Arc::new(FilesystemStore::new(out).map_err(|e| failed(e.to_string()))?);
    let dims = source.dims();
    let all = level_dims(dims, options.coarsest);
    let c = options.chunk;
    let mut levels = Vec::with_capacity(all.len());
    for (k, d) in all.iter().enumerate() {
        // Chunks are cubes of side `c`, so slabs of `c` planes fill a row of them; a level smaller
        // than a chunk is one chunk, padded.
        let array = ArrayBuilder::new(
            vec![d.z as u64, d.y as u64, d.x as u64],
            [c as u64, c as u64, c as u64],
            T::data_type(),
            T::fill_value(),
        )
        .bytes_to_bytes_codecs(vec![Arc::new(ZstdCodec::new(options.zstd_level, false))])
        .dimension_names(Some(["z", "y", "x"]))
        .build(store.clone(), &format!("/{k}"))
        .map_err(|e| failed(format!("level {k}: {e}")))?;
        array.store_metadata().map_err(|e| failed(format!("level {k}: {e}")))?;
        let (gz, gy, gx) = (d.z.div_ceil(c) as u64, d.y.div_ceil(c) as u64, d.x.div_ceil(c) as u64);
        let ranges = ArrayBuilder::new(
            vec![gz, gy, gx, 2],
            [1, gy.min(256), gx.min(256), 2],
            zarrs::array::data_type::float32(),
            f32::NAN,
        )
        .dimension_names(Some(["cz", "cy", "cx", "min_max"]))
        .build(store.clone(), &format!("/chunk_ranges/{k}"))
        .map_err(|e| failed(format!("chunk_ranges/{k}: {e}")))?;
        ranges.store_metadata().map_err(|e| failed(format!("chunk_ranges/{k}: {e}")))?;
        levels.push(LevelWriter::<T> {
            path: k.to_string(),
            array,
            ranges,
            dims: *d,
            chunk: c,
            pending: Vec::new(),
            z0: 0,
        });
    }
    let total = chunk_count(dims, options);
    let mut report = WriteReport { levels: all.clone(), chunks_written: 0, chunks_empty: 0 };
    let mut done = 0;
    let mut z = 0;
    while z < dims.z {
        let end = (z + c).min(dims.z);
        let slab = source.read_slab(z..end).map_err(|e| failed(format!("reading planes {z}..{end}: {e}")))?;
        let slab = T::of(slab).ok_or_else(|| failed("the source changed its voxel type".to_string()))?;
        feed(&mut levels, 0, slab, out, &mut report, &mut |n| {
            done += n;
            progress(done, total);
        })?;
        z = end;
    }
    write_group(&store, source, &all, out)?;
    Ok(report)
}

/// Hands `planes` to level `k`: every full row of chunks (or the level's last planes) is
/// written, halved and handed to level `k + 1`.
fn feed<T: Sample>(
    levels: &mut [LevelWriter<T>],
    k: usize,
    planes: Vec<T>,
    out: &Path,
    report: &mut WriteReport,
    chunks_done: &mut dyn FnMut(u64),
) -> Result<(), ZarrError> {
    let (this, rest) = levels.split_at_mut(k + 1);
    let level = &mut this[k];
    level.pending.extend(planes);
    loop {
        let pending = level.pending_planes();
        let last = level.z0 + pending == level.dims.z;
        let n = if pending >= level.chunk {
            level.chunk
        } else if last && pending > 0 {
            pending
        } else {
            break;
        };
        let (slab, written, empty) = level.write_row(n, out)?;
        report.chunks_written += written;
        report.chunks_empty += empty;
        chunks_done(written + empty);
        if !rest.is_empty() {
            let half = halve(&slab, (level.dims.x, level.dims.y), n);
            feed(rest, 0, half, out, report, chunks_done)?;
        }
    }
    Ok(())
}

/// The root group: NGFF 0.5 multiscales (scale and translation per level; a level's voxel
/// centre is the mean of the finer voxels it averages) and volgraph's own keys.
fn write_group(
    store: &Arc<FilesystemStore>,
    source: &dyn SlabSource,
    all: &[UVec3],
    out: &Path,
) -> Result<(), ZarrError> {
    let (s, o) = (source.spacing(), source.origin());
    let datasets: Vec<serde_json::Value> = (0..all.len())
        .map(|k| {
            let f = (1u64 << k) as f64;
            let shift = (f - 1.0) / 2.0;
            json!({
                "path": k.to_string(),
                "coordinateTransformations": [
                    {"type": "scale", "scale": [s.z * f, s.y * f, s.x * f]},
                    {"type": "translation", "translation": [o.z + shift * s.z, o.y + shift * s.y, o.x + shift * s.x]}
                ]
            })
        })
        .collect();
    // Millimetres where the source lies in the patient frame (DICOM, NIfTI); a volume in index
    // axes has no unit to claim.
    let meta = source.meta();
    let unit = (meta.frame == WorldFrame::Lps).then_some("millimeter");
    let axes = ["z", "y", "x"].map(|n| match unit {
        Some(u) => json!({"name": n, "type": "space", "unit": u}),
        None => json!({"name": n, "type": "space"}),
    });
    let name = out.file_stem().map(|n| n.to_string_lossy().trim_end_matches(".ome").to_string());
    let mut group = zarrs::group::GroupBuilder::new()
        .build(store.clone(), "/")
        .map_err(|e| ZarrError::Write { path: out.to_path_buf(), problem: e.to_string() })?;
    let attributes = group.attributes_mut();
    attributes.insert(
        "ome".into(),
        json!({"version": "0.5", "multiscales": [{"name": name, "axes": axes, "datasets": datasets}]}),
    );
    // What NGFF has no field for, kept for volgraph's reader: the patient frame and the
    // scanner's metadata.
    attributes.insert(
        "volgraph".into(),
        json!({
            "chunk_ranges": "chunk_ranges",
            "chunk_ranges_version": 1,
            "patient_frame": meta.frame == WorldFrame::Lps,
            "value_range": [source.value_range().0, source.value_range().1],
            "modality": meta.modality,
            "units": meta.units,
            "window": meta.window.map(|w| [w.center, w.width]),
            "description": meta.description,
            "frame_of_reference": meta.frame_of_reference,
        }),
    );
    group.store_metadata().map_err(|e| ZarrError::Write { path: out.to_path_buf(), problem: e.to_string() })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_halve_until_the_coarsest_fits() {
        let dims = level_dims(UVec3::new(300, 200, 65), 64);
        assert_eq!(
            dims,
            vec![UVec3::new(300, 200, 65), UVec3::new(150, 100, 33), UVec3::new(75, 50, 17), UVec3::new(38, 25, 9)]
        );
        assert_eq!(level_dims(UVec3::splat(64), 64), vec![UVec3::splat(64)]);
        let options = WriteOptions { chunk: 16, ..Default::default() };
        assert_eq!(chunk_count(UVec3::splat(64), &options), 64);
    }
}
