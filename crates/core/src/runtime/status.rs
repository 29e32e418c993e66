//! Settings and status of a [`Runtime`]: step profiling, the GPU memory budget, the frame index,
//! what the passes and bypasses report, how history was used and the memory held.

use super::{BypassStatus, Runtime};

impl Runtime {
    /// Times every step of the following frames by wall clock, each submitted on its own and
    /// waited for (`FrameStats::step_gpu_ms` then holds these times, `steps_serialised` says
    /// so): per-pass costs on adapters whose timestamps do not cover compute work (lavapipe).
    /// Serialises the GPU, so the frames themselves get slower.
    pub fn set_step_profiling(&mut self, on: bool) {
        self.profile_steps = on;
    }

    /// Whether [`Runtime::set_step_profiling`] is on.
    pub fn step_profiling(&self) -> bool {
        self.profile_steps
    }

    /// The index the next submitted frame gets (`FrameStats::frame_index`).
    pub fn next_frame_index(&self) -> u64 {
        self.frame_index
    }

    /// Bounds the GPU memory passes that stream data may hold (a brick pool), in bytes; `None`
    /// leaves it to the pass (raycast_bricks: 2 GiB, bounded by the 3D texture limit). Takes
    /// effect with the next frame.
    pub fn set_gpu_memory_budget(&mut self, bytes: Option<u64>) {
        self.gpu_memory_budget = bytes;
    }

    /// Waits, up to `timeout` in all, for the work the applied plan's passes have in flight off
    /// the GPU ([`crate::plugin::PassNode::wait_for_background`]: bricks being read).
    pub fn wait_for_background(&self, timeout: std::time::Duration) {
        let Some(live) = &self.live else { return };
        let deadline = std::time::Instant::now() + timeout;
        for entry in live.nodes.values() {
            entry.node.wait_for_background(deadline.saturating_duration_since(std::time::Instant::now()));
        }
    }

    /// Figures the applied plan's passes report about their last frame ([`crate::plugin::PassNode::counters`]),
    /// as `(pass id, name, value)` in step order.
    pub fn pass_counters(&self) -> Vec<(String, &'static str, f64)> {
        let Some(live) = &self.live else { return Vec::new() };
        let mut out = Vec::new();
        let mut seen = std::collections::HashSet::new();
        for step in &live.plan.steps {
            if !seen.insert(step.pass_id.clone()) {
                continue;
            }
            if let Some(entry) = live.nodes.get(&step.pass_id) {
                out.extend(entry.node.counters().into_iter().map(|(name, v)| (step.pass_id.clone(), name, v)));
            }
        }
        out
    }

    /// How the graph's history has been used: frames that read the previous frame's values
    /// (Klein et al. 2005: frames that ran from reprojected starts) and how often it started
    /// over. Zero for a graph without history.
    pub fn history_stats(&self) -> HistoryStats {
        self.history_stats
    }

    /// What each of the plan's bypasses (a graph's `bypass:`) did: left out or not in the last
    /// submitted frame, its newest measure per pixel, frames counted since the plan was applied.
    pub fn bypass_status(&self) -> Vec<BypassStatus> {
        self.bypasses.status()
    }

    /// Memory held, for reports and soak tests.
    pub fn memory(&self) -> MemoryInUse {
        MemoryInUse {
            transient_bytes: self.plan().map_or(0, |p| p.memory().pooled_bytes),
            pooled_free_bytes: self.textures.free_bytes(),
            history_bytes: self.history.bytes(),
            input_bytes: self.inputs.bytes(),
            pipelines: self.pipelines.len(),
            textures_created: self.textures.created(),
            bind_groups_created: self.live.as_ref().map_or(0, |s| s.bind_groups.borrow().created()),
        }
    }
}

/// Memory the runtime holds, for reports and soak tests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MemoryInUse {
    /// Transient targets of the current plan.
    pub transient_bytes: u64,
    /// Free textures kept in the pool.
    pub pooled_free_bytes: u64,
    /// History entries (both textures).
    pub history_bytes: u64,
    /// Bound inputs (volume, LUT).
    pub input_bytes: u64,
    /// Cached pipelines.
    pub pipelines: usize,
    /// Textures created since start.
    pub textures_created: u64,
    /// Bind groups created since the current plan was applied.
    pub bind_groups_created: u64,
}

/// How a graph's history was used (see [`Runtime::history_stats`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HistoryStats {
    /// Frames that read the previous frame's history instead of its initial value.
    pub frames_from_history: u64,
    /// Consecutive frames up to the last one that read the previous frame's history.
    pub run: u64,
    /// How often history started over after being used (resize, edit, new input, camera jump).
    pub restarts: u64,
}
