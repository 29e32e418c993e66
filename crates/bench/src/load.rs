//! `volgraph bench load`: loading a DICOM series against reading the same voxels as one raw
//! file (issue 21: at most 2×). The series is generated (a CT-like int16 phantom in HU, one
//! file per slice, written with dicom-rs) into a scratch folder, with its raw twin beside it;
//! both are loaded `repeats` times, warm (the files in the OS cache, as a second open is), and
//! the medians compared.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context as _;
use glam::{DVec3, UVec3};
use volgraph_accel::load::{LoadOptions, load_volumes};
use volgraph_accel::volume::{Volume, VoxelData};

/// `bench load` arguments.
#[derive(clap::Args, Debug)]
pub struct LoadArgs {
    /// Slices in the series (1..=4096).
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(1..=MAX_EDGE))]
    pub slices: u32,
    /// Rows and columns of each slice (1..=4096).
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(1..=MAX_EDGE))]
    pub size: u32,
    /// Loads of each (the median is reported; 1..=1000).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..=1000))]
    pub repeats: u64,
    /// Write the figures as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// The most slices, and rows and columns per slice: 4096² int16 slices are 32 MiB each, and
/// DICOM's Rows and Columns are 16-bit.
const MAX_EDGE: i64 = 4096;

/// Copies of the phantom's voxels the run holds at once, at most: the phantom, the raw file's
/// bytes, and the volume each loader returns with what it reads.
const COPIES: u64 = 5;

/// Address space kept free under `ulimit -v` besides the copies: thread stacks, allocator
/// arenas, the DICOM writer's and reader's buffers, libraries mapped later.
const MARGIN: u64 = 256 << 20;

/// Refuses a series that would not fit in memory, before anything is allocated.
fn check_memory(args: &LoadArgs) -> anyhow::Result<()> {
    let bytes = u64::from(args.size) * u64::from(args.size) * u64::from(args.slices) * 2;
    let need = bytes.saturating_mul(COPIES);
    if let Some((available, which)) = available_memory()
        && need > available
    {
        anyhow::bail!(
            "--size {} --slices {}: the phantom is {:.0} MB of int16 and the benchmark holds up to {COPIES} copies of \
             it ({:.0} MB), more than the {:.0} MB of memory available; choose a smaller --size or --slices (available: {which})",
            args.size,
            args.slices,
            bytes as f64 / 1e6,
            need as f64 / 1e6,
            available as f64 / 1e6
        );
    }
    Ok(())
}

/// The memory this process may still take, where the system says, and where the figure comes
/// from: `MemAvailable` of `/proc/meminfo`, or, when lower, what the address-space limit
/// (`ulimit -v`, for the whole process) leaves: the limit less the address space the process
/// already uses (`VmSize` of `/proc/self/status`) less [`MARGIN`]. Where `VmSize` cannot be
/// read, the whole limit is taken, as before.
fn available_memory() -> Option<(u64, String)> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok().and_then(|text| {
        let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
        line.split_whitespace().nth(1)?.parse::<u64>().ok().map(|kib| kib * 1024)
    });
    let limit = std::fs::read_to_string("/proc/self/limits").ok().and_then(|text| {
        let line = text.lines().find(|l| l.starts_with("Max address space"))?;
        line.split_whitespace().nth(3)?.parse::<u64>().ok()
    });
    let used = std::fs::read_to_string("/proc/self/status").ok().and_then(|text| {
        let line = text.lines().find(|l| l.starts_with("VmSize:"))?;
        line.split_whitespace().nth(1)?.parse::<u64>().ok().map(|kib| kib * 1024)
    });
    let limit = limit.map(|limit| match used {
        Some(used) => (
            limit.saturating_sub(used).saturating_sub(MARGIN),
            format!(
                "the address-space limit of {:.0} MB less the {:.0} MB this process already uses and a margin of \
                 {:.0} MB",
                limit as f64 / 1e6,
                used as f64 / 1e6,
                MARGIN as f64 / 1e6
            ),
        ),
        None => (limit, format!("the address-space limit of {:.0} MB", limit as f64 / 1e6)),
    });
    let meminfo = meminfo.map(|a| (a, "MemAvailable of /proc/meminfo".to_string()));
    match (meminfo, limit) {
        (Some(a), Some(b)) => Some(if b.0 < a.0 { b } else { a }),
        (a, b) => a.or(b),
    }
}

