//! `volgraph.Volume` and `volgraph.load`: the voxels live in a numpy array (`Volume.array`, a
//! read-only view of the very buffer the loader filled: no copy), beside what the file says of
//! them. A render copies the voxels once, into the volume the GPU upload reads.

use std::path::PathBuf;

use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use volgraph_accel::volume::VoxelData;

use crate::errors::{escaped, raise, value_error, volume_error};

/// A volume: voxels, spacing and what the file says of them.
#[pyclass(module = "volgraph", frozen)]
pub struct Volume {
    /// Everything but the voxels (its data empty): dims, spacing, value range, metadata.
    header: volgraph_accel::volume::Volume,
    /// The voxels, [z, y, x], read-only: the numpy array that owns them.
    array: Py<PyAny>,
    /// A generated Marschner–Lobb volume: its default TF is the band that shows its rings (as
    /// the command line's).
    ring_tf: bool,
    /// The voxels' type (the header's data is empty).
    voxel_type: volgraph_accel::volume::VoxelType,
}

impl Volume {
    /// Moves `volume`'s voxels into a numpy array (no copy) and keeps the rest.
    pub fn new(py: Python<'_>, mut volume: volgraph_accel::volume::Volume, ring_tf: bool) -> PyResult<Self> {
        let d = volume.dims;
        let shape = [d.z as usize, d.y as usize, d.x as usize];
        let voxel_type = volume.data.voxel_type();
        let data = std::mem::replace(&mut volume.data, VoxelData::U8(Vec::new()));
        let array = match data {
            VoxelData::U8(v) => PyArray1::from_vec(py, v).reshape(shape)?.into_any(),
            VoxelData::U16(v) => PyArray1::from_vec(py, v).reshape(shape)?.into_any(),
            VoxelData::I16(v) => PyArray1::from_vec(py, v).reshape(shape)?.into_any(),
            VoxelData::F32(v) => PyArray1::from_vec(py, v).reshape(shape)?.into_any(),
        };
        // Read-only: the metadata (value range, window) describes these values.
        array.getattr("flags")?.setattr("writeable", false)?;
        Ok(Self { header: volume, array: array.unbind(), ring_tf, voxel_type })
    }

    /// The library's volume with its voxels (one copy, out of the numpy array), and whether its
    /// default TF is the Marschner–Lobb band.
    pub fn to_library(&self, py: Python<'_>) -> PyResult<(volgraph_accel::volume::Volume, bool)> {
        let (data, _) = crate::array::voxels(self.array.bind(py), "zyx")?;
        Ok((volgraph_accel::volume::Volume { data, ..self.header.clone() }, self.ring_tf))
    }
}

#[pymethods]
impl Volume {
    /// The voxels as a read-only numpy array indexed [z, y, x]: a view of the buffer the file was
    /// read into (no copy); `v.array.copy()` to change them.
    #[getter]
    fn array(&self, py: Python<'_>) -> Py<PyAny> {
        self.array.clone_ref(py)
    }

    /// Voxel spacing (x, y, z), as the CLI's --spacing.
    #[getter]
    fn spacing(&self) -> (f64, f64, f64) {
        let s = self.header.spacing;
        (s.x, s.y, s.z)
    }

    /// Voxels per axis (x, y, z).
    #[getter]
    fn dims(&self) -> (u32, u32, u32) {
        let d = self.header.dims;
        (d.x, d.y, d.z)
    }

    /// The 4×4 matrix taking a voxel index (x, y, z, 1) — the centre of `array[z, y, x]` — to
    /// the world in the file's units: the patient frame (LPS, mm) where the file places the
    /// volume (the loaders lay its axes along L, P and S), else the spacing from the first voxel.
    #[getter]
    fn world_from_volume<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let s = self.header.spacing;
        let o = self.header.meta.origin.unwrap_or_default();
        let m = vec![s.x, 0.0, 0.0, o.x, 0.0, s.y, 0.0, o.y, 0.0, 0.0, s.z, o.z, 0.0, 0.0, 0.0, 1.0];
        Ok(PyArray1::from_vec(py, m).reshape([4, 4])?.into_any())
    }

    /// The data values that map to 0 and 1 on the GPU.
    #[getter]
    fn value_range(&self) -> (f64, f64) {
        self.header.value_range
    }

    /// Modality, units, window, frame, origin and description, as far as the file says.
    #[getter]
    fn meta<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let m = &self.header.meta;
        let d = PyDict::new(py);
        d.set_item("modality", m.modality.clone())?;
        d.set_item("units", m.units.clone())?;
        d.set_item("window", m.window.map(|w| (w.center, w.width)))?;
        d.set_item("frame", m.frame.describe())?;
        d.set_item("origin", m.origin.map(|o| (o.x, o.y, o.z)))?;
        d.set_item("description", m.description.clone())?;
        d.set_item("frame_of_reference", m.frame_of_reference.clone())?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        let d = self.header.dims;
        format!("volgraph.Volume(\"{}\", {}×{}×{}, {:?})", self.header.name, d.x, d.y, d.z, self.voxel_type)
    }
}

/// `volume` (a Volume or an array) as the library's volume, and whether its default TF is the
/// Marschner–Lobb band; an array takes `spacing` (x, y, z), a Volume keeps its own unless given.
pub fn volume_of(
    volume: &Bound<'_, PyAny>,
    spacing: Option<(f64, f64, f64)>,
    axes: &str,
) -> PyResult<(volgraph_accel::volume::Volume, bool)> {
    if let Ok(v) = volume.cast::<Volume>() {
        let (mut inner, ring_tf) = v.get().to_library(volume.py())?;
        if let Some((x, y, z)) = spacing {
            inner.spacing = glam::DVec3::new(x, y, z);
        }
        return Ok((inner, ring_tf));
    }
    let (data, dims) = crate::array::voxels(volume, axes)?;
    let (x, y, z) = spacing.unwrap_or((1.0, 1.0, 1.0));
    let v = volgraph_app::api::volume_from_memory("array", dims, glam::DVec3::new(x, y, z), data)
        .map_err(|e| raise(e, value_error))?;
    Ok((v, false))
}

/// Reads a volume: a file (.raw named NAME_XxYxZ_TYPE.raw, .nrrd, .nhdr, .mhd, .mha, .nii,
/// .nii.gz), a folder of DICOM slices, a dataset of the data folder by name (`engine`), or a
/// generated volume (`ml64`, `organs128`). `series`: the DICOM series of a folder holding
/// several; `frame`: the volume of a 4D NIfTI file.
#[pyfunction]
#[pyo3(signature = (path, *, series = None, frame = None))]
pub fn load(py: Python<'_>, path: PathBuf, series: Option<String>, frame: Option<u64>) -> PyResult<Volume> {
    let options = volgraph_accel::load::LoadOptions { series, frame, ..Default::default() };
    let shown = py
        .detach(|| volgraph_app::scene::load_shown_volume(&[path], None, &options))
        .map_err(|e| volume_error(escaped(format!("{e:#}"))))?;
    Volume::new(py, shown.volume, shown.marschner_lobb_tf)
}
