//! The frame queue of a [`Runtime`]: the frame contract for a camera, submitting a frame (checks,
//! uniforms, recording, optional window blit, submit without waiting), history across frames
//! (restarts on a camera jump) and collecting the stats of finished frames.

use std::time::Instant;

use super::record_frame::StepRecorder;
use super::{
    CameraData, FrameData, FrameStats, FrameUniforms, GpuFault, PresentTarget, Runtime, RuntimeError, inputs, outputs,
    step_clock,
};
use crate::cut_effects;
use crate::graph::ast::InputKind;
use crate::plan::{Binding, Plan};

impl Runtime {
    /// The frame data the next frame will see for `camera`.
    pub fn frame_data(&self, camera: CameraData) -> Result<FrameData, RuntimeError> {
        let plan = self.plan().ok_or(RuntimeError::NoPlan)?;
        let previous = self.last_camera.filter(|(_, vp)| *vp == plan.viewport).map(|(c, _)| c);
        Ok(FrameData {
            viewport: plan.viewport,
            camera: self.local_camera(camera),
            previous_camera: previous.map(|c| self.local_camera(c)),
            frame_index: self.frame_index,
            history_age: self.history_age,
            volume: self.volume_desc(),
            gpu_memory_budget: self.gpu_memory_budget,
            cuts: self.cuts,
            lights: self.lights,
            environment: self.environment.is_some(),
        })
    }

