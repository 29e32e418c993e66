//! `volgraph`: the command line. `plan` prints a compiled schedule, `render` draws images,
//! `bench` measures. This crate is the only one that talks to a user.

mod bench_accel;
mod bench_compile;
mod bench_graphs;
mod cli;
mod image_out;
mod inputs;
mod stdout;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(cli::CliError::Graph(diagnostics)) => {
            for report in diagnostics.to_miette_reports() {
                eprintln!("{report:?}");
            }
            eprintln!("{}", diagnostics);
            ExitCode::from(1)
        }
        Err(cli::CliError::Other(e)) => {
            eprintln!("error: {e:#}");
            ExitCode::from(1)
        }
    }
}
