//! Frames in flight: each submitted frame gets a slot of a small ring with its own timestamp
//! queries and readback buffer. Submitting returns at once; a new frame waits only when the ring
//! is full (for the oldest frame), and timings are read back asynchronously when the GPU reports
//! the frame done (`FrameRing::poll`).

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use super::gpu::Gpu;

/// How many frames may be queued on the GPU at once.
pub const MAX_FRAMES_IN_FLIGHT: usize = 2;

/// Timing of one finished frame.
#[derive(Clone, Debug, Default)]
pub struct FrameStats {
    /// The frame's index (as in the frame contract).
    pub frame_index: u64,
    /// The pass id of each step, in order (repeat-group instances repeat their pass id).
    pub pass_ids: Arc<Vec<String>>,
    /// GPU milliseconds per step, when timestamps exist.
    pub step_gpu_ms: Option<Vec<f64>>,
    /// Sum of the steps' GPU time, or wall time from submit to completion where timestamps do not
    /// measure the work (no timestamps, or a CPU adapter: see `Gpu::timestamps_cover_work`).
    pub frame_ms: f64,
    /// Wall milliseconds from submit until the GPU reported the frame done.
    pub wall_ms: f64,
    /// True when `frame_ms` is wall time because the adapter has no timestamp queries.
    pub wall_time_fallback: bool,
    /// True when `step_gpu_ms` are wall times of steps submitted one by one
    /// (`Runtime::set_step_profiling`); `frame_ms` is then their sum.
    pub steps_serialised: bool,
}

impl FrameStats {
    /// GPU ms per pass id, repeat-group instances summed, in first-seen order.
    pub fn per_pass_ms(&self) -> Vec<(String, f64)> {
        let mut out: Vec<(String, f64)> = Vec::new();
        let Some(ms) = &self.step_gpu_ms else { return out };
        for (id, ms) in self.pass_ids.iter().zip(ms) {
            match out.iter_mut().find(|(p, _)| p == id) {
                Some((_, total)) => *total += ms,
                None => out.push((id.clone(), *ms)),
            }
        }
        out
    }
}

struct Queries {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    read: wgpu::Buffer,
    capacity: u32,
}

struct Pending {
    submission: wgpu::SubmissionIndex,
    frame_index: u64,
    pass_ids: Arc<Vec<String>>,
    steps: usize,
    submitted: Instant,
    mapped: Arc<AtomicBool>,
    done_at: Arc<Mutex<Option<Instant>>>,
    /// Per-step wall times measured while recording (step profiling).
    profiled: Option<Vec<f64>>,
}

#[derive(Default)]
struct Slot {
    queries: Option<Queries>,
    pending: Option<Pending>,
}

/// The ring of frame slots.
pub struct FrameRing {
    slots: Vec<Slot>,
    next: usize,
    finished: VecDeque<FrameStats>,
}

impl Default for FrameRing {
    fn default() -> Self {
        Self { slots: (0..MAX_FRAMES_IN_FLIGHT).map(|_| Slot::default()).collect(), next: 0, finished: VecDeque::new() }
    }
}

