//! The in-memory scalar volume every other part of volgraph reads.

use glam::{DVec3, UVec3};

/// Voxel storage, in the type the file had (i16 is kept as i16; see [`Volume::normalized`]).
#[derive(Clone, Debug, PartialEq)]
pub enum VoxelData {
    /// One unsigned byte per voxel.
    U8(Vec<u8>),
    /// Two bytes per voxel, native order after loading.
    U16(Vec<u16>),
    /// Signed 16-bit (CT Hounsfield units and the like).
    I16(Vec<i16>),
    /// 32-bit float; loaders replace NaN/Inf before a volume is built.
    F32(Vec<f32>),
}

impl VoxelData {
    /// Number of voxels stored.
    pub fn len(&self) -> usize {
        match self {
            VoxelData::U8(v) => v.len(),
            VoxelData::U16(v) => v.len(),
            VoxelData::I16(v) => v.len(),
            VoxelData::F32(v) => v.len(),
        }
    }

    /// True when no voxel is stored.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The type's name as used in file names (`uint8`, `uint16`, `int16`, `float32`).
    pub fn type_name(&self) -> &'static str {
        match self {
            VoxelData::U8(_) => "uint8",
            VoxelData::U16(_) => "uint16",
            VoxelData::I16(_) => "int16",
            VoxelData::F32(_) => "float32",
        }
    }
}

/// A scalar volume: `dims` voxels, x fastest (`index = x + nx*(y + ny*z)`), with a physical
/// voxel `spacing`. See `docs/rendering_model.md` for how it maps to world and texture space.
#[derive(Clone, Debug, PartialEq)]
pub struct Volume {
    /// Voxels per axis.
    pub dims: UVec3,
    /// Physical size of one voxel per axis (any unit; only ratios matter for rendering).
    pub spacing: DVec3,
    /// The voxels.
    pub data: VoxelData,
    /// A human-readable name (file stem or generator), used in messages and benchmarks.
    pub name: String,
    /// The data values that normalize to 0 and 1 (see [`Volume::normalized`]): the type range
    /// for integer data from [`Volume::new`], the finite (min, max) for float data, and for
    /// scanner data the values the file holds ([`Volume::fit_range_to_data`]).
    pub value_range: (f64, f64),
    /// Modality, units, window and patient frame, as far as the file says.
    pub meta: crate::volume_meta::VolumeMeta,
}

impl Volume {
    /// Number of voxels (`nx*ny*nz`).
    pub fn voxel_count(&self) -> usize {
        self.dims.x as usize * self.dims.y as usize * self.dims.z as usize
    }

    /// Linear index of voxel `(x, y, z)`.
    #[inline]
    pub fn index(&self, x: u32, y: u32, z: u32) -> usize {
        x as usize + self.dims.x as usize * (y as usize + self.dims.y as usize * z as usize)
    }

    /// The normalized value in \[0,1\] of voxel `i`, exactly as the GPU texture holds it:
    /// `(v - lo)/(hi - lo)` over [`Volume::value_range`] — with the type range of
    /// [`Volume::new`], u8 → v/255, u16 → v/65535, i16 → (v+32768)/65535; f32 →
    /// (v-min)/(max-min). An empty range gives 0.
    #[inline]
    pub fn normalized(&self, i: usize) -> f64 {
        self.normalize_value(self.raw_value(i))
    }

    /// The data value of voxel `i` (the stored value, as f64).
    #[inline]
    pub fn raw_value(&self, i: usize) -> f64 {
        match &self.data {
            VoxelData::U8(v) => v[i] as f64,
            VoxelData::U16(v) => v[i] as f64,
            VoxelData::I16(v) => v[i] as f64,
            VoxelData::F32(v) => v[i] as f64,
        }
    }

    /// Where data value `v` lies in the normalized values: `(v - lo)/(hi - lo)`, 0 for an empty
    /// range.
    #[inline]
    pub fn normalize_value(&self, v: f64) -> f64 {
        let (lo, hi) = self.value_range;
        if hi > lo { (v - lo) / (hi - lo) } else { 0.0 }
    }

    /// The data value at normalized value `s` (the inverse of [`Self::normalize_value`]).
    pub fn data_value(&self, s: f64) -> f64 {
        let (lo, hi) = self.value_range;
        lo + s * (hi - lo)
    }

    /// The (min, max) of the stored values ((0, 0) for an empty volume).
    pub fn data_min_max(&self) -> (f64, f64) {
        fn fold<T: Copy + Into<f64>>(v: &[T]) -> (f64, f64) {
            v.iter()
                .fold(None, |acc: Option<(f64, f64)>, &x| {
                    let x: f64 = x.into();
                    Some(acc.map_or((x, x), |(lo, hi)| (lo.min(x), hi.max(x))))
                })
                .unwrap_or((0.0, 0.0))
        }
        match &self.data {
            VoxelData::U8(v) => fold(v),
            VoxelData::U16(v) => fold(v),
            VoxelData::I16(v) => fold(v),
            VoxelData::F32(v) => finite_range(v).unwrap_or((0.0, 0.0)),
        }
    }

