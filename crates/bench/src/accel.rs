//! `volgraph bench accel`: CPU timings of the acceleration structures of `volgraph-accel`.
//!
//! (a) Krüger & Westermann 2003 §2.3: build the 8³ min/max grid of the 256³ engine volume and
//! classify it under a transfer function (median of `repeats`).
//! (b) Ruijters & Vilanova 2006 §7/§8: rebuild every per-brick octree of a procedural 512³
//! 16-bit volume (256 MiB, like the paper's) after a transfer-function change, with 64³ bricks
//! and an 8³ octree limit, median over several TF changes, next to the paper's 3.5 ms on a
//! 3.0 GHz Xeon. The volume is generated here so the benchmark needs no large file.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use glam::{DVec3, UVec3};
use rayon::prelude::*;
use serde::Serialize;
use volgraph_accel::bricks::{BrickLayout, ViewPoint};
use volgraph_accel::classify::OpacityClassifier;
use volgraph_accel::minmax::MinMaxGrid;
use volgraph_accel::octree::{OctreeHierarchy, OctreeVisibility};
use volgraph_accel::volume::{Volume, VoxelData};

/// The octree rebuild time Ruijters & Vilanova 2006 §8 report for a 512³ 16-bit volume, 64³
/// bricks and an 8³ octree limit on a 3.0 GHz Xeon.
pub const PAPER_OCTREE_REBUILD_MS: f64 = 3.5;

/// Options of `volgraph bench accel`.
#[derive(Clone, Debug)]
pub struct AccelBenchOptions {
    /// The data folder; the engine volume is read from
    /// `<data_dir>/volumes/engine_vollib_256x256x256_uint8.raw`.
    pub data_dir: PathBuf,
    /// Timed repetitions per measurement (at least 1 is used).
    pub repeats: usize,
    /// Where to write the JSON report, if anywhere.
    pub json_out: Option<PathBuf>,
}

/// Results of `volgraph bench accel` (also written as JSON).
#[derive(Clone, Debug, Serialize)]
pub struct AccelBenchReport {
    /// Rayon worker threads used.
    pub threads: usize,
    /// Repetitions per measurement.
    pub repeats: usize,
    /// (a) Min/max grid of the engine volume.
    pub minmax: MinMaxBench,
    /// (b) Octree rebuild after TF changes.
    pub octree: OctreeBench,
}

/// (a) Krüger & Westermann 2003 §2.3 on the 256³ engine volume.
#[derive(Clone, Debug, Serialize)]
pub struct MinMaxBench {
    /// Volume file read.
    pub volume: String,
    /// Block edge in voxels.
    pub block_size: u32,
    /// Blocks per axis.
    pub grid_dims: [u32; 3],
    /// Median ms to build the min/max grid.
    pub build_ms: f64,
    /// Median ms to classify every block (per-block empty flags) under the TF.
    pub classify_ms: f64,
    /// Median ms for build + classification together.
    pub build_and_classify_ms: f64,
    /// Median ms to fill the 256×256 8-bit classification table.
    pub table_u8_ms: f64,
    /// Fraction of blocks empty under the TF.
    pub empty_fraction: f64,
}

/// (b) Ruijters & Vilanova 2006 §7 octree rebuild on a procedural 512³ u16 volume.
#[derive(Clone, Debug, Serialize)]
pub struct OctreeBench {
    /// Volume dims.
    pub dims: [u32; 3],
    /// Bytes of the volume (256 MiB).
    pub volume_bytes: u64,
    /// Brick edge in cells.
    pub brick_cells: u32,
    /// Octree limit (leaf edge) in cells.
    pub min_node_cells: u32,
    /// Bricks.
    pub bricks: usize,
    /// Octree nodes over all bricks.
    pub nodes: usize,
    /// Leaves over all bricks.
    pub leaves: usize,
    /// ms to generate the volume (not part of any comparison).
    pub generate_ms: f64,
    /// ms for the TF-independent part, once per volume.
    pub hierarchy_build_ms: f64,
    /// Number of TF changes timed.
    pub tf_changes: usize,
    /// Median ms to rebuild every octree after a TF change.
    pub rebuild_ms: f64,
    /// Minimum over the TF changes.
    pub rebuild_min_ms: f64,
    /// The paper's 3.5 ms.
    pub paper_ms: f64,
    /// `rebuild_ms / paper_ms` (below 1: faster than the paper).
    pub ratio_to_paper: f64,
    /// Median ms to traverse every brick's octree front to back (threshold 0.5) after the rebuild.
    pub traverse_ms: f64,
    /// Boxes emitted by that traversal for the last TF.
    pub boxes: usize,
    /// Median ms of everything `raycast_bricks` does on the CPU after a TF change: the octree
    /// rebuild, brick visibility, the boxes rasterized into leaves and their leap distances.
    pub tf_change_ms: f64,
}

