//! Watching the files a session depends on (notify), debounced: editors write a file in several
//! steps (truncate, write, rename), so changes are delivered once the files have been quiet for
//! `QUIET`. Folders are watched rather than files, because an editor that saves by renaming
//! replaces the file a watch would have followed. A watched folder that is deleted takes its
//! watch with it; every `RECHECK` the folders are looked at again, and one that is back (or was
//! replaced by another folder of that name: another inode or creation time, or an event saying
//! the watched folder itself went) is watched anew and its watched files are delivered as
//! changed (they may have been written before the new watch began).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

use notify::{RecursiveMode, Watcher};

/// How long files must be quiet before a change is delivered.
pub const QUIET: Duration = Duration::from_millis(15);

/// How often the watched folders are checked for having been deleted and made again.
pub const RECHECK: Duration = Duration::from_millis(200);

/// Which folder is at a path: its device, inode and creation time (on Unix; a folder deleted
/// and made again may get the same inode number back), `None` while there is none.
type FolderId = Option<(u64, u64, Option<std::time::SystemTime>)>;

fn folder_id(path: &Path) -> FolderId {
    let meta = std::fs::metadata(path).ok().filter(std::fs::Metadata::is_dir)?;
    let created = meta.created().ok();
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        Some((meta.dev(), meta.ino(), created))
    }
    #[cfg(not(unix))]
    {
        Some((0, 0, created))
    }
}

/// A debounced watch over a set of files.
pub struct FileWatch {
    watcher: notify::RecommendedWatcher,
    events: Receiver<notify::Result<notify::Event>>,
    files: BTreeSet<PathBuf>,
    /// The watched folders and which folder each was when its watch was set.
    folders: BTreeMap<PathBuf, FolderId>,
    pending: BTreeSet<PathBuf>,
    last_event: Option<Instant>,
    last_check: Instant,
}

/// `p` absolute, with links resolved as far as it exists: a file whose folder is gone keeps
/// the name it had while it was there, so events after the folder comes back match it.
fn canonical(p: &Path) -> PathBuf {
    if let Ok(c) = p.canonicalize() {
        return c;
    }
    let absolute = if p.is_absolute() {
        p.to_path_buf()
    } else {
        std::env::current_dir().map_or_else(|_| p.to_path_buf(), |d| d.join(p))
    };
    match (absolute.parent(), absolute.file_name()) {
        (Some(parent), Some(name)) if parent != absolute => canonical(parent).join(name),
        _ => absolute,
    }
}

impl FileWatch {
    /// A watch over nothing yet.
    pub fn new() -> notify::Result<Self> {
        let (tx, events) = channel();
        let watcher = notify::recommended_watcher(move |e| {
            let _ = tx.send(e);
        })?;
        Ok(Self {
            watcher,
            events,
            files: BTreeSet::new(),
            folders: BTreeMap::new(),
            pending: BTreeSet::new(),
            last_event: None,
            last_check: Instant::now(),
        })
    }

    /// Watches exactly `files` (and their folders) from now on.
    pub fn set_files(&mut self, files: &[PathBuf]) {
        self.files = files.iter().map(|f| canonical(f)).collect();
        let folders: BTreeSet<PathBuf> = self.files.iter().filter_map(|f| f.parent().map(Path::to_path_buf)).collect();
        let gone: Vec<PathBuf> = self.folders.keys().filter(|f| !folders.contains(*f)).cloned().collect();
        for folder in gone {
            let _ = self.watcher.unwatch(&folder);
            self.folders.remove(&folder);
        }
        for folder in folders {
            if !self.folders.contains_key(&folder) {
                let id = folder_id(&folder);
                let _ = self.watcher.watch(&folder, RecursiveMode::NonRecursive);
                self.folders.insert(folder, id);
            }
        }
    }

