//! Interactive while moving (issue 24 §6; VTK's AutoAdjustSampleDistances and ParaView's LOD
//! do the same): while the camera is dragged or zoomed, the viewer renders fewer pixels so a
//! frame fits a target time, and returns to the full image once input has rested. The window's
//! blit scales the coarse image up (nearest), the panel says which image is on screen.
//!
//! The scale is `sqrt(target / full)` (ray-cast frames cost in proportion to pixels), snapped to
//! a few steps so a drag does not reallocate targets every frame, and never below a quarter.
//! Samples get twice as far apart in a coarse image; where the quarter scale still misses the
//! target (a frame whose cost is per slice or per pass, not per pixel: slice-based rendering),
//! they get further apart again, up to eight times, until the frames fit.

use std::time::{Duration, Instant};

/// How long input must rest before the full image comes back.
const REST: Duration = Duration::from_millis(300);
/// The coarsest scale (per axis).
const MIN_SCALE: f64 = 0.25;
/// The step factor of a coarse image.
const STEP_FACTOR: f64 = 2.0;
/// The largest step factor, where the coarsest scale alone misses the target.
const MAX_STEP_FACTOR: f64 = 8.0;
/// The scales a drag may take (per axis).
const STEPS: [f64; 5] = [1.0, 0.75, 0.5, 0.35, 0.25];

/// The level-of-detail state of one window.
#[derive(Clone, Debug)]
pub struct Lod {
    /// Render coarser while moving.
    pub enabled: bool,
    /// The frame time to hold while moving, ms (default: 15 fps).
    pub target_ms: f64,
    last_motion: Option<Instant>,
    /// Smoothed frame time at full resolution, ms (0 until measured).
    full_ms: f64,
    /// The scale of the image on screen (1 = full).
    scale: f64,
    /// The graph refused a wider step (a parameter range): only the resolution drops.
    pub step_refused: bool,
    /// The step factor of the coarse image now (2, more where the coarsest scale misses the target).
    step: f64,
    /// The widest step the graph took (a wider one was refused).
    step_cap: f64,
    /// Frames before this index were submitted before the scale or step last changed: their
    /// times say nothing about the image on screen now.
    valid_from: u64,
}

impl Default for Lod {
    fn default() -> Self {
        Self {
            enabled: true,
            target_ms: 1000.0 / 15.0,
            last_motion: None,
            full_ms: 0.0,
            scale: 1.0,
            step_refused: false,
            step: STEP_FACTOR,
            step_cap: MAX_STEP_FACTOR,
            valid_from: 0,
        }
    }
}

impl Lod {
    /// The camera moved (a drag step, a wheel turn).
    pub fn moved(&mut self) {
        self.moved_at(Instant::now());
    }

    /// The camera moved at `at`.
    pub fn moved_at(&mut self, at: Instant) {
        self.last_motion = Some(at);
    }

    /// The scale or step just changed: frames from `next_frame` on are rendered with them.
    pub fn changed_at(&mut self, next_frame: u64) {
        self.valid_from = next_frame;
    }

    /// Finished frame `frame_index`'s time; it counts toward the full-resolution figure only when
    /// the full image was on screen and nothing moved, and widens a coarse image's step only
    /// when it was rendered with the scale and step on screen now ([`Self::changed_at`]).
    pub fn observe(&mut self, frame_index: u64, frame_ms: f64) {
        if !(frame_ms.is_finite() && frame_ms > 0.0) || frame_index < self.valid_from {
            return;
        }
        if self.scale == 1.0 && !self.moving() {
            self.full_ms = if self.full_ms == 0.0 { frame_ms } else { self.full_ms + 0.2 * (frame_ms - self.full_ms) };
        } else if self.scale <= MIN_SCALE && self.moving() && frame_ms > self.target_ms {
            // The coarsest image still misses the target: samples further apart.
            self.step = (self.step * 2.0).min(self.step_cap);
        }
    }

    /// The graph refused the step factor asked for (a parameter's range): fall back to the last
    /// one it took, or to the graph's own step.
    pub fn refuse_step(&mut self) {
        if self.step > STEP_FACTOR {
            self.step /= 2.0;
            self.step_cap = self.step;
        } else {
            self.step_refused = true;
        }
    }

    fn moving(&self) -> bool {
        self.last_motion.is_some_and(|t| t.elapsed() < REST)
    }