fn median(v: Vec<f64>) -> f64 {
    volgraph_accel::stats::median(&v)
}

fn time_ms<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let start = Instant::now();
    let out = f();
    (out, start.elapsed().as_secs_f64() * 1e3)
}

/// A LUT of 256 texels, transparent outside `[lo, hi]` (normalized), opaque ramp inside.
fn window_lut(lo: f64, hi: f64) -> Vec<[f32; 4]> {
    (0..256)
        .map(|i| {
            let s = (i as f64 + 0.5) / 256.0;
            let a = if s >= lo && s <= hi { ((s - lo) / (hi - lo).max(1e-9)).max(0.05) } else { 0.0 };
            [1.0, 0.8, 0.6, a as f32]
        })
        .collect()
}

/// Runs both benchmarks, prints a markdown table and writes the JSON report if asked.
pub fn run(opts: &AccelBenchOptions) -> anyhow::Result<AccelBenchReport> {
    let repeats = opts.repeats.max(1);
    let minmax = bench_minmax(opts, repeats)?;
    let octree = bench_octree(repeats)?;
    let report = AccelBenchReport { threads: rayon::current_num_threads(), repeats, minmax, octree };
    print_table(&report)?;
    if let Some(path) = &opts.json_out {
        let json = serde_json::to_string_pretty(&report)?;
        std::fs::write(path, json).with_context(|| format!("writing the JSON report to {}", path.display()))?;
    }
    Ok(report)
}

fn bench_minmax(opts: &AccelBenchOptions, repeats: usize) -> anyhow::Result<MinMaxBench> {
    let path = opts.data_dir.join("volumes/engine_vollib_256x256x256_uint8.raw");
    let bytes = std::fs::read(&path).with_context(|| {
        format!(
            "cannot read the engine volume {} (256³ uint8 raw, 16 MiB); put it there or pass \
             another data folder",
            path.display()
        )
    })?;
    let dims = UVec3::splat(256);
    anyhow::ensure!(
        bytes.len() == 256 * 256 * 256,
        "{} has {} bytes, but a 256³ uint8 volume has {}",
        path.display(),
        bytes.len(),
        256 * 256 * 256
    );
    let volume = Volume {
        dims,
        spacing: DVec3::ONE,
        data: VoxelData::U8(bytes),
        name: "engine".into(),
        value_range: (0.0, 255.0),
        meta: Default::default(),
    };
    let block_size = 8;
    let classifier = OpacityClassifier::new(&window_lut(0.3, 1.0))?;
    let (mut build, mut classify, mut both, mut table) = (vec![], vec![], vec![], vec![]);
    let mut empty_fraction = 0.0;
    let mut grid_dims = UVec3::ZERO;
    for _ in 0..repeats {
        let (grid, b) = time_ms(|| MinMaxGrid::build(&volume, block_size));
        let grid = grid?;
        let (flags, c) = time_ms(|| classifier.empty_flags(&grid));
        let empty = flags.iter().filter(|f| **f != 0).count();
        empty_fraction = empty as f64 / flags.len() as f64;
        grid_dims = grid.dims();
        let (_, t) = time_ms(|| classifier.table_u8());
        build.push(b);
        classify.push(c);
        both.push(b + c);
        table.push(t);
    }
    Ok(MinMaxBench {
        volume: path.display().to_string(),
        block_size,
        grid_dims: grid_dims.to_array(),
        build_ms: median(build),
        classify_ms: median(classify),
        build_and_classify_ms: median(both),
        table_u8_ms: median(table),
        empty_fraction,
    })
}

