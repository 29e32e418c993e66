//! Bypasses at run time (`Plan::bypass`, a graph's `bypass:`): each frame leaves out a
//! bypass's steps while the last measured frame's per-pixel mean of its measure buffer was
//! below the threshold, and clears what they would have written for the steps that still run.
//! The measure is copied out right after its step (its pooled slot may hold something else
//! later in the frame) into a small ring of read-back buffers, mapped without waiting: the
//! decision uses the newest frame the GPU has finished, one or two frames late — "the last
//! frame shows it cannot pay" — and never stalls a frame.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use volgraph_compiler::plan::{Bypass, Plan};

use super::frames::MAX_FRAMES_IN_FLIGHT;
use super::gpu::Gpu;

/// What a bypass did, for viewers, benchmarks and tests.
#[derive(Clone, Debug, PartialEq)]
pub struct BypassStatus {
    /// The graph's name for it.
    pub name: String,
    /// Whether the last submitted frame left its steps out.
    pub bypassed: bool,
    /// The newest measure read back, per viewport pixel (`None` before the first).
    pub measure: Option<f64>,
    /// Its threshold per pixel.
    pub below: f64,
    /// Frames submitted with its steps left out since the plan was applied.
    pub frames_bypassed: u64,
    /// Frames submitted with its steps run.
    pub frames_run: u64,
}

/// One read-back buffer of the ring: idle, or copied into by frame `frame` and being mapped.
struct Readback {
    buffer: wgpu::Buffer,
    /// (frame index, viewport pixels) of the frame whose measure it holds.
    frame: Option<(u64, u64)>,
    mapped: Arc<AtomicBool>,
}

struct Rule {
    plan: Bypass,
    bytes: u64,
    ring: Vec<Readback>,
    /// (frame index, measure per pixel) of the newest measure read.
    newest: Option<(u64, f64)>,
    bypassed: bool,
    frames_bypassed: u64,
    frames_run: u64,
    /// Measures of frames before this one are stale (`Bypasses::forget`).
    measured_from: u64,
    /// Ring slots this frame copies into (mapped after submit).
    copying: Vec<usize>,
}

/// The bypasses of the applied plan.
#[derive(Default)]
pub(crate) struct Bypasses {
    rules: Vec<Rule>,
}

/// This frame's choices: which steps are left out, and after which step a measure is copied
/// into which buffer.
#[derive(Default)]
pub(crate) struct FrameBypass<'a> {
    pub left_out: Vec<bool>,
    pub copies: Vec<(usize, volgraph_compiler::plan::ResourceId, &'a wgpu::Buffer, u64)>,
}

