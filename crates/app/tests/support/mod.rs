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
