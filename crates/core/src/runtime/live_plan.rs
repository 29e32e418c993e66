//! The live plan: a compiled [`Plan`] made live on the GPU — one node per pass, a texture per
//! slot, the owned resources nodes publish and a bind-group cache. (Not the compiler's scheduler,
//! `crates/compiler/src/compile/schedule.rs`, which orders a graph's passes into the plan; this is
//! what the runtime builds from that plan.) `build` makes one from a plan and the previous live
//! plan, reusing what did not change: a node whose kind, ports and shaders are unchanged is kept
//! (its parameters updated in place where the plugin can), everything else is created with
//! pipelines from the runtime's cache. Building is all-or-nothing: on any error the previous
//! live plan is untouched.
//!
//! This module was `runtime/schedule.rs` (the compiler's scheduler is `compile/schedule.rs`).

use std::cell::RefCell;
use std::collections::{BTreeSet, HashMap};
use std::sync::Arc;

use super::create::{CreateContext, PassError, PipelineCache, PortInfo};
use super::gpu::{Gpu, GpuFault};
use super::history::HistoryStore;
use super::record::BindGroupCache;
use super::shaders::ShaderLibrary;
use super::textures::{PooledBuffer, PooledTexture, TextureKey, TexturePool};
use crate::params::Params;
use crate::plan::{Binding, Plan, ResourceDesc, ResourceId, SlotDesc};
use crate::plugin::{Access, PassNode, Registry, Rerun};
pub use volgraph_compiler::binding_rules::port_infos;

/// A node with what it was built from.
pub(crate) struct NodeEntry {
    pub node: Box<dyn PassNode>,
    /// When the node is recorded (see [`crate::plugin::Rerun`]).
    pub rerun: Rerun,
    /// For a [`Rerun::WhenInputsChange`] node: the versions of what it read when it last ran
    /// (cleared when its parameters change).
    pub last_inputs: Option<Vec<u64>>,
    kind: String,
    params: Params,
    ports: Vec<PortInfo>,
    /// Shader modules its pipelines came from.
    modules: BTreeSet<String>,
    /// The frame's `#if` names its modules were compiled with (the scene's cuts).
    frame_defines: Vec<&'static str>,
}

/// The texture or buffer behind one plan slot.
pub(crate) enum SlotTexture {
    /// A pooled transient target.
    Transient(PooledTexture),
    /// A pooled storage buffer.
    Buffer(PooledBuffer),
    /// The current-frame texture of a history entry.
    History(String),
}

/// What a fresh slot got: a texture or buffer, and whether it is shared with the old live plan.
enum Fresh {
    Texture(PooledTexture, bool),
    Buffer(PooledBuffer, bool),
}

impl Fresh {
    fn give_back(self, pool: &mut TexturePool) {
        match self {
            Fresh::Texture(t, false) => pool.release(t),
            Fresh::Buffer(b, false) => pool.release_buffer(b),
            _ => {}
        }
    }
}

/// A live plan.
pub(crate) struct LivePlan {
    pub plan: Plan,
    pub nodes: HashMap<String, NodeEntry>,
    pub slots: Vec<SlotTexture>,
    pub owned: HashMap<ResourceId, wgpu::TextureView>,
    pub bind_groups: RefCell<BindGroupCache>,
    pub pass_ids: Arc<Vec<String>>,
    /// The cut `#if` names the nodes were built with (`volgraph_compiler::cut_effects`).
    pub cut_defines: Vec<&'static str>,
    /// Per step: whether it may be skipped when its inputs are unchanged (its node says
    /// [`Rerun::WhenInputsChange`] and the plan lets it: see [`skippable`]).
    pub skippable: Vec<bool>,
    /// Version of each Owned resource (by name, so it survives a plan change): bumped whenever
    /// the step writing it runs.
    pub owned_versions: HashMap<String, u64>,
    /// The next version handed out.
    pub next_version: u64,
}

