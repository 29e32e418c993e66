//! `volgraph bench` and `volgraph sweep` in the stock binary: the benchmarks are a program of
//! their own (`volgraph-bench`, crate `crates/bench`, which depends on this library and never
//! the other way round). The stock binary hands these subcommands to it, as git and cargo hand
//! theirs to `git-x` and `cargo-x`: the `volgraph-bench` beside this executable, else on `PATH`.

use std::ffi::OsString;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::anyhow;

use crate::cli::CliError;
use crate::program::Commands;

/// The benchmark program's file name.
pub const BENCH_PROGRAM: &str = "volgraph-bench";

/// The subcommands that belong to it.
const FORWARDED: [(&str, &str); 2] = [
    ("bench", "Measure: graphs (speed, samples, accuracy), fetch, live, compile, accel (runs volgraph-bench)"),
    ("sweep", "What accuracy costs in time: every knob against the converged f64 reference (runs volgraph-bench)"),
];

/// Hands `bench` and `sweep` to [`BENCH_PROGRAM`].
pub struct ToBenchProgram;

impl Commands for ToBenchProgram {
    fn augment(&self, mut command: clap::Command) -> clap::Command {
        for (name, about) in FORWARDED {
            command = command.subcommand(
                clap::Command::new(name).about(about).disable_help_flag(true).arg(
                    clap::Arg::new("args")
                        .num_args(0..)
                        .trailing_var_arg(true)
                        .allow_hyphen_values(true)
                        .value_parser(clap::value_parser!(OsString)),
                ),
            );
        }
        command
    }

    fn handles(&self, name: &str) -> bool {
        FORWARDED.iter().any(|(n, _)| *n == name)
    }

    fn run(&self, matches: &clap::ArgMatches) -> Result<ExitCode, CliError> {
        let Some((name, sub)) = matches.subcommand() else { return Ok(ExitCode::SUCCESS) };
        let program = bench_program().ok_or_else(|| {
            anyhow!(
                "`volgraph {name}` runs the benchmark program {BENCH_PROGRAM}, which is neither beside this binary \
                 nor on PATH; install it with `cargo install --path crates/bench` (from a volgraph checkout), or run \
                 `cargo run --release -p volgraph-bench -- {name} …`"
            )
        })?;
        let mut child = std::process::Command::new(&program);
        if let Some(dir) = matches.get_one::<PathBuf>("data") {
            child.arg("--data").arg(dir);
        }
        child.arg(name).args(sub.get_many::<OsString>("args").into_iter().flatten());
        let status = child.status().map_err(|e| anyhow!("cannot run {}: {e}", program.display()))?;
        match status.code() {
            Some(0) => Ok(ExitCode::SUCCESS),
            Some(code) => Ok(ExitCode::from(u8::try_from(code).unwrap_or(1))),
            // Killed by a signal: say so rather than exit 1 in silence.
            None => {
                #[cfg(unix)]
                let signal = std::os::unix::process::ExitStatusExt::signal(&status);
                #[cfg(not(unix))]
                let signal: Option<i32> = None;
                Err(CliError::Other(anyhow!(
                    "{} was stopped by signal {}",
                    program.display(),
                    signal.map_or_else(|| "?".to_string(), |s| s.to_string())
                )))
            }
        }
    }
}

/// The benchmark program beside the running executable, else the first on `PATH`.
fn bench_program() -> Option<PathBuf> {
    let file = format!("{BENCH_PROGRAM}{}", std::env::consts::EXE_SUFFIX);
    let beside = std::env::current_exe().ok().and_then(|exe| exe.parent().map(|d| d.join(&file)));
    let on_path = std::env::var_os("PATH")
        .map(|p| std::env::split_paths(&p).map(|d| d.join(&file)).collect::<Vec<_>>())
        .unwrap_or_default();
    beside.into_iter().chain(on_path).find(|p| p.is_file())
}
