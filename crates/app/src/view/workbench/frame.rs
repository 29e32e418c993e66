//! The frame policy: what the window asks before each frame. While the camera moves the level of
//! detail ([`Lod`]) lowers the resolution and widens the step so frames hold their target time;
//! at rest the full image comes back. Once the full image has rested a moment, the view's error
//! against the converged reference is measured (`accuracy.rs`), once per view. The policy decides
//! and the window carries it out, on anything that can take a viewport and a step factor
//! ([`LodTarget`]: the live session, or a test's stand-in).

use std::time::{Duration, Instant};

use crate::view::accuracy::Accuracy;
use crate::view::lod::Lod;
use crate::view::session::Event;

/// How long the view must rest (unchanged, full resolution) before its error is measured.
pub const MEASURE_AFTER: Duration = Duration::from_millis(600);

/// What the level of detail changes: the image's viewport and the step factor.
pub trait LodTarget {
    /// The viewport rendered now.
    fn viewport(&self) -> (u32, u32);
    /// Renders at `size` from now on; the events of the change.
    fn resize(&mut self, width: u32, height: u32) -> Vec<Event>;
    /// The step factor now (1: the graph's own).
    fn step_factor(&self) -> f64;
    /// Widens the step by `factor`; whether it is now `factor` (a graph may refuse it).
    fn set_step_factor(&mut self, factor: f64) -> bool;
    /// The index the next submitted frame gets.
    fn next_frame_index(&self) -> u64;
}

/// The level of detail and the live accuracy's schedule of one window.
#[derive(Clone, Debug)]
pub struct FramePolicy {
    lod: Lod,
    /// Since when the view on screen has changed without being measured.
    unmeasured_since: Option<Instant>,
}

impl Default for FramePolicy {
    fn default() -> Self {
        Self { lod: Lod::default(), unmeasured_since: Some(Instant::now()) }
    }
}

impl FramePolicy {
    /// The level of detail (for the panel).
    pub fn lod(&self) -> &Lod {
        &self.lod
    }

    /// The panel's level-of-detail settings: on or off, and the frame rate to hold while moving.
    pub fn set_lod(&mut self, enabled: bool, target_fps: f64) {
        self.lod.enabled = enabled;
        self.lod.target_ms = 1000.0 / target_fps.max(1.0);
    }

    /// The view on screen changed (an edit, a turn of `--turn`): it is measured again once it
    /// rests.
    pub fn changed(&mut self) {
        self.changed_at(Instant::now());
    }

    /// [`Self::changed`] at `at`.
    pub fn changed_at(&mut self, at: Instant) {
        self.unmeasured_since = Some(at);
    }

    /// The camera moved (a drag step, a wheel turn) or a TF point was dragged: coarse frames
    /// until it rests.
    pub fn moved(&mut self) {
        self.moved_at(Instant::now());
    }

    /// [`Self::moved`] at `at`.
    pub fn moved_at(&mut self, at: Instant) {
        self.lod.moved_at(at);
        self.changed_at(at);
    }

    /// Before a frame in a window of `window` pixels: puts the viewport and step factor the
    /// level of detail wants on `target`; the events of the resize. A step the graph refuses is
    /// not asked for again, and frames submitted before a change do not count toward the next.
    pub fn apply_lod(&mut self, window: (u32, u32), target: &mut impl LodTarget) -> Vec<Event> {
        let before = (target.viewport(), target.step_factor());
        let want = self.lod.viewport(window);
        let mut events = Vec::new();
        if want != target.viewport() {
            events = target.resize(want.0, want.1);
        }
        if !target.set_step_factor(self.lod.step_factor()) {
            self.lod.refuse_step();
        }
        if (target.viewport(), target.step_factor()) != before {
            self.lod.changed_at(target.next_frame_index());
        }
        events
    }

    /// Frame `frame_index` took `frame_ms` on the GPU.
    pub fn observe(&mut self, frame_index: u64, frame_ms: f64) {
        self.lod.observe(frame_index, frame_ms);
    }

    /// Whether to measure the view's error now: it changed and has rested [`MEASURE_AFTER`] at
    /// full resolution, nothing is dragged and no measurement is running. Yes marks the view
    /// measured.
    pub fn measure_now(&mut self, dragging: bool, measuring: bool) -> bool {
        self.measure_at(Instant::now(), dragging, measuring)
    }

    /// [`Self::measure_now`] at `now`.
    pub fn measure_at(&mut self, now: Instant, dragging: bool, measuring: bool) -> bool {
        let due = self.unmeasured_since.is_some_and(|since| now.saturating_duration_since(since) > MEASURE_AFTER)
            && self.lod.step_factor() == 1.0
            && !dragging
            && !measuring;
        if due {
            self.unmeasured_since = None;
        }
        due
    }

    /// The panel's accuracy line, from the last measurement and whether one is running.
    pub fn accuracy_line(&self, last: Option<&Accuracy>, measuring: bool) -> String {
        match (last, measuring) {
            (_, true) => "error vs converged f64: measuring…".to_string(),
            (Some(a), false) if self.unmeasured_since.is_none() => a.line(),
            (Some(_), false) => "error vs converged f64: measured once the view rests".to_string(),
            (None, false) => "error vs converged f64: not measured for this graph".to_string(),
        }
    }
}