    /// Watches again every folder that was deleted and made again (or first made) since it was
    /// watched; its watched files count as changed.
    fn rewatch(&mut self) {
        let mut back = Vec::new();
        for (folder, id) in &mut self.folders {
            let now = folder_id(folder);
            if now != *id {
                *id = now;
                if now.is_some() {
                    back.push(folder.clone());
                }
            }
        }
        for folder in back {
            // The old watch died with the old folder; notify may still hold its entry.
            let _ = self.watcher.unwatch(&folder);
            let _ = self.watcher.watch(&folder, RecursiveMode::NonRecursive);
            let written: Vec<PathBuf> =
                self.files.iter().filter(|f| f.parent() == Some(folder.as_path()) && f.exists()).cloned().collect();
            if !written.is_empty() {
                self.pending.extend(written);
                self.last_event = Some(Instant::now());
            }
        }
    }

    /// The watched files that changed and have been quiet since, if any.
    pub fn poll(&mut self) -> Vec<PathBuf> {
        if self.last_check.elapsed() >= RECHECK {
            self.last_check = Instant::now();
            self.rewatch();
        }
        while let Ok(event) = self.events.try_recv() {
            let Ok(event) = event else { continue };
            if matches!(event.kind, notify::EventKind::Access(_)) {
                continue;
            }
            for path in event.paths {
                let path = canonical(&path);
                // The watched folder itself went (deleted, or renamed away): its watch went with
                // it, and the next check watches whatever folder is there then.
                if let Some(id) = self.folders.get_mut(&path) {
                    let renamed = matches!(event.kind, notify::EventKind::Modify(notify::event::ModifyKind::Name(_)));
                    if matches!(event.kind, notify::EventKind::Remove(_)) || (renamed && folder_id(&path) != *id) {
                        *id = None;
                    }
                }
                if self.files.contains(&path) {
                    self.pending.insert(path);
                    self.last_event = Some(Instant::now());
                }
            }
        }
        match self.last_event {
            Some(t) if !self.pending.is_empty() && t.elapsed() >= QUIET => {
                self.last_event = None;
                std::mem::take(&mut self.pending).into_iter().collect()
            }
            _ => Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Polls `watch` for up to 10 s until it delivers `file`.
    fn delivers(watch: &mut FileWatch, file: &Path) -> bool {
        let want = canonical(file);
        let deadline = Instant::now() + Duration::from_secs(10);
        while Instant::now() < deadline {
            if watch.poll().contains(&want) {
                return true;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        false
    }

    /// Issue 47 §6: a graph's folder deleted and made again lost its watch (inotify drops it
    /// with the folder), and edits after that never reloaded.
    #[test]
    fn a_folder_deleted_and_made_again_is_watched_again() {
        let root = std::env::temp_dir().join(format!("volgraph-rewatch-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let dir = root.join("graphs");
        std::fs::create_dir_all(&dir).expect("scratch folder");
        let graph = dir.join("graph.ron");
        std::fs::write(&graph, "one").expect("write");
        let mut watch = FileWatch::new().expect("a watcher");
        watch.set_files(std::slice::from_ref(&graph));
        std::fs::write(&graph, "two").expect("write");
        assert!(delivers(&mut watch, &graph), "an edit is seen");
        std::fs::remove_dir_all(&dir).expect("delete the folder");
        assert!(delivers(&mut watch, &graph), "the deletion is seen");
        // Made again at once: the new folder may get the old one's inode number back.
        std::fs::create_dir_all(&dir).expect("make it again");
        std::fs::write(&graph, "three").expect("write");
        assert!(delivers(&mut watch, &graph), "the file in the new folder is seen");
        // Later edits, through the new watch.
        std::thread::sleep(RECHECK * 2);
        let _ = watch.poll();
        std::fs::write(&graph, "four").expect("write");
        assert!(delivers(&mut watch, &graph), "an edit after the folder came back is seen");
        let _ = std::fs::remove_dir_all(&root);
    }
}
