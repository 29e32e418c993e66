//! Recording one frame's steps into a command encoder ([`StepRecorder`]): each step's ports bound
//! to the live plan's textures, buffers, history and bound inputs; steps whose inputs did not
//! change, or that a bypass leaves out, recorded as empty passes; Owned outputs published and
//! versioned as their steps run.

use std::collections::HashMap;

use super::bypass::{self, FrameBypass};
use super::footprint::Footprint;
use super::history::HistoryStore;
use super::inputs::InputStore;
use super::live_plan::{LivePlan, SlotTexture};
use super::record::BoundPort;
use super::step_clock::StepClock;
use super::{ApplyError, FrameData, Gpu, PassError, RecordContext, RuntimeError, SystemBindings};
use crate::plan::{Binding, Plan, ResourceDesc};
use crate::plugin::Access;

/// What recording a frame's steps reads, each part borrowed separately from the runtime (the
/// live plan, the encoder and the step clock are handed to [`StepRecorder::record`]).
pub(super) struct StepRecorder<'a> {
    pub gpu: &'a Gpu,
    pub history: &'a HistoryStore,
    pub inputs: &'a InputStore,
    pub system: &'a SystemBindings,
    /// The frame contract.
    pub frame: &'a FrameData,
    /// The volume's screen footprint this frame.
    pub footprint: &'a Footprint,
    /// The frame's timestamp query set and its first index (two per step), when timed.
    pub timestamps: Option<&'a (wgpu::QuerySet, u32)>,
    /// This frame's bypass choices.
    pub bypassing: &'a FrameBypass<'a>,
}

