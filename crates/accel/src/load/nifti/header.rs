//! The NIfTI-1 (348 bytes, `nifti1.h`) and NIfTI-2 (540 bytes, `nifti2.h`) headers, read field
//! by field at the standard's offsets. The byte order is the one in which `sizeof_hdr` reads 348
//! or 540: unlike the `dim[0] > 7` test of the reference library, it cannot be fooled by a
//! hostile `dim[0]` into reading every other field byte-swapped. Sizes are kept signed as the
//! file stores them, so a negative size is reported as written, not as 65535.

use std::path::Path;

use super::super::{Endianness, LoadError};

/// The bytes of a NIfTI-1 header.
pub(super) const NIFTI1_BYTES: usize = 348;
/// The bytes of a NIfTI-2 header.
pub(super) const NIFTI2_BYTES: usize = 540;

/// The header fields a volume needs, from either NIfTI version.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Header {
    /// 1 or 2.
    pub version: u8,
    /// `dim[0]` (the number of axes) and `dim[1..=7]` (their sizes).
    pub dim: [i64; 8],
    /// `pixdim[0]` (qfac) and the voxel sizes.
    pub pixdim: [f64; 8],
    /// The NIfTI datatype code.
    pub datatype: i16,
    /// `vox_offset` as stored (a float in NIfTI-1).
    pub vox_offset: f64,
    /// `scl_slope`.
    pub scl_slope: f64,
    /// `scl_inter`.
    pub scl_inter: f64,
    /// `(cal_min, cal_max)`.
    pub cal: (f64, f64),
    /// `qform_code`.
    pub qform_code: i32,
    /// `sform_code`.
    pub sform_code: i32,
    /// `quatern_b`, `quatern_c`, `quatern_d`.
    pub quatern: [f64; 3],
    /// `qoffset_x`, `qoffset_y`, `qoffset_z`.
    pub qoffset: [f64; 3],
    /// `srow_x`, `srow_y`, `srow_z`.
    pub srow: [[f64; 4]; 3],
    /// `descrip`, up to its first NUL, control characters escaped.
    pub description: String,
    /// The byte order of every multi-byte field and voxel.
    pub order: Endianness,
}

/// The version and byte order the first four bytes (`sizeof_hdr`) announce, or the value they
/// hold read little-endian (for the message) when it is neither 348 nor 540 either way.
pub(super) fn sniff(first: [u8; 4]) -> Result<(u8, Endianness), i32> {
    for (value, order) in
        [(i32::from_le_bytes(first), Endianness::Little), (i32::from_be_bytes(first), Endianness::Big)]
    {
        match value {
            348 => return Ok((1, order)),
            540 => return Ok((2, order)),
            _ => {}
        }
    }
    Err(i32::from_le_bytes(first))
}

/// Reads fixed-size fields of a header held in `b` (its length checked by the caller).
struct Fields<'a> {
    b: &'a [u8],
    big: bool,
}

impl Fields<'_> {
    fn bytes<const N: usize>(&self, at: usize) -> [u8; N] {
        let mut a: [u8; N] = std::array::from_fn(|i| self.b.get(at + i).copied().unwrap_or(0));
        if self.big {
            a.reverse();
        }
        a
    }
    fn i16(&self, at: usize) -> i16 {
        i16::from_le_bytes(self.bytes(at))
    }
    fn i32(&self, at: usize) -> i32 {
        i32::from_le_bytes(self.bytes(at))
    }
    fn i64(&self, at: usize) -> i64 {
        i64::from_le_bytes(self.bytes(at))
    }
    fn f32(&self, at: usize) -> f64 {
        f32::from_le_bytes(self.bytes(at)) as f64
    }
    fn f64(&self, at: usize) -> f64 {
        f64::from_le_bytes(self.bytes(at))
    }
    fn text(&self, range: std::ops::Range<usize>) -> String {
        let raw = self.b.get(range).unwrap_or_default();
        let raw = raw.split(|&c| c == 0).next().unwrap_or_default();
        let text: String = String::from_utf8_lossy(raw)
            .chars()
            .flat_map(|c| if c.is_control() { c.escape_default().collect::<Vec<_>>() } else { vec![c] })
            .collect();
        text.trim().to_string()
    }
}

/// A readable form of a magic string: printable ASCII as is, other bytes as `\xNN`.
fn shown(bytes: &[u8]) -> String {
    bytes.iter().flat_map(|b| std::ascii::escape_default(*b)).map(char::from).collect()
}

