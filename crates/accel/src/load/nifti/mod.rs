//! NIfTI-1 and NIfTI-2 single files (`.nii`, `.nii.gz`). The header (348 or 540 bytes,
//! [`header`]) is read first, from the file or from the gzip stream, and checked ([`layout`]);
//! only then are the voxels of the one frame wanted read — from a plain file after checking its
//! length, from a gzip stream only as far as the header says, after checking that the
//! compressed size can hold that much at all (DEFLATE expands at most 1032 times) — so a small
//! hostile file cannot make the loader inflate or allocate gigabytes. Both versions become one
//! geometry: the sform (when its code is set), else the qform quaternion, else the plain pixdim
//! scale; RAS world coordinates are turned into LPS as ITK does (x and y negated), so a NIfTI
//! file and the DICOM series it came from render alike. `scl_slope`/`scl_inter` are applied (one
//! that is not finite is ignored, with a note naming it); a 4D file needs a frame.

mod header;
mod layout;

use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use glam::{DMat3, DQuat, DVec3};
use header::Header;
use layout::{Layout, layout, size_error};

use super::{AxisOrientation, LoadError, LoadReport, LoadedVolume, Location, VolumeFormat};
use crate::volume::{Volume, VoxelData};
use crate::volume_meta::{VolumeMeta, Window, WorldFrame};

/// The most bytes DEFLATE produces from one compressed byte (RFC 1951's longest match, 258
/// bytes, in under two bits: 1032:1); a gzip file of `n` bytes inflates to at most `1032·n`.
const DEFLATE_MAX_RATIO: u64 = 1032;

/// Loads `path`; `frame` picks the volume of a 4D file.
pub fn load(path: &Path, frame: Option<u64>) -> Result<LoadedVolume, LoadError> {
    super::check_is_file(path)?;
    let io = |source| LoadError::Io { path: path.to_path_buf(), source };
    let file = std::fs::File::open(path).map_err(io)?;
    let stored = file.metadata().map_err(io)?.len();
    read(path, std::io::BufReader::new(file), stored, frame)
}

/// Parses a NIfTI file held in memory, plain or gzip-compressed; `path` names it in messages.
/// Never panics.
pub fn parse(path: &Path, bytes: &[u8], frame: Option<u64>) -> Result<LoadedVolume, LoadError> {
    read(path, std::io::Cursor::new(bytes), bytes.len() as u64, frame)
}

fn read_error(path: &Path, reason: impl Into<String>) -> LoadError {
    LoadError::NiftiRead { path: path.to_path_buf(), reason: reason.into() }
}

/// Reads a file of `stored` bytes from `input` (at its start).
fn read<R: Read + Seek>(path: &Path, mut input: R, stored: u64, frame: Option<u64>) -> Result<LoadedVolume, LoadError> {
    let io = |source| LoadError::Io { path: path.to_path_buf(), source };
    let mut magic = [0u8; 2];
    let n = read_up_to(&mut input, &mut magic).map_err(io)?;
    input.seek(SeekFrom::Start(0)).map_err(io)?;
    if n == 2 && magic == [0x1f, 0x8b] {
        let mut stream = Stream { path, reader: flate2::read::MultiGzDecoder::new(input), gzip: true };
        let (header, header_bytes) = stream.header()?;
        let layout = layout(path, &header, frame)?;
        let most = stored.saturating_mul(DEFLATE_MAX_RATIO);
        if layout.end > most {
            let found = format!("the gzip file has {stored} bytes, which inflate to at most {most}");
            return Err(size_error(path, &layout, &found));
        }
        stream.skip(layout.start - header_bytes as u64, &layout)?;
        let data = stream.take(&layout)?;
        build(path, &header, layout, &data)
    } else {
        let mut stream = Stream { path, reader: input, gzip: false };
        let (header, _) = stream.header()?;
        let layout = layout(path, &header, frame)?;
        if layout.end > stored {
            return Err(size_error(path, &layout, &format!("the file has {stored} bytes")));
        }
        stream.reader.seek(SeekFrom::Start(layout.start)).map_err(io)?;
        let data = stream.take(&layout)?;
        build(path, &header, layout, &data)
    }
}