/// Whether `step` of `plan` may be skipped when nothing it reads changed: it is outside repeat
/// groups, modifies nothing, writes only Owned resources, and no later step modifies those in
/// place (their content must stay what this step wrote).
pub(crate) fn skippable(plan: &Plan, step: &crate::plan::Step) -> bool {
    if step.iteration.is_some() {
        return false;
    }
    step.ports.iter().all(|bp| match (&bp.binding, bp.access) {
        (_, Access::Modify) => false,
        (Binding::Resource { id, .. }, Access::Write) => {
            matches!(plan.resources[*id].desc, ResourceDesc::Owned(_))
                && !plan.resources.iter().any(|r| r.modifies == Some(*id))
        }
        _ => true,
    })
}

/// What applying a plan reused and rebuilt.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ApplyReport {
    /// Nodes kept as they were.
    pub nodes_kept: usize,
    /// Nodes kept with their parameters written in place.
    pub nodes_updated: usize,
    /// Nodes built anew.
    pub nodes_created: usize,
    /// Pipelines compiled for this plan.
    pub pipelines_built: u64,
    /// Pipelines taken from the cache.
    pub pipelines_reused: u64,
    /// Textures created (the rest came from the pool or were kept).
    pub textures_created: u64,
    /// History entries whose content survived.
    pub history_kept: Vec<String>,
    /// History entries that start over from their initial value.
    pub history_reset: Vec<String>,
    /// Pass ids whose node was updated in place or built anew (their parameters changed).
    pub changed_passes: Vec<String>,
}

/// Why a plan could not be applied.
#[derive(Debug, thiserror::Error)]
pub enum ApplyError {
    /// A step's kind is not in the registry (the plan came from another registry).
    #[error("pass kind \"{0}\" is not registered")]
    UnknownKind(String),
    /// A pass failed to build.
    #[error(transparent)]
    Pass(#[from] PassError),
    /// The GPU refused a texture.
    #[error(transparent)]
    Gpu(#[from] GpuFault),
    /// The scene cuts the volume and a pass cannot take only the samples the cuts keep.
    #[error(
        "pass \"{pass}\" ({kind}) cannot crop or clip: it samples the volume its own way; render this graph without cuts"
    )]
    CannotCut {
        /// The pass id.
        pass: String,
        /// Its kind.
        kind: String,
    },
}

/// The slot's history entry name, if it is the current-frame texture of one.
fn history_of_slot(plan: &Plan, slot: usize) -> Option<&str> {
    plan.history.iter().find(|(_, h)| plan.resources[h.source].slot == Some(slot)).map(|(n, _)| n.as_str())
}

enum Decision {
    Keep,
    Update,
    Create(Box<dyn PassNode>, BTreeSet<String>),
}

/// The runtime's long-lived state a live plan is built against.
pub(crate) struct Resources<'a> {
    pub gpu: &'a Gpu,
    pub shaders: &'a ShaderLibrary,
    pub pipelines: &'a PipelineCache,
    pub textures: &'a mut TexturePool,
    pub history: &'a mut HistoryStore,
}

