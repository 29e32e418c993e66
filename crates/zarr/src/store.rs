//! An OME-Zarr image opened: its multiscales metadata and each level's array (shape, chunks,
//! data type, codecs), checked before any voxel is read — sizes, chunk shapes and halving — so
//! a broken store is a message, never a huge allocation or a panic.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{DVec3, UVec3};
use serde_json::Value;
use volgraph_accel::volume::VoxelType;
use zarrs::array::Array;
use zarrs::filesystem::FilesystemStore;
use zarrs::group::Group;

use crate::ZarrError;
use crate::ngff::{AxisKind, Multiscale, millimetres_per};

/// The longest axis a level may have, in voxels (2²⁰: a petavoxel volume is 2²⁰ on a side).
pub const MAX_AXIS: u64 = 1 << 20;

/// One resolution level, opened.
pub struct Level {
    /// Its path in the store.
    pub path: String,
    /// The array.
    pub array: Array<FilesystemStore>,
    /// Voxels per space axis, (x, y, z).
    pub dims: UVec3,
    /// Chunk shape per space axis, (x, y, z).
    pub chunk: UVec3,
    /// The voxel type.
    pub voxel_type: VoxelType,
    /// Voxel size (x, y, z) in the axes' units.
    pub spacing: DVec3,
    /// Position of voxel (0, 0, 0)'s centre (x, y, z) in the axes' units.
    pub origin: DVec3,
    /// The codecs, named as the metadata names them (`zstd`, `blosc`, `sharding_indexed`…).
    pub codecs: Vec<String>,
}

/// An OME-Zarr image: the multiscales metadata and its levels, finest first.
pub struct OmeZarr {
    /// The store's folder.
    pub path: PathBuf,
    /// The metadata.
    pub multiscale: Multiscale,
    /// The levels.
    pub levels: Vec<Level>,
    /// The store's group attributes (for a writer's own keys: `volgraph`).
    pub attributes: serde_json::Map<String, Value>,
    /// Array extents of the time and channel axes (1 where there is none).
    pub times: u64,
    /// See `times`.
    pub channels: u64,
}

/// A file the store would read, refused unless it is a regular file (or absent): a FIFO or a
/// device would block the read or never end it.
pub(crate) fn check_file(path: &Path) -> Result<(), String> {
    match volgraph_accel::input_file::special_kind(path) {
        Ok(Some(what)) => Err(format!("{} is {what}, not a file; a store holds files and folders", path.display())),
        _ => Ok(()),
    }
}

/// [`check_file`] of every metadata file Zarr v2 or v3 keeps in folder `dir`.
fn check_metadata_files(dir: &Path) -> Result<(), String> {
    ["zarr.json", ".zgroup", ".zarray", ".zattrs"].iter().try_for_each(|name| check_file(&dir.join(name)))
}

/// The data type of an array's metadata, if volgraph renders it.
fn voxel_type(metadata: &Value) -> Result<VoxelType, String> {
    // v3: "data_type": "uint16"; v2: "dtype": "<u2".
    let name = metadata.get("data_type").or_else(|| metadata.get("dtype")).and_then(Value::as_str).unwrap_or("?");
    Ok(match name {
        "uint8" | "|u1" | "<u1" | "u1" => VoxelType::U8,
        "uint16" | "<u2" => VoxelType::U16,
        "int16" | "<i2" => VoxelType::I16,
        "float32" | "<f4" => VoxelType::F32,
        ">u2" | ">i2" | ">f4" => {
            return Err(format!("big-endian \"{name}\" (v2) is not read; rewrite it little-endian"));
        }
        other => {
            return Err(format!(
                "data type \"{other}\": volgraph renders uint8, uint16, int16 and float32 volumes; convert the store"
            ));
        }
    })
}

/// The codecs an array's metadata names (v3 `codecs`, nested sharding codecs too; v2
/// `compressor` and `filters`).
fn codec_names(metadata: &Value) -> Vec<String> {
    fn collect(list: &Value, out: &mut Vec<String>) {
        for c in list.as_array().into_iter().flatten() {
            if let Some(name) = c.get("name").and_then(Value::as_str) {
                out.push(name.to_string());
            }
            if let Some(inner) = c.get("configuration").and_then(|c| c.get("codecs")) {
                collect(inner, out);
            }
        }
    }
    let mut out = Vec::new();
    if let Some(list) = metadata.get("codecs") {
        collect(list, &mut out);
    }
    for key in ["filters", "compressor"] {
        match metadata.get(key) {
            Some(Value::Array(list)) => {
                out.extend(list.iter().filter_map(|f| f.get("id")?.as_str().map(str::to_string)))
            }
            Some(Value::Object(c)) => out.extend(c.get("id").and_then(Value::as_str).map(str::to_string)),
            _ => {}
        }
    }
    out
}

