//! numpy arrays in and out. A volume array is indexed `[z, y, x]` (napari, scikit-image,
//! SimpleITK, OME-Zarr; a C-order array then has x varying fastest, like a `.raw` file) or, with
//! `axes="xyz"`, `[x, y, z]` (nibabel). u8, u16, i16 and f32 are taken, in any order and with
//! any strides: the voxels are copied once into the volume the GPU upload reads.

use numpy::ndarray::{ArrayViewD, Axis};
use numpy::{PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use volgraph_accel::volume::VoxelData;

/// The voxels of `array` in x-fastest order and the volume's dims (x, y, z).
pub fn voxels(array: &Bound<'_, PyAny>, axes: &str) -> PyResult<(VoxelData, glam::UVec3)> {
    let xyz = match axes {
        "zyx" => false,
        "xyz" => true,
        other => {
            return Err(PyValueError::new_err(format!(
                "axes=\"{other}\": \"zyx\" ([z, y, x], the default) or \"xyz\""
            )));
        }
    };
    if let Ok(a) = array.extract::<PyReadonlyArrayDyn<'_, u8>>() {
        let (data, dims) = flatten(a.as_array(), xyz)?;
        return Ok((VoxelData::U8(data), dims));
    }
    if let Ok(a) = array.extract::<PyReadonlyArrayDyn<'_, u16>>() {
        let (data, dims) = flatten(a.as_array(), xyz)?;
        return Ok((VoxelData::U16(data), dims));
    }
    if let Ok(a) = array.extract::<PyReadonlyArrayDyn<'_, i16>>() {
        let (data, dims) = flatten(a.as_array(), xyz)?;
        return Ok((VoxelData::I16(data), dims));
    }
    if let Ok(a) = array.extract::<PyReadonlyArrayDyn<'_, f32>>() {
        let (data, dims) = flatten(a.as_array(), xyz)?;
        if !data.iter().any(|v| v.is_finite()) {
            return Err(PyValueError::new_err("the array holds no finite value (all NaN or infinite)"));
        }
        return Ok((VoxelData::F32(data), dims));
    }
    let dtype = match array.cast::<numpy::PyUntypedArray>() {
        Ok(a) => a.dtype().str().map(|s| s.to_string()).unwrap_or_else(|_| "?".to_string()),
        Err(_) => {
            let kind = array.get_type().name().map(|n| n.to_string()).unwrap_or_default();
            return Err(PyValueError::new_err(format!(
                "a volume is a numpy array (or a volgraph.Volume), not a {kind}"
            )));
        }
    };
    Err(PyValueError::new_err(format!(
        "an array of dtype {dtype}: volgraph renders uint8, uint16, int16 and float32 volumes; convert it \
         (a.astype(np.float32), or np.int16 for CT in HU)"
    )))
}

/// `view` as x-fastest voxels and its dims (x, y, z): three axes, none empty.
fn flatten<T: Copy>(view: ArrayViewD<'_, T>, xyz: bool) -> PyResult<(Vec<T>, glam::UVec3)> {
    if view.ndim() != 3 {
        return Err(PyValueError::new_err(format!(
            "a volume has 3 axes; this array has {} (shape {:?}){}",
            view.ndim(),
            view.shape(),
            if view.ndim() == 4 { ": take one channel or time point, a[..., 0] or a[0]" } else { "" }
        )));
    }
    if view.shape().contains(&0) {
        return Err(PyValueError::new_err(format!("the array is empty (shape {:?})", view.shape())));
    }
    // [z, y, x] in C order is x fastest; an [x, y, z] array is read through its reversed axes.
    let view = if xyz { view.reversed_axes() } else { view };
    let too_big =
        |n: usize| u32::try_from(n).map_err(|_| PyValueError::new_err(format!("an axis of {n} voxels is too long")));
    let dims = glam::UVec3::new(
        too_big(view.len_of(Axis(2)))?,
        too_big(view.len_of(Axis(1)))?,
        too_big(view.len_of(Axis(0)))?,
    );
    let data = match view.as_slice() {
        Some(contiguous) => contiguous.to_vec(),
        None => view.iter().copied().collect(),
    };
    Ok((data, dims))
}