/// Fills as much of `buf` as `r` holds; the count read.
fn read_up_to(r: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut filled = 0;
    while filled < buf.len() {
        match r.read(&mut buf[filled..]) {
            Ok(0) => break,
            Ok(n) => filled += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(filled)
}

/// The file's bytes as a stream: the file itself, or what its gzip members inflate to.
struct Stream<'a, R> {
    path: &'a Path,
    reader: R,
    gzip: bool,
}

impl<R: Read> Stream<'_, R> {
    fn error(&self, source: std::io::Error) -> LoadError {
        if self.gzip {
            LoadError::Decompress { path: self.path.to_path_buf(), codec: "gzip", source }
        } else {
            LoadError::Io { path: self.path.to_path_buf(), source }
        }
    }

    fn inflated(&self) -> &'static str {
        if self.gzip { " once inflated" } else { "" }
    }

    /// Reads and parses the header; its length in bytes.
    fn header(&mut self) -> Result<(Header, usize), LoadError> {
        let mut first = [0u8; 4];
        let n = read_up_to(&mut self.reader, &mut first).map_err(|e| self.error(e))?;
        if n < 4 {
            return Err(read_error(
                self.path,
                format!(
                    "the file holds {n} bytes{}; a NIfTI header needs 348 (NIfTI-1) or 540 (NIfTI-2)",
                    self.inflated()
                ),
            ));
        }
        let (version, order) = header::sniff(first).map_err(|found| {
            read_error(
                self.path,
                format!(
                    "not a NIfTI file: the header size (sizeof_hdr, bytes 0..4{}) is {found}, neither 348 (NIfTI-1) nor \
                     540 (NIfTI-2)",
                    self.inflated()
                ),
            )
        })?;
        let len = if version == 1 { header::NIFTI1_BYTES } else { header::NIFTI2_BYTES };
        let mut bytes = vec![0u8; len];
        bytes[..4].copy_from_slice(&first);
        let n = 4 + read_up_to(&mut self.reader, &mut bytes[4..]).map_err(|e| self.error(e))?;
        if n < len {
            return Err(read_error(
                self.path,
                format!("the NIfTI-{version} header needs {len} bytes, but the file holds {n}{}", self.inflated()),
            ));
        }
        Ok((header::parse(self.path, &bytes, version, order)?, len))
    }

    /// Reads past `count` bytes (the extensions and the frames before the one wanted).
    fn skip(&mut self, count: u64, layout: &Layout) -> Result<(), LoadError> {
        let skipped =
            std::io::copy(&mut (&mut self.reader).take(count), &mut std::io::sink()).map_err(|e| self.error(e))?;
        if skipped < count {
            let found = format!("the file holds {} bytes{}", layout.start - count + skipped, self.inflated());
            return Err(size_error(self.path, layout, &found));
        }
        Ok(())
    }

    /// Reads the frame's bytes. A plain file's length was checked against the header, so the
    /// whole frame is reserved at once; a gzip stream may end early (and a small file may claim
    /// up to 1032 times its size), so its bytes are reserved as they come: at most
    /// [`GZIP_CHUNK`] ahead of what was read, the capacity doubling up to the frame's size.
    fn take(&mut self, layout: &Layout) -> Result<Vec<u8>, LoadError> {
        let total = layout.frame_bytes;
        let mut data;
        if self.gzip {
            data = try_vec(self.path, total.min(GZIP_CHUNK))?;
            let mut rest = total;
            while rest > 0 {
                let chunk = rest.min(GZIP_CHUNK);
                let spare = (data.capacity() - data.len()) as u64;
                if spare < chunk {
                    // Double the capacity (fewer copies), but never past the frame's size.
                    let target = (data.capacity() as u64).saturating_mul(2).max(data.len() as u64 + chunk).min(total);
                    let more =
                        usize::try_from(target - data.len() as u64).map_err(|_| no_memory(self.path, total, 1))?;
                    data.try_reserve_exact(more).map_err(|_| no_memory(self.path, total, 1))?;
                }
                let got = (&mut self.reader).take(chunk).read_to_end(&mut data).map_err(|e| self.error(e))? as u64;
                rest -= got;
                if got < chunk {
                    break;
                }
            }
        } else {
            data = try_vec(self.path, total)?;
            (&mut self.reader).take(total).read_to_end(&mut data).map_err(|e| self.error(e))?;
        }
        if (data.len() as u64) < total {
            let found = format!("the file holds {} bytes{}", layout.start + data.len() as u64, self.inflated());
            return Err(size_error(self.path, layout, &found));
        }
        Ok(data)
    }
}