impl StepRecorder<'_> {
    /// Records every step of `live`'s plan into `encoder`; with a `clock`, what came before each
    /// step is timed on its own (profiling).
    pub fn record(
        &self,
        live: &mut LivePlan,
        encoder: &mut wgpu::CommandEncoder,
        mut clock: Option<&mut StepClock<'_>>,
    ) -> Result<(), RuntimeError> {
        let Self { gpu, history, inputs, system, frame, footprint, timestamps, bypassing } = *self;
        let LivePlan { plan, nodes, slots, owned, bind_groups, skippable, owned_versions, next_version, .. } = live;
        for (i, step) in plan.steps.iter().enumerate() {
            // Profiling: what came before this step is done before its clock starts.
            if let Some(clock) = clock.as_deref_mut() {
                clock.lap(encoder);
            }
            // A pass that runs only when its inputs change: the versions of what it reads (None when
            // it reads something made every frame).
            let read_versions = if skippable[i] { input_versions(plan, step, inputs, owned_versions) } else { None };
            let mut ports = Vec::with_capacity(step.ports.len());
            for bp in &step.ports {
                let mut buffer = None;
                let (mut voxels, mut table, mut pyramid) = (None, None, None);
                let version = match &bp.binding {
                    Binding::Input(name) | Binding::InputVoxels(name) => inputs.version(name),
                    Binding::Resource { id, .. } if matches!(plan.resources[*id].desc, ResourceDesc::Owned(_)) => {
                        owned_versions.get(&plan.resources[root_owned(plan, *id)].name).copied()
                    }
                    _ => None,
                };
                let (view, extent) = match &bp.binding {
                    Binding::Resource { id, written } => {
                        let rid = if bp.access == Access::Modify { written.unwrap_or(*id) } else { *id };
                        let r = &plan.resources[rid];
                        let extent = match &r.desc {
                            ResourceDesc::Target { extent, .. } => Some(*extent),
                            ResourceDesc::Buffer { .. } | ResourceDesc::Owned(_) => None,
                        };
                        let view = match r.slot {
                            Some(s) => match &slots[s] {
                                SlotTexture::Transient(t) => Some(&t.view),
                                SlotTexture::Buffer(b) => {
                                    buffer = Some(&b.buffer);
                                    None
                                }
                                SlotTexture::History(name) => history.get(name).map(|e| &e.current().view),
                            },
                            None => owned.get(&root_owned(plan, rid)),
                        };
                        (view, extent)
                    }
                    Binding::Input(name) => {
                        table = inputs.table(name);
                        voxels = inputs.voxels(name);
                        (inputs.get(name).map(|t| &t.view), None)
                    }
                    Binding::InputVoxels(name) => {
                        voxels = inputs.voxels(name);
                        pyramid = inputs.pyramid(name);
                        (None, None)
                    }
                    Binding::History(name) => (history.get(name).map(|e| &e.previous().view), None),
                    Binding::Unbound => (None, None),
                };
                let zeroed = bp.access == Access::Read
                    && matches!(bp.binding, Binding::Resource { id, .. }
                        if bypassing.left_out.get(plan.resources[id].producer).copied().unwrap_or(false));
                ports.push(BoundPort {
                    zeroed,
                    name: bp.port.clone(),
                    access: bp.access,
                    view,
                    buffer,
                    extent,
                    version,
                    voxels,
                    pyramid,
                    table,
                });
            }
            let entry = nodes.get_mut(&step.pass_id).ok_or_else(|| ApplyError::UnknownKind(step.kind.clone()))?;
            let outputs_published = step.ports.iter().all(|bp| match &bp.binding {
                Binding::Resource { id, .. } if bp.access == Access::Write => owned.contains_key(id),
                _ => true,
            });
            let unchanged = read_versions.is_some() && read_versions == entry.last_inputs && outputs_published;
            let left_out = bypassing.left_out.get(i).copied().unwrap_or(false);
            if left_out {
                // A graph's bypass leaves this step out: what the running steps read of it is zero.
                bypass::clear_for_left_out(plan, i, encoder, |rid| match plan.resources[rid].slot.map(|s| &slots[s]) {
                    Some(SlotTexture::Transient(t)) => (Some(t.view.clone()), None),
                    Some(SlotTexture::Buffer(b)) => (None, Some(b.buffer.clone())),
                    _ => (None, None),
                });
            }
            let mut ctx = RecordContext {
                gpu,
                encoder,
                label: &step.label,
                iteration: step.iteration,
                params: &step.params,
                viewport: plan.viewport,
                frame,
                footprint,
                ports,
                system,
                timestamps: timestamps.map(|(set, base)| (set, base + 2 * i as u32)),
                began_pass: false,
                bind_groups,
            };
            if unchanged || left_out {
                // Nothing it reads changed (its Owned outputs still hold what it wrote), or a
                // bypass leaves it out. An empty pass keeps the step's label and timestamps.
                drop(ctx.begin_compute_pass());
                continue;
            }
            entry.node.record(&mut ctx)?;
            // A bypass's measure leaves its pooled slot for a read-back buffer right away.
            for &(_, rid, readback, bytes) in bypassing.copies.iter().filter(|c| c.0 == i) {
                if let Some(SlotTexture::Buffer(b)) = plan.resources[rid].slot.map(|s| &slots[s]) {
                    encoder.copy_buffer_to_buffer(&b.buffer, 0, readback, 0, bytes);
                }
            }
            entry.last_inputs = read_versions;
            for bp in &step.ports {
                if let Binding::Resource { id, .. } = &bp.binding
                    && bp.access != Access::Read
                    && matches!(plan.resources[*id].desc, ResourceDesc::Owned(_))
                {
                    owned_versions.insert(plan.resources[root_owned(plan, *id)].name.clone(), *next_version);
                    *next_version += 1;
                }
            }
            // Owned outputs created or replaced while recording (sized by a graph input).
            for bp in &step.ports {
                if let Binding::Resource { id, written: None } = &bp.binding
                    && bp.access == Access::Write
                    && matches!(plan.resources[*id].desc, ResourceDesc::Owned(_))
                {
                    let view = entry.node.owned_output(&bp.port).ok_or_else(|| PassError {
                        pass: step.label.clone(),
                        message: format!(
                            "declares owned output \"{}\" but its node provides no texture for it",
                            bp.port
                        ),
                    })?;
                    owned.insert(*id, view);
                }
            }
        }
        Ok(())
    }
}

/// Versions of what `step` reads — graph inputs' content, Owned resources' versions, 0 for an
/// unwired port — or `None` when it reads a transient target or history, which change every
/// frame.
fn input_versions(
    plan: &Plan,
    step: &crate::plan::Step,
    inputs: &InputStore,
    owned_versions: &HashMap<String, u64>,
) -> Option<Vec<u64>> {
    let mut versions = Vec::new();
    for bp in step.ports.iter().filter(|bp| bp.access != Access::Write) {
        versions.push(match &bp.binding {
            Binding::Input(name) | Binding::InputVoxels(name) => inputs.version(name).unwrap_or(0),
            Binding::Resource { id, .. } if matches!(plan.resources[*id].desc, ResourceDesc::Owned(_)) => {
                owned_versions.get(&plan.resources[root_owned(plan, *id)].name).copied().unwrap_or(0)
            }
            Binding::Unbound => 0,
            Binding::Resource { .. } | Binding::History(_) => return None,
        });
    }
    Some(versions)
}

/// The resource an Owned value's chain starts at (Modify ports on owned resources keep the
/// producer's texture).
fn root_owned(plan: &Plan, mut rid: usize) -> usize {
    while let Some(prev) = plan.resources[rid].modifies {
        rid = prev;
    }
    rid
}
