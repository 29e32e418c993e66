//! Timing one case: a compiled graph renders one warm-up frame, then `frames` frames with the
//! volume turning about y; per-frame GPU time from timestamp queries (wall time where the
//! adapter has none) and per-pass GPU time summed over a pass's repeat-group instances.

use std::collections::BTreeMap;
use std::time::Instant;

use volgraph_accel::camera::OrbitCamera;
use volgraph_core::runtime::{CameraData, Runtime, RuntimeError};

pub use volgraph_accel::stats::median;

/// What the timed frames of one case gave.
#[derive(Clone, Debug)]
pub struct Timing {
    /// ms per timed frame (GPU or wall, see `wall_time_fallback`).
    pub frame_ms: Vec<f64>,
    /// Wall ms per timed frame, submit to completion as the CPU saw it.
    pub wall_ms: Vec<f64>,
    /// True when any frame's `frame_ms` is wall time (no timestamp queries).
    pub wall_time_fallback: bool,
    /// Median GPU ms per frame of each pass id (repeat-group instances summed within a frame);
    /// empty without timestamps.
    pub pass_ms: BTreeMap<String, f64>,
}

/// The camera of timed frame `index`: the start camera turned `index · degrees_per_frame` about y.
pub fn frame_camera(start: &OrbitCamera, degrees_per_frame: f64, index: u32) -> OrbitCamera {
    OrbitCamera { azimuth_deg: start.azimuth_deg + index as f64 * degrees_per_frame, ..*start }
}

/// Renders one warm-up frame (pipelines, first uploads) of the runtime's applied plan, then
/// `frames` timed frames, each submitted and waited for; `tick` is called after every frame.
pub fn time_frames(
    runtime: &mut Runtime,
    start: &OrbitCamera,
    degrees_per_frame: f64,
    frames: u32,
    mut tick: impl FnMut(),
) -> Result<Timing, RuntimeError> {
    let viewport = runtime.plan().ok_or(RuntimeError::NoPlan)?.viewport;
    runtime.render(CameraData::from_orbit(start, viewport))?;
    tick();
    let mut timing =
        Timing { frame_ms: Vec::new(), wall_ms: Vec::new(), wall_time_fallback: false, pass_ms: BTreeMap::new() };
    let mut per_pass: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    for f in 0..frames {
        let camera = frame_camera(start, degrees_per_frame, f);
        let t0 = Instant::now();
        let stats = runtime.render(CameraData::from_orbit(&camera, viewport))?;
        timing.wall_ms.push(t0.elapsed().as_secs_f64() * 1e3);
        timing.frame_ms.push(stats.frame_ms);
        timing.wall_time_fallback |= stats.wall_time_fallback;
        for (pass, ms) in stats.per_pass_ms() {
            per_pass.entry(pass).or_default().push(ms);
        }
        tick();
    }
    if !timing.wall_time_fallback {
        timing.pass_ms = per_pass.into_iter().map(|(pass, v)| (pass, median(&v))).collect();
    }
    Ok(timing)
}
