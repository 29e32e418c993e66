//! Compositing alone, timed: `volgraph composite-bench` under mpirun, which
//! `volgraph bench distributed` runs for each image size, rank count and algorithm. Every rank
//! makes a synthetic image shaped like a rank's render of a volume split along x (a band of the
//! volume's disc on screen, overlapping its neighbours, partly transparent), then the ranks
//! composite it `repeats` times; rank 0 times each from a common start to the gathered image.

use std::time::Instant;

use anyhow::anyhow;
use serde::{Deserialize, Serialize};
use volgraph_composite::{Compositor, Exchange, Layer, agree, all_gather};

use super::CompositeAlgorithm;
use crate::cli::CliError;

/// `volgraph composite-bench`'s arguments.
#[derive(clap::Args, Debug, Clone)]
pub struct CompositeBenchArgs {
    /// Image side in pixels (square).
    #[arg(long, default_value_t = 512)]
    pub size: u32,
    /// The algorithm.
    #[arg(long, value_enum, default_value = "radix-k")]
    pub composite: CompositeAlgorithm,
    /// The largest radix-k group.
    #[arg(long = "radix-k", default_value_t = 8)]
    pub radix_k: u32,
    /// Timed repetitions (after one warm-up).
    #[arg(long, default_value_t = 5)]
    pub repeats: u32,
}

/// One configuration's figures (rank 0's JSON line).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CompositeTiming {
    /// Ranks.
    pub ranks: usize,
    /// Image side.
    pub size: u32,
    /// Algorithm.
    pub algorithm: CompositeAlgorithm,
    /// Rounds of exchange.
    pub rounds: u32,
    /// Median ms from a common start to the whole image on rank 0 (compositing and gather).
    pub median_ms: f64,
    /// Bytes all ranks sent while compositing (spans only), plus the gather.
    pub bytes: u64,
    /// Non-empty pixels over all rank images.
    pub pixels: u64,
}

/// Runs the benchmark under MPI and prints rank 0's line.
#[cfg(feature = "mpi")]
pub fn launch(args: &CompositeBenchArgs) -> Result<(), CliError> {
    let mut ex = volgraph_composite::mpi_exchange::MpiExchange::initialize()
        .ok_or_else(|| CliError::Other(anyhow!("internal: MPI was initialized twice")))?;
    if let Some(timing) = run(&mut ex, args)? {
        crate::stdout::write_stdout(&(serde_json::to_string(&timing).map_err(|e| anyhow!(e))? + "\n"))?;
    }
    Ok(())
}

/// Without MPI: says how to get a build with it.
#[cfg(not(feature = "mpi"))]
pub fn launch(_: &CompositeBenchArgs) -> Result<(), CliError> {
    super::launch()
}

/// The synthetic image of `rank` of `ranks`.
pub fn synthetic_layer(size: u32, rank: usize, ranks: usize) -> Layer {
    let mut layer = Layer::transparent(size, size);
    let n = size as f64;
    let (band_lo, band_hi) = (n * rank as f64 / ranks as f64 - n / 8.0, n * (rank + 1) as f64 / ranks as f64 + n / 8.0);
    for y in 0..size {
        for x in 0..size {
            let (fx, fy) = (x as f64 + 0.5, y as f64 + 0.5);
            let r = ((fx - n / 2.0).powi(2) + (fy - n / 2.0).powi(2)).sqrt() / n;
            if r < 0.45 && fx >= band_lo && fx < band_hi {
                let a = (0.3 * (1.0 - r)) as f32;
                layer.pixels[(y * size + x) as usize] = [a * 0.8, a * 0.6, a * 0.4, a];
            }
        }
    }
    layer
}

/// Times compositing on every rank of `ex`; rank 0 gets the figures.
pub fn run<E: Exchange + ?Sized>(ex: &mut E, args: &CompositeBenchArgs) -> Result<Option<CompositeTiming>, CliError> {
    let (rank, ranks) = (ex.rank(), ex.size());
    let fail = |e: volgraph_composite::ExchangeError| CliError::Other(anyhow!("{e}"));
    let layer = synthetic_layer(args.size, rank, ranks);
    let factors = volgraph_accel::kd_split::radix_factors(ranks, args.radix_k.max(2) as usize);
    let rounds: Vec<usize> = factors.iter().rev().copied().collect();
    // Slabs along x seen from -x: front to back is rank order, and every node's children too.
    let orders: Vec<Vec<usize>> = rounds.iter().map(|&k| (0..k).collect()).collect();
    let order: Vec<usize> = (0..ranks).collect();
    let mut times = Vec::new();
    let mut sent = 0;
    let mut round_count = 0;
    // One compositor for every repeat, as a renderer keeps one from frame to frame: the warm-up
    // allocates its buffers.
    // Compositing works in the rank's image, as a renderer's freshly read frame: each repeat
    // starts from a copy, made before the clock starts.
    let mut compositor = Compositor::new();
    let mut image = layer.clone();
    for repeat in 0..=args.repeats {
        image.clone_from(&layer);
        agree(ex, Ok(())).map_err(fail)?;
        let started = Instant::now();
        let stats = match args.composite {
            CompositeAlgorithm::DirectSend => compositor.direct_send(ex, &mut image, 0..args.size, &order),
            CompositeAlgorithm::RadixK => compositor.radix_k(ex, &mut image, &rounds, &orders),
        }
        .map_err(fail)?;
        compositor.gather(ex, &mut image).map_err(fail)?;
        let ms = started.elapsed().as_secs_f64() * 1e3;
        if repeat > 0 {
            times.push(ms);
        }
        sent = stats.bytes_sent + compositor.gathered_bytes();
        round_count = stats.rounds;
    }
    let all = all_gather(ex, sent.to_le_bytes().to_vec()).map_err(fail)?;
    let bytes = all.iter().map(|b| u64::from_le_bytes(b.as_slice().try_into().unwrap_or([0; 8]))).sum();
    let pixels: u64 = (0..ranks)
        .map(|r| synthetic_layer(args.size, r, ranks).pixels.iter().filter(|p| p[3] > 0.0).count() as u64)
        .sum();
    Ok((rank == 0).then(|| CompositeTiming {
        ranks,
        size: args.size,
        algorithm: args.composite,
        rounds: round_count,
        median_ms: volgraph_accel::stats::median(&times),
        bytes,
        pixels,
    }))
}
