//! NIfTI-1 and NIfTI-2 files written field by field (offsets of `nifti1.h` and `nifti2.h`), in
//! either byte order, with any field set to any value: what the NIfTI loader tests and the
//! NIfTI fuzzer start from.
#![allow(dead_code)] // Each test binary uses a different subset of these helpers.

/// Every header field the loader reads, as a test sets it.
#[derive(Clone, Debug)]
pub struct NiftiSpec {
    /// 1 (348-byte header, data from byte 352) or 2 (540 bytes, data from 544).
    pub version: u8,
    /// Big-endian fields and voxels.
    pub big: bool,
    /// The datatype code.
    pub datatype: i16,
    /// `dim[0..8]`.
    pub dim: [i64; 8],
    /// `pixdim[0..8]`.
    pub pixdim: [f64; 8],
    /// `vox_offset`.
    pub vox_offset: f64,
    /// `scl_slope`, `scl_inter`.
    pub scl: (f64, f64),
    /// `qform_code`, `sform_code`.
    pub codes: (i32, i32),
    /// `quatern_b/c/d`.
    pub quatern: [f64; 3],
    /// `srow_x/y/z`.
    pub srow: [[f64; 4]; 3],
    /// `descrip` (up to 80 bytes).
    pub descrip: Vec<u8>,
    /// `sizeof_hdr` written in the other byte order than every other field.
    pub swapped_size: bool,
}

impl NiftiSpec {
    /// A 3D (or 4D, `frames > 1`) file of `dims` voxels of `datatype`, spacing 1, no orientation.
    pub fn new(version: u8, dims: [i64; 3], frames: i64, datatype: i16) -> NiftiSpec {
        let four = frames > 1;
        NiftiSpec {
            version,
            big: false,
            datatype,
            dim: [if four { 4 } else { 3 }, dims[0], dims[1], dims[2], frames.max(1), 1, 1, 1],
            pixdim: [1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0],
            vox_offset: Self::data_start(version) as f64,
            scl: (1.0, 0.0),
            codes: (0, 0),
            quatern: [0.0; 3],
            srow: [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]],
            descrip: Vec::new(),
            swapped_size: false,
        }
    }

    /// Where the voxels of a header of `version` start.
    pub fn data_start(version: u8) -> usize {
        if version == 1 { 352 } else { 544 }
    }

    /// The header (with NIfTI-1's four extension bytes), ending where the voxels start.
    pub fn header(&self) -> Vec<u8> {
        let mut h = vec![0u8; Self::data_start(self.version)];
        let big = self.big;
        let mut put = |at: usize, le: &[u8]| {
            let mut b = le.to_vec();
            if big {
                b.reverse();
            }
            h[at..at + b.len()].copy_from_slice(&b);
        };
        if self.version == 1 {
            put(0, &348i32.to_le_bytes());
            for (i, d) in self.dim.iter().enumerate() {
                put(40 + 2 * i, &(*d as i16).to_le_bytes());
            }
            put(70, &self.datatype.to_le_bytes());
            put(72, &(bits(self.datatype)).to_le_bytes());
            for (i, p) in self.pixdim.iter().enumerate() {
                put(76 + 4 * i, &(*p as f32).to_le_bytes());
            }
            put(108, &(self.vox_offset as f32).to_le_bytes());
            put(112, &(self.scl.0 as f32).to_le_bytes());
            put(116, &(self.scl.1 as f32).to_le_bytes());
            put(252, &(self.codes.0 as i16).to_le_bytes());
            put(254, &(self.codes.1 as i16).to_le_bytes());
            for (i, q) in self.quatern.iter().enumerate() {
                put(256 + 4 * i, &(*q as f32).to_le_bytes());
            }
            for (r, row) in self.srow.iter().enumerate() {
                for (c, v) in row.iter().enumerate() {
                    put(280 + 16 * r + 4 * c, &(*v as f32).to_le_bytes());
                }
            }
            h[344..348].copy_from_slice(b"n+1\0");
            let n = self.descrip.len().min(80);
            h[148..148 + n].copy_from_slice(&self.descrip[..n]);
        } else {
            put(0, &540i32.to_le_bytes());
            put(12, &self.datatype.to_le_bytes());
            put(14, &(bits(self.datatype)).to_le_bytes());
            for (i, d) in self.dim.iter().enumerate() {
                put(16 + 8 * i, &d.to_le_bytes());
            }
            for (i, p) in self.pixdim.iter().enumerate() {
                put(104 + 8 * i, &p.to_le_bytes());
            }
            put(168, &(self.vox_offset as i64).to_le_bytes());
            put(176, &self.scl.0.to_le_bytes());
            put(184, &self.scl.1.to_le_bytes());
            put(344, &self.codes.0.to_le_bytes());
            put(348, &self.codes.1.to_le_bytes());
            for (i, q) in self.quatern.iter().enumerate() {
                put(352 + 8 * i, &q.to_le_bytes());
            }
            for (r, row) in self.srow.iter().enumerate() {
                for (c, v) in row.iter().enumerate() {
                    put(400 + 32 * r + 8 * c, &v.to_le_bytes());
                }
            }
            h[4..12].copy_from_slice(b"n+2\0\r\n\x1a\n");
            let n = self.descrip.len().min(80);
            h[240..240 + n].copy_from_slice(&self.descrip[..n]);
        }
        if self.swapped_size {
            h[0..4].reverse();
        }
        h
    }

    /// The whole file: the header, then `data`.
    pub fn file(&self, data: &[u8]) -> Vec<u8> {
        let mut bytes = self.header();
        bytes.extend_from_slice(data);
        bytes
    }
}

/// Bits per voxel of a datatype (0 for unknown codes).
fn bits(datatype: i16) -> i16 {
    match datatype {
        2 | 256 => 8,
        4 | 512 => 16,
        8 | 16 | 768 => 32,
        64 | 1024 | 1280 | 32 => 64,
        128 => 24,
        2304 => 32,
        1536 | 1792 => 128,
        2048 => 256,
        _ => 0,
    }
}

/// Bytes per voxel of a datatype the loader reads (1 for others, so a file still has data).
pub fn bytes_per_voxel(datatype: i16) -> usize {
    (bits(datatype).max(8) / 8) as usize
}

/// `count` voxels of `datatype`, `value(i)` each, in the byte order asked for.
pub fn voxels(datatype: i16, count: usize, big: bool, value: impl Fn(usize) -> f64) -> Vec<u8> {
    let mut out = Vec::new();
    for i in 0..count {
        let v = value(i);
        let mut b: Vec<u8> = match datatype {
            2 => vec![v as u8],
            256 => vec![v as i8 as u8],
            4 => (v as i16).to_le_bytes().to_vec(),
            512 => (v as u16).to_le_bytes().to_vec(),
            8 => (v as i32).to_le_bytes().to_vec(),
            768 => (v as u32).to_le_bytes().to_vec(),
            16 => (v as f32).to_le_bytes().to_vec(),
            64 => v.to_le_bytes().to_vec(),
            1024 => (v as i64).to_le_bytes().to_vec(),
            1280 => (v as u64).to_le_bytes().to_vec(),
            other => vec![v as u8; bytes_per_voxel(other)],
        };
        if big {
            b.reverse();
        }
        out.extend(b);
    }
    out
}

/// gzip-compresses `bytes`.
pub fn gzip(bytes: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    enc.write_all(bytes).expect("gzip into memory");
    enc.finish().expect("gzip into memory")
}
