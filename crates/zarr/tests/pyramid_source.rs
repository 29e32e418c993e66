//! A store read brick by brick (`ZarrPyramid`, the streaming raycaster's source) gives the
//! texels the same volume gives as an in-memory pyramid (`InCorePyramid`, the converter's
//! means): at every level, for boxes across chunk borders and past the faces (clamped); its
//! chunk ranges bound every box's values without reading them; a lost chunk is drawn as the fill
//! value and named once, an undecodable one named as an error.

use std::sync::Arc;

use glam::{DVec3, IVec3, UVec3};
use volgraph_accel::pyramid::{InCorePyramid, PyramidSource};
use volgraph_accel::volume::{Volume, VoxelData};
use volgraph_zarr::{InMemory, OmeZarr, Pick, WriteOptions, ZarrPyramid, write_pyramid};

/// 45×30×21 bytes: a bright ball on a faint ramp, zero in the first 8 planes.
fn ball() -> Volume {
    let d = UVec3::new(45, 30, 21);
    let mut data = Vec::with_capacity(d.element_product() as usize);
    for z in 0..d.z {
        for y in 0..d.y {
            for x in 0..d.x {
                let r = (DVec3::new(x as f64, y as f64, z as f64) - DVec3::new(22.0, 15.0, 13.0)).length();
                data.push(if z < 8 { 0 } else { ((x + y) as f64 * 0.5 + 200.0 * (1.0 - r / 9.0).max(0.0)) as u8 });
            }
        }
    }
    Volume::new("ball", d, DVec3::new(1.0, 1.0, 1.5), VoxelData::U8(data))
}

fn store(dir: &std::path::Path) -> ZarrPyramid {
    let path = dir.join("ball.ome.zarr");
    let options = WriteOptions { chunk: 8, coarsest: 8, zstd_level: 1 };
    write_pyramid(&mut InMemory(ball()), &path, &options, &mut |_, _| {}).expect("written");
    ZarrPyramid::new(OmeZarr::open(&path).expect("opens"), Pick::default(), 1 << 20).expect("a pyramid")
}

#[test]
fn boxes_equal_the_in_memory_pyramid_at_every_level() {
    let dir = tempfile::tempdir().expect("temp dir");
    let zarr = store(dir.path());
    let memory = InCorePyramid::new(Arc::new(ball()), 8);
    let levels: Vec<UVec3> = zarr.levels().iter().map(|l| l.dims).collect();
    assert_eq!(levels, memory.levels().iter().map(|l| l.dims).collect::<Vec<_>>());
    assert_eq!(levels.len(), 4, "45 → 23 → 12 → 6 voxels wide");
    for (l, dims) in levels.iter().enumerate() {
        for lo in [IVec3::new(-2, -1, -3), IVec3::new(5, 3, 6), dims.as_ivec3() - IVec3::new(4, 3, 2)] {
            let size = UVec3::new(11, 7, 9);
            let (a, b) = (zarr.read_box(l, lo, size).expect("reads"), memory.read_box(l, lo, size).expect("reads"));
            assert_eq!(a, b, "level {l}, box at {lo}");
            // The stored chunk ranges bound the box's values, unread.
            let (lo_v, hi_v) = a.range().expect("voxels");
            let (lo_r, hi_r) = zarr.box_range(l, lo, lo + size.as_ivec3()).expect("ranges were written");
            assert!(lo_r <= lo_v && hi_v <= hi_r, "level {l}: [{lo_v}, {hi_v}] outside [{lo_r}, {hi_r}]");
        }
    }
    // The empty first planes: a box there is known empty without a read.
    assert_eq!(zarr.box_range(0, IVec3::ZERO, IVec3::new(8, 8, 8)), Some((0.0, 0.0)));
    assert!(zarr.notes().is_empty());
}

#[test]
fn a_lost_chunk_is_named_once_and_an_undecodable_one_as_an_error() {
    let dir = tempfile::tempdir().expect("temp dir");
    let _ = store(dir.path());
    let root = dir.path().join("ball.ome.zarr");
    std::fs::remove_file(root.join("0/c/1/1/2")).expect("the ball crosses chunk (1, 1, 2)");
    std::fs::write(root.join("0/c/2/1/2"), b"not zstd").expect("garbled");
    let zarr = ZarrPyramid::new(OmeZarr::open(&root).expect("opens"), Pick::default(), 1 << 20).expect("a pyramid");
    for _ in 0..2 {
        let lost = zarr.read_box(0, IVec3::new(16, 8, 8), UVec3::splat(8)).expect("drawn as the fill value");
        assert_eq!(lost.range(), Some((0.0, 0.0)));
        zarr.read_box(0, IVec3::new(16, 8, 16), UVec3::splat(8)).expect("drawn as the fill value");
    }
    let notes = zarr.notes();
    assert_eq!(notes.iter().filter(|n| n.contains("chunk (z, y, x) 1/1/2 is missing")).count(), 1, "{notes:?}");
    assert!(notes.iter().any(|n| n.starts_with("error:") && n.contains("2/1/2")), "{notes:?}");
}

/// A store whose coarsest level is large (one level of 1024³ bytes, written as metadata with no
/// chunks) is refused before a voxel is read: streaming holds only the coarsest level whole.
#[test]
fn a_store_without_a_small_level_is_refused_before_reading() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("big.ome.zarr");
    let big = Volume::new("big", UVec3::new(1024, 1024, 1), DVec3::ONE, VoxelData::U8(vec![0; 1 << 20]));
    let options = WriteOptions { chunk: 64, coarsest: 1024, zstd_level: 1 };
    write_pyramid(&mut InMemory(big), &path, &options, &mut |_, _| {}).expect("written");
    // The level's metadata says 1024³: rewrite its shape, as a store of one big level would.
    let meta_path = path.join("0/zarr.json");
    let meta = std::fs::read_to_string(&meta_path).expect("metadata");
    std::fs::write(
        &meta_path,
        meta.replacen("[\n    1,\n    1024,\n    1024\n  ]", "[\n    1024,\n    1024,\n    1024\n  ]", 1),
    )
    .expect("rewritten");
    let image = OmeZarr::open(&path).expect("opens");
    assert_eq!(image.levels[0].dims, UVec3::splat(1024), "the shape was rewritten");
    let err = ZarrPyramid::new(image, Pick::default(), 1 << 20).err().expect("refused").to_string();
    assert!(err.contains("1024×1024×1024 (1024 MiB)") && err.contains("at most 256 MiB"), "{err}");
}
