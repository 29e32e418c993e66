//! A volume file larger than memory as a pyramid ([`FilePyramid`]): a raw, NRRD or MetaImage
//! file (any [`VolumeHeader`] that reads boxes) streamed by `raycast_stream` without an OME-Zarr
//! store and without ever being in memory whole.
//!
//! Opening reads the file once, a few slices at a time, through a cascade of 2×2×2 means: each
//! pair of slices of a level makes one slice of the next, so every level is built while only
//! two slices per level are held. The coarse levels that fit in the budget are kept in memory;
//! the levels between them and the file are written, as they are made, to scratch raw files in
//! the temporary folder (`TMPDIR`; about a seventh of the file's bytes, removed when the pyramid
//! is dropped — or, where a killed process left them, by the next pyramid opened), and a brick of any level is then one box read — level 0 from the file, the
//! others from their scratch file (a plane of the box's rows per read). The pass also keeps each
//! 32³ block's value range, so bricks the transfer function leaves transparent are never read.
//! Every level holds, bit for bit, what [`InCorePyramid`] holds for the whole volume (and what
//! `volgraph convert` writes): the same sums in the same order, one function
//! ([`halve_box`]) for both.
//!
//! [`InCorePyramid`]: crate::pyramid::InCorePyramid

use glam::{DVec3, IVec3, UVec3};

use crate::kd_split::VoxelBox;
use crate::load::{LoadError, VolumeHeader};
use crate::pyramid::{
    BoxTexels, PyramidLevel, PyramidSource, TexelKind, clamped_indices, halve_box, pyramid_levels, texel_kind_of,
    texels_of,
};
use crate::volume::{Volume, VoxelData, VoxelType};

/// The edge of the blocks whose value ranges the opening pass keeps.
const RANGE_BLOCK: u32 = 32;
/// Bytes of slices read at once by the opening pass: buffers this small are reused by the
/// allocator (64 MiB ones, allocated anew, had the kernel zero their pages: a fifth of the pass).
const PASS_SLAB_BYTES: u64 = 8 << 20;

/// A volume file read as a pyramid: see the module.
pub struct FilePyramid {
    header: VolumeHeader,
    /// The volume's type, value range, name, spacing and metadata, with no voxels: how values
    /// become texels.
    template: Volume,
    levels: Vec<PyramidLevel>,
    kind: TexelKind,
    integer: bool,
    /// Levels `held_from..` in memory, as stored values.
    held_from: usize,
    held: Vec<Vec<f32>>,
    /// Level-0 (min, max) stored value of each [`RANGE_BLOCK`]³ block, x fastest.
    block_ranges: Vec<(f32, f32)>,
    blocks: UVec3,
    /// Non-finite voxels of a float file, read as the range's ends.
    non_finite: u64,
    /// Levels `1..held_from`: their scratch files, written by the pass, read box by box.
    scratch: Vec<Scratch>,
}

/// A level written to a scratch raw file (`name_XxYxZ_type.raw`, little-endian, the file's
/// type): while the pass runs, its writer; then its header, to read boxes.
struct Scratch {
    path: std::path::PathBuf,
    writer: Option<std::io::BufWriter<std::fs::File>>,
    header: Option<VolumeHeader>,
}

impl Drop for Scratch {
    fn drop(&mut self) {
        self.writer = None;
        let _ = std::fs::remove_file(&self.path);
    }
}

/// The prefix of every scratch file's name, then the owning process's id.
const SCRATCH_PREFIX: &str = "volgraph-pyramid-";

/// Removes the scratch files in `dir` whose process is gone: a process killed while streaming
/// (no `Drop`) leaves its levels behind, up to a seventh of the file's bytes. A process is
/// gone when the system lists no such process (`/proc/PID`; where there is no `/proc`, nothing
/// is removed). Returns how many files were removed.
fn remove_stale_scratch(dir: &std::path::Path) -> usize {
    let proc = std::path::Path::new("/proc");
    if !proc.join("self").exists() {
        return 0;
    }
    let Ok(entries) = std::fs::read_dir(dir) else { return 0 };
    let mut removed = 0;
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) =
            name.to_str().and_then(|n| n.strip_prefix(SCRATCH_PREFIX)).and_then(|rest| rest.split('-').next())
        else {
            continue;
        };
        let own = entry.file_type().is_ok_and(|t| t.is_file());
        if own && pid.parse::<u32>().is_ok() && !proc.join(pid).exists() && std::fs::remove_file(entry.path()).is_ok() {
            removed += 1;
        }
    }
    removed
}