impl Bypasses {
    /// The bypasses of `plan`, starting with every step run (nothing is measured yet); a rule of
    /// the same name and steps as before keeps its last measure.
    pub(crate) fn for_plan(&mut self, gpu: &Gpu, plan: &Plan, keep_measures: bool) {
        let old = if keep_measures {
            std::mem::take(&mut self.rules)
        } else {
            self.rules.clear();
            Vec::new()
        };
        for b in &plan.bypass {
            let bytes = plan.resources[b.measure].desc.bytes().max(4);
            let kept = old.iter().find(|r| r.plan.name == b.name && r.bytes == bytes);
            let ring = (0..MAX_FRAMES_IN_FLIGHT + 1)
                .map(|_| Readback {
                    buffer: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("bypass measure readback"),
                        size: bytes,
                        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    }),
                    frame: None,
                    mapped: Arc::new(AtomicBool::new(false)),
                })
                .collect();
            self.rules.push(Rule {
                plan: b.clone(),
                bytes,
                ring,
                newest: kept.and_then(|r| r.newest),
                bypassed: kept.is_some_and(|r| r.bypassed),
                frames_bypassed: 0,
                frames_run: 0,
                measured_from: kept.map_or(0, |r| r.measured_from),
                copying: Vec::new(),
            });
        }
    }

    /// Reads every measure the GPU has finished (without waiting) and decides this frame's
    /// left-out steps; picks the ring slots this frame's measures go to.
    pub(crate) fn begin_frame(&mut self, gpu: &Gpu, steps: usize, frame_index: u64, pixels: u64) -> FrameBypass<'_> {
        if self.rules.is_empty() {
            return FrameBypass { left_out: vec![false; steps], copies: Vec::new() };
        }
        let _ = gpu.device.poll(wgpu::PollType::Poll);
        let mut left_out = vec![false; steps];
        for rule in &mut self.rules {
            rule.collect();
            rule.bypassed = rule.newest.is_some_and(|(_, mean)| mean < rule.plan.below);
            if rule.bypassed {
                rule.frames_bypassed += 1;
                for &s in rule.plan.steps.iter().filter(|&&s| s < steps) {
                    left_out[s] = true;
                }
            } else {
                rule.frames_run += 1;
            }
            rule.copying.clear();
            // A free slot, or none (the measure of this frame is then not read: the ring is
            // one longer than the frames in flight, so this happens only when results pile up).
            if let Some(slot) = rule.ring.iter().position(|r| r.frame.is_none()) {
                rule.ring[slot].frame = Some((frame_index, pixels));
                rule.copying.push(slot);
            }
        }
        let copies = self
            .rules
            .iter()
            .flat_map(|rule| {
                rule.copying
                    .iter()
                    .map(|&slot| (rule.plan.measure_step, rule.plan.measure, &rule.ring[slot].buffer, rule.bytes))
            })
            .collect();
        FrameBypass { left_out, copies }
    }

    /// After the frame is submitted: maps the buffers its measures were copied into.
    pub(crate) fn submitted(&mut self) {
        for rule in &mut self.rules {
            for &slot in &rule.copying {
                let readback = &rule.ring[slot];
                let flag = readback.mapped.clone();
                readback.buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
                    if r.is_ok() {
                        flag.store(true, Ordering::Release);
                    }
                });
            }
            rule.copying.clear();
        }
    }

    /// Forgets every measure of frames before `frame` (history started over: a new volume or
    /// TF, a camera jump): until one of the new view arrives, every step runs.
    pub(crate) fn forget(&mut self, frame: u64) {
        for rule in &mut self.rules {
            rule.newest = None;
            rule.bypassed = false;
            rule.measured_from = frame;
        }
    }

    /// A frame failed to record or submit: its ring slots hold nothing.
    pub(crate) fn abandoned(&mut self) {
        for rule in &mut self.rules {
            for &slot in &rule.copying {
                rule.ring[slot].frame = None;
            }
            rule.copying.clear();
        }
    }

    /// What each bypass did.
    pub(crate) fn status(&self) -> Vec<BypassStatus> {
        self.rules
            .iter()
            .map(|r| BypassStatus {
                name: r.plan.name.clone(),
                bypassed: r.bypassed,
                measure: r.newest.map(|(_, m)| m),
                below: r.plan.below,
                frames_bypassed: r.frames_bypassed,
                frames_run: r.frames_run,
            })
            .collect()
    }
}

impl Rule {
    /// Takes the measures whose mapping finished: the newest frame's wins.
    fn collect(&mut self) {
        for readback in &mut self.ring {
            let Some((frame, pixels)) = readback.frame else { continue };
            if !readback.mapped.swap(false, Ordering::Acquire) {
                continue;
            }
            let sum: u64 = match readback.buffer.slice(..).get_mapped_range() {
                Ok(bytes) => bytemuck::cast_slice::<u8, u32>(&bytes).iter().map(|&w| u64::from(w)).sum(),
                Err(_) => 0,
            };
            readback.buffer.unmap();
            readback.frame = None;
            let mean = sum as f64 / pixels.max(1) as f64;
            if frame >= self.measured_from && self.newest.is_none_or(|(f, _)| f < frame) {
                self.newest = Some((frame, mean));
            }
        }
    }
}

/// Clears what a left-out step would have written for the steps that still run: targets to
/// zero (colour and depth), buffers to zero.
pub(crate) fn clear_for_left_out(
    plan: &Plan,
    step: usize,
    encoder: &mut wgpu::CommandEncoder,
    view_of: impl Fn(volgraph_compiler::plan::ResourceId) -> (Option<wgpu::TextureView>, Option<wgpu::Buffer>),
) {
    use volgraph_compiler::format::TargetFormat;
    use volgraph_compiler::plan::ResourceDesc;
    for b in plan.bypass.iter().filter(|b| b.steps.contains(&step)) {
        for &rid in b.clears.iter().filter(|&&r| plan.resources[r].producer == step) {
            let (view, buffer) = view_of(rid);
            if let Some(buffer) = buffer {
                encoder.clear_buffer(&buffer, 0, None);
            }
            let Some(view) = view else { continue };
            let depth =
                matches!(plan.resources[rid].desc, ResourceDesc::Target { format: TargetFormat::Depth32Float, .. });
            let label = format!("bypass {}: clear {}", b.name, plan.resources[rid].name);
            super::record::clear_view(encoder, &view, depth, &label, None);
        }
    }
}
