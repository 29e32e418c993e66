//! NIfTI-1 and NIfTI-2 single files (`.nii`, `.nii.gz`). The NIfTI-1 header is read by the
//! `nifti` crate; NIfTI-2 (the same fields widened to 64 bits, 540 bytes), which that crate
//! does not read, by [`Nifti2Header`] here. Both become one [`Geometry`]: the sform (when its
//! code is set), else the qform quaternion, else the plain pixdim scale; RAS world coordinates
//! are turned into LPS as ITK does (x and y negated), so a NIfTI file and the DICOM series it
//! came from render alike. `scl_slope`/`scl_inter` are applied; a 4D file needs a frame.

use std::path::Path;

use glam::{DMat3, DQuat, DVec3};

use super::{AxisOrientation, Endianness, LoadError, LoadReport, LoadedVolume, Location, VolumeFormat};
use crate::volume::{Volume, VoxelData, VoxelType};
use crate::volume_meta::{VolumeMeta, Window, WorldFrame};

/// The largest decompressed file accepted (a `.nii.gz` bomb stops here).
const MAX_BYTES: u64 = 1 << 36;

/// The header fields a volume needs, from either NIfTI version.
#[derive(Clone, Debug, PartialEq)]
struct Geometry {
    version: u8,
    dim: [i64; 8],
    pixdim: [f64; 8],
    datatype: i16,
    vox_offset: u64,
    scl_slope: f64,
    scl_inter: f64,
    cal: (f64, f64),
    qform_code: i32,
    sform_code: i32,
    quatern: [f64; 3],
    qoffset: [f64; 3],
    srow: [[f64; 4]; 3],
    description: String,
    order: Endianness,
}

/// Loads `path`; `frame` picks the volume of a 4D file.
pub fn load(path: &Path, frame: Option<u64>) -> Result<LoadedVolume, LoadError> {
    let bytes = super::read_file(path)?;
    let bytes = if bytes.starts_with(&[0x1f, 0x8b]) { super::inflate(path, &bytes, false, MAX_BYTES)? } else { bytes };
    parse(path, &bytes, frame)
}

fn read_error(path: &Path, reason: impl Into<String>) -> LoadError {
    LoadError::NiftiRead { path: path.to_path_buf(), reason: reason.into() }
}

/// Parses a whole (decompressed) NIfTI file. Never panics.
pub fn parse(path: &Path, bytes: &[u8], frame: Option<u64>) -> Result<LoadedVolume, LoadError> {
    let size = |b: &[u8]| -> Option<(i32, Endianness)> {
        let raw: [u8; 4] = b.get(..4)?.try_into().ok()?;
        [(i32::from_le_bytes(raw), Endianness::Little), (i32::from_be_bytes(raw), Endianness::Big)]
            .into_iter()
            .find(|(n, _)| *n == 348 || *n == 540)
    };
    let g = match size(bytes) {
        Some((348, _)) => from_nifti1(path, bytes)?,
        Some((_, order)) => Nifti2Header::parse(path, bytes, order)?,
        None => {
            return Err(read_error(
                path,
                "not a NIfTI file: the header size is neither 348 (NIfTI-1) nor 540 (NIfTI-2)",
            ));
        }
    };
    build(path, bytes, &g, frame)
}

fn from_nifti1(path: &Path, bytes: &[u8]) -> Result<Geometry, LoadError> {
    let h = nifti::NiftiHeader::from_reader(bytes).map_err(|e| read_error(path, format!("{e}")))?;
    if &h.magic == nifti::header::MAGIC_CODE_NI1 {
        return Err(read_error(
            path,
            "a header of a .hdr/.img pair (magic ni1); save the image as one .nii file (e.g. with nibabel or 3D Slicer)",
        ));
    }
    let f = |v: f32| v as f64;
    Ok(Geometry {
        version: 1,
        dim: h.dim.map(|d| d as i64),
        pixdim: h.pixdim.map(f),
        datatype: h.datatype,
        vox_offset: h.vox_offset.max(0.0) as u64,
        scl_slope: f(h.scl_slope),
        scl_inter: f(h.scl_inter),
        cal: (f(h.cal_min), f(h.cal_max)),
        qform_code: h.qform_code as i32,
        sform_code: h.sform_code as i32,
        quatern: [f(h.quatern_b), f(h.quatern_c), f(h.quatern_d)],
        qoffset: [f(h.quatern_x), f(h.quatern_y), f(h.quatern_z)],
        srow: [h.srow_x.map(f), h.srow_y.map(f), h.srow_z.map(f)],
        description: String::from_utf8_lossy(&h.descrip).trim_end_matches('\0').trim().to_string(),
        order: if h.endianness == nifti::Endianness::Big { Endianness::Big } else { Endianness::Little },
    })
}