    /// Records and submits one frame seen by `camera`, optionally presenting an output to a
    /// window; returns the frame's index at once (at most [`MAX_FRAMES_IN_FLIGHT`](super::MAX_FRAMES_IN_FLIGHT) frames are
    /// queued: a further submit waits for the oldest).
    pub fn submit(&mut self, camera: CameraData, present: Option<&PresentTarget<'_>>) -> Result<u64, RuntimeError> {
        if self.camera_jumped(&camera) {
            self.invalidate_history();
        }
        let frame = self.frame_data(camera)?;
        let Some(live) = self.live.as_mut() else { return Err(RuntimeError::NoPlan) };
        let wanted = cut_effects::defines_of(&cut_effects::features_of(&self.cuts));
        if !wanted.iter().all(|d| live.cut_defines.contains(d)) {
            let wanted = cut_effects::features_of(&self.cuts).into_iter().collect::<Vec<_>>().join(", ");
            return Err(RuntimeError::CutsNotApplied { wanted });
        }
        if self.window.is_some() && !live.cut_defines.contains(&cut_effects::WINDOW) {
            return Err(RuntimeError::WindowNotApplied);
        }
        Self::check_inputs_of(&self.inputs, &live.plan)?;
        for step in &live.plan.steps {
            for bp in &step.ports {
                if let Binding::Input(name) = &bp.binding {
                    self.inputs.ensure_volume_texture(&self.gpu, name)?;
                }
            }
        }
        let gpu = self.gpu.clone();
        let (uniforms, footprint) = FrameUniforms::and_footprint(&frame);
        self.gpu.queue.write_buffer(&self.system.frame, 0, bytemuck::bytes_of(&uniforms));
        let steps = live.plan.steps.len();
        // Profiled frames time their steps by wall clock: no timestamp queries to write or resolve.
        let timed_steps = if self.profile_steps { 0 } else { steps };
        let timestamps = self.frames.begin(&gpu, timed_steps);
        let mut clock = self.profile_steps.then(|| step_clock::StepClock::new(&gpu));
        let pixels = u64::from(frame.viewport.0) * u64::from(frame.viewport.1);
        let bypassing = self.bypasses.begin_frame(&gpu, steps, frame.frame_index, pixels);
        let what = format!("frame {} of graph \"{}\"", frame.frame_index, live.plan.name);
        let history = &mut self.history;
        let inputs = &self.inputs;
        let system = &self.system;
        let frames = &self.frames;
        let blitter = &mut self.blitter;
        let pipelines = &self.pipelines;
        // A validation error names bindings by number; say which port each number is.
        let named = |mut fault: GpuFault| {
            for line in pipelines.binding_names_in(&fault.message) {
                fault.message.push_str(&format!("\n  {line}"));
            }
            fault
        };
        let commands = gpu
            .checked(
                || what.clone(),
                || -> Result<wgpu::CommandBuffer, RuntimeError> {
                    let mut encoder = gpu
                        .device
                        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(&live.plan.name) });
                    history.begin_frame(&mut encoder);
                    let steps = StepRecorder {
                        gpu: &gpu,
                        history,
                        inputs,
                        system,
                        frame: &frame,
                        footprint: &footprint,
                        timestamps: timestamps.as_ref(),
                        bypassing: &bypassing,
                    };
                    steps.record(live, &mut encoder, clock.as_mut())?;
                    if let Some(clock) = clock.as_mut() {
                        clock.lap(&mut encoder);
                    }
                    if let Some(target) = present {
                        let (view, encoded) = outputs::output_view(live, history, target.output)?;
                        blitter.record(&gpu, &mut encoder, &view, encoded, target)?;
                    }
                    frames.resolve(&mut encoder, timed_steps);
                    Ok(encoder.finish())
                },
            )
            .map_err(|fault| RuntimeError::from(named(fault)))
            .and_then(|recorded| recorded);
        drop(bypassing);
        let commands = match commands {
            Ok(c) => c,
            Err(e) => {
                self.bypasses.abandoned();
                return Err(e);
            }
        };
        let submitted = Instant::now();
        let submission = match gpu.checked(|| what.clone(), || gpu.queue.submit([commands])) {
            Ok(s) => s,
            Err(fault) => {
                self.bypasses.abandoned();
                return Err(named(fault).into());
            }
        };
        self.bypasses.submitted();
        self.history.end_frame();
        let pass_ids = live.pass_ids.clone();
        let profiled = clock.map(|c| c.ms);
        self.frames.submitted(&gpu, submission, frame.frame_index, pass_ids, submitted, profiled);
        live.bind_groups.borrow_mut().evict_older_than(frame.frame_index, 8);
        self.last_camera = Some((camera, frame.viewport));
        self.frame_index += 1;
        if frame.history_age > 0 && !live.plan.history.is_empty() {
            self.history_stats.frames_from_history += 1;
        }
        self.history_stats.run = frame.history_age;
        self.history_age += 1;
        Ok(frame.frame_index)
    }

    fn check_inputs_of(inputs: &inputs::InputStore, plan: &Plan) -> Result<(), RuntimeError> {
        for (name, kind) in &plan.inputs {
            let used = plan.steps.iter().any(|s| {
                s.ports.iter().any(|p| matches!(&p.binding, Binding::Input(n) | Binding::InputVoxels(n) if n == name))
            });
            if used && !inputs.is_bound(name) {
                let (kind, hint) = match kind {
                    InputKind::Volume => ("Volume", "bind it with Runtime::bind_volume"),
                    InputKind::TransferFunction => ("TransferFunction", "bind the LUT with Runtime::bind_lut"),
                    InputKind::LabelTable => ("LabelTable", "bind the table with Runtime::bind_label_table"),
                    InputKind::Scalar(_) | InputKind::Data(_) => ("Scalar", "scalars are compile-time scene values"),
                };
                return Err(RuntimeError::UnboundInput {
                    name: name.clone(),
                    kind: kind.to_string(),
                    hint: hint.to_string(),
                });
            }
        }
        Ok(())
    }

    /// Whether `camera` turned further from the last frame's than some history entry allows
    /// (`max_camera_degrees`): a camera jump starts that history over (Klein et al. 2005 §4.1);
    /// or moved at all where an entry accumulates (`while_camera_still`).
    fn camera_jumped(&self, camera: &CameraData) -> bool {
        let (Some(plan), Some((last, _))) = (self.plan(), self.last_camera) else { return false };
        let turned = last.forward.angle_between(camera.forward).to_degrees();
        let moved = last.clip_from_world != camera.clip_from_world || last.eye != camera.eye;
        plan.history
            .values()
            .any(|h| h.max_camera_degrees.is_some_and(|bound| turned > bound) || (h.while_camera_still && moved))
    }

    /// Forgets history: the next frame reads every entry's initial value (resize, transfer
    /// function or isovalue change, camera jump; Klein et al. 2005 §4).
    pub fn invalidate_history(&mut self) {
        self.history.invalidate();
        // What a bypass measured was of the old view, volume or TF.
        self.bypasses.forget(self.frame_index);
        if self.history_age > 0 {
            self.history_stats.restarts += 1;
        }
        self.history_age = 0;
        self.last_camera = None;
    }

    /// Submits a frame and waits for it: its stats.
    pub fn render(&mut self, camera: CameraData) -> Result<FrameStats, RuntimeError> {
        let index = self.submit(camera, None)?;
        let stats = self.finish();
        stats
            .into_iter()
            .find(|s| s.frame_index == index)
            .ok_or_else(|| RuntimeError::Readback(format!("frame {index} finished without stats")))
    }

    /// Stats of the frames the GPU has finished, without blocking.
    pub fn poll(&mut self) -> Vec<FrameStats> {
        self.frames.poll(&self.gpu)
    }

    /// Waits for every frame in flight: their stats, oldest first.
    pub fn finish(&mut self) -> Vec<FrameStats> {
        self.frames.finish(&self.gpu)
    }

    /// Frames submitted and not yet collected.
    pub fn in_flight(&self) -> usize {
        self.frames.in_flight()
    }
}