impl FrameRing {
    /// Takes the next slot for a frame of `steps` steps, waiting for its previous frame if it is
    /// still on the GPU; returns the query set and base index to time the steps with.
    pub(crate) fn begin(&mut self, gpu: &Gpu, steps: usize) -> Option<(wgpu::QuerySet, u32)> {
        let index = self.next;
        if let Some(p) = self.slots[index].pending.as_ref() {
            let submission = p.submission.clone();
            let _ = gpu.device.poll(wgpu::PollType::Wait { submission_index: Some(submission), timeout: None });
            self.collect(gpu, index);
        }
        if !gpu.has_timestamps || steps == 0 {
            return None;
        }
        let needed = (2 * steps) as u32;
        let slot = &mut self.slots[index];
        if slot.queries.as_ref().is_none_or(|q| q.capacity < needed) {
            let capacity = needed.next_power_of_two().max(16);
            let size = capacity as u64 * 8;
            slot.queries = Some(Queries {
                set: gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("step timestamps"),
                    ty: wgpu::QueryType::Timestamp,
                    count: capacity,
                }),
                resolve: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("timestamp resolve"),
                    size,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                }),
                read: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("timestamp readback"),
                    size,
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }),
                capacity,
            });
        }
        slot.queries.as_ref().map(|q| (q.set.clone(), 0))
    }

    /// Records the resolve of this frame's timestamps at the end of `encoder`.
    pub(crate) fn resolve(&self, encoder: &mut wgpu::CommandEncoder, steps: usize) {
        if let Some(q) = &self.slots[self.next].queries {
            let count = (2 * steps) as u32;
            if count > 0 && count <= q.capacity {
                encoder.resolve_query_set(&q.set, 0..count, &q.resolve, 0);
                encoder.copy_buffer_to_buffer(&q.resolve, 0, &q.read, 0, count as u64 * 8);
            }
        }
    }

    /// Tracks the frame just submitted in the current slot and moves on.
    pub(crate) fn submitted(
        &mut self,
        gpu: &Gpu,
        submission: wgpu::SubmissionIndex,
        frame_index: u64,
        pass_ids: Arc<Vec<String>>,
        submitted: Instant,
        profiled: Option<Vec<f64>>,
    ) {
        let slot = &mut self.slots[self.next];
        let mapped = Arc::new(AtomicBool::new(false));
        let done_at = Arc::new(Mutex::new(None));
        let steps = pass_ids.len();
        {
            let done_at = done_at.clone();
            let mapped_no_queries = mapped.clone();
            let has_queries = slot.queries.is_some() && steps > 0 && profiled.is_none();
            gpu.queue.on_submitted_work_done(move || {
                if let Ok(mut d) = done_at.lock() {
                    *d = Some(Instant::now());
                }
                if !has_queries {
                    mapped_no_queries.store(true, Ordering::Release);
                }
            });
            if has_queries && let Some(q) = &slot.queries {
                let flag = mapped.clone();
                let bytes = (2 * steps) as u64 * 8;
                q.read.slice(..bytes).map_async(wgpu::MapMode::Read, move |r| {
                    if r.is_ok() {
                        flag.store(true, Ordering::Release);
                    }
                });
            }
        }
        slot.pending = Some(Pending { submission, frame_index, pass_ids, steps, submitted, mapped, done_at, profiled });
        self.next = (self.next + 1) % self.slots.len();
    }

    fn collect(&mut self, gpu: &Gpu, index: usize) {
        let slot = &mut self.slots[index];
        let Some(p) = slot.pending.take() else { return };
        let done = p.done_at.lock().ok().and_then(|d| *d).unwrap_or_else(Instant::now);
        let wall_ms = done.saturating_duration_since(p.submitted).as_secs_f64() * 1e3;
        if let Some(ms) = p.profiled {
            let steps_ms: f64 = ms.iter().sum();
            self.finished.push_back(FrameStats {
                frame_index: p.frame_index,
                pass_ids: p.pass_ids,
                frame_ms: steps_ms,
                step_gpu_ms: Some(ms),
                // The steps were waited for before the last submit (the blit) was timed.
                wall_ms: steps_ms + wall_ms,
                wall_time_fallback: false,
                steps_serialised: true,
            });
            return;
        }
        let mut step_gpu_ms = None;
        if let Some(q) = &slot.queries
            && p.steps > 0
            && p.mapped.load(Ordering::Acquire)
        {
            let bytes = (2 * p.steps) as u64 * 8;
            let period_ns = gpu.queue.get_timestamp_period() as f64;
            if let Ok(data) = q.read.slice(..bytes).get_mapped_range() {
                let values: Vec<u64> = data
                    .chunks_exact(8)
                    .map(|c| u64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]))
                    .collect();
                step_gpu_ms = Some(
                    (0..p.steps)
                        .map(|i| {
                            let (a, b) = (values[2 * i], values[2 * i + 1]);
                            if b > a { (b - a) as f64 * period_ns / 1e6 } else { 0.0 }
                        })
                        .collect::<Vec<f64>>(),
                );
            }
            q.read.unmap();
        }
        let gpu_ms = step_gpu_ms.as_ref().filter(|_| gpu.timestamps_cover_work).map(|v: &Vec<f64>| v.iter().sum());
        let frame_ms = gpu_ms.unwrap_or(wall_ms);
        self.finished.push_back(FrameStats {
            frame_index: p.frame_index,
            pass_ids: p.pass_ids,
            wall_time_fallback: gpu_ms.is_none(),
            step_gpu_ms,
            frame_ms,
            wall_ms,
            steps_serialised: false,
        });
    }

    /// Collects the frames the GPU has finished, without blocking.
    pub(crate) fn poll(&mut self, gpu: &Gpu) -> Vec<FrameStats> {
        let _ = gpu.device.poll(wgpu::PollType::Poll);
        for i in 0..self.slots.len() {
            let ready = self.slots[i].pending.as_ref().is_some_and(|p| p.mapped.load(Ordering::Acquire));
            if ready {
                self.collect(gpu, i);
            }
        }
        self.drain()
    }

    /// Waits for every frame in flight and returns the finished frames' stats, oldest first.
    pub(crate) fn finish(&mut self, gpu: &Gpu) -> Vec<FrameStats> {
        gpu.wait_idle();
        // Oldest first: the slot after the last one used.
        for k in 0..self.slots.len() {
            let i = (self.next + k) % self.slots.len();
            self.collect(gpu, i);
        }
        self.drain()
    }

    fn drain(&mut self) -> Vec<FrameStats> {
        let mut out: Vec<FrameStats> = self.finished.drain(..).collect();
        out.sort_by_key(|s| s.frame_index);
        out
    }

    /// Frames submitted and not yet collected.
    pub fn in_flight(&self) -> usize {
        self.slots.iter().filter(|s| s.pending.is_some()).count()
    }
}
