//! Reading the user's text inputs — graph, scene, transfer-function and manifest files, WGSL
//! imports — without ever blocking or exhausting memory: a FIFO, a socket, a device such as
//! `/dev/zero` or a directory is refused before it is opened, and a file is read only up to a
//! size limit (a file that grows while it is read, or a `/proc` file that reports size 0, is
//! still bounded).

use std::io::Read;
use std::path::{Path, PathBuf};

/// The largest text input read: far beyond any graph, scene or TF file (the largest shipped is
/// a few KiB), small enough that a mistaken multi-gigabyte path fails at once.
pub const MAX_TEXT_BYTES: u64 = 16 << 20;

/// Why a text input could not be read.
#[derive(Debug, thiserror::Error)]
pub enum InputFileError {
    /// The OS refused (missing file, permissions, ...).
    #[error("{}: cannot read the {what}: {reason}", .path.display())]
    Io {
        /// The path.
        path: PathBuf,
        /// What the file was meant to be ("graph file", "scene file", ...).
        what: &'static str,
        /// The OS error (in the message, not a `source`: printed once).
        reason: std::io::Error,
    },
    /// The path is a directory, a FIFO, a socket or a device.
    #[error("{}: is {kind}, not a {what}; give the path of a regular file", .path.display())]
    NotAFile {
        /// The path.
        path: PathBuf,
        /// What the file was meant to be.
        what: &'static str,
        /// `"a directory"`, `"a FIFO (named pipe)"`, ...
        kind: &'static str,
    },
    /// The file is larger than [`MAX_TEXT_BYTES`].
    #[error("{}: is larger than {} MiB, far more than any {what}; check the path", .path.display(), .limit >> 20)]
    TooLarge {
        /// The path.
        path: PathBuf,
        /// What the file was meant to be.
        what: &'static str,
        /// The limit in bytes.
        limit: u64,
    },
    /// The file is not UTF-8 text.
    #[error("{}: is not UTF-8 text (byte {offset} is not valid UTF-8), so it cannot be a {what}", .path.display())]
    NotText {
        /// The path.
        path: PathBuf,
        /// What the file was meant to be.
        what: &'static str,
        /// The first invalid byte.
        offset: usize,
    },
}

/// What kind of thing `path` is when it is not a regular file (or a link to one), else `None`.
/// Follows links, like opening the file would.
pub fn special_kind(path: &Path) -> std::io::Result<Option<&'static str>> {
    let kind = std::fs::metadata(path)?.file_type();
    if kind.is_file() {
        return Ok(None);
    }
    if kind.is_dir() {
        return Ok(Some("a directory"));
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return Ok(Some("a FIFO (named pipe)"));
        }
        if kind.is_socket() {
            return Ok(Some("a socket"));
        }
        if kind.is_block_device() || kind.is_char_device() {
            return Ok(Some("a device"));
        }
    }
    Ok(Some("not a regular file"))
}

/// Reads the text file at `path` (a `what`, for messages): refuses special files, reads at
/// most [`MAX_TEXT_BYTES`], and requires UTF-8.
pub fn read_text(path: &Path, what: &'static str) -> Result<String, InputFileError> {
    read_text_limited(path, what, MAX_TEXT_BYTES)
}

/// [`read_text`] with a given size limit.
pub fn read_text_limited(path: &Path, what: &'static str, limit: u64) -> Result<String, InputFileError> {
    let io = |reason| InputFileError::Io { path: path.to_path_buf(), what, reason };
    if let Some(kind) = special_kind(path).map_err(io)? {
        return Err(InputFileError::NotAFile { path: path.to_path_buf(), what, kind });
    }
    let file = std::fs::File::open(path).map_err(io)?;
    let mut bytes = Vec::new();
    file.take(limit.saturating_add(1)).read_to_end(&mut bytes).map_err(io)?;
    if bytes.len() as u64 > limit {
        return Err(InputFileError::TooLarge { path: path.to_path_buf(), what, limit });
    }
    String::from_utf8(bytes).map_err(|e| InputFileError::NotText {
        path: path.to_path_buf(),
        what,
        offset: e.utf8_error().valid_up_to(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_directory_is_named_as_one() {
        let dir = std::env::temp_dir();
        let err = read_text(&dir, "graph file").expect_err("a directory");
        assert!(err.to_string().contains("is a directory, not a graph file"), "{err}");
    }

    #[cfg(unix)]
    #[test]
    fn dev_zero_is_refused_before_it_is_read() {
        let err = read_text(Path::new("/dev/zero"), "scene file").expect_err("a device");
        assert!(err.to_string().contains("is a device, not a scene file"), "{err}");
    }

    #[test]
    fn a_file_over_the_limit_is_refused() {
        let path = std::env::temp_dir().join(format!("volgraph-input-file-{}.txt", std::process::id()));
        std::fs::write(&path, vec![b'a'; 100]).expect("writable temp dir");
        let err = read_text_limited(&path, "transfer function", 99).expect_err("over the limit");
        assert!(matches!(err, InputFileError::TooLarge { limit: 99, .. }), "{err}");
        assert_eq!(read_text_limited(&path, "transfer function", 100).expect("at the limit").len(), 100);
        std::fs::remove_file(&path).ok();
    }

    #[test]
    fn binary_is_not_text() {
        let path = std::env::temp_dir().join(format!("volgraph-input-binary-{}.bin", std::process::id()));
        std::fs::write(&path, [b'o', b'k', 0xff, 0xfe]).expect("writable temp dir");
        let err = read_text(&path, "graph file").expect_err("not UTF-8");
        assert!(matches!(err, InputFileError::NotText { offset: 2, .. }), "{err}");
        std::fs::remove_file(&path).ok();
    }
}
