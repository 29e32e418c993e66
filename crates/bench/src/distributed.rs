//! `volgraph bench distributed`: sort-last rendering measured under a real `mpirun`.
//!
//! 1. Compositing alone (`volgraph composite-bench`, synthetic rank images) for image sizes
//!    256² … 2048², rank counts and both algorithms, beside the memory-copy bound of the same
//!    bytes on this machine (one copy of everything the ranks sent, at this machine's memcpy
//!    rate) and IceT's anchor (radix-k: 64 Mpixel in 0.08 s at 32 K processes, Kendall et al.
//!    2010).
//! 2. Strong scaling of a whole frame (`volgraph render --distributed`), 1, 2, 4 ranks: each
//!    rank's render and compositing time from its line.
//!
//! Ranks of one machine share its cores (2 here): more ranks than cores measure the algorithm's
//! work and messages, not a speed-up.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{Context as _, anyhow, bail};
use serde::Serialize;
use volgraph_app::distributed::bench::CompositeTiming;

/// `bench distributed` arguments.
#[derive(clap::Args, Debug)]
pub struct DistributedArgs {
    /// Image sides for compositing alone.
    #[arg(long, value_delimiter = ',', default_value = "256,512,1024,2048")]
    pub sizes: Vec<u32>,
    /// Rank counts for compositing alone.
    #[arg(long, value_delimiter = ',', default_value = "2,4,8")]
    pub ranks: Vec<usize>,
    /// The largest radix-k group (IceT's default 8; 2 is binary swap).
    #[arg(long = "radix-k", default_value_t = 2)]
    pub radix_k: u32,
    /// Timed repetitions per configuration.
    #[arg(long, default_value_t = 5)]
    pub repeats: u32,
    /// Rank counts for the whole-frame strong scaling.
    #[arg(long = "frame-ranks", value_delimiter = ',', default_value = "1,2,4")]
    pub frame_ranks: Vec<usize>,
    /// The dataset of the whole frame.
    #[arg(long, default_value = "engine")]
    pub dataset: String,
    /// The graph of the whole frame.
    #[arg(long, default_value = "modern/fastest")]
    pub graph: String,
    /// The whole frame's viewport.
    #[arg(long = "frame-size", default_value = "512x512")]
    pub frame_size: String,
    /// Frames per whole-frame run (the last is reported; the first includes pipeline JIT).
    #[arg(long, default_value_t = 4)]
    pub frames: u32,
    /// Write the figures as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

#[derive(Serialize)]
struct CompositeRow {
    #[serde(flatten)]
    timing: CompositeTiming,
    memcpy_bound_ms: f64,
    mpixel_per_s: f64,
}

#[derive(Serialize)]
struct FrameRow {
    ranks: usize,
    /// The slowest rank's render + composite of the last frame.
    frame_ms: f64,
    render_ms: Vec<f64>,
    composite_ms: Vec<f64>,
    voxel_bytes: Vec<u64>,
    /// The bytes of the bricks the view needs (every rank's line says the same).
    needed_bytes: u64,
    /// The most any rank holds, as a share of `needed_bytes` (the goal: ≤ 1.3/N).
    largest_share: f64,
}

#[derive(Serialize)]
struct Report {
    machine: String,
    cores: usize,
    memcpy_gb_per_s: f64,
    icet_anchor: &'static str,
    composite: Vec<CompositeRow>,
    frames: Vec<FrameRow>,
}

/// The volgraph binary beside this program.
fn volgraph_binary() -> anyhow::Result<PathBuf> {
    let me = std::env::current_exe().context("this program's path")?;
    let exe = me.with_file_name(format!("volgraph{}", std::env::consts::EXE_SUFFIX));
    if !exe.exists() {
        bail!("{}: not found; build it with `cargo build -p volgraph-app --features mpi`", exe.display());
    }
    Ok(exe)
}

fn mpirun(ranks: usize, exe: &Path, args: &[String]) -> anyhow::Result<std::process::Output> {
    let mut cmd = Command::new("mpirun");
    cmd.arg("--oversubscribe");
    if Command::new("id").arg("-u").output().is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0") {
        cmd.arg("--allow-run-as-root");
    }
    cmd.args(["-n", &ranks.to_string()]).arg(exe).args(args);
    let out = cmd.output().context("mpirun (apt-get install openmpi-bin libopenmpi-dev libclang-dev)")?;
    if !out.status.success() {
        bail!("mpirun -n {ranks} volgraph {}: {}", args.join(" "), String::from_utf8_lossy(&out.stderr));
    }
    Ok(out)
}