    /// Narrows [`Volume::value_range`] of 16-bit data to the values it holds, so that a
    /// transfer function over them (CT's −1024…3071 HU in int16) gets the whole LUT rather
    /// than the sixteenth of it the type range would leave. Scanner loaders call it; other
    /// volumes keep the type range. 8-bit and float data are unchanged; a constant volume keeps
    /// its range.
    pub fn fit_range_to_data(&mut self) {
        if matches!(self.data, VoxelData::U16(_) | VoxelData::I16(_)) {
            let (lo, hi) = self.data_min_max();
            if hi > lo {
                self.value_range = (lo, hi);
            }
        }
    }

    /// Voxel `i` as the 16-bit normalized texel the GPU samples: `round(normalized · 65535)`,
    /// exact for the type range (`v` for u16, `v + 32768` for i16).
    #[inline]
    pub fn unorm16(&self, i: usize) -> u16 {
        (self.normalized(i).clamp(0.0, 1.0) * 65535.0).round() as u16
    }

    /// All voxels normalized to \[0,1\] as f32 (what an R32Float texture upload wants).
    pub fn normalized_f32(&self) -> Vec<f32> {
        (0..self.voxel_count()).map(|i| self.normalized(i) as f32).collect()
    }

    /// Physical extent `dims * spacing`.
    pub fn extent(&self) -> DVec3 {
        self.dims.as_dvec3() * self.spacing
    }

    /// Half size of the volume box in world space: the longest side has length 1.
    pub fn half_extent_world(&self) -> DVec3 {
        let e = self.extent();
        e / (2.0 * e.max_element())
    }

    /// The size of one voxel in world units per axis.
    pub fn voxel_world(&self) -> DVec3 {
        let e = self.extent();
        self.spacing / e.max_element()
    }

    /// The renderer's unit step in world units: the smallest voxel side.
    pub fn unit_step_world(&self) -> f64 {
        self.voxel_world().min_element()
    }

    /// Trilinear sample of the normalized field at texture coordinate `u` with clamp-to-edge,
    /// voxel centres at `(i+0.5)/n` (`docs/rendering_model.md`).
    pub fn sample_trilinear(&self, u: DVec3) -> f64 {
        let n = self.dims.as_dvec3();
        let p = u * n - 0.5;
        let base = p.floor();
        let f = p - base;
        let clamp = |v: f64, n: u32| -> u32 { v.clamp(0.0, (n - 1) as f64) as u32 };
        let (bx, by, bz) = (base.x, base.y, base.z);
        let x0 = clamp(bx, self.dims.x);
        let x1 = clamp(bx + 1.0, self.dims.x);
        let y0 = clamp(by, self.dims.y);
        let y1 = clamp(by + 1.0, self.dims.y);
        let z0 = clamp(bz, self.dims.z);
        let z1 = clamp(bz + 1.0, self.dims.z);
        let v = |x, y, z| self.normalized(self.index(x, y, z));
        let c00 = v(x0, y0, z0) * (1.0 - f.x) + v(x1, y0, z0) * f.x;
        let c10 = v(x0, y1, z0) * (1.0 - f.x) + v(x1, y1, z0) * f.x;
        let c01 = v(x0, y0, z1) * (1.0 - f.x) + v(x1, y0, z1) * f.x;
        let c11 = v(x0, y1, z1) * (1.0 - f.x) + v(x1, y1, z1) * f.x;
        let c0 = c00 * (1.0 - f.y) + c10 * f.y;
        let c1 = c01 * (1.0 - f.y) + c11 * f.y;
        c0 * (1.0 - f.z) + c1 * f.z
    }

    /// Tricubic B-spline sample at texture coordinate `u`: the 4×4×4 voxels around it weighted by
    /// the uniform cubic B-spline, indices clamped to the volume (clamp-to-edge), voxel centres at
    /// `(i+0.5)/n`. A smoothing filter (it does not pass through the voxel values); the GPU
    /// evaluates it with 8 trilinear fetches (Sigg & Hadwiger 2005, `shaders/common/volume.wgsl`).
    pub fn sample_tricubic(&self, u: DVec3) -> f64 {
        let n = self.dims.as_dvec3();
        let p = u * n - 0.5;
        let base = p.floor();
        let f = p - base;
        let weights = |t: f64| {
            let it = 1.0 - t;
            [
                it * it * it / 6.0,
                (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0,
                (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) / 6.0,
                t * t * t / 6.0,
            ]
        };
        let (wx, wy, wz) = (weights(f.x), weights(f.y), weights(f.z));
        let clamp = |v: f64, n: u32| -> u32 { v.clamp(0.0, (n - 1) as f64) as u32 };
        let mut sum = 0.0;
        for (k, w_z) in wz.iter().enumerate() {
            let z = clamp(base.z + k as f64 - 1.0, self.dims.z);
            for (j, w_y) in wy.iter().enumerate() {
                let y = clamp(base.y + j as f64 - 1.0, self.dims.y);
                for (i, w_x) in wx.iter().enumerate() {
                    let x = clamp(base.x + i as f64 - 1.0, self.dims.x);
                    sum += w_x * w_y * w_z * self.normalized(self.index(x, y, z));
                }
            }
        }
        sum
    }
}

/// The voxel types volgraph stores, one per [`VoxelData`] variant.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum VoxelType {
    /// `uint8`.
    U8,
    /// `uint16`.
    U16,
    /// `int16`.
    I16,
    /// `float32`.
    F32,
}