/// A CT-like phantom in HU: air, a body of soft tissue, a bone core, with noise.
fn phantom(size: u32, slices: u32) -> anyhow::Result<Volume> {
    let (n, nz) = (size as usize, slices as usize);
    let mut values = Vec::new();
    values.try_reserve_exact(n * n * nz).map_err(|_| anyhow::anyhow!("not enough memory for the phantom"))?;
    values.resize(n * n * nz, 0i16);
    values.chunks_mut(n * n).enumerate().for_each(|(z, slice)| {
        for (i, v) in slice.iter_mut().enumerate() {
            let (x, y) = ((i % n) as f64 / n as f64 - 0.5, (i / n) as f64 / n as f64 - 0.5);
            let r = (x * x + y * y * 1.4).sqrt();
            let noise = ((i * 7919 + z * 104729) % 41) as i16 - 20;
            *v = if r < 0.12 {
                900
            } else if r < 0.4 {
                40
            } else {
                -1000
            } + noise;
        }
    });
    Ok(Volume::new("bench_ct", UVec3::new(size, size, slices), DVec3::new(0.7, 0.7, 1.0), VoxelData::I16(values)))
}

fn median_ms(mut runs: Vec<f64>) -> f64 {
    runs.sort_by(f64::total_cmp);
    runs[runs.len() / 2]
}

/// Runs the benchmark and prints the table.
pub fn run(args: &LoadArgs) -> anyhow::Result<serde_json::Value> {
    check_memory(args)?;
    let dir = std::env::temp_dir().join(format!("volgraph-bench-load-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let volume = phantom(args.size, args.slices)?;
    eprintln!("writing {} slices of {}² int16 to {} …", args.slices, args.size, dir.display());
    let series = dir.join("series");
    volgraph_accel::load::dicom::write_ct_series(&series, &volume).context("writing the series")?;
    let raw = dir.join(format!("bench_ct_{0}x{0}x{1}_int16.raw", args.size, args.slices));
    let VoxelData::I16(values) = &volume.data else { unreachable!("the phantom is int16") };
    std::fs::write(&raw, values.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>()).context("writing raw")?;

    let time = |paths: &[PathBuf]| -> anyhow::Result<(f64, Volume)> {
        let start = Instant::now();
        let loaded = load_volumes(paths, &LoadOptions::default()).map_err(|e| anyhow::anyhow!("{e}"))?;
        Ok((start.elapsed().as_secs_f64() * 1e3, loaded.volume))
    };
    // One untimed load of each warms the OS cache for both alike.
    let (_, from_raw) = time(std::slice::from_ref(&raw))?;
    let (_, from_dicom) = time(std::slice::from_ref(&series))?;
    anyhow::ensure!(from_raw.data == from_dicom.data, "the series and its raw twin loaded different voxels");
    let (mut raw_ms, mut dicom_ms) = (Vec::new(), Vec::new());
    for _ in 0..args.repeats {
        raw_ms.push(time(std::slice::from_ref(&raw))?.0);
        dicom_ms.push(time(std::slice::from_ref(&series))?.0);
    }
    let (r, d) = (median_ms(raw_ms), median_ms(dicom_ms));
    let bytes = volume.voxel_count() * 2;
    let threads = rayon::current_num_threads();
    println!(
        "load {} slices of {}² int16 ({:.0} MB), median of {}, {threads} threads",
        args.slices,
        args.size,
        bytes as f64 / 1e6,
        args.repeats
    );
    println!("| input | ms | MB/s | vs raw |");
    println!("|---|---:|---:|---:|");
    println!("| raw file | {r:.1} | {:.0} | 1.00× |", bytes as f64 / 1e3 / r);
    println!("| DICOM series ({} files) | {d:.1} | {:.0} | {:.2}× |", args.slices, bytes as f64 / 1e3 / d, d / r);
    println!("goal: DICOM ≤ 2× raw — {}", if d <= 2.0 * r { "met" } else { "not met" });
    let report = serde_json::json!({
        "slices": args.slices, "size": args.size, "bytes": bytes, "threads": threads,
        "raw_ms": r, "dicom_ms": d, "ratio": d / r,
    });
    if let Some(path) = &args.json {
        std::fs::write(path, serde_json::to_string_pretty(&report)?).with_context(|| path.display().to_string())?;
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(report)
}
