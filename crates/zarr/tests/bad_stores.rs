//! Broken stores get messages naming the store, the level or chunk and the field — never a
//! panic, a hang or a huge allocation: a missing chunk (drawn empty, one warning naming it), a
//! corrupt chunk (an error line naming it; the rest still reads), an unknown codec, an NGFF
//! version not read, 10⁹ voxels per axis, a chunk shape of 0, levels that do not halve.

use std::path::{Path, PathBuf};

use glam::{DVec3, UVec3};
use volgraph_accel::volume::{Volume, VoxelData};
use volgraph_zarr::{InMemory, OmeZarr, Pick, WriteOptions, write_pyramid};

/// A 32³ uint8 store of two levels (chunks 16³), every voxel 200.
fn store(dir: &Path) -> PathBuf {
    let out = dir.join("full.ome.zarr");
    let source = Volume::new("full", UVec3::splat(32), DVec3::ONE, VoxelData::U8(vec![200; 32 * 32 * 32]));
    write_pyramid(
        &mut InMemory(source.clone()),
        &out,
        &WriteOptions { chunk: 16, coarsest: 16, zstd_level: 1 },
        &mut |_, _| {},
    )
    .expect("written");
    out
}

fn edit_json(path: &Path, edit: impl FnOnce(&mut serde_json::Value)) {
    let mut value: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).expect("read json")).expect("json");
    edit(&mut value);
    std::fs::write(path, serde_json::to_string_pretty(&value).expect("json")).expect("write json");
}

fn open_error(path: &Path) -> String {
    match OmeZarr::open(path) {
        Ok(_) => panic!("{} opened", path.display()),
        Err(e) => e.to_string(),
    }
}

#[test]
fn a_missing_chunk_reads_as_the_fill_value_with_a_warning_naming_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = store(dir.path());
    std::fs::remove_file(out.join("0/c/1/0/1")).expect("chunk 1/0/1 is a file");
    let image = OmeZarr::open(&out).expect("opened");
    let read = image.read_level(0, Pick::default(), 1 << 30).expect("read");
    assert_eq!(read.notes.len(), 1, "{:?}", read.notes);
    assert!(read.notes[0].contains("chunk (z, y, x) 1/0/1 is missing"), "{}", read.notes[0]);
    let VoxelData::U8(v) = &read.volume.data else { panic!("u8") };
    let at = |x: usize, y: usize, z: usize| v[(z * 32 + y) * 32 + x];
    assert_eq!((at(20, 3, 20), at(3, 3, 3)), (0, 200));
}

#[test]
fn a_corrupt_chunk_is_an_error_naming_it_and_the_rest_still_reads() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = store(dir.path());
    std::fs::write(out.join("0/c/0/1/0"), b"not zstd at all").expect("overwrite");
    let read = OmeZarr::open(&out).and_then(|i| i.read_level(0, Pick::default(), 1 << 30)).expect("read");
    assert_eq!(read.notes.len(), 1, "{:?}", read.notes);
    assert!(
        read.notes[0].starts_with("error:") && read.notes[0].contains("chunk (z, y, x) 0/1/0"),
        "{}",
        read.notes[0]
    );
    let VoxelData::U8(v) = &read.volume.data else { panic!("u8") };
    assert_eq!(v.iter().filter(|&&x| x == 200).count(), 32 * 32 * 32 - 16 * 16 * 16);
}

/// A metadata edit: which store, which file, the edit, what the message must say.
type Edit = (&'static str, &'static str, Box<dyn Fn(&mut serde_json::Value)>, &'static str);

#[test]
fn metadata_problems_are_named() {
    let dir = tempfile::tempdir().expect("temp dir");
    let cases: [Edit; 5] = [
        ("codec", "0/zarr.json", Box::new(|v| v["codecs"][1]["name"] = "lz_unheard_of".into()), "lz_unheard_of"),
        ("version", "zarr.json", Box::new(|v| v["attributes"]["ome"]["version"] = "0.3".into()), "\"0.3\""),
        ("huge", "0/zarr.json", Box::new(|v| v["shape"][2] = 1_000_000_000u64.into()), "holds 1000000000 voxels"),
        (
            "chunk0",
            "0/zarr.json",
            Box::new(|v| v["chunk_grid"]["configuration"]["chunk_shape"][0] = 0.into()),
            "level \"0\"",
        ),
        ("halving", "1/zarr.json", Box::new(|v| v["shape"] = serde_json::json!([16, 16, 7])), "halves an axis"),
    ];
    for (name, file, edit, want) in cases {
        let case = dir.path().join(name);
        std::fs::create_dir(&case).expect("dir");
        let out = store(&case);
        edit_json(&out.join(file), edit);
        let e = open_error(&out);
        assert!(e.contains(want) && e.contains("full.ome.zarr"), "{name}: {e}");
    }
    let e = open_error(dir.path());
    assert!(e.contains("not a Zarr store"), "{e}");
}

#[test]
fn a_level_over_the_limit_is_refused_naming_the_coarser_ones() {
    let dir = tempfile::tempdir().expect("temp dir");
    let image = OmeZarr::open(&store(dir.path())).expect("opened");
    assert_eq!(image.finest_within(10_000), Some(1));
    let e = image.read_level(0, Pick::default(), 10_000).err().expect("refused").to_string();
    assert!(e.contains("level \"0\"") && e.contains("coarser levels: 1"), "{e}");
    let e = image.read_level(0, Pick { time: 2, channel: 0 }, 1 << 30).err().expect("refused").to_string();
    assert!(e.contains("time point 2") && e.contains("no time point axis"), "{e}");
}

/// Replaces `path` by a FIFO (a read of it would block for ever).
fn fifo_at(path: &Path) {
    std::fs::remove_file(path).expect("a file to replace");
    let made = std::process::Command::new("mkfifo").arg(path).status().expect("mkfifo runs");
    assert!(made.success(), "mkfifo {}", path.display());
}

#[test]
fn a_fifo_in_a_store_is_refused_never_read() {
    let dir = tempfile::tempdir().expect("temp dir");
    // In a level's metadata: the store does not open.
    let meta = dir.path().join("meta");
    std::fs::create_dir(&meta).expect("dir");
    let out = store(&meta);
    fifo_at(&out.join("0/zarr.json"));
    let e = open_error(&out);
    assert!(e.contains("level \"0\"") && e.contains("FIFO"), "{e}");
    // In a chunk's place: that chunk is an error line, the rest reads.
    let chunk = dir.path().join("chunk");
    std::fs::create_dir(&chunk).expect("dir");
    let out = store(&chunk);
    fifo_at(&out.join("0/c/0/0/0"));
    let read = OmeZarr::open(&out).and_then(|i| i.read_level(0, Pick::default(), 1 << 30)).expect("read");
    assert!(
        read.notes.len() == 1 && read.notes[0].contains("0/0/0") && read.notes[0].contains("FIFO"),
        "{:?}",
        read.notes
    );
    // Among the chunk ranges: they are left unused (the missing-chunk warnings fall back to a note).
    let ranges = dir.path().join("ranges");
    std::fs::create_dir(&ranges).expect("dir");
    let out = store(&ranges);
    fifo_at(&out.join("chunk_ranges/0/c/0/0/0/0"));
    assert!(OmeZarr::open(&out).and_then(|i| i.read_level(0, Pick::default(), 1 << 30)).is_ok());
}
