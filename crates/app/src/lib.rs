//! The `volgraph` program as a library: every subcommand a user runs — `render`, `plan`,
//! `passes`, `graphs`, `view` with hot reload — and [`main_with`], which gives a plugin crate's
//! own binary all of them with its pass kinds and shaders added ([`Extension`]). The benchmarks
//! and the sweep are `volgraph-bench` (`crates/bench`), which builds on this library; the stock
//! binary hands `bench` and `sweep` to it ([`forward`]). This crate is the one that talks to a
//! user: inputs are read and checked here, before any GPU work.

pub mod api;
pub mod atomic_write;
pub mod builtin_graphs;
pub mod builtin_scenes;
pub mod cli;
#[cfg(test)]
mod cli_fuzz;
pub mod convert_cmd;
pub mod convert_sources;
pub mod distributed;
pub mod environment_file;
pub mod forward;
#[cfg(test)]
mod fuzz_runner;
pub mod image_out;
pub mod info_cmd;
#[cfg(test)]
mod input_fuzz;
pub mod inputs;
pub mod label_tables;
pub mod load_progress;
pub mod named_inputs;
pub mod passes_cmd;
pub mod plan_svg;
pub mod program;
pub mod render;
pub mod scene;
pub mod scene_args;
pub mod set_cmd;
#[cfg(test)]
mod set_fuzz;
pub mod shader_dir;
pub mod stdout;
pub mod stream_progress;
pub mod view;
pub mod zarr_input;

pub use program::{Commands, Extension, main_with, registry, shaders};