#[allow(
    clippy::result_large_err,
    reason = "the old live plan is handed back by value on failure, once per plan change"
)]
/// Builds the live plan of `plan`, reusing from `old` (consumed only on success: on error `old`
/// is handed back untouched). `stale_modules` are shader modules edited since `old` was built.
pub(crate) fn build(
    r: Resources<'_>,
    registry: &Registry,
    plan: Plan,
    old: Option<LivePlan>,
    stale_modules: &[String],
    cut_defines: &[&'static str],
) -> Result<(LivePlan, ApplyReport), (ApplyError, Option<LivePlan>)> {
    let (hits0, misses0) = r.pipelines.counts();
    let created0 = r.textures.created();
    // 1. Decide per pass; build new nodes (fallible, no side effects on `old`).
    let mut decisions: Vec<(String, Decision, String, Params, Vec<PortInfo>, Vec<&'static str>)> = Vec::new();
    for step in &plan.steps {
        if decisions.iter().any(|(id, ..)| *id == step.pass_id) {
            continue;
        }
        let Some(plugin) = registry.get(&step.kind) else {
            return Err((ApplyError::UnknownKind(step.kind.clone()), old));
        };
        let ports = port_infos(&plan, step, &plugin.ports(&step.params));
        // The scene's cuts (and a sort-last window) compile into the passes that take only the
        // samples they keep (the compiler refused a plan with a cut and any other pass; a
        // distributed render refuses a graph with one).
        let frame_defines = crate::cut_effects::defines_for_pass(plugin.as_ref(), cut_defines);
        if crate::cut_effects::cuts_among(cut_defines) && !plugin.takes_cuts() {
            return Err((ApplyError::CannotCut { pass: step.pass_id.clone(), kind: step.kind.clone() }, old));
        }
        let previous = old.as_ref().and_then(|o| o.nodes.get(&step.pass_id));
        let reusable = previous.filter(|e| {
            e.kind == step.kind
                && e.ports == ports
                && e.frame_defines == frame_defines
                && !e.modules.iter().any(|m| stale_modules.contains(m))
        });
        let decision = match reusable {
            Some(e) if e.params == step.params => Decision::Keep,
            Some(e) if plugin.updates_in_place(&e.params, &step.params) => Decision::Update,
            _ => {
                let ctx = CreateContext::new(
                    r.gpu,
                    r.shaders,
                    r.pipelines,
                    &step.pass_id,
                    &step.params,
                    &ports,
                    plugin.as_ref(),
                )
                .with_frame_defines(frame_defines.clone());
                match plugin.create(&ctx) {
                    Ok(node) => Decision::Create(node, ctx.modules.into_inner()),
                    Err(e) => return Err((e.into(), old)),
                }
            }
        };
        decisions.push((step.pass_id.clone(), decision, step.kind.clone(), step.params.clone(), ports, frame_defines));
    }
    // 2. Textures and buffers for the transient slots: the old live plan's of the same descriptor
    //    (shared, handed over on commit), else one from the pool (given back on failure).
    let mut claimed = vec![false; old.as_ref().map_or(0, |o| o.slots.len())];
    let mut fresh: Vec<Option<Fresh>> = Vec::with_capacity(plan.slots.len());
    for (i, slot) in plan.slots.iter().enumerate() {
        if slot.persistent && history_of_slot(&plan, i).is_some() {
            fresh.push(None);
            continue;
        }
        let inherited = old.as_ref().and_then(|o| {
            o.slots.iter().enumerate().find_map(|(k, s)| match (s, slot.desc) {
                (SlotTexture::Transient(t), SlotDesc::Target { format, extent })
                    if t.key == (TextureKey { format, extent }) && !claimed[k] =>
                {
                    Some((k, Fresh::Texture(t.clone(), true)))
                }
                (SlotTexture::Buffer(b), SlotDesc::Buffer { size }) if b.size == size && !claimed[k] => {
                    Some((k, Fresh::Buffer(b.clone(), true)))
                }
                _ => None,
            })
        });
        if let Some((k, f)) = inherited {
            claimed[k] = true;
            fresh.push(Some(f));
            continue;
        }
        let held = slot.holds.first().map_or(String::new(), |rid| format!(" for \"{}\"", plan.resources[*rid].name));
        let label = format!("slot{i}{held}");
        let made = match slot.desc {
            SlotDesc::Target { format, extent } => {
                r.textures.acquire(r.gpu, TextureKey { format, extent }, &label).map(|t| Fresh::Texture(t, false))
            }
            SlotDesc::Buffer { size } => {
                r.textures.acquire_buffer(r.gpu, size, &label).map(|b| Fresh::Buffer(b, false))
            }
        };
        match made {
            Ok(f) => fresh.push(Some(f)),
            Err(e) => {
                for f in fresh.into_iter().flatten() {
                    f.give_back(r.textures);
                }
                return Err((e.into(), old));
            }
        }
    }
    // 3. History entries (kept when their descriptor is unchanged).
    let mut report = ApplyReport::default();
    for (name, h) in &plan.history {
        let Some(slot) = plan.resources[h.source].slot else { continue };
        let SlotDesc::Target { format, extent } = plan.slots[slot].desc else { continue };
        let key = TextureKey { format, extent };
        match r.history.ensure(r.gpu, r.textures, name, key, &h.initial) {
            Ok(true) => report.history_kept.push(name.clone()),
            Ok(false) => report.history_reset.push(name.clone()),
            Err(e) => {
                for f in fresh.into_iter().flatten() {
                    f.give_back(r.textures);
                }
                return Err((e.into(), old));
            }
        }
    }
    let names: Vec<&str> = plan.history.keys().map(String::as_str).collect();
    r.history.retain(r.textures, &names);

    // 4. Commit: take kept nodes from `old`, give its textures back.
    let mut old_nodes = HashMap::new();
    let (mut owned_versions, mut next_version) = (HashMap::new(), 1);
    if let Some(old) = old {
        old_nodes = old.nodes;
        (owned_versions, next_version) = (old.owned_versions, old.next_version);
        for (k, slot) in old.slots.into_iter().enumerate() {
            match slot {
                SlotTexture::Transient(t) if !claimed[k] => r.textures.release(t),
                SlotTexture::Buffer(b) if !claimed[k] => r.textures.release_buffer(b),
                _ => {}
            }
        }
    }
    let mut nodes = HashMap::new();
    for (id, decision, kind, params, ports, frame_defines) in decisions {
        let entry = match decision {
            Decision::Keep => {
                report.nodes_kept += 1;
                old_nodes.remove(&id)
            }
            Decision::Update => {
                report.nodes_updated += 1;
                report.changed_passes.push(id.clone());
                old_nodes.remove(&id).map(|mut e| {
                    e.node.update_params(r.gpu, &params);
                    e.params = params.clone();
                    e.last_inputs = None;
                    e
                })
            }
            Decision::Create(node, modules) => {
                report.nodes_created += 1;
                report.changed_passes.push(id.clone());
                let rerun = registry.get(&kind).map_or(Rerun::EveryFrame, |p| p.rerun());
                Some(NodeEntry {
                    node,
                    rerun,
                    last_inputs: None,
                    kind: kind.clone(),
                    params: params.clone(),
                    ports: ports.clone(),
                    modules,
                    frame_defines,
                })
            }
        };
        if let Some(e) = entry {
            nodes.insert(id, e);
        }
    }
    let slots = fresh
        .into_iter()
        .enumerate()
        .map(|(i, t)| match t {
            Some(Fresh::Texture(t, _)) => SlotTexture::Transient(t),
            Some(Fresh::Buffer(b, _)) => SlotTexture::Buffer(b),
            None => SlotTexture::History(history_of_slot(&plan, i).unwrap_or_default().to_string()),
        })
        .collect();
    // Owned outputs that kept nodes already hold (sized by a graph input, created when recording).
    let mut owned = HashMap::new();
    for step in &plan.steps {
        for bp in &step.ports {
            if let Binding::Resource { id, written: None } = &bp.binding
                && bp.access == Access::Write
                && matches!(plan.resources[*id].desc, ResourceDesc::Owned(_))
                && let Some(view) = nodes.get(&step.pass_id).and_then(|e: &NodeEntry| e.node.owned_output(&bp.port))
            {
                owned.insert(*id, view);
            }
        }
    }
    let (hits, misses) = r.pipelines.counts();
    report.pipelines_reused = hits - hits0;
    report.pipelines_built = misses - misses0;
    report.textures_created = r.textures.created() - created0;
    r.textures.next_generation();
    let pass_ids = Arc::new(plan.steps.iter().map(|s| s.pass_id.clone()).collect());
    let skippable = plan
        .steps
        .iter()
        .map(|step| {
            nodes.get(&step.pass_id).is_some_and(|e| e.rerun == Rerun::WhenInputsChange) && skippable(&plan, step)
        })
        .collect();
    owned_versions.retain(|name, _| plan.resources.iter().any(|r| &r.name == name));
    let live = LivePlan {
        plan,
        nodes,
        slots,
        owned,
        bind_groups: RefCell::new(BindGroupCache::default()),
        pass_ids,
        cut_defines: cut_defines.to_vec(),
        skippable,
        owned_versions,
        next_version,
    };
    Ok((live, report))
}