    /// The viewport to render now for a window of `window` pixels.
    pub fn viewport(&mut self, window: (u32, u32)) -> (u32, u32) {
        self.scale = if self.enabled && self.moving() && self.full_ms > self.target_ms {
            let wanted = (self.target_ms / self.full_ms).sqrt().clamp(MIN_SCALE, 1.0);
            // The largest step that still fits the target.
            STEPS.iter().copied().find(|s| *s <= wanted + 1e-9).unwrap_or(MIN_SCALE)
        } else {
            self.step = STEP_FACTOR;
            1.0
        };
        let scaled = |n: u32| ((n as f64 * self.scale).round() as u32).max(1);
        (scaled(window.0), scaled(window.1))
    }

    /// The factor on every raycaster's step: twice as far apart while the image is coarse (the
    /// samples per ray halve, as VTK's AutoAdjustSampleDistances does; a slicer's slices and a
    /// multipass graph's segments get as much further apart and longer:
    /// `LiveSession::set_step_factor`), 1 for the full image.
    pub fn step_factor(&self) -> f64 {
        if self.scale < 1.0 && !self.step_refused { self.step } else { 1.0 }
    }

    /// What the panel says about the image on screen.
    pub fn line(&self) -> String {
        if self.scale < 1.0 {
            format!(
                "image: coarse, {:.0}% per axis{} while moving (full: {:.0} ms, target {:.0} ms)",
                self.scale * 100.0,
                if self.step_factor() > 1.0 { format!(", step ×{}", self.step_factor()) } else { String::new() },
                self.full_ms,
                self.target_ms
            )
        } else {
            "image: full resolution".to_string()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moving_renders_coarser_to_hold_the_target_and_resting_restores_the_full_image() {
        let mut lod = Lod::default();
        lod.observe(0, 400.0);
        assert_eq!(lod.viewport((800, 600)), (800, 600), "at rest: the full image");
        lod.moved();
        // sqrt(66.7 / 400) = 0.41 → the 0.35 step.
        assert_eq!(lod.viewport((800, 600)), (280, 210));
        assert!(lod.line().contains("coarse, 35% per axis, step ×2"), "{}", lod.line());
        assert_eq!(lod.step_factor(), 2.0);
        // A frame observed while moving does not count as a full-resolution time.
        lod.observe(0, 30.0);
        assert_eq!(lod.viewport((800, 600)), (280, 210));
        lod.last_motion = Some(Instant::now() - REST - Duration::from_millis(1));
        assert_eq!(lod.viewport((800, 600)), (800, 600), "rested: full again");
        assert_eq!(lod.step_factor(), 1.0);
        // A view that already fits the target is never coarsened.
        let mut fast = Lod::default();
        fast.observe(0, 20.0);
        fast.moved();
        assert_eq!(fast.viewport((800, 600)), (800, 600));
        fast.enabled = false;
        assert_eq!(fast.viewport((800, 600)), (800, 600));
    }

    #[test]
    fn where_the_coarsest_image_misses_the_target_the_step_widens_up_to_eight() {
        let mut lod = Lod::default();
        lod.observe(0, 3000.0);
        lod.moved();
        assert_eq!(lod.viewport((800, 600)), (200, 150), "the coarsest scale");
        assert_eq!(lod.step_factor(), 2.0);
        lod.observe(0, 130.0);
        assert_eq!(lod.step_factor(), 4.0, "130 ms > the 67 ms target");
        lod.observe(0, 90.0);
        lod.observe(0, 80.0);
        assert_eq!(lod.step_factor(), 8.0, "never more than eight");
        lod.observe(0, 40.0);
        assert_eq!(lod.step_factor(), 8.0, "kept while moving");
        // A frame submitted before the step changed does not widen it again.
        lod.changed_at(10);
        lod.observe(9, 500.0);
        assert_eq!(lod.step_factor(), 8.0);
        // The graph refuses ×8: back to ×4, and never asked for more.
        lod.refuse_step();
        assert_eq!(lod.step_factor(), 4.0);
        lod.observe(11, 200.0);
        assert_eq!(lod.step_factor(), 4.0);
        // At rest the full image, and the next drag starts at ×2 again.
        lod.last_motion = Some(Instant::now() - REST - Duration::from_millis(1));
        assert_eq!(lod.viewport((800, 600)), (800, 600));
        assert_eq!(lod.step_factor(), 1.0);
        lod.moved();
        lod.viewport((800, 600));
        assert_eq!(lod.step_factor(), 2.0);
    }
}