/// Parses the header of `version` in byte order `order` from `b`, which holds at least
/// [`NIFTI1_BYTES`] or [`NIFTI2_BYTES`] bytes.
pub(super) fn parse(path: &Path, b: &[u8], version: u8, order: Endianness) -> Result<Header, LoadError> {
    let read_error = |reason: String| LoadError::NiftiRead { path: path.to_path_buf(), reason };
    let f = Fields { b, big: order == Endianness::Big };
    if version == 1 {
        let magic = b.get(344..348).unwrap_or_default();
        if magic == b"ni1\0" {
            return Err(read_error(
                "a header of a .hdr/.img pair (magic ni1); save the image as one .nii file (e.g. with nibabel or 3D \
                 Slicer)"
                    .into(),
            ));
        }
        if magic != b"n+1\0" {
            return Err(read_error(format!(
                "the NIfTI-1 header's magic (bytes 344..348) is \"{}\", not \"n+1\\0\"; the file is corrupt or not NIfTI",
                shown(magic)
            )));
        }
        return Ok(Header {
            version,
            dim: std::array::from_fn(|i| f.i16(40 + 2 * i) as i64),
            pixdim: std::array::from_fn(|i| f.f32(76 + 4 * i)),
            datatype: f.i16(70),
            vox_offset: f.f32(108),
            scl_slope: f.f32(112),
            scl_inter: f.f32(116),
            cal: (f.f32(128), f.f32(124)),
            description: f.text(148..228),
            qform_code: f.i16(252) as i32,
            sform_code: f.i16(254) as i32,
            quatern: [f.f32(256), f.f32(260), f.f32(264)],
            qoffset: [f.f32(268), f.f32(272), f.f32(276)],
            srow: std::array::from_fn(|r| std::array::from_fn(|c| f.f32(280 + 16 * r + 4 * c))),
            order,
        });
    }
    let magic = b.get(4..8).unwrap_or_default();
    if magic != b"n+2\0" {
        return Err(read_error(format!(
            "the NIfTI-2 header's magic (bytes 4..8) is \"{}\", not \"n+2\\0\" of a single .nii file",
            shown(magic)
        )));
    }
    Ok(Header {
        version,
        datatype: f.i16(12),
        dim: std::array::from_fn(|i| f.i64(16 + 8 * i)),
        pixdim: std::array::from_fn(|i| f.f64(104 + 8 * i)),
        vox_offset: f.i64(168) as f64,
        scl_slope: f.f64(176),
        scl_inter: f.f64(184),
        cal: (f.f64(200), f.f64(192)),
        description: f.text(240..320),
        qform_code: f.i32(344),
        sform_code: f.i32(348),
        quatern: [f.f64(352), f.f64(360), f.f64(368)],
        qoffset: [f.f64(376), f.f64(384), f.f64(392)],
        srow: std::array::from_fn(|r| std::array::from_fn(|c| f.f64(400 + 32 * r + 8 * c))),
        order,
    })
}

/// The name of a NIfTI datatype code (`nifti1.h`), for messages.
pub(super) fn datatype_name(code: i16) -> Option<&'static str> {
    Some(match code {
        2 => "uint8",
        4 => "int16",
        8 => "int32",
        16 => "float32",
        32 => "complex64",
        64 => "float64",
        128 => "RGB24",
        256 => "int8",
        512 => "uint16",
        768 => "uint32",
        1024 => "int64",
        1280 => "uint64",
        1536 => "float128",
        1792 => "complex128",
        2048 => "complex256",
        2304 => "RGBA32",
        _ => return None,
    })
}

/// Reads one stored value (its bytes in the file's order) as f64.
pub(super) type ReadValue = fn(&[u8], bool) -> f64;

/// The bytes per voxel and the reader of a supported datatype, or `None`.
pub(super) fn element(datatype: i16) -> Option<(usize, ReadValue)> {
    fn ordered<const N: usize>(b: &[u8], big: bool) -> [u8; N] {
        let mut a: [u8; N] = std::array::from_fn(|i| b.get(i).copied().unwrap_or(0));
        if big {
            a.reverse();
        }
        a
    }
    Some(match datatype {
        2 => (1, |b, _| b.first().copied().unwrap_or(0) as f64),
        256 => (1, |b, _| b.first().copied().unwrap_or(0) as i8 as f64),
        4 => (2, |b, big| i16::from_le_bytes(ordered(b, big)) as f64),
        512 => (2, |b, big| u16::from_le_bytes(ordered(b, big)) as f64),
        8 => (4, |b, big| i32::from_le_bytes(ordered(b, big)) as f64),
        768 => (4, |b, big| u32::from_le_bytes(ordered(b, big)) as f64),
        16 => (4, |b, big| f32::from_le_bytes(ordered(b, big)) as f64),
        64 => (8, |b, big| f64::from_le_bytes(ordered(b, big))),
        1024 => (8, |b, big| i64::from_le_bytes(ordered(b, big)) as f64),
        1280 => (8, |b, big| u64::from_le_bytes(ordered(b, big)) as f64),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizeof_hdr_gives_version_and_byte_order() {
        assert_eq!(sniff(348i32.to_le_bytes()), Ok((1, Endianness::Little)));
        assert_eq!(sniff(348i32.to_be_bytes()), Ok((1, Endianness::Big)));
        assert_eq!(sniff(540i32.to_be_bytes()), Ok((2, Endianness::Big)));
        assert_eq!(sniff([0; 4]), Err(0));
    }

    #[test]
    fn a_big_endian_header_reads_its_sizes_as_written() {
        let mut h = vec![0u8; NIFTI1_BYTES];
        h[0..4].copy_from_slice(&348i32.to_be_bytes());
        for (i, d) in [3i16, 300, -1, 8].iter().enumerate() {
            h[40 + 2 * i..42 + 2 * i].copy_from_slice(&d.to_be_bytes());
        }
        h[70..72].copy_from_slice(&8i16.to_be_bytes());
        h[344..348].copy_from_slice(b"n+1\0");
        let parsed = parse(Path::new("b.nii"), &h, 1, Endianness::Big).expect("parses");
        assert_eq!(&parsed.dim[..4], &[3, 300, -1, 8]);
        assert_eq!(parsed.datatype, 8);
        assert_eq!(datatype_name(parsed.datatype), Some("int32"));
    }
}
