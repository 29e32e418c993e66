//! `volgraph bench graphs`: graphs × datasets × transfer functions × viewports (× a parameter
//! sweep), each timed over frames that turn the volume about y, as the papers did. Prints a
//! markdown table of median ms/frame, speed-up against a baseline graph measured in the same run,
//! per-pass GPU time, samples per pixel and million samples per second; with a sweep, error
//! against a converged CPU reference and the Pareto front (what accuracy costs in time:
//! `docs/accuracy.md`). JSON and a PNG plot on request; progress on stderr.
//!
//! Layout: [`args`] (flags → configuration), [`preset`] (the papers' comparisons as data),
//! [`dataset`], [`measure`] (frames and clocks), [`accuracy`] (CPU reference side), [`run`]
//! (the case loop, cross-row figures), [`case`] (one case: compile, time, count, error),
//! [`report`] (rows, markdown), [`plot`], [`antialias_study`] (Klein et al. 2005 §5, run by the
//! `klein2005` preset after its table).

pub mod accuracy;
pub mod antialias_study;
pub mod args;
pub mod case;
pub mod dataset;
pub mod gpu_count;
pub mod measure;
pub mod peer;
pub mod plot;
pub mod preset;
pub mod report;
pub mod run;
pub mod tf_choice;

#[cfg(test)]
mod tests;

use anyhow::{Context, anyhow};
use volgraph_core::runtime::Gpu;

pub use args::GraphsArgs;
pub use report::GraphBenchReport;

/// Runs `volgraph bench graphs` with these flags: measures, prints the markdown table to stdout
/// and writes the JSON, plot and markdown files asked for.
pub fn run_cli(args: &GraphsArgs) -> anyhow::Result<GraphBenchReport> {
    let config = args.resolve()?;
    let gpu = std::sync::Arc::new(Gpu::new_headless().map_err(|e| anyhow!(e))?);
    let report = run::run(gpu, &config)?;
    let markdown = report.to_markdown();
    volgraph_app::stdout::write_stdout(&markdown)?;
    write_outputs(&config, &report, &markdown)?;
    Ok(report)
}

/// Writes the files `config` names.
pub fn write_outputs(config: &args::BenchConfig, report: &GraphBenchReport, markdown: &str) -> anyhow::Result<()> {
    if let Some(path) = &config.json {
        let text = serde_json::to_string_pretty(report).context("serializing the report")?;
        std::fs::write(path, text + "\n")
            .with_context(|| format!("--json {}: cannot write the file", path.display()))?;
    }
    if let Some(path) = &config.markdown {
        std::fs::write(path, markdown)
            .with_context(|| format!("--markdown {}: cannot write the file", path.display()))?;
    }
    if let Some(path) = &config.plot {
        plot::write_plot(path, report)?;
    }
    Ok(())
}
