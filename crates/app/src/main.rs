//! `volgraph`: the command line. `plan` prints a compiled schedule, `render` draws images,
//! `view` shows a graph live; `bench` and `sweep` run the benchmark program `volgraph-bench`.

use std::process::ExitCode;

fn main() -> ExitCode {
    volgraph_app::main_with(volgraph_app::Extension {
        commands: vec![Box::new(volgraph_app::forward::ToBenchProgram)],
        ..Default::default()
    })
}
