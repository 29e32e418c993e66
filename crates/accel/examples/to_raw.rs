//! Loads any volume volgraph reads (raw, NRRD, MetaImage, NIfTI, a DICOM folder) and writes its
//! data values, in the LPS patient frame, as little-endian float32 `NAME_XxYxZ_float32.raw`:
//! what the SimpleITK cross-check of issue 21 compared against.
//!
//! `cargo run --release -p volgraph-accel --example to_raw -- INPUT... OUT_DIR`

use std::path::PathBuf;

use volgraph_accel::load::{LoadOptions, load_volumes};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args: Vec<PathBuf> = std::env::args_os().skip(1).map(PathBuf::from).collect();
    let out = args.pop().ok_or("usage: to_raw INPUT... OUT_DIR")?;
    let loaded = load_volumes(&args, &LoadOptions::default())?;
    let v = &loaded.volume;
    let bytes: Vec<u8> = (0..v.voxel_count()).flat_map(|i| (v.raw_value(i) as f32).to_le_bytes()).collect();
    let path = out.join(format!("{}_{}x{}x{}_float32.raw", v.name.replace(' ', "_"), v.dims.x, v.dims.y, v.dims.z));
    std::fs::write(&path, bytes)?;
    println!("{} (spacing {:?}, origin {:?})", path.display(), v.spacing, v.meta.origin);
    Ok(())
}