/// The NIfTI-2 header (540 bytes; field offsets from `nifti2.h`).
struct Nifti2Header;

impl Nifti2Header {
    fn parse(path: &Path, b: &[u8], order: Endianness) -> Result<Geometry, LoadError> {
        if b.len() < 540 {
            return Err(read_error(path, format!("the NIfTI-2 header needs 540 bytes, the file has {}", b.len())));
        }
        if &b[4..8] != b"n+2\0" {
            return Err(read_error(path, "a NIfTI-2 header without the n+2 magic of a single .nii file"));
        }
        let big = order == Endianness::Big;
        let bytes8 = |o: usize| -> [u8; 8] { std::array::from_fn(|i| b[o + i]) };
        let i64_at = |o: usize| if big { i64::from_be_bytes(bytes8(o)) } else { i64::from_le_bytes(bytes8(o)) };
        let f64_at = |o: usize| if big { f64::from_be_bytes(bytes8(o)) } else { f64::from_le_bytes(bytes8(o)) };
        let i32_at = |o: usize| {
            let r = [b[o], b[o + 1], b[o + 2], b[o + 3]];
            if big { i32::from_be_bytes(r) } else { i32::from_le_bytes(r) }
        };
        let i16_at =
            |o: usize| if big { i16::from_be_bytes([b[o], b[o + 1]]) } else { i16::from_le_bytes([b[o], b[o + 1]]) };
        Ok(Geometry {
            version: 2,
            datatype: i16_at(12),
            dim: std::array::from_fn(|i| i64_at(16 + 8 * i)),
            pixdim: std::array::from_fn(|i| f64_at(104 + 8 * i)),
            vox_offset: i64_at(168).max(0) as u64,
            scl_slope: f64_at(176),
            scl_inter: f64_at(184),
            cal: (f64_at(200), f64_at(192)),
            description: String::from_utf8_lossy(&b[240..320]).trim_end_matches('\0').trim().to_string(),
            qform_code: i32_at(344),
            sform_code: i32_at(348),
            quatern: [f64_at(352), f64_at(360), f64_at(368)],
            qoffset: [f64_at(376), f64_at(384), f64_at(392)],
            srow: std::array::from_fn(|r| std::array::from_fn(|c| f64_at(400 + 32 * r + 8 * c))),
            order,
        })
    }
}

impl Geometry {
    /// The world step of one voxel along each file axis and the position of voxel (0,0,0), in
    /// LPS, and whether the file gives an orientation at all.
    fn directions_lps(&self) -> ([DVec3; 3], DVec3, bool) {
        let ras_to_lps = |v: DVec3| DVec3::new(-v.x, -v.y, v.z);
        if self.sform_code > 0 {
            let column = |c: usize| DVec3::new(self.srow[0][c], self.srow[1][c], self.srow[2][c]);
            let dirs = [column(0), column(1), column(2)].map(ras_to_lps);
            return (dirs, ras_to_lps(column(3)), true);
        }
        if self.qform_code > 0 {
            let [b, c, d] = self.quatern;
            let a = (1.0 - (b * b + c * c + d * d)).max(0.0).sqrt();
            let r = DMat3::from_quat(DQuat::from_xyzw(b, c, d, a));
            let qfac = if self.pixdim[0] < 0.0 { -1.0 } else { 1.0 };
            let dirs = [r.x_axis * self.pixdim[1], r.y_axis * self.pixdim[2], r.z_axis * self.pixdim[3] * qfac];
            return (dirs.map(ras_to_lps), ras_to_lps(DVec3::from_array(self.qoffset)), true);
        }
        let p = |i: usize| if self.pixdim[i] > 0.0 { self.pixdim[i] } else { 1.0 };
        ([DVec3::X * p(1), DVec3::Y * p(2), DVec3::Z * p(3)], DVec3::ZERO, false)
    }
}