impl FilePyramid {
    /// Opens `header`'s file as a pyramid halving until every axis is at most `coarsest_edge`,
    /// keeping in memory the coarse levels whose stored values fit in `held_bytes` (the
    /// coarsest always). Reads the file once (twice for float data: its finite range first).
    pub fn open(header: VolumeHeader, coarsest_edge: u32, held_bytes: u64) -> Result<Self, LoadError> {
        let dims = header.dims;
        // Float data: the finite range first (what NaN and ±∞ are replaced by, as the loaders
        // replace them), counting what is replaced.
        let (value_range, non_finite) = match header.type_range() {
            Some(range) => (range, 0),
            None => {
                let (lo_hi, non_finite) = header.finite_survey(0..dims.z)?;
                (if lo_hi.0 <= lo_hi.1 { lo_hi } else { (0.0, 0.0) }, non_finite)
            }
        };
        let empty = match header.dtype {
            VoxelType::U8 => VoxelData::U8(Vec::new()),
            VoxelType::U16 => VoxelData::U16(Vec::new()),
            VoxelType::I16 => VoxelData::I16(Vec::new()),
            VoxelType::F32 => VoxelData::F32(Vec::new()),
        };
        let mut template = Volume::new(header.name.clone(), UVec3::ZERO, header.spacing, empty);
        template.value_range = value_range;
        template.meta = header.meta.clone();
        let levels = pyramid_levels(dims, coarsest_edge);
        let last = levels.len() - 1;
        // The coarse levels kept: from the coarsest up while they fit (the coarsest always).
        let mut held_from = levels.len().max(2) - 1;
        let mut bytes = 0u64;
        for l in (1..levels.len()).rev() {
            bytes += levels[l].dims.as_u64vec3().element_product() * 4;
            if bytes > held_bytes && l < last {
                break;
            }
            held_from = l;
        }
        let mut pyramid = Self {
            kind: texel_kind_of(&template),
            integer: header.dtype != VoxelType::F32,
            template,
            levels,
            held_from,
            held: Vec::new(),
            block_ranges: Vec::new(),
            blocks: (dims + (RANGE_BLOCK - 1)) / RANGE_BLOCK,
            non_finite,
            scratch: Vec::new(),
            header,
        };
        pyramid.open_scratch()?;
        pyramid.cascade(value_range)?;
        pyramid.close_scratch()?;
        Ok(pyramid)
    }

    /// How many voxels of a float file were NaN or infinite (read as the finite range's low
    /// end for NaN and −∞, its high end for +∞, as the loaders replace them).
    pub fn non_finite_replaced(&self) -> u64 {
        self.non_finite
    }

    /// Creates the scratch files of levels `1..held_from` (first removing those a killed
    /// process left behind).
    fn open_scratch(&mut self) -> Result<(), LoadError> {
        remove_stale_scratch(&std::env::temp_dir());
        static OPENED: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let n = OPENED.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        for level in 1..self.held_from {
            let d = self.levels[level].dims;
            let name = format!(
                "{SCRATCH_PREFIX}{}-{n}-level{level}_{}x{}x{}_{}.raw",
                std::process::id(),
                d.x,
                d.y,
                d.z,
                self.header.dtype.name()
            );
            let path = std::env::temp_dir().join(name);
            let io = |source| LoadError::Io { path: path.clone(), source };
            let file = std::fs::OpenOptions::new().write(true).create_new(true).open(&path).map_err(io)?;
            self.scratch.push(Scratch { writer: Some(std::io::BufWriter::new(file)), header: None, path });
        }
        Ok(())
    }

