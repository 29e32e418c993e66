//! The threads that read the bricks the streaming raycaster's rays asked for
//! ([`crate::stream_cache`]), while frames go on: a frame never waits for disk. Requests are
//! taken in the order the cache gave them (coarse before fine, near before far); a new frame's
//! requests go to the front, and a queue longer than [`MAX_QUEUED`] drops its oldest, so what
//! the camera no longer sees is not read. Finished bricks wait in a bounded channel (host memory
//! stays bounded: at most [`MAX_FINISHED`] bricks between the readers and the GPU).

use std::collections::VecDeque;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TrySendError, sync_channel};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;

use glam::{IVec3, UVec3};
use volgraph_accel::pyramid::{BoxTexels, PyramidSource};

/// Requests queued at most; older ones are dropped (and may be asked for again).
pub const MAX_QUEUED: usize = 8192;
/// Bricks read and not yet taken by the GPU side, at most.
pub const MAX_FINISHED: usize = 1024;

/// One brick to read: its page-table entry, level and voxel box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BrickRequest {
    /// Page-table entry.
    pub entry: u32,
    /// Level.
    pub level: usize,
    /// First voxel (apron included; may lie past a face).
    pub lo: IVec3,
    /// Voxels per axis.
    pub dims: UVec3,
}

/// A brick read (or the reason it could not be).
pub struct BrickRead {
    /// What was asked.
    pub request: BrickRequest,
    /// The voxels, normalized.
    pub texels: Result<BoxTexels, String>,
}

#[derive(Default)]
struct Queue {
    requests: VecDeque<BrickRequest>,
    /// Requests dropped from the queue since last taken.
    dropped: Vec<u32>,
    in_flight: usize,
    stop: bool,
}

/// Reader threads over one source.
pub struct StreamLoader {
    shared: Arc<(Mutex<Queue>, Condvar)>,
    /// Bricks read and not yet taken.
    waiting: Arc<AtomicUsize>,
    finished: Receiver<BrickRead>,
    threads: Vec<JoinHandle<()>>,
}

impl StreamLoader {
    /// `threads` readers (at least 1) of `source`.
    pub fn new(source: Arc<dyn PyramidSource>, threads: usize) -> Self {
        let shared = Arc::new((Mutex::new(Queue::default()), Condvar::new()));
        let (sender, finished) = sync_channel(MAX_FINISHED);
        let waiting = Arc::new(AtomicUsize::new(0));
        let threads = (0..threads.max(1))
            .map(|i| {
                let (shared, source, sender, waiting) =
                    (shared.clone(), source.clone(), sender.clone(), waiting.clone());
                std::thread::Builder::new()
                    .name(format!("volgraph brick reader {i}"))
                    .spawn(move || read_loop(&shared, source.as_ref(), &sender, &waiting))
                    .expect("spawning a reader thread")
            })
            .collect();
        Self { shared, waiting, finished, threads }
    }

    /// Puts a frame's requests (in order) before everything queued.
    pub fn enqueue(&self, requests: impl IntoIterator<Item = BrickRequest>) {
        let (lock, wake) = &*self.shared;
        let mut q = lock.lock().unwrap_or_else(|e| e.into_inner());
        let mut fresh: VecDeque<BrickRequest> = requests.into_iter().collect();
        if fresh.is_empty() {
            return;
        }
        fresh.append(&mut q.requests);
        while fresh.len() > MAX_QUEUED {
            if let Some(old) = fresh.pop_back() {
                q.dropped.push(old.entry);
            }
        }
        q.requests = fresh;
        wake.notify_all();
    }

    /// Bricks read since last asked (without waiting), at most `most`.
    pub fn take_finished(&self, most: usize) -> Vec<BrickRead> {
        let mut out = Vec::new();
        while out.len() < most {
            match self.finished.try_recv() {
                Ok(read) => {
                    self.waiting.fetch_sub(1, Ordering::Relaxed);
                    out.push(read);
                }
                Err(_) => break,
            }
        }
        out
    }

    /// Waits up to `timeout` for a brick to finish; `None` when none did.
    pub fn wait_finished(&self, timeout: std::time::Duration) -> Option<BrickRead> {
        let read = self.finished.recv_timeout(timeout).ok();
        if read.is_some() {
            self.waiting.fetch_sub(1, Ordering::Relaxed);
        }
        read
    }

