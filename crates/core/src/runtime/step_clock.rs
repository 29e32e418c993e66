//! Per-step wall times for adapters whose timestamps do not cover the work (Mesa lavapipe's
//! cover no compute dispatch): with [`super::Runtime::set_step_profiling`] on, every step of a
//! frame is submitted on its own and waited for, so the wall time between two waits is that
//! step's cost (plus one submit). It serialises the GPU, so frames get slower: a tool for finding
//! where a frame's time goes, not for measuring its total.

use std::time::Instant;

use super::gpu::Gpu;

/// Laps between steps: each lap submits what was recorded so far, waits for it, and closes the
/// previous step's time.
pub(crate) struct StepClock<'a> {
    gpu: &'a Gpu,
    started: Option<Instant>,
    /// Wall milliseconds per step closed so far, in step order.
    pub(crate) ms: Vec<f64>,
}

impl<'a> StepClock<'a> {
    pub(crate) fn new(gpu: &'a Gpu) -> Self {
        Self { gpu, started: None, ms: Vec::new() }
    }

    /// Submits `encoder`'s commands (leaving a fresh encoder in its place), waits for the GPU,
    /// closes the running step's time and starts the next one's.
    pub(crate) fn lap(&mut self, encoder: &mut wgpu::CommandEncoder) {
        let fresh =
            self.gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("step clock") });
        let recorded = std::mem::replace(encoder, fresh);
        self.gpu.queue.submit([recorded.finish()]);
        self.gpu.wait_idle();
        if let Some(t0) = self.started.take() {
            self.ms.push(t0.elapsed().as_secs_f64() * 1e3);
        }
        self.started = Some(Instant::now());
    }
}
