//! A whole level read into a [`Volume`], chunk by chunk: a missing chunk is drawn as the fill
//! value with one note naming it, a chunk that cannot be decoded with an error line naming it
//! (the rest still draws); a level over the memory limit is refused, naming the coarser ones.

use glam::UVec3;
use volgraph_accel::volume::{Volume, VoxelData, VoxelType};
use zarrs::array::ElementOwned;

use crate::ZarrError;
use crate::ngff::AxisKind;
use crate::store::{Level, OmeZarr};

/// Which volume of a 5-D image to read.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Pick {
    /// The time point (0-based).
    pub time: u64,
    /// The channel (0-based).
    pub channel: u64,
}

/// A level read, with what the reader had to say.
pub struct ReadLevel {
    /// The volume: voxels, spacing and origin in the axes' units (millimetres where the unit is
    /// a known length, so volumes of different units line up).
    pub volume: Volume,
    /// Missing or undecodable chunks, one line each (at most 8, then a count).
    pub notes: Vec<String>,
}

/// How many chunk lines a read reports before counting the rest.
const NOTED_CHUNKS: usize = 8;

impl OmeZarr {
    /// The finest level whose voxels fit in `limit_bytes`.
    pub fn finest_within(&self, limit_bytes: u64) -> Option<usize> {
        self.levels.iter().position(|l| level_bytes(l) <= limit_bytes)
    }

    /// Reads level `index` whole (at most `limit_bytes` of voxels).
    pub fn read_level(&self, index: usize, pick: Pick, limit_bytes: u64) -> Result<ReadLevel, ZarrError> {
        let level = &self.levels[index];
        for (kind, value, count, what) in [
            (AxisKind::Time, pick.time, self.times, "time point"),
            (AxisKind::Channel, pick.channel, self.channels, "channel"),
        ] {
            if value >= count {
                let (field, problem) = match self.multiscale.axis_of(&kind) {
                    Some(a) => (
                        format!("axis \"{}\"", self.multiscale.axes[a].name),
                        format!("{what} {value} asked for; the image has {count} (0..{count})"),
                    ),
                    None => (
                        "axes".to_string(),
                        format!("{what} {value} asked for; the image has no {what} axis (one volume)"),
                    ),
                };
                return Err(ZarrError::Metadata { path: self.path.clone(), field, problem });
            }
        }
        let bytes = level_bytes(level);
        if bytes > limit_bytes {
            let coarser: Vec<&str> = self.levels[index + 1..].iter().map(|l| l.path.as_str()).collect();
            return Err(ZarrError::TooLarge {
                path: self.path.clone(),
                level: level.path.clone(),
                shape: format!("{}×{}×{}", level.dims.x, level.dims.y, level.dims.z),
                mb: bytes >> 20,
                limit_mb: limit_bytes >> 20,
                coarser: if coarser.is_empty() { "none".into() } else { coarser.join(", ") },
            });
        }
        let mut notes = Vec::new();
        let data = match level.voxel_type {
            VoxelType::U8 => VoxelData::U8(self.read_voxels::<u8>(level, pick, &mut notes)?),
            VoxelType::U16 => VoxelData::U16(self.read_voxels::<u16>(level, pick, &mut notes)?),
            VoxelType::I16 => VoxelData::I16(self.read_voxels::<i16>(level, pick, &mut notes)?),
            VoxelType::F32 => VoxelData::F32(self.read_voxels::<f32>(level, pick, &mut notes)?),
        };
        let mm = self.millimetres_per_unit().unwrap_or(1.0);
        let name = self.path.file_name().map_or("ome-zarr".into(), |n| n.to_string_lossy().into_owned());
        // As a raw file of the same voxels is read (non-finite values replaced, spacing checked).
        let loaded =
            volgraph_accel::load::from_memory(&format!("{name}#{}", level.path), level.dims, level.spacing * mm, data)
                .map_err(|e| ZarrError::Level {
                    path: self.path.clone(),
                    level: level.path.clone(),
                    problem: e.to_string(),
                })?;
        let mut volume = loaded.volume;
        volume.meta = self.volgraph_meta();
        // The range the source mapped to 0..1 (a scanner file's, fitted to its data), so the
        // store renders as the file it came from.
        if let Some(range) = self.volgraph_value_range() {
            volume.value_range = range;
        }
        volume.meta.origin = Some(level.origin * mm);
        if volume.meta.description.is_none() {
            volume.meta.description = self.multiscale.name.clone();
        }
        Ok(ReadLevel { volume, notes })
    }