/// A smooth 512³ u16 volume: a few Gaussian blobs over a dark background plus hashed noise.
fn generate_blobs(n: u32) -> Volume {
    let blobs: [(DVec3, f64, f64); 6] = [
        (DVec3::new(0.3, 0.35, 0.4), 0.12, 0.9),
        (DVec3::new(0.65, 0.6, 0.5), 0.18, 0.6),
        (DVec3::new(0.5, 0.25, 0.7), 0.08, 1.0),
        (DVec3::new(0.2, 0.75, 0.3), 0.10, 0.4),
        (DVec3::new(0.8, 0.3, 0.25), 0.06, 0.75),
        (DVec3::new(0.45, 0.7, 0.8), 0.14, 0.3),
    ];
    let slice = (n * n) as usize;
    let mut data = vec![0u16; slice * n as usize];
    data.par_chunks_mut(slice).enumerate().for_each(|(z, out)| {
        let pz = (z as f64 + 0.5) / n as f64;
        for y in 0..n {
            let py = (y as f64 + 0.5) / n as f64;
            for x in 0..n {
                let p = DVec3::new((x as f64 + 0.5) / n as f64, py, pz);
                let mut v = 0.0;
                for (c, r, w) in &blobs {
                    let d2 = (p - *c).length_squared() / (r * r);
                    if d2 < 9.0 {
                        v += w * (-d2).exp();
                    }
                }
                let i = x + n * (y + n * z as u32);
                let hash = i.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
                let noise = ((hash >> 16) & 0x3ff) as f64 / 1023.0 - 0.5;
                let value = (v.min(1.0) * 60000.0 + noise * 800.0 + 400.0).clamp(0.0, 65535.0);
                out[(x + n * y) as usize] = value as u16;
            }
        }
    });
    Volume {
        dims: UVec3::splat(n),
        spacing: DVec3::ONE,
        data: VoxelData::U16(data),
        name: format!("blobs-{n}"),
        value_range: (0.0, 65535.0),
        meta: Default::default(),
    }
}

