//! `volgraph`: the command line. `plan` prints a compiled schedule, `render` draws images,
//! `bench` measures. This crate is the only one that talks to a user.

mod bench_accel;
mod bench_compile;
mod bench_fetch;
mod bench_graphs;
mod bench_live;
mod builtin_graphs;
mod cli;
#[cfg(test)]
mod cli_fuzz;
#[cfg(test)]
mod fuzz_runner;
mod image_out;
#[cfg(test)]
mod input_fuzz;
mod inputs;
mod passes_cmd;
mod plan_svg;
mod render;
mod scene;
mod scene_args;
mod shader_dir;
mod stdout;
mod sweep;
mod view;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn,notify=error")).init();
    // No input may crash volgraph; should a bug do so anyway, say so in one line instead of a
    // Rust backtrace.
    std::panic::set_hook(Box::new(|info| {
        let location = info.location().map_or(String::new(), |l| format!(" at {}:{}", l.file(), l.line()));
        let message = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_default();
        eprintln!(
            "error: volgraph hit an internal error{location}: {message}\n  this is a bug in volgraph, not in your \
             input; please report it with the command you ran"
        );
    }));
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(cli::CliError::Graph(diagnostics)) => {
            // Each problem once: drawn with its source excerpt on a terminal, as the
            // compiler-style `file:line:col: message` lines when stderr is a file or a pipe.
            use std::io::IsTerminal as _;
            if std::io::stderr().is_terminal() {
                for report in diagnostics.to_miette_reports() {
                    eprintln!("{report:?}");
                }
            } else {
                eprintln!("{}", volgraph_core::terminal::escape_controls(&diagnostics.to_string()));
            }
            ExitCode::from(1)
        }
        Err(cli::CliError::Other(e)) => {
            eprintln!("error: {}", volgraph_core::terminal::escape_controls(&format!("{e:#}")));
            ExitCode::from(1)
        }
    }
}
