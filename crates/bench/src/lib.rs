//! volgraph's benchmarks and the accuracy sweep, a program of their own (`volgraph-bench`) built
//! on the app's library (`volgraph_app`): user-facing code never calls into benchmark code.
//! Graphs come from the ones compiled into the program (a file on disk wins), data from
//! `--data DIR` or `$VOLGRAPH_DATA`, so every preset and the sweep run from any folder.
//!
//! - `bench graphs` ([`graphs`]): render graphs over datasets, transfer functions and viewports;
//!   presets reproduce the papers' tables as ratios measured in one run.
//! - `bench fetch` ([`fetch`]): the device's trilinear-sampling ceiling.
//! - `bench live` ([`live`]): reload latency, frames in flight, a soak.
//! - `bench compile` ([`compile_time`]): compile time and pooled memory of every graph.
//! - `bench accel` ([`accel`]): the CPU acceleration structures.
//! - `sweep` ([`sweep`]): every quality knob against the converged f64 reference.

pub mod accel;
pub mod api;
pub mod cinematic;
mod commands;
pub mod compile_time;
pub mod cuts;
pub mod distributed;
pub mod fetch;
pub mod graphs;
pub mod live;
pub mod load;
pub mod multi;
pub mod multi_toggle;
pub mod report_files;
pub mod slices;
pub mod stream;
pub mod sweep;
pub mod workbench;

pub use commands::BenchCommands;

use std::process::ExitCode;

/// A volgraph program with the benchmarks: every subcommand of [`volgraph_app::main_with`]
/// plus `bench` and `sweep`, with `extension`'s pass kinds, shaders and commands.
pub fn main_with(mut extension: volgraph_app::Extension) -> ExitCode {
    extension.commands.push(Box::new(BenchCommands));
    volgraph_app::main_with(extension)
}
