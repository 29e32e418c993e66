//! Writing a file the viewer or `volgraph set` changes (a graph, a transfer function, a saved
//! view) so that a reader — the viewer's own watcher, an editor — sees the old file or the new
//! one, never half of it; and never over something that is not a file.
//!
//! The new text goes to a temporary file created exclusively (`O_EXCL`, a random name: the
//! `tempfile` crate) beside the file, then renamed over it. A predictable temporary name would
//! let anyone who can write to the folder plant a link there and have volgraph overwrite the
//! link's target. A path that is a symbolic link is written through: the link's target is
//! replaced (beside the target) and the link stays a link, as an editor saving through it does.

use std::path::{Path, PathBuf};

use anyhow::anyhow;

/// How many links a path may pass through before it is taken for a loop (Linux's own limit).
const MAX_LINKS: usize = 40;

/// Writes `text` to `path` by renaming a fresh temporary file in the same folder over it,
/// keeping the old file's permissions (and owner, where the process may set it). A symbolic
/// link is followed to the file it names, which is replaced. A directory, FIFO or device is
/// refused before anything is written, and so is a file without its owner's write permission
/// (checked on the permission bits, so root is refused too). Errors name `path`, never the
/// temporary file, which is removed when anything fails.
pub fn write_atomically(path: &Path, text: &str) -> anyhow::Result<()> {
    write_bytes_atomically(path, text.as_bytes())
}

/// [`write_atomically`] for bytes (an image): the one implementation. Never opens `path` itself,
/// so a FIFO there (made at any moment) never blocks the writer: it is refused, or replaced by
/// the rename.
pub fn write_bytes_atomically(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let shown = path.display();
    if let Ok(Some(kind)) = volgraph_accel::input_file::special_kind(path) {
        return Err(anyhow!("{shown}: is {kind}, not a file to write; give the path of a file"));
    }
    let target = resolve_links(path)?;
    let existing = std::fs::metadata(&target).ok();
    if let Some(meta) = &existing
        && !meta.is_file()
    {
        return Err(anyhow!("{shown}: is not a regular file; give the path of a file"));
    }
    if existing.as_ref().is_some_and(is_read_only) {
        return Err(anyhow!("{shown} is read-only; make it writable (chmod u+w) or save elsewhere"));
    }
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = target.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    // At most 32 characters of the name: a legal name near NAME_MAX (255 bytes) would make the
    // temporary name too long and the folder seem to refuse a new file.
    let short: String = name.chars().take(32).collect();
    let prefix = format!(".{short}.");
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".volgraph.tmp");
    // Created with the old file's permissions (or, for a new file, what the umask leaves of
    // rw-rw-rw-, as any new file), so the new text is never readable by more users than the old.
    if let Some(permissions) = existing.as_ref().map(std::fs::Metadata::permissions).or_else(new_file_permissions) {
        builder.permissions(permissions);
    }
    let mut tmp = builder.tempfile_in(&dir).map_err(|e| {
        anyhow!("{shown}: cannot write: the folder {} refused a new file: {}", dir.display(), os_reason(&e))
    })?;
    use std::io::Write as _;
    tmp.write_all(bytes).and_then(|()| tmp.flush()).map_err(|e| anyhow!("{shown}: cannot write: {}", os_reason(&e)))?;
    if let Some(meta) = &existing {
        // The mode the file was created with lost what the umask masks; set it exactly.
        let _ = tmp.as_file().set_permissions(meta.permissions());
        keep_owner(tmp.as_file(), meta);
    }
    tmp.persist(&target).map_err(|e| anyhow!("{shown}: cannot replace the file: {}", os_reason(&e.error)))?;
    Ok(())
}

/// What went wrong, without the path tempfile adds to its errors (the hidden temporary file's,
/// which the user never named).
fn os_reason(e: &std::io::Error) -> String {
    match e.raw_os_error() {
        Some(code) => std::io::Error::from_raw_os_error(code).to_string(),
        None => e.kind().to_string(),
    }
}