/// How a NIfTI datatype is read: the stored type, and the type it is kept as.
fn element(path: &Path, datatype: i16) -> Result<(usize, fn(&[u8], bool) -> f64), LoadError> {
    fn le_or_be<const N: usize>(b: &[u8], big: bool) -> [u8; N] {
        let mut a: [u8; N] = std::array::from_fn(|i| b[i]);
        if big {
            a.reverse();
        }
        a
    }
    Ok(match datatype {
        2 => (1, |b, _| b[0] as f64),
        256 => (1, |b, _| b[0] as i8 as f64),
        4 => (2, |b, big| i16::from_le_bytes(le_or_be(b, big)) as f64),
        512 => (2, |b, big| u16::from_le_bytes(le_or_be(b, big)) as f64),
        8 => (4, |b, big| i32::from_le_bytes(le_or_be(b, big)) as f64),
        768 => (4, |b, big| u32::from_le_bytes(le_or_be(b, big)) as f64),
        16 => (4, |b, big| f32::from_le_bytes(le_or_be(b, big)) as f64),
        64 => (8, |b, big| f64::from_le_bytes(le_or_be(b, big))),
        1024 => (8, |b, big| i64::from_le_bytes(le_or_be(b, big)) as f64),
        1280 => (8, |b, big| u64::from_le_bytes(le_or_be(b, big)) as f64),
        other => {
            return Err(LoadError::UnsupportedType {
                at: Location::file(path),
                found: format!("NIfTI datatype {other}"),
                supported: "uint8, int8, int16, uint16, int32, uint32, int64, uint64, float32, float64 (scalar)",
            });
        }
    })
}

fn build(path: &Path, bytes: &[u8], g: &Geometry, frame: Option<u64>) -> Result<LoadedVolume, LoadError> {
    let ndim = g.dim[0];
    if !(2..=7).contains(&ndim) {
        return Err(LoadError::NotThreeD { at: Location::file(path), field: "dim[0]", found: ndim.to_string() });
    }
    let axis = |i: usize| if (i as i64) <= ndim { g.dim[i] } else { 1 };
    if (1..=7).any(|i| axis(i) < 1) {
        return Err(read_error(path, format!("dim {:?} has an axis of size < 1", &g.dim[1..=ndim as usize])));
    }
    if (5..=7).any(|i| axis(i) > 1) {
        return Err(read_error(
            path,
            format!(
                "dim {:?}: vector or higher-dimensional data; volgraph reads scalar 3D or 4D files",
                &g.dim[1..=ndim as usize]
            ),
        ));
    }
    let frames = axis(4) as u64;
    let frame = match frame {
        None if frames > 1 => {
            return Err(LoadError::NiftiFrame {
                path: path.to_path_buf(),
                frames,
                what: "no --frame was given".into(),
            });
        }
        None => 0,
        Some(f) if f >= frames => {
            return Err(LoadError::NiftiFrame {
                path: path.to_path_buf(),
                frames,
                what: format!("--frame {f} is past the end"),
            });
        }
        Some(f) => f,
    };
    let file_dims = super::check_dims(
        &Location::file(path),
        "dim",
        &format!("{:?}", &g.dim[1..4]),
        [axis(1) as u64, axis(2) as u64, axis(3) as u64],
    )?;
    let (size, read) = element(path, g.datatype)?;
    let voxels = file_dims.x as u64 * file_dims.y as u64 * file_dims.z as u64;
    // Checked: a header's offset or sizes may be anything (1e39 saturates to u64::MAX).
    let frame_bytes = voxels.checked_mul(size as u64);
    let start = frame_bytes
        .and_then(|b| b.checked_mul(frame))
        .and_then(|b| b.checked_add(g.vox_offset.max(if g.version == 1 { 352 } else { 544 })));
    let end = start.zip(frame_bytes).and_then(|(s, b)| s.checked_add(b)).unwrap_or(u64::MAX);
    let start = start.unwrap_or(u64::MAX);
    if (bytes.len() as u64) < end {
        return Err(LoadError::DataSize {
            path: path.to_path_buf(),
            dims: super::dims_text(file_dims),
            dtype: VoxelType::F32,
            expected: end,
            actual: bytes.len() as u64,
            hint: "the file is truncated (copy it again) or its header is wrong",
        });
    }
    let data = &bytes[start as usize..end as usize];
    let big = g.order == Endianness::Big;
    let values: Vec<f64> = data.chunks_exact(size).map(|c| read(c, big)).collect();
    let (slope, inter) =
        if g.scl_slope == 0.0 || !g.scl_slope.is_finite() { (1.0, 0.0) } else { (g.scl_slope, g.scl_inter) };
    let mut report = LoadReport::new(VolumeFormat::Nifti, path);
    let voxels = scaled(values, slope, inter, g.datatype);

    let (directions, origin, oriented) = g.directions_lps();
    let field = if g.sform_code > 0 { "sform (srow_x/y/z)" } else { "qform (quatern_b/c/d, pixdim)" };
    let (orientation, spacing) = AxisOrientation::from_directions(directions, &Location::file(path), field)?;
    if !orientation.is_identity() {
        report.notes.push(format!(
            "voxels reordered to the LPS patient frame ({}) from the file's RAS {field}",
            orientation.describe()
        ));
    }
    let origin = (0..3)
        .fold(origin, |o, i| if orientation.flipped[i] { o + directions[i] * (file_dims[i] as f64 - 1.0) } else { o });
    let data = orientation.reorder(file_dims, voxels);
    let mut volume = Volume::new(nifti_stem(path), orientation.world_dims(file_dims), spacing, data);
    let (nan, pos, neg) = super::sanitize_volume(&mut volume);
    (report.nan_replaced, report.pos_inf_replaced, report.neg_inf_replaced) = (nan, pos, neg);
    volume.fit_range_to_data();
    volume.meta = VolumeMeta {
        frame: if oriented { WorldFrame::Lps } else { WorldFrame::IndexAxes },
        origin: oriented.then_some(origin),
        window: (g.cal.1 > g.cal.0).then(|| Window { center: (g.cal.0 + g.cal.1) / 2.0, width: g.cal.1 - g.cal.0 }),
        description: (!g.description.is_empty()).then(|| g.description.clone()),
        ..VolumeMeta::default()
    };
    Ok(LoadedVolume { volume, report })
}

