//! `volgraph-bench`: volgraph with its benchmarks (`bench …`, `sweep`) — what the stock `volgraph`
//! binary runs for `volgraph bench` and `volgraph sweep`.

use std::process::ExitCode;

fn main() -> ExitCode {
    volgraph_bench::main_with(volgraph_app::Extension::default())
}
