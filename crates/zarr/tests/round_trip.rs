//! A volume written as a pyramid and read back: level 0 equals the volume voxel for voxel,
//! every coarser level equals the 2×2×2 means of the one above, the levels' transforms place
//! their voxel centres where the means are, every chunk's stored range equals its voxels' range,
//! and chunks of the fill value alone are not stored.

use glam::{DVec3, UVec3};
use volgraph_accel::volume::{Volume, VoxelData};
use volgraph_zarr::{InMemory, OmeZarr, Pick, WriteOptions, write_pyramid};

/// 70×50×37 uint16: a ramp in x and z, zero in the first 16 planes (whole empty chunks).
fn ramp() -> Volume {
    let d = UVec3::new(70, 50, 37);
    let mut data = Vec::with_capacity((d.x * d.y * d.z) as usize);
    for z in 0..d.z {
        for y in 0..d.y {
            for x in 0..d.x {
                data.push(if z < 16 { 0 } else { (x * 300 + y * 7 + z * 500) as u16 });
            }
        }
    }
    let mut v = Volume::new("ramp", d, DVec3::new(0.5, 0.5, 2.0), VoxelData::U16(data));
    v.meta.origin = Some(DVec3::new(-10.0, 5.0, 100.0));
    v.meta.frame = volgraph_accel::volume_meta::WorldFrame::Lps;
    v.meta.modality = Some("CT".into());
    v
}

/// Writes `source` at `out` with cubes of `chunk` voxels, levels halving until ≤ `coarsest`.
fn write(source: &Volume, out: &std::path::Path, chunk: u32, coarsest: u32) {
    let options = WriteOptions { chunk, coarsest, zstd_level: 1 };
    write_pyramid(&mut InMemory(source.clone()), out, &options, &mut |_, _| {}).expect("written");
}

fn voxels(v: &Volume) -> Vec<u16> {
    match &v.data {
        VoxelData::U16(d) => d.clone(),
        _ => panic!("uint16 expected"),
    }
}

/// The 2×2×2 means of `data` (dims `d`), odd edges averaged with themselves.
fn halve(data: &[u16], d: UVec3) -> (Vec<u16>, UVec3) {
    let h = UVec3::new(d.x.div_ceil(2), d.y.div_ceil(2), d.z.div_ceil(2));
    let at = |x: u32, y: u32, z: u32| f64::from(data[((z * d.y + y) * d.x + x) as usize]);
    let mut out = Vec::new();
    for z in 0..h.z {
        for y in 0..h.y {
            for x in 0..h.x {
                let mut sum = 0.0;
                for dz in 0..2 {
                    for dy in 0..2 {
                        for dx in 0..2 {
                            sum += at((2 * x + dx).min(d.x - 1), (2 * y + dy).min(d.y - 1), (2 * z + dz).min(d.z - 1));
                        }
                    }
                }
                out.push((sum / 8.0).round() as u16);
            }
        }
    }
    (out, h)
}

#[test]
fn a_pyramid_reads_back_exactly() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("ramp.ome.zarr");
    let source = ramp();
    let options = WriteOptions { chunk: 16, coarsest: 16, zstd_level: 3 };
    let mut calls = 0;
    let report = write_pyramid(&mut InMemory(source.clone()), &out, &options, &mut |_, _| calls += 1).expect("written");
    assert_eq!(
        report.levels,
        vec![UVec3::new(70, 50, 37), UVec3::new(35, 25, 19), UVec3::new(18, 13, 10), UVec3::new(9, 7, 5)]
    );
    // Level 0: 5×4×3 chunks, the first z row (16 zero planes) empty: 20 chunks not stored.
    assert!(report.chunks_empty >= 20 && calls > 0);

    let image = OmeZarr::open(&out).expect("opened");
    assert_eq!(image.levels.len(), 4);
    assert_eq!(image.space_unit(), Some("millimeter"));
    let mut expected = voxels(&source);
    let mut dims = source.dims;
    for (k, level) in image.levels.iter().enumerate() {
        let f = (1u32 << k) as f64;
        assert_eq!(level.dims, dims, "level {k}");
        assert_eq!(level.spacing, DVec3::new(0.5, 0.5, 2.0) * f, "level {k}");
        // A level's voxel 0 is the mean of 2^k finer voxels from the first: its centre lies
        // (2^k − 1)/2 finer voxels further on.
        let shift = (f - 1.0) / 2.0;
        let want = DVec3::new(-10.0, 5.0, 100.0) + DVec3::new(0.5, 0.5, 2.0) * shift;
        assert!((level.origin - want).abs().max_element() < 1e-9, "level {k}: {:?}", level.origin);
        let read = image.read_level(k, Pick::default(), 1 << 30).expect("read");
        assert!(read.notes.is_empty(), "{:?}", read.notes);
        assert_eq!(voxels(&read.volume), expected, "level {k}");
        // NGFF has no patient frame: the writer keeps it (and the modality) for the reader.
        assert_eq!(read.volume.meta.frame, volgraph_accel::volume_meta::WorldFrame::Lps);
        assert_eq!(read.volume.meta.modality.as_deref(), Some("CT"));
        assert_eq!(read.volume.meta.origin, Some(level.origin));
        (expected, dims) = halve(&expected, dims);
    }
}

#[test]
fn every_chunks_range_is_stored_beside_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("ramp.ome.zarr");
    let source = ramp();
    write(&source, &out, 16, 64);
    let store = std::sync::Arc::new(zarrs::filesystem::FilesystemStore::new(&out).expect("store"));
    let ranges = zarrs::array::Array::open(store, "/chunk_ranges/0").expect("ranges");
    assert_eq!(ranges.shape(), &[3, 4, 5, 2]);
    let all: Vec<f32> = ranges.retrieve_array_subset::<Vec<f32>>(&ranges.subset_all()).expect("read");
    let data = voxels(&source);
    let d = source.dims;
    for cz in 0..3u32 {
        for cy in 0..4u32 {
            for cx in 0..5u32 {
                let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
                for z in cz * 16..((cz + 1) * 16).min(d.z) {
                    for y in cy * 16..((cy + 1) * 16).min(d.y) {
                        for x in cx * 16..((cx + 1) * 16).min(d.x) {
                            let v = f32::from(data[((z * d.y + y) * d.x + x) as usize]);
                            lo = lo.min(v);
                            hi = hi.max(v);
                        }
                    }
                }
                let i = (((cz * 4 + cy) * 5 + cx) * 2) as usize;
                assert_eq!((all[i], all[i + 1]), (lo, hi), "chunk {cz}/{cy}/{cx}");
            }
        }
    }
}

#[test]
fn float_and_signed_volumes_round_trip() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = UVec3::new(20, 18, 17);
    let n = (d.x * d.y * d.z) as usize;
    for (name, data) in [
        ("f32", VoxelData::F32((0..n).map(|i| (i as f32 * 0.37).sin() * 1000.0).collect())),
        ("i16", VoxelData::I16((0..n).map(|i| (i % 3000) as i16 - 1024).collect())),
    ] {
        let source = Volume::new(name, d, DVec3::ONE, data);
        let out = dir.path().join(format!("{name}.ome.zarr"));
        write(&source, &out, 8, 8);
        let read = OmeZarr::open(&out).and_then(|i| i.read_level(0, Pick::default(), 1 << 30)).expect("read");
        assert_eq!(read.volume.data, source.data, "{name}");
    }
}
