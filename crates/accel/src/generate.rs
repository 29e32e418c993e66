//! Generated volumes with known content, for tests and benchmarks: the Marschner–Lobb function,
//! spheres, shells, slabs, checkerboards, one-voxel sheets, seeded noise and edge cases.
//!
//! Voxel `i` of an `n`-voxel axis sits at `p = -1 + 2(i + 0.5)/n` in the box `[-1, 1]³`, the
//! texel-centre convention of `docs/rendering_model.md` (texture coordinate `u = (p + 1)/2`), so
//! an analytic function sampled here can be compared with the renderer at any `u`. Every volume
//! has spacing (1, 1, 1) and a name like `marschner_lobb_64`. Binary shapes are `uint8` with 0
//! outside and 255 inside.

use glam::{DVec3, UVec3};
use rayon::prelude::*;

use crate::volume::{Volume, VoxelData};

/// An axis of the volume.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    /// x (fastest in memory).
    X,
    /// y.
    Y,
    /// z (slowest in memory).
    Z,
}

impl Axis {
    fn name(self) -> &'static str {
        match self {
            Axis::X => "x",
            Axis::Y => "y",
            Axis::Z => "z",
        }
    }

    fn pick(self, v: UVec3) -> u32 {
        match self {
            Axis::X => v.x,
            Axis::Y => v.y,
            Axis::Z => v.z,
        }
    }
}

/// The position in `[-1, 1]³` of voxel `(x, y, z)`'s centre in an `n³` volume.
pub fn voxel_centre(n: u32, x: u32, y: u32, z: u32) -> DVec3 {
    let c = |i: u32| -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
    DVec3::new(c(x), c(y), c(z))
}

/// Fills an `n³` volume with `f(voxel index)`, one z slice per rayon task.
fn fill<T: Send + Copy + Default>(n: u32, f: impl Fn(UVec3) -> T + Sync) -> Vec<T> {
    let slice = n as usize * n as usize;
    let mut out = vec![T::default(); slice * n as usize];
    out.par_chunks_mut(slice.max(1)).enumerate().for_each(|(z, chunk)| {
        for (i, v) in chunk.iter_mut().enumerate() {
            let (x, y) = ((i % n as usize) as u32, (i / n as usize) as u32);
            *v = f(UVec3::new(x, y, z as u32));
        }
    });
    out
}

fn binary(name: String, n: u32, inside: impl Fn(UVec3) -> bool + Sync) -> Volume {
    let data = fill(n, |v| if inside(v) { 255u8 } else { 0 });
    Volume::new(name, UVec3::splat(n), DVec3::ONE, VoxelData::U8(data))
}

/// Marschner–Lobb modulation frequency `f_M` (Marschner & Lobb 1994, §6).
pub const MARSCHNER_LOBB_FM: f64 = 6.0;
/// Marschner–Lobb amplitude `α` (Marschner & Lobb 1994, §6).
pub const MARSCHNER_LOBB_ALPHA: f64 = 0.25;

/// The Marschner–Lobb test signal at `p ∈ [-1, 1]³`, in [0, 1]:
/// `ρ = (1 - sin(πz/2) + α(1 + cos(2π f_M cos(πr/2)))) / (2(1 + α))`, `r = √(x² + y²)`,
/// with the standard `f_M = 6`, `α = 0.25`.
pub fn marschner_lobb_value(p: DVec3) -> f64 {
    use std::f64::consts::PI;
    let r = (p.x * p.x + p.y * p.y).sqrt();
    let rho_r = (2.0 * PI * MARSCHNER_LOBB_FM * (PI * r / 2.0).cos()).cos();
    (1.0 - (PI * p.z / 2.0).sin() + MARSCHNER_LOBB_ALPHA * (1.0 + rho_r)) / (2.0 * (1.0 + MARSCHNER_LOBB_ALPHA))
}

/// Marschner–Lobb sampled on `n³` voxels as `uint8` (`round(255 ρ)`), named
/// `marschner_lobb_<n>`.
pub fn marschner_lobb(n: u32) -> Volume {
    let data = fill(n, |v| {
        let rho = marschner_lobb_value(voxel_centre(n, v.x, v.y, v.z));
        (rho * 255.0).round().clamp(0.0, 255.0) as u8
    });
    Volume::new(format!("marschner_lobb_{n}"), UVec3::splat(n), DVec3::ONE, VoxelData::U8(data))
}

/// Marschner–Lobb sampled on `n³` voxels as `float32` ρ, named `marschner_lobb_f32_<n>`. Its
/// `value_range` is the function's range (0, 1), not the sampled min/max, so
/// [`Volume::normalized`] returns ρ itself.
pub fn marschner_lobb_f32(n: u32) -> Volume {
    let data = fill(n, |v| marschner_lobb_value(voxel_centre(n, v.x, v.y, v.z)) as f32);
    let mut volume = Volume::new(format!("marschner_lobb_f32_{n}"), UVec3::splat(n), DVec3::ONE, VoxelData::F32(data));
    volume.value_range = (0.0, 1.0);
    volume
}