impl OmeZarr {
    /// Opens the image at `path` (the store's folder) and checks its metadata and levels.
    pub fn open(path: &Path) -> Result<Self, ZarrError> {
        if !path.join("zarr.json").is_file() && !path.join(".zgroup").is_file() {
            return Err(ZarrError::NotZarr { path: path.to_path_buf() });
        }
        check_metadata_files(path).map_err(|problem| ZarrError::Metadata {
            path: path.to_path_buf(),
            field: "the root group".into(),
            problem,
        })?;
        let store = Arc::new(FilesystemStore::new(path).map_err(|e| ZarrError::Level {
            path: path.to_path_buf(),
            level: "/".into(),
            problem: e.to_string(),
        })?);
        let group = Group::open(store.clone(), "/").map_err(|e| ZarrError::Metadata {
            path: path.to_path_buf(),
            field: "the root group".into(),
            problem: e.to_string(),
        })?;
        let attributes = group.attributes().clone();
        let multiscale = Multiscale::from_attributes(path, &attributes)?;
        let [az, ay, ax] = multiscale.space_axes();
        let mut levels: Vec<Level> = Vec::with_capacity(multiscale.levels.len());
        let (mut times, mut channels) = (1, 1);
        for meta in &multiscale.levels {
            let level_error =
                |problem: String| ZarrError::Level { path: path.to_path_buf(), level: meta.path.clone(), problem };
            check_metadata_files(&path.join(&meta.path)).map_err(&level_error)?;
            let array =
                Array::open(store.clone(), &format!("/{}", meta.path)).map_err(|e| level_error(e.to_string()))?;
            let json = serde_json::to_value(array.metadata()).unwrap_or(Value::Null);
            let voxel_type = voxel_type(&json).map_err(&level_error)?;
            let shape = array.shape().to_vec();
            if shape.len() != multiscale.axes.len() {
                return Err(level_error(format!(
                    "{} dimensions, but the metadata names {} axes",
                    shape.len(),
                    multiscale.axes.len()
                )));
            }
            if let Some((i, n)) = shape.iter().enumerate().find(|(_, n)| **n == 0 || **n > MAX_AXIS) {
                return Err(level_error(format!(
                    "axis \"{}\" holds {n} voxels: each axis holds 1 to {MAX_AXIS}",
                    multiscale.axes[i].name
                )));
            }
            let chunk =
                array.chunk_shape(&vec![0; shape.len()]).map_err(|e| level_error(format!("its chunk grid: {e}")))?;
            let chunk: Vec<u64> = chunk.iter().map(|c| c.get()).collect();
            let dims = UVec3::new(shape[ax] as u32, shape[ay] as u32, shape[az] as u32);
            let spacing = DVec3::new(meta.scale[ax], meta.scale[ay], meta.scale[az]);
            let origin = DVec3::new(meta.translation[ax], meta.translation[ay], meta.translation[az]);
            if let Some(t) = multiscale.axis_of(&AxisKind::Time) {
                times = shape[t];
            }
            if let Some(c) = multiscale.axis_of(&AxisKind::Channel) {
                channels = shape[c];
            }
            if let Some(finer) = levels.last() {
                check_halving(finer, dims, spacing).map_err(&level_error)?;
            }
            levels.push(Level {
                path: meta.path.clone(),
                dims,
                chunk: UVec3::new(chunk[ax] as u32, chunk[ay] as u32, chunk[az] as u32),
                voxel_type,
                spacing,
                origin,
                codecs: codec_names(&json),
                array,
            });
        }
        Ok(OmeZarr { path: path.to_path_buf(), multiscale, levels, attributes, times, channels })
    }

    /// The unit of the space axes (`micrometer`), where the file gives one.
    pub fn space_unit(&self) -> Option<&str> {
        let [z, _, _] = self.multiscale.space_axes();
        self.multiscale.axes[z].unit.as_deref()
    }

    /// Millimetres per unit of the space axes, where the unit is a known length.
    pub fn millimetres_per_unit(&self) -> Option<f64> {
        self.space_unit().and_then(millimetres_per)
    }

    /// Lines for `volgraph info`: version, axes, and per level its shape, chunks, type, codecs
    /// and physical size.
    pub fn describe(&self) -> Vec<String> {
        let m = &self.multiscale;
        let unit = self.space_unit().unwrap_or("(no unit)");
        let axes: Vec<&str> = m.axes.iter().map(|a| a.name.as_str()).collect();
        let mut lines = vec![
            format!(
                "OME-Zarr (NGFF {}){}: axes {}, {} level{}",
                m.version.as_str(),
                m.name.as_deref().map(|n| format!(" \"{n}\"")).unwrap_or_default(),
                axes.join(", "),
                self.levels.len(),
                if self.levels.len() == 1 { "" } else { "s" }
            ),
            format!("time points {}, channels {}", self.times, self.channels),
        ];
        for l in &self.levels {
            let size = l.dims.as_dvec3() * l.spacing;
            lines.push(format!(
                "level \"{}\": {}×{}×{} {:?}, chunks {}×{}×{}, codecs [{}], voxel {:.4}×{:.4}×{:.4} {unit}, size \
                 {:.3}×{:.3}×{:.3} {unit}",
                l.path,
                l.dims.x,
                l.dims.y,
                l.dims.z,
                l.voxel_type,
                l.chunk.x,
                l.chunk.y,
                l.chunk.z,
                l.codecs.join(", "),
                l.spacing.x,
                l.spacing.y,
                l.spacing.z,
                size.x,
                size.y,
                size.z
            ));
        }
        lines
    }
}

/// A coarser level halves each space axis (rounding up as volgraph writes, or down as
/// ome-zarr-py does) or keeps it, and its voxels grow as
/// its extent says.
fn check_halving(finer: &Level, dims: UVec3, spacing: DVec3) -> Result<(), String> {
    for axis in 0..3 {
        let (n, m) = (finer.dims[axis], dims[axis]);
        if m != n && m != n.div_ceil(2) && m != n / 2 {
            return Err(format!(
                "{} voxels on axis {} after {n} at level \"{}\": each level halves an axis (rounding either way) or \
                 keeps it",
                m,
                ["x", "y", "z"][axis],
                finer.path
            ));
        }
        let factor = spacing[axis] / finer.spacing[axis];
        let want = n as f64 / m as f64;
        if (factor - want).abs() > 0.5 * want {
            return Err(format!(
                "its voxels on axis {} are {factor:.3}× level \"{}\"'s, but it holds 1/{want:.3} of its voxels: the \
                 scale transforms do not match the shapes",
                ["x", "y", "z"][axis],
                finer.path
            ));
        }
    }
    Ok(())
}