    /// The voxels of `level` at `pick`, x fastest, chunk by chunk.
    fn read_voxels<T: ElementOwned + Copy + Default + Send + Sync>(
        &self,
        level: &Level,
        pick: Pick,
        notes: &mut Vec<String>,
    ) -> Result<Vec<T>, ZarrError> {
        let axes = &self.multiscale.axes;
        let [az, ay, ax] = self.multiscale.space_axes();
        let grid = level.array.chunk_grid_shape().to_vec();
        let d = level.dims;
        let (nx, ny) = (d.x as usize, d.y as usize);
        let mut out = vec![T::default(); nx * ny * d.z as usize];
        let (mut missing, mut broken, mut unstored) = (0usize, 0usize, 0usize);
        // What the writer recorded of each chunk: a chunk it left out as all fill is expected
        // to be missing; one it saw data in is not.
        let ranges = self.chunk_ranges(level);
        let fixed = |kind: AxisKind, value: u64| self.multiscale.axis_of(&kind).map(|a| (a, value));
        let picks: Vec<(usize, u64)> =
            [fixed(AxisKind::Time, pick.time), fixed(AxisKind::Channel, pick.channel)].into_iter().flatten().collect();
        for cz in 0..grid[az] {
            for cy in 0..grid[ay] {
                for cx in 0..grid[ax] {
                    let mut index = vec![0u64; axes.len()];
                    (index[az], index[ay], index[ax]) = (cz, cy, cx);
                    let origin_of = |i: &[u64]| level.array.chunk_origin(i);
                    // The chunk along t and c holding the picked volume.
                    for &(a, value) in &picks {
                        let size = level.array.chunk_shape(&index).map(|s| s[a].get()).unwrap_or(1);
                        index[a] = value / size;
                    }
                    let chunk_error = |problem: String| ZarrError::Chunk {
                        path: self.path.clone(),
                        level: level.path.clone(),
                        chunk: [cz, cy, cx],
                        problem,
                    };
                    let shape = level.array.chunk_shape(&index).map_err(|e| chunk_error(e.to_string()))?;
                    let shape: Vec<u64> = shape.iter().map(|s| s.get()).collect();
                    let origin = origin_of(&index).map_err(|e| chunk_error(e.to_string()))?;
                    // A FIFO or device in a chunk's place would block the read: an undecodable chunk.
                    let file = self.path.join(level.array.chunk_key(&index).as_str());
                    let read = crate::store::check_file(&file)
                        .map_err(zarrs::array::ArrayError::Other)
                        .and_then(|()| level.array.retrieve_chunk_if_exists::<Vec<T>>(&index));
                    let elements = match read {
                        Ok(Some(elements)) => elements,
                        Ok(None) => {
                            let i = ((cz * grid[ay] + cy) * grid[ax] + cx) as usize * 2;
                            let had_data = ranges.as_ref().and_then(|r| r.get(i..i + 2)).map(|r| r != [0.0, 0.0]);
                            if had_data != Some(true) {
                                unstored += 1;
                                continue;
                            }
                            missing += 1;
                            if missing <= NOTED_CHUNKS {
                                notes.push(format!(
                                    "warning: {}: level \"{}\", chunk (z, y, x) {cz}/{cy}/{cx} is missing; drawn as \
                                     the fill value",
                                    self.path.display(),
                                    level.path
                                ));
                            }
                            continue;
                        }
                        Err(e) => {
                            broken += 1;
                            if broken <= NOTED_CHUNKS {
                                notes.push(format!("error: {}; drawn as the fill value", chunk_error(e.to_string())));
                            }
                            continue;
                        }
                    };
                    copy_chunk(&elements, &shape, &origin, &picks, [az, ay, ax], d, &mut out);
                }
            }
        }
        if unstored > 0 && ranges.is_none() {
            notes.push(format!(
                "{}: {unstored} chunks of level \"{}\" are not stored (Zarr leaves out chunks of the fill value): \
                 drawn as the fill value",
                self.path.display(),
                level.path
            ));
        }
        for (count, what) in [(missing, "missing"), (broken, "undecodable")] {
            if count > NOTED_CHUNKS {
                notes.push(format!("… and {} more {what} chunks of level \"{}\"", count - NOTED_CHUNKS, level.path));
            }
        }
        Ok(out)
    }
}