/// What a gzip stream's frame is reserved ahead of the bytes read, at most (64 MiB).
const GZIP_CHUNK: u64 = 64 << 20;

/// The error for `count` elements of `size` bytes that cannot be allocated.
fn no_memory(path: &Path, count: u64, size: usize) -> LoadError {
    let mb = count as f64 * size as f64 / 1e6;
    read_error(path, format!("cannot allocate {mb:.0} MB for the voxels: not enough memory"))
}

/// An empty vector with room for `count` elements, or an error naming the file when the
/// memory is not there (instead of aborting the process).
fn try_vec<T>(path: &Path, count: u64) -> Result<Vec<T>, LoadError> {
    let mut v = Vec::new();
    let fail = || no_memory(path, count, std::mem::size_of::<T>());
    let count = usize::try_from(count).map_err(|_| fail())?;
    v.try_reserve_exact(count).map_err(|_| fail())?;
    Ok(v)
}

/// The world step of one voxel along each file axis and the position of voxel (0,0,0), in LPS,
/// whether the file gives an orientation at all, and notes on pixdim values not used.
fn directions_lps(h: &Header) -> ([DVec3; 3], DVec3, bool, Vec<String>) {
    let ras_to_lps = |v: DVec3| DVec3::new(-v.x, -v.y, v.z);
    if h.sform_code > 0 {
        let column = |c: usize| DVec3::new(h.srow[0][c], h.srow[1][c], h.srow[2][c]);
        let dirs = [column(0), column(1), column(2)].map(ras_to_lps);
        return (dirs, ras_to_lps(column(3)), true, Vec::new());
    }
    if h.qform_code > 0 {
        let [b, c, d] = h.quatern;
        let a = (1.0 - (b * b + c * c + d * d)).max(0.0).sqrt();
        let r = DMat3::from_quat(DQuat::from_xyzw(b, c, d, a));
        let qfac = if h.pixdim[0] < 0.0 { -1.0 } else { 1.0 };
        let dirs = [r.x_axis * h.pixdim[1], r.y_axis * h.pixdim[2], r.z_axis * h.pixdim[3] * qfac];
        return (dirs.map(ras_to_lps), ras_to_lps(DVec3::from_array(h.qoffset)), true, Vec::new());
    }
    let mut notes = Vec::new();
    let mut p = |i: usize| {
        if h.pixdim[i].is_finite() && h.pixdim[i] > 0.0 {
            h.pixdim[i]
        } else {
            notes.push(format!("pixdim[{i}] is {}, not a voxel size; 1 is used", h.pixdim[i]));
            1.0
        }
    };
    let dirs = [DVec3::X * p(1), DVec3::Y * p(2), DVec3::Z * p(3)];
    (dirs, DVec3::ZERO, false, notes)
}

