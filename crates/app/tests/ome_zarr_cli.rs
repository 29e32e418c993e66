//! OME-Zarr on the command line (issue 48, items 1–2): `volgraph convert` writes a pyramid,
//! `volgraph info` lists its levels, chunks, codecs and sizes, and `--volume` of the store
//! renders exactly as the volume it was written from; a chunk lost from the store is drawn
//! empty with a warning naming it. (Cross-checked against ome-zarr-py by
//! `crates/python/tests/test_ome_zarr.py`.)

use std::path::Path;
use std::process::Command;

fn volgraph(args: &[&str], dir: &Path) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_volgraph"))
        .args(args)
        .current_dir(dir)
        .env("XDG_RUNTIME_DIR", std::env::var_os("XDG_RUNTIME_DIR").unwrap_or_else(|| "/tmp".into()))
        .output()
        .expect("runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn a_converted_store_renders_as_its_source_and_info_lists_its_levels() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let (ok, out, err) = volgraph(&["convert", "vessels96", "v.ome.zarr", "--chunk", "32"], d);
    assert!(ok, "{err}");
    assert!(out.contains("2 levels (96×96×96, 48×48×48)"), "{out}");
    let (ok, out, err) = volgraph(&["info", "v.ome.zarr"], d);
    assert!(ok, "{err}");
    assert!(out.contains("OME-Zarr (NGFF 0.5)") && out.contains("level \"1\": 48×48×48 U8, chunks 32×32×32"), "{out}");
    assert!(out.contains("codecs [bytes, zstd]") && out.contains("read in core: level \"0\""), "{out}");
    for (volume, png) in [("vessels96", "a.png"), ("v.ome.zarr", "b.png")] {
        let (ok, _, err) = volgraph(&["render", "modern/fastest", "--volume", volume, "--size", "64x64", "-o", png], d);
        assert!(ok, "{err}");
    }
    let (a, b) = (std::fs::read(d.join("a.png")).expect("a"), std::fs::read(d.join("b.png")).expect("b"));
    assert!(a == b, "the store's image differs from its source's");
    // A chunk with data lost from the store: drawn empty, named once.
    let chunk = d.join("v.ome.zarr/0/c/1/1/1");
    std::fs::remove_file(&chunk).expect("the tree crosses the middle chunk");
    let (ok, _, err) =
        volgraph(&["render", "modern/fastest", "--volume", "v.ome.zarr", "--size", "64x64", "-o", "c.png"], d);
    assert!(ok, "{err}");
    assert_eq!(err.matches("chunk (z, y, x) 1/1/1 is missing").count(), 1, "{err}");
    assert!(std::fs::read(d.join("c.png")).expect("c") != a);
}

#[test]
fn bad_conversions_say_why() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    std::fs::create_dir(d.join("full.zarr")).expect("dir");
    std::fs::write(d.join("full.zarr/x"), b"x").expect("file");
    for (args, want) in [
        (vec!["convert", "ml32", "full.zarr"], "exists and is not an empty folder"),
        (vec!["convert", "ml32", "o.zarr", "--chunk", "5"], "an even side from 2 to 1024"),
        (vec!["info", "full.zarr"], "not a Zarr store"),
    ] {
        let (ok, _, err) = volgraph(&args, d);
        assert!(!ok && err.contains(want), "{args:?}: {err}");
    }
}