impl VoxelType {
    /// Every supported type, in the order error messages list them.
    pub const ALL: [VoxelType; 4] = [VoxelType::U8, VoxelType::U16, VoxelType::I16, VoxelType::F32];

    /// Bytes per voxel.
    pub fn size_bytes(self) -> usize {
        match self {
            VoxelType::U8 => 1,
            VoxelType::U16 | VoxelType::I16 => 2,
            VoxelType::F32 => 4,
        }
    }

    /// The name used in file names (`uint8`, `uint16`, `int16`, `float32`).
    pub fn name(self) -> &'static str {
        match self {
            VoxelType::U8 => "uint8",
            VoxelType::U16 => "uint16",
            VoxelType::I16 => "int16",
            VoxelType::F32 => "float32",
        }
    }

    /// Parses a file-name type token: `uint8`/`u8`, `uint16`/`u16`, `int16`/`i16`,
    /// `float32`/`f32` (case-insensitive). `None` for anything else.
    pub fn from_name(token: &str) -> Option<VoxelType> {
        match token.to_ascii_lowercase().as_str() {
            "uint8" | "u8" => Some(VoxelType::U8),
            "uint16" | "u16" => Some(VoxelType::U16),
            "int16" | "i16" => Some(VoxelType::I16),
            "float32" | "f32" => Some(VoxelType::F32),
            _ => None,
        }
    }

    /// The data values that normalize to 0 and 1 for integer types (the full type range,
    /// see [`Volume::normalized`]); `None` for `float32`, whose range comes from the data.
    pub fn integer_range(self) -> Option<(f64, f64)> {
        match self {
            VoxelType::U8 => Some((0.0, 255.0)),
            VoxelType::U16 => Some((0.0, 65535.0)),
            VoxelType::I16 => Some((-32768.0, 32767.0)),
            VoxelType::F32 => None,
        }
    }
}

impl std::fmt::Display for VoxelType {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl VoxelData {
    /// The type of the stored voxels.
    pub fn voxel_type(&self) -> VoxelType {
        match self {
            VoxelData::U8(_) => VoxelType::U8,
            VoxelData::U16(_) => VoxelType::U16,
            VoxelData::I16(_) => VoxelType::I16,
            VoxelData::F32(_) => VoxelType::F32,
        }
    }
}

/// The `(min, max)` of the finite values of `values`, or `None` when none is finite.
pub fn finite_range(values: &[f32]) -> Option<(f64, f64)> {
    let mut range: Option<(f32, f32)> = None;
    for &v in values.iter().filter(|v| v.is_finite()) {
        range = Some(match range {
            None => (v, v),
            Some((lo, hi)) => (lo.min(v), hi.max(v)),
        });
    }
    range.map(|(lo, hi)| (lo as f64, hi as f64))
}

impl Volume {
    /// Builds a volume and sets `value_range` to the data values that normalize to 0 and 1:
    /// the full type range for integer types (`uint8` → (0, 255), `uint16` → (0, 65535),
    /// `int16` → (-32768, 32767), matching [`Volume::normalized`]), the finite (min, max) for
    /// `float32` ((0, 0) when no value is finite).
    ///
    /// The caller promises `data.len() == dims.x * dims.y * dims.z`; loaders check it and return
    /// an error before they get here.
    pub fn new(name: impl Into<String>, dims: UVec3, spacing: DVec3, data: VoxelData) -> Volume {
        let value_range = match &data {
            VoxelData::F32(v) => finite_range(v).unwrap_or((0.0, 0.0)),
            other => other.voxel_type().integer_range().unwrap_or((0.0, 1.0)),
        };
        Volume { dims, spacing, data, name: name.into(), value_range, meta: Default::default() }
    }
}

impl Volume {
    /// A copy of everything but the voxels (dims, spacing, name, value range), with no data:
    /// what camera and frame set-up need.
    pub fn clone_header(&self) -> Volume {
        Volume {
            dims: self.dims,
            spacing: self.spacing,
            data: VoxelData::U8(Vec::new()),
            name: self.name.clone(),
            value_range: self.value_range,
            meta: self.meta.clone(),
        }
    }
}
