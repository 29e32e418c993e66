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
    /// Slices in the series.
    #[arg(long, default_value_t = 512)]
    pub slices: u32,
    /// Rows and columns of each slice.
    #[arg(long, default_value_t = 512)]
    pub size: u32,
    /// Loads of each (the median is reported).
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
    /// Write the figures as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// A CT-like phantom in HU: air, a body of soft tissue, a bone core, with noise.
fn phantom(size: u32, slices: u32) -> Volume {
    let (n, nz) = (size as usize, slices as usize);
    let mut values = vec![0i16; n * n * nz];
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
    Volume::new("bench_ct", UVec3::new(size, size, slices), DVec3::new(0.7, 0.7, 1.0), VoxelData::I16(values))
}

fn median_ms(mut runs: Vec<f64>) -> f64 {
    runs.sort_by(f64::total_cmp);
    runs[runs.len() / 2]
}

/// Runs the benchmark and prints the table.
pub fn run(args: &LoadArgs) -> anyhow::Result<serde_json::Value> {
    let dir = std::env::temp_dir().join(format!("volgraph-bench-load-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let volume = phantom(args.size, args.slices);
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
    for _ in 0..args.repeats.max(1) {
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