    /// Flushes the scratch files and opens them for box reads.
    fn close_scratch(&mut self) -> Result<(), LoadError> {
        use std::io::Write as _;
        for scratch in &mut self.scratch {
            let path = scratch.path.clone();
            if let Some(mut writer) = scratch.writer.take() {
                writer.flush().map_err(|source| LoadError::Io { path: path.clone(), source })?;
            }
            scratch.header = Some(VolumeHeader::read(&path, &crate::load::LoadOptions::default())?);
        }
        Ok(())
    }

    /// The opening pass: every slice of the file through the cascade of means, the kept levels
    /// gathered and each block's range taken.
    fn cascade(&mut self, value_range: (f64, f64)) -> Result<(), LoadError> {
        let dims = self.header.dims;
        let slice_voxels = (dims.x * dims.y) as usize;
        self.held = (self.held_from..self.levels.len())
            .map(|l| Vec::with_capacity(self.levels[l].dims.as_u64vec3().element_product() as usize))
            .collect();
        self.block_ranges =
            vec![(f32::INFINITY, f32::NEG_INFINITY); self.blocks.as_u64vec3().element_product() as usize];
        let mut pending: Vec<Option<Vec<f32>>> = vec![None; self.levels.len()];
        let slice_bytes = (slice_voxels * self.header.dtype.size_bytes()) as u64;
        let slices = (PASS_SLAB_BYTES / slice_bytes.max(1)).clamp(1, u64::from(dims.z)) as u32;
        let header = self.header.clone();
        let mut written = Ok(());
        header.for_each_slab(0..dims.z, slices, value_range, |z0, slab| {
            for lz in 0..slab.dims.z {
                let at = lz as usize * slice_voxels..(lz as usize + 1) * slice_voxels;
                // By type, not a match per voxel (a fifth of the pass).
                let slice: Vec<f32> = match &slab.data {
                    VoxelData::U8(v) => v[at].iter().map(|&x| f32::from(x)).collect(),
                    VoxelData::U16(v) => v[at].iter().map(|&x| f32::from(x)).collect(),
                    VoxelData::I16(v) => v[at].iter().map(|&x| f32::from(x)).collect(),
                    VoxelData::F32(v) => v[at].to_vec(),
                };
                self.take_ranges(&slice, z0 + lz);
                if written.is_ok() {
                    written = self.feed(0, slice, z0 + lz, &mut pending);
                }
            }
        })?;
        written
    }

    /// Widens the range of the blocks slice `z` crosses.
    fn take_ranges(&mut self, slice: &[f32], z: u32) {
        let dims = self.header.dims;
        let bz = z / RANGE_BLOCK;
        for y in 0..dims.y {
            let row = &slice[(y * dims.x) as usize..((y + 1) * dims.x) as usize];
            let base = (bz * self.blocks.y + y / RANGE_BLOCK) * self.blocks.x;
            for (bx, chunk) in row.chunks(RANGE_BLOCK as usize).enumerate() {
                let r = &mut self.block_ranges[base as usize + bx];
                for &v in chunk {
                    *r = (r.0.min(v), r.1.max(v));
                }
            }
        }
    }

    /// Slice `z` of `level` made: kept if the level is, and paired with the one before into
    /// the next level's slice `z / 2` (an odd last slice pairs with itself).
    fn feed(
        &mut self,
        level: usize,
        slice: Vec<f32>,
        z: u32,
        pending: &mut [Option<Vec<f32>>],
    ) -> Result<(), LoadError> {
        if level >= self.held_from {
            self.held[level - self.held_from].extend_from_slice(&slice);
        } else if level > 0 {
            self.write_scratch(level, &slice)?;
        }
        if level + 1 >= self.levels.len() {
            return Ok(());
        }
        let dims = self.levels[level].dims;
        if z.is_multiple_of(2) && z + 1 < dims.z {
            pending[level] = Some(slice);
            return Ok(());
        }
        // Slice z/2 of the next level from slices 2·(z/2) (held) and z (an odd last one: itself).
        let first = if z.is_multiple_of(2) { None } else { pending[level].take() };
        let out = z / 2;
        let value = |v: UVec3| {
            let from = if v.z == 2 * out { first.as_deref().unwrap_or(&slice) } else { &slice };
            f64::from(from[(v.y * dims.x + v.x) as usize])
        };
        let half = (dims + 1) / 2;
        let next = halve_box(value, dims, UVec3::new(0, 0, out), UVec3::new(half.x, half.y, out + 1), self.integer);
        self.feed(level + 1, next, out, pending)
    }

