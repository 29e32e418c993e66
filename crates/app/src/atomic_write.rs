//! Writing a file the viewer or `volgraph set` changes (a graph, a transfer function, a saved
//! view) so that a reader — the viewer's own watcher, an editor — sees the old file or the new
//! one, never half of it; and never over something that is not a file.

use std::path::Path;

use anyhow::anyhow;

/// Writes `text` to `path` by renaming a sibling temporary file over it (keeping the old file's
/// permissions). A directory, FIFO or device at `path` is refused before anything is written;
/// the temporary file is removed when the rename fails.
pub fn write_atomically(path: &Path, text: &str) -> anyhow::Result<()> {
    if let Ok(Some(kind)) = volgraph_accel::input_file::special_kind(path) {
        return Err(anyhow!("{}: is {kind}, not a file to write; give the path of a file", path.display()));
    }
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.volgraph.tmp"));
    std::fs::write(&tmp, text).map_err(|e| anyhow!("{}: cannot write: {e}", tmp.display()))?;
    if let Ok(meta) = std::fs::metadata(path) {
        let _ = std::fs::set_permissions(&tmp, meta.permissions());
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        anyhow!("{}: cannot replace the file: {e}", path.display())
    })
}
