//! What a streaming raycaster (`raycast_stream`, graphs/streaming/) reports after each frame,
//! and the frames `volgraph render` adds until the image is complete: the rays asked for no
//! brick they lacked and none is being read (or `--time-budget-ms` ran out).

use std::time::{Duration, Instant};

/// One streaming pass's counters after a frame.
#[derive(Clone, Debug, PartialEq)]
pub struct StreamProgress {
    /// The pass.
    pub pass: String,
    /// Levels of the pyramid.
    pub levels: f64,
    /// Bricks of all levels.
    pub bricks: f64,
    /// Bricks read since the volume was bound.
    pub read: f64,
    /// Resident in the pool now.
    pub resident: f64,
    /// Known transparent (never read, or read and transparent).
    pub empty: f64,
    /// Asked for and not yet placed.
    pub pending: f64,
    /// Asked for by the last frame's rays.
    pub requested: f64,
    /// Placed in the pool this frame.
    pub placed: f64,
    /// Refused for want of a pool slot.
    pub refused: f64,
    /// Could not be read (drawn empty).
    pub unreadable: f64,
    /// This frame read the feedback of the frame before, which saw what it sees (else
    /// `missing` is not known yet).
    pub feedback_read: bool,
    /// Bricks the frame before wanted and lacked (drawn from a coarser level).
    pub missing: f64,
    /// Pool slots and bytes.
    pub slots: f64,
    /// See `slots`.
    pub pool_bytes: f64,
}

impl StreamProgress {
    /// The streaming passes among `counters` (`Runtime::pass_counters`).
    pub fn of(counters: &[(String, &'static str, f64)]) -> Vec<Self> {
        let mut passes: Vec<&str> =
            counters.iter().filter(|(_, n, _)| *n == "pending_bricks").map(|(p, _, _)| p.as_str()).collect();
        passes.dedup();
        passes
            .into_iter()
            .map(|pass| {
                let get = |name: &str| counters.iter().find(|(p, n, _)| p == pass && *n == name).map_or(0.0, |c| c.2);
                Self {
                    pass: pass.to_string(),
                    levels: get("levels"),
                    bricks: get("bricks"),
                    read: get("read_bricks"),
                    resident: get("resident_bricks"),
                    empty: get("empty_bricks"),
                    pending: get("pending_bricks"),
                    requested: get("requested_bricks"),
                    placed: get("placed_bricks"),
                    refused: get("refused_bricks"),
                    unreadable: get("unreadable_bricks"),
                    feedback_read: get("feedback_read") > 0.0,
                    missing: get("missing_bricks"),
                    slots: get("pool_slots"),
                    pool_bytes: get("pool_bytes"),
                }
            })
            .collect()
    }

    /// The frame drew everything its rays wanted at the level they wanted: the frame before,
    /// which saw the same view, lacked no brick, and this one holds every brick that one drew
    /// (the pool never evicts what the last frame drew).
    pub fn complete(&self) -> bool {
        self.feedback_read && self.missing == 0.0
    }

    /// The line `volgraph render` prints.
    pub fn line(&self) -> String {
        let mut line = format!(
            "{}: {} levels; {} of {} bricks read, {} resident in {} slots ({:.1} MiB), {} empty; {} pending",
            self.pass,
            self.levels,
            self.read,
            self.bricks,
            self.resident,
            self.slots,
            self.pool_bytes / (1024.0 * 1024.0),
            self.empty,
            self.pending
        );
        if self.refused > 0.0 {
            line.push_str(&format!(
                "; {} bricks found no slot (the pool holds what one frame draws and no more): drawn coarser; raise \
                 --gpu-memory-mb",
                self.refused
            ));
        }
        if self.unreadable > 0.0 {
            line.push_str(&format!("; {} bricks could not be read (drawn empty)", self.unreadable));
        }
        line
    }
}

/// Renders frames at the same camera until every streaming pass is complete or `budget` has
/// passed since `started`; returns whether it completed. Between frames it waits for the
/// bricks asked for to be read (`wait`, up to the budget left), so a frame is drawn when there
/// is more to show, not while the readers need the cores.
pub fn refine(
    started: Instant,
    budget: Option<Duration>,
    mut frame: impl FnMut() -> Result<Vec<StreamProgress>, anyhow::Error>,
    mut wait: impl FnMut(Duration),
    mut progress: Vec<StreamProgress>,
) -> Result<(bool, Vec<StreamProgress>), anyhow::Error> {
    loop {
        if progress.iter().all(StreamProgress::complete) {
            return Ok((true, progress));
        }
        let left = budget.map(|b| b.saturating_sub(started.elapsed()));
        if left == Some(Duration::ZERO) {
            return Ok((false, progress));
        }
        wait(left.unwrap_or(Duration::from_secs(10)).min(Duration::from_secs(10)));
        progress = frame()?;
    }
}

/// [`refine`] on `runtime` at `camera`: frames until every streaming pass is complete or
/// `budget` has passed since `started`, waiting for the readers between frames
/// (`Runtime::wait_for_background`); `on_frame` sees each frame's stats. What `volgraph render`,
/// the Python API and `bench stream` run after a first frame.
pub fn refine_runtime(
    runtime: &mut volgraph_core::runtime::Runtime,
    camera: volgraph_core::runtime::CameraData,
    started: Instant,
    budget: Option<Duration>,
    mut on_frame: impl FnMut(volgraph_core::runtime::FrameStats),
) -> Result<(bool, Vec<StreamProgress>), anyhow::Error> {
    let progress = StreamProgress::of(&runtime.pass_counters());
    // The two closures take turns with the runtime: one draws, the other waits.
    let runtime = std::cell::RefCell::new(runtime);
    refine(
        started,
        budget,
        || {
            let mut runtime = runtime.borrow_mut();
            on_frame(runtime.render(camera).map_err(|e| anyhow::anyhow!(e))?);
            Ok(StreamProgress::of(&runtime.pass_counters()))
        },
        |timeout| runtime.borrow().wait_for_background(timeout),
        progress,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn counters(pending: f64, missing: f64) -> Vec<(String, &'static str, f64)> {
        vec![
            ("march".into(), "pending_bricks", pending),
            ("march".into(), "missing_bricks", missing),
            ("march".into(), "placed_bricks", 1.0),
            ("march".into(), "feedback_read", 1.0),
        ]
    }

    /// Frames go on until the frame before lacked nothing (bricks still pending from older
    /// requests do not matter).
    #[test]
    fn refinement_stops_when_nothing_is_pending_or_asked_for() {
        let mut script = vec![counters(2.0, 5.0), counters(3.0, 1.0), counters(1.0, 0.0)].into_iter();
        let mut frames = 0;
        let mut waits = 0;
        let (done, last) = refine(
            Instant::now(),
            None,
            || {
                frames += 1;
                Ok(StreamProgress::of(&script.next().expect("no more frames than scripted")))
            },
            |_| waits += 1,
            StreamProgress::of(&counters(1.0, 1.0)),
        )
        .unwrap();
        assert_eq!(waits, 3, "a wait for the readers before each frame");
        assert!(done && last[0].complete());
        assert_eq!(frames, 3);
        let (done, _) = refine(
            Instant::now(),
            Some(Duration::ZERO),
            || unreachable!(),
            |_| (),
            StreamProgress::of(&counters(1.0, 1.0)),
        )
        .unwrap();
        assert!(!done, "a spent budget stops at once");
    }
}