#[test]
fn raw_files_convert_a_slab_at_a_time_and_render_as_the_file() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let (nx, ny, nz) = (40u32, 30u32, 21u32);
    let mut u16s = Vec::new();
    let mut f32s = Vec::new();
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let r = ((x as f32 - 20.0).powi(2) + (y as f32 - 15.0).powi(2) + (z as f32 - 10.0).powi(2)).sqrt();
                u16s.extend(((60_000.0 * (1.0 - r / 20.0).max(0.0)) as u16).to_le_bytes());
                // A float file with a NaN: its range is surveyed, the NaN replaced as the loader does.
                let v = if (x, y, z) == (1, 1, 1) { f32::NAN } else { 3.5 - r / 6.0 };
                f32s.extend(v.to_le_bytes());
            }
        }
    }
    std::fs::write(d.join("ball_40x30x21_uint16.raw"), u16s).expect("write");
    std::fs::write(d.join("ballf_40x30x21_float32.raw"), f32s).expect("write");
    for (raw, store) in [("ball_40x30x21_uint16.raw", "u.ome.zarr"), ("ballf_40x30x21_float32.raw", "f.ome.zarr")] {
        let (ok, out, err) = volgraph(&["convert", raw, store, "--chunk", "8", "--spacing", "1,1,2"], d);
        assert!(ok, "{err}");
        assert!(out.contains("(read a slab at a time)") && out.contains("1 levels (40×30×21)"), "{out}");
        let mut images = Vec::new();
        for volume in [raw, store] {
            let png = format!("{volume}.png");
            let spacing: &[&str] = if volume == raw { &["--spacing", "1,1,2"] } else { &[] };
            let mut args = vec!["render", "modern/fastest", "--volume", volume, "--size", "48x48", "-o", &png];
            args.extend(spacing);
            let (ok, _, err) = volgraph(&args, d);
            assert!(ok, "{err}");
            images.push(std::fs::read(d.join(&png)).expect("png"));
        }
        assert!(images[0] == images[1], "{store} renders unlike {raw}");
    }
}

/// Issue 48 item 3 at the command line: a store shown by the streaming graph is read brick by
/// brick — only what the view needs — and renders as the same volume held in memory as a
/// pyramid (the same levels, the same means; within 1/255); a chunk lost from the store is named
/// once and drawn empty; `--time-budget-ms 0` writes what the first frame drew and says so.
#[test]
fn a_store_streams_brick_by_brick_as_the_volume_in_memory_does() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let (ok, out, err) = volgraph(&["convert", "vessels256", "v.ome.zarr"], d);
    assert!(ok && out.contains("3 levels"), "{out}{err}");
    let graph = concat!(env!("CARGO_MANIFEST_DIR"), "/../../graphs/streaming/ray_guided.ron");
    let mut images = Vec::new();
    for (volume, png) in [("vessels256", "memory.png"), ("v.ome.zarr", "store.png")] {
        let (ok, _, err) = volgraph(&["render", graph, "--volume", volume, "--size", "96x96", "-o", png], d);
        assert!(ok, "{err}");
        assert!(err.contains("3 levels;") && err.contains("0 pending") && err.contains("to the full image"), "{err}");
        if volume.ends_with(".zarr") {
            assert!(err.contains("streamed brick by brick from 3 levels"), "{err}");
            // Only what the view needs: far fewer bricks than the 73 the store holds.
            let read: f64 = err
                .split("levels; ")
                .nth(1)
                .and_then(|rest| rest.split(" of ").next())
                .and_then(|n| n.trim().parse().ok())
                .unwrap_or(f64::NAN);
            assert!(read < 73.0, "{read} bricks read: {err}");
        }
        images.push(image::open(d.join(png)).expect("png").to_rgba8());
    }
    // Bricks land in whichever slots are free when they arrive, and the sampler's fixed-point
    // weights depend on where in the atlas a sample falls: 1/255 between runs, as between the
    // store and the volume in memory; a brick of the wrong level or place would differ by far more.
    let most = images[0].as_raw().iter().zip(images[1].as_raw()).map(|(a, b)| a.abs_diff(*b)).max();
    assert!(most.is_some_and(|m| m <= 1), "the streamed store renders unlike the volume in memory: {most:?}/255");
    // A chunk with data lost: named once, drawn empty.
    std::fs::remove_file(d.join("v.ome.zarr/0/c/2/2/2")).expect("the tree crosses the middle chunk");
    let (ok, _, err) = volgraph(
        &["render", graph, "--volume", "v.ome.zarr", "--size", "96x96", "--camera", "0,0,1.2", "-o", "lost.png"],
        d,
    );
    assert!(ok, "{err}");
    assert_eq!(err.matches("chunk (z, y, x) 2/2/2 is missing").count(), 1, "{err}");
    // No time to refine: the first frame, drawn from the coarsest level, and a note.
    let (ok, _, err) = volgraph(
        &["render", graph, "--volume", "v.ome.zarr", "--size", "96x96", "--time-budget-ms", "0", "-o", "first.png"],
        d,
    );
    assert!(ok, "{err}");
    assert!(err.contains("--time-budget-ms 0:") && err.contains("drawn from a coarser level"), "{err}");
    let first = image::open(d.join("first.png")).expect("png").to_rgba8();
    let most = first.as_raw().iter().zip(images[1].as_raw()).map(|(a, b)| a.abs_diff(*b)).max();
    assert!(most.is_some_and(|m| m > 8), "the first frame is drawn coarser than the full image: {most:?}/255");
}