/// This machine's memcpy rate, GB/s (best of five 256 MiB copies).
fn memcpy_rate() -> f64 {
    let src = vec![1u8; 256 << 20];
    let mut dst = vec![0u8; 256 << 20];
    let best = (0..5)
        .map(|_| {
            let t = Instant::now();
            dst.copy_from_slice(&src);
            std::hint::black_box(&dst);
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min);
    src.len() as f64 / best / 1e9
}

/// Runs the benchmark and prints the tables.
pub fn run(args: &DistributedArgs) -> anyhow::Result<()> {
    let exe = volgraph_binary()?;
    let gbps = memcpy_rate();
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!("bench distributed: {cores} cores, memcpy {gbps:.1} GB/s; ranks beyond {cores} share cores");
    println!();
    println!("Compositing alone (synthetic rank images: slabs along x of a disc; median of {} runs):", args.repeats);
    println!(
        "{:>5} {:>6} {:>12} {:>7} {:>10} {:>10} {:>12} {:>10}",
        "ranks", "size", "algorithm", "rounds", "ms", "MiB sent", "memcpy ms", "Mpixel/s"
    );
    let mut composite = Vec::new();
    for &ranks in &args.ranks {
        for &size in &args.sizes {
            for algorithm in ["direct-send", "radix-k"] {
                let out = mpirun(
                    ranks,
                    &exe,
                    &[
                        "composite-bench".into(),
                        "--size".into(),
                        size.to_string(),
                        "--composite".into(),
                        algorithm.into(),
                        "--radix-k".into(),
                        args.radix_k.to_string(),
                        "--repeats".into(),
                        args.repeats.to_string(),
                    ],
                )?;
                let line = String::from_utf8_lossy(&out.stdout);
                let timing: CompositeTiming =
                    serde_json::from_str(line.trim()).with_context(|| format!("rank 0 said: {line}"))?;
                let memcpy_bound_ms = timing.bytes as f64 / (gbps * 1e9) * 1e3;
                let mpixel_per_s = (size as f64 * size as f64) / (timing.median_ms / 1e3) / 1e6;
                println!(
                    "{:>5} {:>6} {:>12} {:>7} {:>10.2} {:>10.1} {:>12.2} {:>10.1}",
                    ranks,
                    format!("{size}²"),
                    algorithm,
                    timing.rounds,
                    timing.median_ms,
                    timing.bytes as f64 / (1 << 20) as f64,
                    memcpy_bound_ms,
                    mpixel_per_s
                );
                composite.push(CompositeRow { timing, memcpy_bound_ms, mpixel_per_s });
            }
        }
    }
    println!(
        "IceT anchor (Kendall et al. 2010): radix-k composites 64 Mpixel in 0.08 s at 32 K processes = 800 Mpixel/s"
    );
    println!();
    let volume = volgraph_accel::data_dir::dataset_path(&args.dataset).map_err(|e| anyhow!("{e}"))?;
    println!(
        "Whole frames: {} on {} at {}, frame {} of {} (the slowest rank's render + composite):",
        args.graph,
        volume.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default(),
        args.frame_size,
        args.frames,
        args.frames
    );
    println!(
        "{:>5} {:>10} {:>22} {:>22} {:>22} {:>16}",
        "ranks", "frame ms", "render ms (per rank)", "composite ms", "MiB voxels/rank", "most held/needed"
    );
    let out_png = std::env::temp_dir().join(format!("volgraph-bench-distributed-{}.png", std::process::id()));
    let mut frames = Vec::new();
    for &ranks in &args.frame_ranks {
        let out = mpirun(
            ranks,
            &exe,
            &[
                "render".into(),
                args.graph.clone(),
                "--volume".into(),
                volume.to_string_lossy().into_owned(),
                "--size".into(),
                args.frame_size.clone(),
                "--frames".into(),
                args.frames.to_string(),
                "--distributed".into(),
                "-o".into(),
                out_png.to_string_lossy().into_owned(),
            ],
        )?;
        let stderr = String::from_utf8_lossy(&out.stderr);
        let mut per_rank: Vec<(usize, u64, f64, f64, u64)> = stderr.lines().filter_map(parse_rank_line).collect();
        per_rank.sort_by_key(|r| r.0);
        if per_rank.len() != ranks {
            bail!("expected {ranks} rank lines, got:\n{stderr}");
        }
        let row = FrameRow {
            ranks,
            frame_ms: per_rank.iter().map(|r| r.2 + r.3).fold(0.0, f64::max),
            render_ms: per_rank.iter().map(|r| r.2).collect(),
            composite_ms: per_rank.iter().map(|r| r.3).collect(),
            voxel_bytes: per_rank.iter().map(|r| r.1).collect(),
            needed_bytes: per_rank[0].4,
            largest_share: per_rank.iter().map(|r| r.1).max().unwrap_or(0) as f64 / per_rank[0].4.max(1) as f64,
        };
        let list = |v: &[f64]| v.iter().map(|x| format!("{x:.1}")).collect::<Vec<_>>().join(" ");
        println!(
            "{:>5} {:>10.1} {:>22} {:>22} {:>22} {:>16}",
            ranks,
            row.frame_ms,
            list(&row.render_ms),
            list(&row.composite_ms),
            row.voxel_bytes
                .iter()
                .map(|b| format!("{:.1}", *b as f64 / (1 << 20) as f64))
                .collect::<Vec<_>>()
                .join(" "),
            format!("{:.1} % (1.3/N {:.1} %)", 100.0 * row.largest_share, 130.0 / ranks as f64)
        );
        frames.push(row);
    }
    std::fs::remove_file(&out_png).ok();
    let report = Report {
        machine: format!("{cores} cores"),
        cores,
        memcpy_gb_per_s: gbps,
        icet_anchor: "Kendall et al. 2010: radix-k, 64 Mpixel in 0.08 s at 32K processes",
        composite,
        frames,
    };
    if let Some(path) = &args.json {
        std::fs::write(path, serde_json::to_string_pretty(&report)? + "\n")
            .with_context(|| path.display().to_string())?;
    }
    Ok(())
}

/// `rank R of N holds B bytes of voxels (P % of the V bytes the view needs), rendered in X ms,
/// composited in Y ms`: (R, B, X, Y, V).
fn parse_rank_line(line: &str) -> Option<(usize, u64, f64, f64, u64)> {
    let rest = line.strip_prefix("rank ")?;
    let (rank, rest) = rest.split_once(" of ")?;
    let (_, rest) = rest.split_once(" holds ")?;
    let (bytes, rest) = rest.split_once(" bytes of voxels (")?;
    let (share, rest) = rest.split_once("), rendered in ")?;
    let needed = match share.split_once(" % of the ") {
        Some((_, needed)) => needed.strip_suffix(" bytes the view needs")?,
        None => "0",
    };
    let (render, rest) = rest.split_once(" ms, composited in ")?;
    let composite = rest.strip_suffix(" ms")?;
    Some((rank.parse().ok()?, bytes.parse().ok()?, render.parse().ok()?, composite.parse().ok()?, needed.parse().ok()?))
}

#[cfg(test)]
mod tests {
    #[test]
    fn rank_lines_parse() {
        assert_eq!(
            super::parse_rank_line(
                "rank 2 of 4 holds 591872 bytes of voxels (21.3 % of the 2778112 bytes the view needs), rendered in \
                 75.85 ms, composited in 0.16 ms"
            ),
            Some((2, 591872, 75.85, 0.16, 2778112))
        );
        assert_eq!(
            super::parse_rank_line(
                "rank 0 of 2 holds 27 bytes of voxels (the view needs none), rendered in 5.00 ms, composited in 0.10 ms"
            ),
            Some((0, 27, 5.0, 0.1, 0))
        );
    }
}