/// The file `path` names after following every symbolic link (a relative link from the link's
/// own folder); `path` itself when it is no link. A loop of links is an error.
fn resolve_links(path: &Path) -> anyhow::Result<PathBuf> {
    let mut current = path.to_path_buf();
    for _ in 0..MAX_LINKS {
        match std::fs::symlink_metadata(&current) {
            Ok(meta) if meta.file_type().is_symlink() => {
                let link = std::fs::read_link(&current)
                    .map_err(|e| anyhow!("{}: cannot read the link: {e}", path.display()))?;
                current = match current.parent() {
                    Some(dir) if link.is_relative() => dir.join(link),
                    _ => link,
                };
            }
            _ => return Ok(current),
        }
    }
    Err(anyhow!(
        "{}: symbolic links lead to links more than {MAX_LINKS} times (a loop?); give the path of a file",
        path.display()
    ))
}

/// Whether the file's owner may not write it, by its permission bits alone (root may write
/// anything, so asking the OS would not tell).
fn is_read_only(meta: &std::fs::Metadata) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt as _;
        meta.permissions().mode() & 0o200 == 0
    }
    #[cfg(not(unix))]
    {
        meta.permissions().readonly()
    }
}

/// The permissions a new file is created with: rw for all, less the umask (applied by `open`);
/// `None` leaves tempfile's default.
fn new_file_permissions() -> Option<std::fs::Permissions> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt as _;
        Some(std::fs::Permissions::from_mode(0o666))
    }
    #[cfg(not(unix))]
    {
        None
    }
}

/// Gives the new file the old one's owner and group (only root may, or an owner keeping its
/// own; a failure leaves the writer's).
fn keep_owner(file: &std::fs::File, meta: &std::fs::Metadata) {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt as _;
        let _ = std::os::unix::fs::fchown(file, Some(meta.uid()), Some(meta.gid()));
    }
    #[cfg(not(unix))]
    let _ = (file, meta);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("volgraph-atomic-write-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch");
        dir
    }

    #[test]
    fn a_new_file_is_written_and_no_temporary_file_stays() {
        let dir = scratch("new");
        let path = dir.join("a.ron");
        write_atomically(&path, "one").expect("write");
        write_atomically(&path, "two").expect("rewrite");
        assert_eq!(std::fs::read_to_string(&path).expect("read"), "two");
        let names: Vec<_> = std::fs::read_dir(&dir).expect("dir").flatten().map(|e| e.file_name()).collect();
        assert_eq!(names, vec![std::ffi::OsString::from("a.ron")]);
    }

    #[cfg(unix)]
    #[test]
    fn the_old_mode_is_kept_and_a_link_loop_is_an_error() {
        use std::os::unix::fs::PermissionsExt as _;
        let dir = scratch("mode");
        let path = dir.join("a.ron");
        std::fs::write(&path, "one").expect("write");
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o640)).expect("chmod");
        write_atomically(&path, "two").expect("rewrite");
        assert_eq!(std::fs::metadata(&path).expect("meta").permissions().mode() & 0o777, 0o640);
        std::os::unix::fs::symlink("b", dir.join("a")).expect("link");
        std::os::unix::fs::symlink("a", dir.join("b")).expect("link");
        let e = write_atomically(&dir.join("a"), "x").expect_err("a loop");
        assert!(e.to_string().contains("a loop?"), "{e}");
    }

    /// A legal name of 250 bytes: the temporary name beside it was longer than NAME_MAX, and
    /// the folder seemed to refuse a new file.
    #[test]
    fn a_name_near_the_length_limit_is_written() {
        let dir = scratch("long");
        let path = dir.join(format!("{}.ron", "g".repeat(246)));
        write_atomically(&path, "one").expect("a legal name is written");
        assert_eq!(std::fs::read_to_string(&path).expect("read"), "one");
    }
}