/// A raw file larger than a volume is read into memory with, shown by a graph that holds its
/// volume whole, is refused before a byte of it is read, naming the streaming graph (a sparse
/// 3 GiB file: no disk).
#[test]
fn a_file_too_large_for_memory_is_refused_by_a_whole_volume_graph_with_the_way_to_stream_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let file = std::fs::File::create(d.join("big_1536x1024x2048_uint8.raw")).expect("create");
    file.set_len(3 << 30).expect("a sparse file");
    let (ok, _, err) =
        volgraph(&["render", "modern/fastest", "--volume", "big_1536x1024x2048_uint8.raw", "-o", "x.png"], d);
    assert!(
        !ok && err.contains("3.0 GiB of voxels")
            && err.contains("volgraph render streaming/ray_guided --volume big_1536x1024x2048_uint8.raw"),
        "{err}"
    );
}

/// Issue 48 item 4: a raw file larger than `--memory-mb`, shown by the streaming graph, is
/// streamed from the file brick by brick (one pass builds the coarse levels; the finer bricks
/// are read as rays ask for them) and renders as the same file read in core.
#[test]
fn a_raw_file_over_the_memory_budget_streams_from_the_file() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    // 18 MiB of shells and a rod: more than --memory-mb 16.
    let (nx, ny, nz) = (288u32, 256u32, 256u32);
    let mut bytes = Vec::with_capacity((nx * ny * nz) as usize);
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let p = glam::Vec3::new(x as f32, y as f32, z as f32);
                let shell = (p.distance(glam::Vec3::new(140.0, 128.0, 120.0)) - 80.0).abs();
                let rod = glam::Vec2::new(x as f32 - 200.0, z as f32 - 150.0).length();
                let v = (255.0 * (1.0 - shell / 6.0).max(0.0)).max(200.0 * (1.0 - rod / 10.0).max(0.0));
                bytes.push(v as u8);
            }
        }
    }
    std::fs::write(d.join("shells_288x256x256_uint8.raw"), bytes).expect("write");
    let graph = concat!(env!("CARGO_MANIFEST_DIR"), "/../../graphs/streaming/ray_guided.ron");
    let mut images = Vec::new();
    for (budget, png) in [("512", "core.png"), ("16", "file.png")] {
        let args = [
            "render",
            graph,
            "--volume",
            "shells_288x256x256_uint8.raw",
            "--memory-mb",
            budget,
            "--size",
            "96x96",
            "-o",
            png,
        ];
        let (ok, _, err) = volgraph(&args, d);
        assert!(ok, "{err}");
        assert!(err.contains("0 pending"), "{err}");
        assert_eq!(err.contains("streamed brick by brick from the file"), budget == "16", "{err}");
        images.push(image::open(d.join(png)).expect("png").to_rgba8());
    }
    // The same pyramid texel for texel (volgraph_accel::pyramid_file's tests); 1/255 between
    // runs for where bricks land in the atlas (as between a store and the volume in memory).
    let most = images[0].as_raw().iter().zip(images[1].as_raw()).map(|(a, b)| a.abs_diff(*b)).max();
    assert!(most.is_some_and(|m| m <= 1), "streamed from the file unlike in core: {most:?}/255");
    let shown = images[1].as_raw().chunks_exact(4).filter(|p| p[0] != p[1] || p[1] != p[2]).count();
    assert!(shown > 96 * 96 / 10, "the image shows the volume ({shown} coloured pixels)");
}