/// Builds the volume from the frame's bytes.
fn build(path: &Path, h: &Header, layout: Layout, data: &[u8]) -> Result<LoadedVolume, LoadError> {
    let mut report = LoadReport::new(VolumeFormat::Nifti, path);
    report.notes.extend(layout.notes.iter().cloned());
    let (slope, inter) = if h.scl_slope == 0.0 {
        (1.0, 0.0)
    } else if !h.scl_slope.is_finite() {
        report
            .notes
            .push(format!("scl_slope is {}, not a number to scale by; the voxels are not rescaled", h.scl_slope));
        (1.0, 0.0)
    } else if !h.scl_inter.is_finite() {
        report.notes.push(format!(
            "scl_inter is {}, not a number to add; the voxels are scaled by scl_slope only",
            h.scl_inter
        ));
        (h.scl_slope, 0.0)
    } else {
        (h.scl_slope, h.scl_inter)
    };
    let big = h.order == super::Endianness::Big;
    let voxels = scaled(path, data, &layout, big, slope, inter, h.datatype)?;

    let (directions, origin, oriented, notes) = directions_lps(h);
    report.notes.extend(notes);
    let field = if h.sform_code > 0 { "sform (srow_x/y/z)" } else { "qform (quatern_b/c/d, pixdim)" };
    let (orientation, spacing) = AxisOrientation::from_directions(directions, &Location::file(path), field)?;
    if !orientation.is_identity() {
        report.notes.push(format!(
            "voxels reordered to the LPS patient frame ({}) from the file's RAS {field}",
            orientation.describe()
        ));
    }
    let file_dims = layout.file_dims;
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
        window: (h.cal.1 > h.cal.0).then(|| Window { center: (h.cal.0 + h.cal.1) / 2.0, width: h.cal.1 - h.cal.0 }),
        description: (!h.description.is_empty()).then(|| h.description.clone()),
        ..VolumeMeta::default()
    };
    Ok(LoadedVolume { volume, report })
}

/// Rescaled values in the narrowest type that holds them exactly: the file's own type where
/// the scale is the identity or integral, float32 otherwise. Two passes over the bytes, no
/// intermediate copy.
fn scaled(
    path: &Path,
    data: &[u8],
    layout: &Layout,
    big: bool,
    slope: f64,
    inter: f64,
    datatype: i16,
) -> Result<VoxelData, LoadError> {
    let (size, read) = (layout.size, layout.read);
    let values = || data.chunks_exact(size).map(move |c| read(c, big) * slope + inter);
    let integral_scale = slope.fract() == 0.0 && inter.fract() == 0.0;
    let integer_type = !matches!(datatype, 16 | 64);
    let (lo, hi) = values().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), s| (lo.min(s), hi.max(s)));
    let count = (data.len() / size) as u64;
    fn fill<T>(mut v: Vec<T>, values: impl Iterator<Item = T>) -> Vec<T> {
        v.extend(values);
        v
    }
    Ok(if integral_scale && integer_type && lo >= 0.0 && hi <= 255.0 && datatype == 2 {
        VoxelData::U8(fill(try_vec(path, count)?, values().map(|v| v as u8)))
    } else if integral_scale && integer_type && lo >= -32768.0 && hi <= 32767.0 {
        VoxelData::I16(fill(try_vec(path, count)?, values().map(|v| v as i16)))
    } else if integral_scale && integer_type && lo >= 0.0 && hi <= 65535.0 {
        VoxelData::U16(fill(try_vec(path, count)?, values().map(|v| v as u16)))
    } else {
        VoxelData::F32(fill(try_vec(path, count)?, values().map(|v| v as f32)))
    })
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
        let h = Header {
            version: 1,
            dim: [3, 2, 2, 2, 1, 1, 1, 1],
            pixdim: [1.0, 1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 0.0],
            datatype: 2,
            vox_offset: 352.0,
            scl_slope: 1.0,
            scl_inter: 0.0,
            cal: (0.0, 0.0),
            qform_code: 1,
            sform_code: 0,
            quatern: [0.0, 0.0, 1.0],
            qoffset: [0.0; 3],
            srow: [[0.0; 4]; 3],
            description: String::new(),
            order: super::super::Endianness::Little,
        };
        let (d, _, oriented, _) = directions_lps(&h);
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
