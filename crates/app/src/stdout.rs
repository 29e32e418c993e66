//! Writing results to standard output. A closed pipe (`volgraph plan … | head`) ends the
//! output quietly instead of panicking as `print!` would.

use anyhow::Context as _;

/// Writes `text` to stdout; a closed pipe is not an error.
pub fn write_stdout(text: &str) -> anyhow::Result<()> {
    use std::io::Write as _;
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        other => other.context("cannot write to standard output"),
    }
}