    /// Appends a slice of `level` to its scratch file, in the file's type (a mean of integers is
    /// rounded to one, so it fits).
    fn write_scratch(&mut self, level: usize, slice: &[f32]) -> Result<(), LoadError> {
        use std::io::Write as _;
        let dtype = self.header.dtype;
        let scratch = &mut self.scratch[level - 1];
        let io = |source| LoadError::Io { path: scratch.path.clone(), source };
        let Some(writer) = scratch.writer.as_mut() else { return Ok(()) };
        let bytes: Vec<u8> = match dtype {
            VoxelType::U8 => slice.iter().map(|&v| v as u8).collect(),
            VoxelType::U16 => slice.iter().flat_map(|&v| (v as u16).to_le_bytes()).collect(),
            VoxelType::I16 => slice.iter().flat_map(|&v| (v as i16).to_le_bytes()).collect(),
            VoxelType::F32 => slice.iter().flat_map(|&v| v.to_le_bytes()).collect(),
        };
        writer.write_all(&bytes).map_err(io)
    }

    /// Stored values of voxels `[lo, hi)` of `level` (within it), x fastest: one box read, from
    /// the file at level 0, from the level's scratch file above it, from memory at a kept level.
    fn values(&self, level: usize, lo: UVec3, hi: UVec3) -> Result<Vec<f32>, String> {
        if level >= self.held_from {
            let d = self.levels[level].dims;
            let held = &self.held[level - self.held_from];
            let mut out = Vec::with_capacity((hi - lo).as_u64vec3().element_product() as usize);
            for z in lo.z..hi.z {
                for y in lo.y..hi.y {
                    let row = ((z * d.y + y) * d.x) as usize;
                    out.extend_from_slice(&held[row + lo.x as usize..row + hi.x as usize]);
                }
            }
            return Ok(out);
        }
        let header = match level {
            0 => &self.header,
            l => self.scratch[l - 1]
                .header
                .as_ref()
                .ok_or_else(|| "internal: a scratch level not written".to_string())?,
        };
        let read = header
            .read_box(VoxelBox::new(lo, hi), self.template.value_range)
            .map_err(|e| format!("{}: {e}", self.header.name))?;
        Ok((0..read.voxel_count()).map(|i| read.raw_value(i) as f32).collect())
    }

    fn block_range(&self, lo: UVec3, hi: UVec3) -> (f32, f32) {
        let (blo, bhi) = (lo / RANGE_BLOCK, ((hi + (RANGE_BLOCK - 1)) / RANGE_BLOCK).min(self.blocks));
        let mut range = (f32::INFINITY, f32::NEG_INFINITY);
        for z in blo.z..bhi.z {
            for y in blo.y..bhi.y {
                for x in blo.x..bhi.x {
                    let r = self.block_ranges[((z * self.blocks.y + y) * self.blocks.x + x) as usize];
                    range = (range.0.min(r.0), range.1.max(r.1));
                }
            }
        }
        range
    }
}

impl PyramidSource for FilePyramid {
    fn name(&self) -> &str {
        &self.header.name
    }

    fn levels(&self) -> &[PyramidLevel] {
        &self.levels
    }

    fn spacing(&self) -> DVec3 {
        self.header.spacing
    }

    fn texel_kind(&self) -> TexelKind {
        self.kind
    }