/// A solid sphere of `radius` (in box units, the box being `[-1, 1]³`) centred in an `n³`
/// volume: 255 where `|p| ≤ radius`. Named `sphere_<n>`.
pub fn sphere(n: u32, radius: f64) -> Volume {
    binary(format!("sphere_{n}"), n, |v| voxel_centre(n, v.x, v.y, v.z).length() <= radius)
}

/// A spherical shell: 255 where `inner ≤ |p| ≤ outer` (box units). Named `shell_<n>`.
pub fn spherical_shell(n: u32, inner: f64, outer: f64) -> Volume {
    binary(format!("shell_{n}"), n, |v| {
        let r = voxel_centre(n, v.x, v.y, v.z).length();
        (inner..=outer).contains(&r)
    })
}

/// Axis-aligned slabs `slab_voxels` thick across `axis`, alternating 0 and 255 starting with 0
/// at index 0. Named `slabs_<axis>_<n>`. `slab_voxels = 0` is treated as 1.
pub fn slabs(n: u32, axis: Axis, slab_voxels: u32) -> Volume {
    let thick = slab_voxels.max(1);
    binary(format!("slabs_{}_{n}", axis.name()), n, |v| (axis.pick(v) / thick) % 2 == 1)
}

/// A 3D checkerboard of cubes `cell_voxels` wide: 255 where `x/c + y/c + z/c` is odd. Named
/// `checkerboard_<n>`. `cell_voxels = 0` is treated as 1.
pub fn checkerboard(n: u32, cell_voxels: u32) -> Volume {
    let c = cell_voxels.max(1);
    binary(format!("checkerboard_{n}"), n, |v| (v.x / c + v.y / c + v.z / c) % 2 == 1)
}

/// A one-voxel-thick sheet: 255 on the plane `axis = index`, 0 elsewhere (thin features that
/// large steps or coarse empty-space skipping must not lose). Named `sheet_<axis>_<n>`.
pub fn sheet(n: u32, axis: Axis, index: u32) -> Volume {
    binary(format!("sheet_{}_{n}", axis.name()), n, |v| axis.pick(v) == index)
}

/// SplitMix64 (Steele, Lea & Flood 2014): a tiny, well-mixed, seedable generator; the same seed
/// always gives the same volume on every platform.
#[derive(Clone, Debug)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

/// Uniform white noise in 0..=255 from `seed`, named `noise_<n>_seed<seed>`. Voxel `i` takes
/// the top byte of the `i`-th SplitMix64 output, so the volume depends only on `(n, seed)`.
pub fn noise(n: u32, seed: u64) -> Volume {
    let mut rng = SplitMix64(seed);
    let count = n as usize * n as usize * n as usize;
    let data: Vec<u8> = (0..count).map(|_| (rng.next_u64() >> 56) as u8).collect();
    Volume::new(format!("noise_{n}_seed{seed}"), UVec3::splat(n), DVec3::ONE, VoxelData::U8(data))
}

/// A scanned object in its noise floor, named `scanned_sphere_<n>`: a sphere of radius 0.5 (box
/// units) at 200 inside a background of 70..=80 — 0.27–0.31 of the range, where a CT's air and
/// noise often sit — so a default transfer function must find the background to show the object
/// rather than a box of noise.
pub fn scanned_sphere(n: u32) -> Volume {
    let data = fill(n, |v| {
        let index = u64::from(v.x) + u64::from(n) * (u64::from(v.y) + u64::from(n) * u64::from(v.z));
        let noise = 70 + (SplitMix64(index).next_u64() % 11) as u8;
        if voxel_centre(n, v.x, v.y, v.z).length() <= 0.5 { 200 } else { noise }
    });
    Volume::new(format!("scanned_sphere_{n}"), UVec3::splat(n), DVec3::ONE, VoxelData::U8(data))
}

/// All zeros (`uint8`), named `zeros_<n>`: nothing to see, every skip structure is empty.
pub fn zeros(n: u32) -> Volume {
    binary(format!("zeros_{n}"), n, |_| false)
}

/// One voxel at `at` set to `value`, all others 0 (`uint8`), named `one_voxel_<n>`. An `at`
/// outside the volume gives all zeros.
pub fn one_voxel(n: u32, at: UVec3, value: u8) -> Volume {
    let data = fill(n, |v| if v == at { value } else { 0 });
    Volume::new(format!("one_voxel_{n}"), UVec3::splat(n), DVec3::ONE, VoxelData::U8(data))
}

