//! Writing results to standard output. A closed pipe (`volgraph plan … | head`) ends the
//! output quietly instead of panicking as `print!` would.

use anyhow::Context as _;
pub use volgraph_core::terminal::escape_controls;

/// Writes `text` to stdout, control characters from the user's files escaped
/// ([`volgraph_core::terminal`]); a closed pipe is not an error.
pub fn write_stdout(text: &str) -> anyhow::Result<()> {
    use std::io::Write as _;
    let text = volgraph_core::terminal::escape_controls(text);
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        other => other.context("cannot write to standard output"),
    }
}

/// `eprintln!` with control characters from the user's files escaped
/// ([`volgraph_core::terminal`]): every note, warning and error volgraph writes to stderr.
#[macro_export]
macro_rules! eprintln_escaped {
    ($($arg:tt)*) => {
        eprintln!("{}", $crate::stdout::escape_controls(&format!($($arg)*)))
    };
}
pub use crate::eprintln_escaped;

/// `println!` with control characters escaped, like [`eprintln_escaped`].
#[macro_export]
macro_rules! println_escaped {
    ($($arg:tt)*) => {
        println!("{}", $crate::stdout::escape_controls(&format!($($arg)*)))
    };
}
pub use crate::println_escaped;