fn bench_octree(repeats: usize) -> anyhow::Result<OctreeBench> {
    let n = 512;
    let (volume, generate_ms) = time_ms(|| generate_blobs(n));
    let (brick_cells, min_node_cells) = (64, 8);
    let layout = BrickLayout::new(volume.dims, brick_cells, 1)?;
    let (hierarchy, hierarchy_build_ms) = time_ms(|| OctreeHierarchy::build(&volume, &layout, min_node_cells));
    let hierarchy = hierarchy?;
    drop(volume); // Only the hierarchy is needed from here on.
    // TF changes: windows sliding over the value range, as when a user drags a TF editor.
    let windows: Vec<(f64, f64)> = (0..8).map(|k| (0.05 + 0.1 * k as f64, 0.25 + 0.1 * k as f64)).collect();
    let classifiers =
        windows.iter().map(|(lo, hi)| OpacityClassifier::new(&window_lut(*lo, *hi))).collect::<Result<Vec<_>, _>>()?;
    let mut visibility = OctreeVisibility::default();
    hierarchy.classify_into(&classifiers[0], &mut visibility); // warm-up: allocations
    let mut rebuild = Vec::new();
    for _ in 0..repeats {
        for classifier in &classifiers {
            let (_, ms) = time_ms(|| hierarchy.classify_into(classifier, &mut visibility));
            rebuild.push(ms);
        }
    }
    let view = ViewPoint::Direction(DVec3::new(0.3, -0.5, 0.8));
    let order = layout.front_to_back(view);
    let mut traverse = Vec::new();
    let mut boxes = Vec::new();
    for _ in 0..repeats {
        boxes.clear();
        let (_, ms) = time_ms(|| {
            for brick in &order {
                hierarchy.draw_boxes(&visibility, *brick as usize, 0.5, view, &mut boxes);
            }
        });
        traverse.push(ms);
    }
    // The whole CPU side of a TF change in raycast_bricks (ratio 1, as its graphs use).
    let grid = volgraph_accel::brick_leaves::leaf_grid(layout.volume_dims(), min_node_cells);
    let mut tf_change = Vec::new();
    for _ in 0..repeats {
        for classifier in &classifiers {
            let (_, ms) = time_ms(|| {
                hierarchy.classify_into(classifier, &mut visibility);
                volgraph_accel::brick_leaves::classify_leaves(&hierarchy, &visibility, &layout, grid, 1.0)
            });
            tf_change.push(ms);
        }
    }
    let rebuild_min_ms = rebuild.iter().copied().fold(f64::INFINITY, f64::min);
    let rebuild_ms = median(rebuild);
    Ok(OctreeBench {
        dims: [n; 3],
        volume_bytes: (n as u64).pow(3) * 2,
        brick_cells,
        min_node_cells,
        bricks: layout.brick_count(),
        nodes: hierarchy.node_count(),
        leaves: hierarchy.leaf_count(),
        generate_ms,
        hierarchy_build_ms,
        tf_changes: classifiers.len() * repeats,
        rebuild_ms,
        rebuild_min_ms,
        paper_ms: PAPER_OCTREE_REBUILD_MS,
        ratio_to_paper: rebuild_ms / PAPER_OCTREE_REBUILD_MS,
        traverse_ms: median(traverse),
        boxes: boxes.len(),
        tf_change_ms: median(tf_change),
    })
}

fn print_table(r: &AccelBenchReport) -> anyhow::Result<()> {
    use std::fmt::Write as _;
    let mut out = String::new();
    let m = &r.minmax;
    let o = &r.octree;
    let _ = writeln!(out, "## volgraph bench accel ({} threads, median of {} repeats)\n", r.threads, r.repeats);
    let _ = writeln!(out, "| measurement | ms | notes |");
    let _ = writeln!(out, "|---|---:|---|");
    let _ = writeln!(
        out,
        "| min/max grid build, engine 256³ u8, {}³ blocks | {:.2} | grid {:?} |",
        m.block_size, m.build_ms, m.grid_dims
    );
    let _ = writeln!(
        out,
        "| classify all blocks (empty flags) | {:.3} | {:.1}% empty |",
        m.classify_ms,
        100.0 * m.empty_fraction
    );
    let _ = writeln!(out, "| build + classify | {:.2} | K-W 2003 §2.3 |", m.build_and_classify_ms);
    let _ = writeln!(out, "| 256×256 u8 table | {:.3} | |", m.table_u8_ms);
    let _ = writeln!(
        out,
        "| octree hierarchy build (once per volume), 512³ u16 | {:.1} | {} bricks, {} nodes, {} leaves |",
        o.hierarchy_build_ms, o.bricks, o.nodes, o.leaves
    );
    let _ = writeln!(
        out,
        "| **octree rebuild after a TF change** | **{:.3}** | min {:.3}; {} TF changes |",
        o.rebuild_ms, o.rebuild_min_ms, o.tf_changes
    );
    let _ =
        writeln!(out, "| R-V 2006 §8 (3.0 GHz Xeon) | {:.1} | ours / paper = {:.3} |", o.paper_ms, o.ratio_to_paper);
    let _ = writeln!(out, "| octree traversal, all bricks, threshold 0.5 | {:.3} | {} boxes |", o.traverse_ms, o.boxes);
    let _ = writeln!(
        out,
        "| **TF change in raycast_bricks: octrees + brick visibility + leaves + leap distances** | **{:.3}** | ours / \
         paper's octree rebuild = {:.3} |",
        o.tf_change_ms,
        o.tf_change_ms / o.paper_ms
    );
    volgraph_app::stdout::write_stdout(&out)
}