/// Rescaled values in the narrowest type that holds them exactly: the file's own type where
/// the scale is the identity or integral, float32 otherwise.
fn scaled(values: Vec<f64>, slope: f64, inter: f64, datatype: i16) -> VoxelData {
    let integral_scale = slope.fract() == 0.0 && inter.fract() == 0.0;
    let integer_type = !matches!(datatype, 16 | 64);
    let (lo, hi) = values.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
        let s = v * slope + inter;
        (lo.min(s), hi.max(s))
    });
    let map = || values.iter().map(|&v| v * slope + inter);
    if integral_scale && integer_type && lo >= 0.0 && hi <= 255.0 && matches!(datatype, 2) {
        VoxelData::U8(map().map(|v| v as u8).collect())
    } else if integral_scale && integer_type && lo >= -32768.0 && hi <= 32767.0 {
        VoxelData::I16(map().map(|v| v as i16).collect())
    } else if integral_scale && integer_type && lo >= 0.0 && hi <= 65535.0 {
        VoxelData::U16(map().map(|v| v as u16).collect())
    } else {
        VoxelData::F32(map().map(|v| v as f32).collect())
    }
}

/// `brain.nii.gz` → `brain`.
fn nifti_stem(path: &Path) -> String {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let lower = name.to_ascii_lowercase();
    for suffix in [".nii.gz", ".nii"] {
        if lower.ends_with(suffix) {
            return name[..name.len() - suffix.len()].to_string();
        }
    }
    name
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_qform_quaternion_of_180_degrees_about_z_flips_x_and_y_in_ras_so_not_in_lps() {
        // (b, c, d) = (0, 0, 1): a rotation by 180° about z; RAS −x,−y is LPS +x,+y.
        let g = Geometry {
            version: 1,
            dim: [3, 2, 2, 2, 1, 1, 1, 1],
            pixdim: [1.0, 1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 0.0],
            datatype: 2,
            vox_offset: 352,
            scl_slope: 1.0,
            scl_inter: 0.0,
            cal: (0.0, 0.0),
            qform_code: 1,
            sform_code: 0,
            quatern: [0.0, 0.0, 1.0],
            qoffset: [0.0; 3],
            srow: [[0.0; 4]; 3],
            description: String::new(),
            order: Endianness::Little,
        };
        let (d, _, oriented) = g.directions_lps();
        assert!(oriented);
        for (got, want) in
            d.iter().zip([DVec3::new(1.0, 0.0, 0.0), DVec3::new(0.0, 2.0, 0.0), DVec3::new(0.0, 0.0, 3.0)])
        {
            assert!((*got - want).length() < 1e-12, "{d:?}");
        }
    }

    #[test]
    fn names_lose_both_extensions() {
        assert_eq!(nifti_stem(Path::new("/x/brain.nii.gz")), "brain");
        assert_eq!(nifti_stem(Path::new("b.NII")), "b");
    }
}
