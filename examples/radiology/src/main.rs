//! `radiology`: volgraph's whole command line — render, plan, passes, graphs, view with hot
//! reload, bench, sweep — with this crate's pass kinds and shaders added.

use std::process::ExitCode;

fn main() -> ExitCode {
    volgraph_bench::main_with(volgraph_app::Extension {
        name: "radiology",
        register: volgraph_example_radiology::register,
        shaders: volgraph_example_radiology::SHADERS,
        ..Default::default()
    })
}
