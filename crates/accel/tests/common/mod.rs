//! Helpers shared by the loader tests: unique temporary folders and voxel byte encoders.
#![allow(dead_code)] // Each test binary uses a different subset of these helpers.

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

use volgraph_accel::volume::VoxelData;

/// A fresh, empty folder under the system temp dir, unique per process and call.
pub fn temp_dir(tag: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("volgraph-accel-{tag}-{}-{n}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create a temp dir");
    dir
}

/// The voxels as bytes in the given byte order.
pub fn voxel_bytes(data: &VoxelData, big_endian: bool) -> Vec<u8> {
    match data {
        VoxelData::U8(v) => v.clone(),
        VoxelData::U16(v) => {
            v.iter().flat_map(|x| if big_endian { x.to_be_bytes() } else { x.to_le_bytes() }).collect()
        }
        VoxelData::I16(v) => {
            v.iter().flat_map(|x| if big_endian { x.to_be_bytes() } else { x.to_le_bytes() }).collect()
        }
        VoxelData::F32(v) => {
            v.iter().flat_map(|x| if big_endian { x.to_be_bytes() } else { x.to_le_bytes() }).collect()
        }
    }
}

/// gzip-compresses `bytes`.
pub fn gzip(bytes: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    enc.write_all(bytes).expect("gzip into memory");
    enc.finish().expect("gzip into memory")
}

/// zlib-compresses `bytes`.
pub fn zlib(bytes: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let mut enc = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
    enc.write_all(bytes).expect("zlib into memory");
    enc.finish().expect("zlib into memory")
}