    /// Waits up to `timeout` until every request is read (or the finished bricks fill the
    /// channel, so the readers wait for them to be taken).
    pub fn wait_idle(&self, timeout: std::time::Duration) {
        let deadline = std::time::Instant::now() + timeout;
        while std::time::Instant::now() < deadline {
            if self.outstanding() == 0 || self.waiting.load(Ordering::Relaxed) >= MAX_FINISHED {
                return;
            }
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
    }

    /// Requests dropped from the queue since last asked.
    pub fn take_dropped(&self) -> Vec<u32> {
        let (lock, _) = &*self.shared;
        std::mem::take(&mut lock.lock().unwrap_or_else(|e| e.into_inner()).dropped)
    }

    /// Requests queued or being read (not those read and waiting to be taken).
    pub fn outstanding(&self) -> usize {
        let (lock, _) = &*self.shared;
        let q = lock.lock().unwrap_or_else(|e| e.into_inner());
        q.requests.len() + q.in_flight
    }
}

fn read_loop(
    shared: &(Mutex<Queue>, Condvar),
    source: &dyn PyramidSource,
    sender: &SyncSender<BrickRead>,
    waiting: &AtomicUsize,
) {
    let (lock, wake) = shared;
    loop {
        let request = {
            let mut q = lock.lock().unwrap_or_else(|e| e.into_inner());
            loop {
                if q.stop {
                    return;
                }
                if let Some(r) = q.requests.pop_front() {
                    q.in_flight += 1;
                    break r;
                }
                q = wake.wait(q).unwrap_or_else(|e| e.into_inner());
            }
        };
        let texels = source.read_box(request.level, request.lo, request.dims);
        // Counted as waiting before it leaves the flight, so `wait_idle` never sees neither.
        waiting.fetch_add(1, Ordering::Relaxed);
        lock.lock().unwrap_or_else(|e| e.into_inner()).in_flight -= 1;
        let mut read = BrickRead { request, texels };
        // A full channel: wait for the GPU side, unless it is gone.
        loop {
            match sender.try_send(read) {
                Ok(()) => break,
                Err(TrySendError::Full(back)) => {
                    if lock.lock().unwrap_or_else(|e| e.into_inner()).stop {
                        return;
                    }
                    read = back;
                    std::thread::sleep(std::time::Duration::from_millis(1));
                }
                Err(TrySendError::Disconnected(_)) => return,
            }
        }
    }
}

impl Drop for StreamLoader {
    fn drop(&mut self) {
        let (lock, wake) = &*self.shared;
        lock.lock().unwrap_or_else(|e| e.into_inner()).stop = true;
        wake.notify_all();
        // Drain so a reader blocked on a full channel sees the stop.
        while self.finished.try_recv().is_ok() {}
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use volgraph_accel::pyramid::InCorePyramid;
    use volgraph_accel::volume::{Volume, VoxelData};

    /// Every request is read once and comes back with its voxels.
    #[test]
    fn every_request_comes_back_read() {
        let v = Volume::new("ramp", UVec3::splat(16), DVec3::ONE, VoxelData::U8((0..4096).map(|i| i as u8).collect()));
        let source: Arc<dyn PyramidSource> = Arc::new(InCorePyramid::new(Arc::new(v), 4));
        let loader = StreamLoader::new(source.clone(), 2);
        let requests: Vec<BrickRequest> = (0..10)
            .map(|i| BrickRequest { entry: i, level: 0, lo: IVec3::new(i as i32, 0, 0), dims: UVec3::splat(2) })
            .collect();
        loader.enqueue(requests.clone());
        let mut got: Vec<u32> = Vec::new();
        while got.len() < 10 {
            let read = loader.wait_finished(std::time::Duration::from_secs(10)).expect("a brick within 10 s");
            let expected = source.read_box(0, read.request.lo, read.request.dims).unwrap();
            assert_eq!(read.texels.unwrap(), expected);
            got.push(read.request.entry);
        }
        got.sort_unstable();
        assert_eq!(got, (0..10).collect::<Vec<_>>());
        assert_eq!(loader.outstanding(), 0);
    }
}