    fn read_box(&self, level: usize, lo: IVec3, dims: UVec3) -> Result<BoxTexels, String> {
        let level_dims = self.levels.get(level).ok_or_else(|| format!("no level {level}"))?.dims;
        // The box clamped to the level, read once; the asked voxels repeat its faces, which is
        // clamping the same indices to the read box.
        let n = level_dims.as_ivec3() - 1;
        let clo = lo.clamp(IVec3::ZERO, n);
        let chi = (lo + dims.as_ivec3() - 1).clamp(IVec3::ZERO, n) + 1;
        let values = self.values(level, clo.as_uvec3(), chi.as_uvec3())?;
        let local = clamped_indices((chi - clo).as_uvec3(), lo - clo, dims).map(|i| f64::from(values[i]));
        Ok(texels_of(&self.template, self.kind, local))
    }

    fn box_range(&self, level: usize, lo: IVec3, hi: IVec3) -> Option<(f32, f32)> {
        let level = self.levels.get(level)?;
        let n = level.dims.as_ivec3() - 1;
        let (clo, chi) = (lo.clamp(IVec3::ZERO, n).as_uvec3(), (hi - 1).clamp(IVec3::ZERO, n).as_uvec3() + 1);
        // A mean lies within its level-0 voxels' range; the box's level-0 voxels lie in blocks.
        let f = level.factor.as_uvec3();
        let (lo0, hi0) = (clo * f, (chi * f).min(self.header.dims));
        let (lo_v, hi_v) = self.block_range(lo0, hi0);
        if lo_v > hi_v {
            return None;
        }
        let normalized = |v: f32| self.template.normalize_value(f64::from(v)).clamp(0.0, 1.0) as f32;
        // A 16-bit texel rounds to the nearest 65535th: widened by one.
        let slack = if self.kind == TexelKind::Unorm16 { 1.0 / 65535.0 } else { 0.0 };
        Some(((normalized(lo_v) - slack).max(0.0), (normalized(hi_v) + slack).min(1.0)))
    }

    fn coarsest(&self) -> Result<Volume, String> {
        let last = self.levels.len() - 1;
        let level = self.levels[last];
        let values = match self.held.last() {
            Some(values) if last >= self.held_from => values.clone(),
            _ => self.values(last, UVec3::ZERO, level.dims)?,
        };
        let mut v = Volume::new(
            self.header.name.clone(),
            level.dims,
            self.header.spacing * level.factor,
            VoxelData::F32(values),
        );
        v.value_range = self.template.value_range;
        v.meta = self.template.meta.clone();
        Ok(v)
    }
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;
    use std::sync::Arc;

    use super::*;
    use crate::load::{LoadOptions, RawOptions, load_volume};
    use crate::pyramid::InCorePyramid;

    fn write_raw(name: &str, bytes: &[u8]) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("volgraph-pyramid-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join(name);
        std::fs::write(&path, bytes).expect("write raw");
        path
    }

    /// Every box of every level (faces, past faces, whole levels) equals the in-memory
    /// pyramid's, whichever levels are kept, and each box's known range holds its texels.
    fn check(path: &std::path::Path, edge: u32) {
        let whole = Arc::new(load_volume(path, &RawOptions::default()).expect("loads").volume);
        let memory = InCorePyramid::new(whole.clone(), edge);
        for held in [0, 1 << 30] {
            let header = VolumeHeader::read(path, &LoadOptions::default()).expect("header");
            let file = FilePyramid::open(header, edge, held).expect("opens");
            assert_eq!(file.levels(), memory.levels());
            assert_eq!(file.texel_kind(), memory.texel_kind());
            assert!(held > 0 || file.held_from == file.levels().len() - 1, "only the coarsest kept");
            for (level, l) in file.levels().iter().enumerate() {
                let d = l.dims.as_ivec3();
                let boxes = [
                    (IVec3::ZERO, l.dims),
                    (IVec3::new(-2, -1, -3), UVec3::new(5, 4, 6)),
                    (d - 3, UVec3::new(6, 5, 4)),
                    (d / 2 - 1, UVec3::new(3, 3, 3)),
                ];
                for (lo, dims) in boxes {
                    let a = file.read_box(level, lo, dims).expect("reads");
                    let b = memory.read_box(level, lo, dims).expect("reads");
                    assert_eq!(a, b, "level {level} box {lo} + {dims}, held {held}");
                    let (lo_v, hi_v) = file.box_range(level, lo, lo + dims.as_ivec3()).expect("ranges known");
                    let (min, max) = a.range().expect("not empty");
                    assert!(lo_v <= min && max <= hi_v, "level {level}: {min}..{max} outside {lo_v}..{hi_v}");
                }
            }
            assert_eq!(file.coarsest().expect("coarsest").data, memory.coarsest().expect("coarsest").data);
            // The levels between the file and the kept ones live in scratch files until the
            // pyramid is dropped.
            let scratch: Vec<std::path::PathBuf> = file.scratch.iter().map(|s| s.path.clone()).collect();
            assert_eq!(scratch.len(), file.held_from - 1);
            assert!(scratch.iter().all(|p| p.exists()));
            drop(file);
            assert!(scratch.iter().all(|p| !p.exists()), "scratch files removed");
        }
        std::fs::remove_file(path).ok();
    }

