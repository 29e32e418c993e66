//! One volgraph program: the stock `volgraph` binary, or a plugin crate's own binary that adds
//! pass kinds, shaders and subcommands through an [`Extension`] and gets every subcommand —
//! render, plan, passes, graphs, view with hot reload, and whatever the extension adds (the
//! benchmarks of `volgraph-bench`) — from [`main_with`]:
//!
//! ```no_run
//! fn main() -> std::process::ExitCode {
//!     volgraph_app::main_with(volgraph_app::Extension {
//!         name: "radiology",
//!         register: |registry| { /* registry.register(MyPass); */ },
//!         shaders: &[/* ("my_pass.wgsl", include_str!("../shaders/my_pass.wgsl")) */],
//!         ..Default::default()
//!     })
//! }
//! ```

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::OnceLock;

use clap::{CommandFactory as _, FromArgMatches as _};
use volgraph_core::shader_source::{EmbeddedShaders, ShaderSources};
use volgraph_core::{KindLookup as _, Registry};

use crate::cli::{Cli, CliError};

/// Subcommands a program adds to volgraph's own (`volgraph-bench` adds `bench` and `sweep`).
pub trait Commands: Send + Sync {
    /// Adds the subcommands to the program's command line.
    fn augment(&self, command: clap::Command) -> clap::Command;

    /// Whether `name` is one of them.
    fn handles(&self, name: &str) -> bool;

    /// Runs the one the user chose (`matches` are the whole command line's).
    fn run(&self, matches: &clap::ArgMatches) -> Result<ExitCode, CliError>;
}

/// What a program adds to volgraph.
pub struct Extension {
    /// The program's name in usage lines (`volgraph` for the stock binary).
    pub name: &'static str,
    /// Adds the program's pass kinds to the built-in ones.
    pub register: fn(&mut Registry),
    /// The program's own shaders, searched before volgraph's (whose `common/` they may import).
    /// The WGSL structs of its kinds' uniform blocks come with them, as `params/NAME.wgsl`
    /// (gathered from what the kinds declare: `KindLookup::uniform_imports`).
    pub shaders: EmbeddedShaders,
    /// Subcommands beyond volgraph's own.
    pub commands: Vec<Box<dyn Commands>>,
}

impl Default for Extension {
    fn default() -> Self {
        Self { name: "volgraph", register: |_| {}, shaders: &[], commands: Vec::new() }
    }
}

/// The pass kinds and shaders of the running program, set once by [`main_with`].
struct Program {
    register: fn(&mut Registry),
    shaders: EmbeddedShaders,
}

static PROGRAM: OnceLock<Program> = OnceLock::new();

/// Every pass kind this program knows: volgraph's built-in ones and its extension's.
pub fn registry() -> Registry {
    let mut registry = volgraph_passes::builtin_registry();
    if let Some(p) = PROGRAM.get() {
        (p.register)(&mut registry);
    }
    registry
}

/// The shaders compiled into this program: its extension's first, then volgraph's, with the
/// uniform structs every registered kind declares.
pub fn shaders() -> ShaderSources {
    let builtin = volgraph_passes::builtin_shaders();
    match PROGRAM.get() {
        Some(p) => builtin.prepend_embedded(p.shaders).with_generated(registry().uniform_imports()),
        None => builtin,
    }
}

/// Runs the program: parses the command line (volgraph's subcommands and the extension's), runs
/// the chosen one and turns its outcome into an exit code, graph problems drawn with their
/// source excerpts. No input makes it panic; should a bug do so anyway, it says so in one line.
pub fn main_with(extension: Extension) -> ExitCode {
    // jpeg2k logs OpenJPEG's messages on a corrupt codestream (eight lines before the error);
    // the loader's error says what failed, so they are shown only when RUST_LOG asks.
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn,notify=error,jpeg2k=off")).init();
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
    // An installed binary finds data where its user says, never in the build machine's tree.
    volgraph_accel::data_dir::forget_build_path();
    let Extension { name, register, shaders, commands } = extension;
    let _ = PROGRAM.set(Program { register, shaders });
    let mut command = Cli::command().name(name).bin_name(name);
    let about = command.get_about().cloned();
    for c in &commands {
        command = c.augment(command);
    }
    // An extension's derive may set the program's about line; volgraph's stays.
    if let Some(about) = about {
        command = command.about(about);
    }
    // A usage error quotes the arguments as given: drawn by a copy of the command without
    // styles, its only control characters are the user's, and they are escaped (an argument
    // holding an escape sequence would otherwise retitle or clear the terminal).
    let plain = command.clone().styles(clap::builder::Styles::plain());
    let matches = match command.try_get_matches() {
        Ok(matches) => matches,
        Err(e) if e.use_stderr() => return clap_exit(&plain.try_get_matches().err().unwrap_or(e)),
        Err(e) => return clap_exit(&e),
    };
    report(run(&matches, &commands))
}

/// Prints what clap has to say and gives its exit status: `--help` and `--version` as clap
/// draws them (status 0); a usage error (status 2) with every control character of its text
/// escaped (styles, if any, included: call it with an error drawn without them).
fn clap_exit(e: &clap::Error) -> ExitCode {
    let code = u8::try_from(e.exit_code()).unwrap_or(2);
    if !e.use_stderr() {
        let _ = e.print();
        return ExitCode::from(code);
    }
    let text = e.render().ansi().to_string();
    eprint!("{}", volgraph_core::terminal::escape_controls(&text));
    ExitCode::from(code)
}

fn run(matches: &clap::ArgMatches, commands: &[Box<dyn Commands>]) -> Result<ExitCode, CliError> {
    if let Some(dir) = matches.get_one::<PathBuf>("data") {
        if !dir.is_dir() {
            return Err(CliError::Other(anyhow::anyhow!(
                "--data {}: not a folder; give the folder that holds volumes/ (and tf/)",
                dir.display()
            )));
        }
        volgraph_accel::data_dir::set_data_dir(dir.clone());
    }
    let chosen = matches.subcommand_name().and_then(|n| commands.iter().find(|c| c.handles(n)));
    match chosen {
        Some(c) => c.run(matches),
        None => {
            let cli = match Cli::from_arg_matches(matches) {
                Ok(cli) => cli,
                Err(e) => return Ok(clap_exit(&e)),
            };
            crate::cli::run(cli).map(|()| ExitCode::SUCCESS)
        }
    }
}

/// The exit code of an outcome, its error printed.
fn report(outcome: Result<ExitCode, CliError>) -> ExitCode {
    match outcome {
        Ok(code) => code,
        Err(CliError::Graph(diagnostics)) => {
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
        Err(CliError::Other(e)) => {
            eprintln!("error: {}", volgraph_core::terminal::escape_controls(&format!("{e:#}")));
            ExitCode::from(1)
        }
    }
}
