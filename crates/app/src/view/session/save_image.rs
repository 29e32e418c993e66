//! "Save image…" at a chosen size (issue 45 item 3): the view rendered again at that size at
//! full quality — the graph applied at the new viewport, the level of detail's step back to 1,
//! a path tracer given the samples the window has accumulated — written as PNG, and the window's
//! viewport and step put back. `S` saves what the window shows at the window's size.

use std::path::Path;

use anyhow::{anyhow, bail};
use volgraph_accel::camera::OrbitCamera;

use super::{Event, LiveSession};

/// The largest side "save image…" renders (a 16K image; the GPU's 2D texture limit is at
/// least 8192 and usually 16384 or more).
pub const MAX_SAVED_SIDE: u32 = 16384;

impl LiveSession {
    /// Renders the view of `camera` at `size` pixels and writes it to `path` (PNG). The window's
    /// viewport and level-of-detail step are restored whatever happens.
    pub fn save_image(&mut self, camera: &OrbitCamera, size: (u32, u32), path: &Path) -> anyhow::Result<()> {
        if !(1..=MAX_SAVED_SIDE).contains(&size.0) || !(1..=MAX_SAVED_SIDE).contains(&size.1) {
            bail!("{}x{}: an image size is 1 to {MAX_SAVED_SIDE} pixels a side", size.0, size.1);
        }
        crate::view::screenshot_target(path).map_err(|e| anyhow!(e))?;
        let (viewport, step) = (self.options().viewport, self.step_factor());
        // A progressive graph gets as many samples as the window shows (at least one).
        let samples = match self.plan() {
            Some(plan) if crate::render::accumulates(plan) => (self.runtime.history_stats().run + 1).min(4096),
            _ => 1,
        };
        let rendered = self.render_at(camera, size, samples, path);
        self.set_step_factor(step);
        let restored = self.resize(viewport.0, viewport.1);
        if let Some(Event::Error { message, .. }) = restored.iter().find(|e| matches!(e, Event::Error { .. })) {
            bail!("the image was saved but the window's viewport could not be restored: {message}");
        }
        rendered
    }

    fn render_at(&mut self, camera: &OrbitCamera, size: (u32, u32), samples: u64, path: &Path) -> anyhow::Result<()> {
        self.set_step_factor(1.0);
        let events = self.resize(size.0, size.1);
        if let Some(Event::Error { message, .. }) = events.iter().find(|e| matches!(e, Event::Error { .. })) {
            bail!("cannot render at {}x{}: {message}", size.0, size.1);
        }
        for _ in 0..samples {
            self.frame(camera, None).map_err(|e| anyhow!("{e}"))?;
        }
        self.runtime.finish();
        let output = self.shown_output();
        let image = self.runtime.read_output(output).map_err(|e| anyhow!("{e}"))?;
        // `display` is `present`'s 8-bit sRGB; `image` is linear.
        crate::image_out::write_png(path, &image, output == "display")
    }
}
