//! What several integration tests of the app share (each test binary uses a part of it).
#![allow(dead_code)]

use glam::{DVec3, UVec3};
use volgraph_accel::volume::{Volume, VoxelData};

/// A CT in HU (int16, n × n−4 × n−8 voxels): air around a soft-tissue ellipsoid with a bone core.
pub fn ct(n: u32, name: &str) -> Volume {
    let dims = UVec3::new(n, n - 4, n - 8);
    let mut values = Vec::new();
    for z in 0..dims.z {
        for y in 0..dims.y {
            for x in 0..dims.x {
                let p = (DVec3::new(x as f64, y as f64, z as f64) + 0.5) / dims.as_dvec3() - 0.5;
                let r = (p * DVec3::new(1.0, 1.2, 1.1)).length();
                values.push(if r < 0.15 {
                    900
                } else if r < 0.4 {
                    40
                } else {
                    -1000
                } as i16);
            }
        }
    }
    Volume::new(name, dims, DVec3::new(0.8, 0.8, 1.5), VoxelData::I16(values))
}

/// The size and RGBA pixels of an EXR (compare pixels, not bytes: the file's chunks are
/// compressed in parallel, so its bytes vary run to run).
pub fn read_exr(path: &std::path::Path) -> (usize, usize, Vec<[f32; 4]>) {
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |resolution, _| (resolution.width(), vec![[0.0f32; 4]; resolution.width() * resolution.height()]),
        |(w, pixels), position, (r, g, b, a): (f32, f32, f32, f32)| {
            pixels[position.y() * *w + position.x()] = [r, g, b, a]
        },
    )
    .expect("an EXR");
    let size = image.layer_data.size;
    (size.width(), size.height(), image.layer_data.channel_data.pixels.1)
}

/// A NIfTI-1 file (written byte by byte from nifti1.h) of two int16 volumes: `ct`, then `ct`
/// with its values halved, so the frames differ.
pub fn write_nifti_4d(path: &std::path::Path, ct: &Volume) {
    let VoxelData::I16(values) = &ct.data else { panic!("int16") };
    let halved: Vec<i16> = values.iter().map(|v| v / 2).collect();
    write_nifti_frames(path, ct, &[values, &halved]);
}

/// A NIfTI-1 file of `n` int16 volumes: `ct`, then `ct` with its values divided by 2, 3, …
/// (a microscope's channels, each fainter).
pub fn write_nifti_channels(path: &std::path::Path, ct: &Volume, n: i16) {
    let VoxelData::I16(values) = &ct.data else { panic!("int16") };
    let frames: Vec<Vec<i16>> = (1..=n).map(|k| values.iter().map(|v| v / k).collect()).collect();
    let refs: Vec<&[i16]> = frames.iter().map(Vec::as_slice).collect();
    write_nifti_frames(path, ct, &refs);
}

/// A NIfTI-1 file of the int16 volume `ct` alone (3D, no orientation: index axes).
pub fn write_nifti(path: &std::path::Path, ct: &Volume) {
    let VoxelData::I16(values) = &ct.data else { panic!("int16") };
    write_nifti_frames(path, ct, &[values]);
}

/// The NIfTI-1 file a converter writes from the DICOM series of `ct` (LPS axes, voxel
/// (0, 0, 0) at the origin, as `write_ct_series` lays it): the same voxels with an sform in RAS
/// (x and y negated); with `flip_rows`, the rows stored bottom up as dcm2niix stores them, the
/// sform's y column and offset saying so.
pub fn write_nifti_from_dicom(path: &std::path::Path, ct: &Volume, flip_rows: bool) {
    let VoxelData::I16(values) = &ct.data else { panic!("int16") };
    let (nx, ny) = (ct.dims.x as usize, ct.dims.y as usize);
    let s = ct.spacing;
    let (stored, y_column, y_offset): (Vec<i16>, f64, f64) = if flip_rows {
        let flipped = values
            .chunks(nx * ny)
            .flat_map(|slice| slice.chunks(nx).rev().flatten().copied().collect::<Vec<_>>())
            .collect();
        (flipped, s.y, -((ny - 1) as f64) * s.y)
    } else {
        (values.clone(), -s.y, 0.0)
    };
    let srow = [[-s.x, 0.0, 0.0, 0.0], [0.0, y_column, 0.0, y_offset], [0.0, 0.0, s.z, 0.0]];
    write_nifti_with(path, ct, &[&stored], Some(srow));
}

/// A NIfTI-1 file of `frames`, each an int16 volume of `ct`'s size and spacing.
fn write_nifti_frames(path: &std::path::Path, ct: &Volume, frames: &[&[i16]]) {
    write_nifti_with(path, ct, frames, None);
}

/// [`write_nifti_frames`] with an sform (rows x, y, z of the RAS affine; sform_code 1) or none.
fn write_nifti_with(path: &std::path::Path, ct: &Volume, frames: &[&[i16]], srow: Option<[[f64; 4]; 3]>) {
    let mut header = vec![0u8; 352];
    header[0..4].copy_from_slice(&348i32.to_le_bytes());
    let rank = if frames.len() > 1 { 4i16 } else { 3 };
    let dims = [rank, ct.dims.x as i16, ct.dims.y as i16, ct.dims.z as i16, frames.len() as i16, 1, 1, 1];
    for (i, d) in dims.iter().enumerate() {
        header[40 + 2 * i..42 + 2 * i].copy_from_slice(&d.to_le_bytes());
    }
    header[70..72].copy_from_slice(&4i16.to_le_bytes()); // DT_INT16
    header[72..74].copy_from_slice(&16i16.to_le_bytes());
    let pixdim = [1.0f32, ct.spacing.x as f32, ct.spacing.y as f32, ct.spacing.z as f32, 1.0, 1.0, 1.0, 1.0];
    for (i, p) in pixdim.iter().enumerate() {
        header[76 + 4 * i..80 + 4 * i].copy_from_slice(&p.to_le_bytes());
    }
    header[108..112].copy_from_slice(&352f32.to_le_bytes());
    header[112..116].copy_from_slice(&1f32.to_le_bytes());
    if let Some(rows) = srow {
        header[254..256].copy_from_slice(&1i16.to_le_bytes()); // sform_code: scanner
        for (r, row) in rows.iter().enumerate() {
            for (c, v) in row.iter().enumerate() {
                let at = 280 + 16 * r + 4 * c;
                header[at..at + 4].copy_from_slice(&(*v as f32).to_le_bytes());
            }
        }
    }
    header[344..348].copy_from_slice(b"n+1\0");
    let mut bytes = header;
    for frame in frames {
        bytes.extend(frame.iter().flat_map(|v| v.to_le_bytes()));
    }
    std::fs::write(path, bytes).expect("nifti written");
}