/// A `float32` ramp along x (`value = x`) with non-finite voxels planted, named
/// `non_finite_<n>`: voxel index `7k` for every `k` is NaN unless it is also a multiple of 11
/// (then `+Inf`) or 13 (then `-Inf`); index 0 stays 0.0 so some finite value always exists.
///
/// This is the only constructor that breaks the no-NaN rule of [`VoxelData::F32`]: it is input
/// for loader tests. Write it to a file or pass it through
/// [`crate::load::sanitize_volume`] before rendering. Returns the volume and the planted
/// `(nan, +inf, -inf)` counts.
pub fn non_finite_f32(n: u32) -> (Volume, (usize, usize, usize)) {
    let (mut nan, mut pos, mut neg) = (0, 0, 0);
    let count = n as usize * n as usize * n as usize;
    let data: Vec<f32> = (0..count)
        .map(|i| {
            if i == 0 || i % 7 != 0 {
                (i % n.max(1) as usize) as f32
            } else if i % 11 == 0 {
                pos += 1;
                f32::INFINITY
            } else if i % 13 == 0 {
                neg += 1;
                f32::NEG_INFINITY
            } else {
                nan += 1;
                f32::NAN
            }
        })
        .collect();
    let volume = Volume::new(format!("non_finite_{n}"), UVec3::splat(n), DVec3::ONE, VoxelData::F32(data));
    (volume, (nan, pos, neg))
}

/// Largest edge of a generated volume named by [`by_name`] (512³ u8 is 128 MiB; more is surely
/// a typo).
pub const MAX_NAMED_EDGE: u32 = 512;

/// The generated volumes [`by_name`] knows, for messages.
pub const NAMED_GENERATORS: &str = "ml<N>, mlf<N>, sphere<N>, noise<N>, vessels<N>, tooth<N>, organs<N> or organs_labels<N> (N = edge in voxels), \
     e.g. ml64";

/// Why a generated-volume name makes no volume.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum NamedVolumeError {
    /// The name is none of the generators.
    #[error("\"{name}\" names no generated volume; use {NAMED_GENERATORS}")]
    Unknown {
        /// The name.
        name: String,
    },
    /// The edge is out of range.
    #[error("\"{name}\": a generated volume's edge must be 2..={MAX_NAMED_EDGE} voxels")]
    Edge {
        /// The name.
        name: String,
    },
    /// The edge of a vessel tree made a slab at a time is out of range.
    #[error("\"{name}\": a vessel tree written a slab at a time has an edge of 2..={MAX_STREAMED_EDGE} voxels")]
    StreamedEdge {
        /// The name.
        name: String,
    },
}

/// The largest edge of a vessel tree made a slab at a time ([`streamed_vessels`]): 8192³ is
/// 512 GiB.
pub const MAX_STREAMED_EDGE: u32 = 8192;

/// The vessel tree `vessels<N>` names, to be made a slab at a time (any N up to
/// [`MAX_STREAMED_EDGE`], beyond what [`by_name`] makes in memory); `None` for another name.
pub fn streamed_vessels(name: &str) -> Option<Result<crate::vessels::VesselTree, NamedVolumeError>> {
    let digits = name.strip_prefix("vessels")?;
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    Some(match digits.parse::<u32>() {
        Ok(edge) if (2..=MAX_STREAMED_EDGE).contains(&edge) => Ok(crate::vessels::VesselTree::new(edge, 1)),
        _ => Err(NamedVolumeError::StreamedEdge { name: name.to_string() }),
    })
}

/// The generated volume a name asks for: `ml64` (Marschner–Lobb, 64³ u8), `mlf64` (f32),
/// `sphere64`, `noise64`, `vessels256` (the sparse vessel tree of [`crate::vessels`]), `tooth256`
/// (the molar CT of [`crate::tooth`], n × n × ⌈0.63 n⌉), `organs128` / `organs_labels128` (the
/// abdominal CT of [`crate::organs`] and its label map, n × n × n/2). `Err(Unknown)`
/// for a name that is none of these, so callers can fall back on a data-folder dataset.
pub fn by_name(name: &str) -> Result<Volume, NamedVolumeError> {
    let unknown = || NamedVolumeError::Unknown { name: name.to_string() };
    let (make, digits): (fn(u32) -> Volume, &str) = if let Some(d) = name.strip_prefix("mlf") {
        (marschner_lobb_f32, d)
    } else if let Some(d) = name.strip_prefix("ml") {
        (marschner_lobb, d)
    } else if let Some(d) = name.strip_prefix("sphere") {
        (|n| sphere(n, 0.6), d)
    } else if let Some(d) = name.strip_prefix("noise") {
        (|n| noise(n, 1), d)
    } else if let Some(d) = name.strip_prefix("vessels") {
        (|n| crate::vessels::vessel_tree(n, 1), d)
    } else if let Some(d) = name.strip_prefix("tooth") {
        (crate::tooth::tooth, d)
    } else if let Some(d) = name.strip_prefix("organs_labels") {
        (crate::organs::organs_labels, d)
    } else if let Some(d) = name.strip_prefix("organs") {
        (crate::organs::organs_ct, d)
    } else {
        return Err(unknown());
    };
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return Err(unknown());
    }
    match digits.parse::<u32>() {
        Ok(edge) if (2..=MAX_NAMED_EDGE).contains(&edge) => Ok(make(edge)),
        _ => Err(NamedVolumeError::Edge { name: name.to_string() }),
    }
}