impl OmeZarr {
    /// The metadata `volgraph convert` kept (patient frame, modality, units, window); empty for
    /// another writer's store.
    pub(crate) fn volgraph_meta(&self) -> volgraph_accel::volume_meta::VolumeMeta {
        use volgraph_accel::volume_meta::{VolumeMeta, Window, WorldFrame};
        let Some(v) = self.attributes.get("volgraph") else { return VolumeMeta::default() };
        let text = |key: &str| v.get(key).and_then(serde_json::Value::as_str).map(str::to_string);
        let window = v
            .get("window")
            .and_then(serde_json::Value::as_array)
            .and_then(|w| Some(Window { center: w.first()?.as_f64()?, width: w.get(1)?.as_f64()? }));
        let lps = v.get("patient_frame").and_then(serde_json::Value::as_bool) == Some(true);
        VolumeMeta {
            modality: text("modality"),
            units: text("units"),
            window,
            frame: if lps { WorldFrame::Lps } else { WorldFrame::IndexAxes },
            origin: None,
            description: text("description"),
            frame_of_reference: text("frame_of_reference"),
        }
    }

    /// The source's value range `volgraph convert` kept.
    fn volgraph_value_range(&self) -> Option<(f64, f64)> {
        let r = self.attributes.get("volgraph")?.get("value_range")?.as_array()?;
        let (lo, hi) = (r.first()?.as_f64()?, r.get(1)?.as_f64()?);
        (lo.is_finite() && hi.is_finite() && lo < hi).then_some((lo, hi))
    }

    /// The value range `volgraph convert` stored for each chunk of `level` (`chunk_ranges/<level>`,
    /// [gz, gy, gx, 2]), if this store has them.
    pub(crate) fn chunk_ranges(&self, level: &Level) -> Option<Vec<f32>> {
        self.attributes.get("volgraph")?.get("chunk_ranges")?;
        let path = format!("/chunk_ranges/{}", level.path);
        // Only regular files: a FIFO among them would block the read (the ranges are then unused).
        let mut stack = vec![self.path.join("chunk_ranges").join(&level.path)];
        while let Some(dir) = stack.pop() {
            for entry in std::fs::read_dir(&dir).ok()?.flatten() {
                let kind = entry.file_type().ok()?;
                match kind.is_dir() {
                    true => stack.push(entry.path()),
                    false => crate::store::check_file(&entry.path()).ok()?,
                }
            }
        }
        let ranges = zarrs::array::Array::open(level.array.storage(), &path).ok()?;
        let grid = level.array.chunk_grid_shape();
        (ranges.shape() == [grid[0], grid[1], grid[2], 2].as_slice()).then_some(())?;
        ranges.retrieve_array_subset::<Vec<f32>>(&ranges.subset_all()).ok()
    }
}

/// Copies the in-bounds part of a chunk (C order over all axes) at the picked t/c into `out`
/// (x fastest, `dims` x, y, z).
fn copy_chunk<T: Copy>(
    elements: &[T],
    shape: &[u64],
    origin: &[u64],
    picks: &[(usize, u64)],
    [az, ay, ax]: [usize; 3],
    dims: UVec3,
    out: &mut [T],
) {
    let n = shape.len();
    let mut strides = vec![1u64; n];
    for a in (0..n.saturating_sub(1)).rev() {
        strides[a] = strides[a + 1] * shape[a + 1];
    }
    let mut base = 0u64;
    for &(a, value) in picks {
        base += (value - origin[a]) * strides[a];
    }
    let z_end = (origin[az] + shape[az]).min(dims.z as u64);
    let y_end = (origin[ay] + shape[ay]).min(dims.y as u64);
    let x_end = (origin[ax] + shape[ax]).min(dims.x as u64);
    let row = (x_end - origin[ax]) as usize;
    for z in origin[az]..z_end {
        for y in origin[ay]..y_end {
            let src = (base + (z - origin[az]) * strides[az] + (y - origin[ay]) * strides[ay]) as usize;
            let dst = ((z * dims.y as u64 + y) * dims.x as u64 + origin[ax]) as usize;
            if strides[ax] == 1 {
                out[dst..dst + row].copy_from_slice(&elements[src..src + row]);
            } else {
                for i in 0..row {
                    out[dst + i] = elements[src + i * strides[ax] as usize];
                }
            }
        }
    }
}

/// Bytes of one volume of `level`.
pub(crate) fn level_bytes(level: &Level) -> u64 {
    let per = match level.voxel_type {
        VoxelType::U8 => 1,
        VoxelType::U16 | VoxelType::I16 => 2,
        VoxelType::F32 => 4,
    };
    level.dims.x as u64 * level.dims.y as u64 * level.dims.z as u64 * per
}