    #[test]
    fn a_16_bit_file_of_odd_dims_is_the_in_memory_pyramid_at_every_level() {
        let dims = UVec3::new(37, 29, 23);
        let bytes: Vec<u8> = (0..dims.element_product())
            .flat_map(|i| {
                let (x, y, z) = (i % 37, i / 37 % 29, i / (37 * 29));
                (((x * 1733 + y * 977 + z * 4099) % 60000) as u16 + 7).to_le_bytes()
            })
            .collect();
        check(&write_raw("odd_37x29x23_uint16.raw", &bytes), 4);
    }

    #[test]
    fn an_8_bit_and_a_float_file_are_the_in_memory_pyramid_at_every_level() {
        let dims = UVec3::new(40, 33, 18);
        let bytes: Vec<u8> = (0..dims.element_product()).map(|i| ((i * 37 + i / 40 * 11) % 251) as u8).collect();
        check(&write_raw("bytes_40x33x18_uint8.raw", &bytes), 3);
        let floats: Vec<u8> = (0..dims.element_product())
            .flat_map(|i| {
                // Positive: a NaN read as 0 would widen the range (it once did).
                let v = if i % 97 == 0 { f32::NAN } else { (i as f32 * 0.37).sin() * 120.5 + 200.0 };
                v.to_le_bytes()
            })
            .collect();
        let path = write_raw("floats_40x33x18_float32.raw", &floats);
        let header = VolumeHeader::read(&path, &LoadOptions::default()).expect("header");
        let nan = (0..dims.element_product()).filter(|i| i % 97 == 0).count() as u64;
        // The header's own range survey (`render --distributed`'s) skips the NaN too.
        let (lo, hi) = header.finite_range(0..dims.z).expect("surveyed");
        assert!(lo > 79.0 && hi < 321.0, "a NaN widened the range to {lo}..{hi}");
        assert_eq!(FilePyramid::open(header, 5, 0).expect("opens").non_finite_replaced(), nan);
        check(&path, 5);
    }

    /// A killed process's scratch files are removed by the next pyramid opened; a live
    /// process's (this one's) and other files stay.
    #[test]
    fn scratch_files_of_a_gone_process_are_removed() {
        let dir = std::env::temp_dir().join(format!("volgraph-stale-scratch-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        // Above any pid_max Linux allows (2²²): no such process.
        let gone = dir.join(format!("{SCRATCH_PREFIX}4294967295-0-level1_2x2x2_uint8.raw"));
        let live = dir.join(format!("{SCRATCH_PREFIX}{}-0-level1_2x2x2_uint8.raw", std::process::id()));
        let other = dir.join(format!("{SCRATCH_PREFIX}notes.txt"));
        for path in [&gone, &live, &other] {
            std::fs::write(path, [0u8; 8]).expect("write");
        }
        let removed = remove_stale_scratch(&dir);
        if std::path::Path::new("/proc/self").exists() {
            assert_eq!(removed, 1);
            assert!(!gone.exists(), "the gone process's level is removed");
        }
        assert!(live.exists() && other.exists(), "a live process's level and other files stay");
        std::fs::remove_dir_all(&dir).ok();
    }
}
