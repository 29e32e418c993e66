//! Watching the files a session depends on (notify), debounced: editors write a file in several
//! steps (truncate, write, rename), so changes are delivered once the files have been quiet for
//! `QUIET`. Folders are watched rather than files, because an editor that saves by renaming
//! replaces the file a watch would have followed.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

use notify::{RecursiveMode, Watcher};

/// How long files must be quiet before a change is delivered.
pub const QUIET: Duration = Duration::from_millis(15);

/// A debounced watch over a set of files.
pub struct FileWatch {
    watcher: notify::RecommendedWatcher,
    events: Receiver<notify::Result<notify::Event>>,
    files: BTreeSet<PathBuf>,
    folders: BTreeSet<PathBuf>,
    pending: BTreeSet<PathBuf>,
    last_event: Option<Instant>,
}

fn canonical(p: &Path) -> PathBuf {
    p.canonicalize().unwrap_or_else(|_| p.to_path_buf())
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
            folders: BTreeSet::new(),
            pending: BTreeSet::new(),
            last_event: None,
        })
    }

    /// Watches exactly `files` (and their folders) from now on.
    pub fn set_files(&mut self, files: &[PathBuf]) {
        self.files = files.iter().map(|f| canonical(f)).collect();
        let folders: BTreeSet<PathBuf> = self.files.iter().filter_map(|f| f.parent().map(Path::to_path_buf)).collect();
        for gone in self.folders.difference(&folders) {
            let _ = self.watcher.unwatch(gone);
        }
        for new in folders.difference(&self.folders) {
            let _ = self.watcher.watch(new, RecursiveMode::NonRecursive);
        }
        self.folders = folders;
    }

    /// The watched files that changed and have been quiet since, if any.
    pub fn poll(&mut self) -> Vec<PathBuf> {
        while let Ok(event) = self.events.try_recv() {
            let Ok(event) = event else { continue };
            if matches!(event.kind, notify::EventKind::Access(_)) {
                continue;
            }
            for path in event.paths {
                let path = canonical(&path);
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
