//! The compiled, scheduled graph: what the executor runs and `volgraph plan` prints.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;

use crate::decl::Access;
use crate::format::{TargetFormat, TargetSize};
use crate::graph::ast::{HistoryInitial, InputKind};
use crate::params::Params;

/// Index into [`Plan::resources`].
pub type ResourceId = usize;

/// A compiled graph for one viewport and feature set.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The graph's name.
    pub name: String,
    /// Viewport in pixels.
    pub viewport: (u32, u32),
    /// Scene features that were on.
    pub features: BTreeSet<String>,
    /// Graph inputs the application binds.
    pub inputs: BTreeMap<String, InputKind>,
    /// Pass instances in execution order (repeat groups unrolled).
    pub steps: Vec<Step>,
    /// Passes that no output needs, with the reason.
    pub culled: Vec<String>,
    /// Passes switched off by scene features: (pass id, the features it needs).
    pub gated: Vec<(String, Vec<String>)>,
    /// Every value a step writes.
    pub resources: Vec<Resource>,
    /// Physical textures: pooled transient slots, then history pairs.
    pub slots: Vec<Slot>,
    /// Graph outputs → the resource holding each.
    pub outputs: BTreeMap<String, ResourceId>,
    /// History entries: name → what they track.
    pub history: BTreeMap<String, History>,
    /// Steps the runtime may leave out by measurement (`GraphDoc::bypass`).
    pub bypass: Vec<Bypass>,
    /// Pass kinds the graph declares itself (WGSL-only passes): the runtime adds them to its
    /// registry when it applies the plan ([`crate::wgsl_kind::with_graph_kinds`]).
    pub kinds: BTreeMap<String, crate::graph::ast::WgslKindDoc>,
    /// Every scene feature some pass of the graph needs, on or off (what a viewer offers as
    /// toggles, and what `--features` may name).
    pub known_features: BTreeSet<String>,
    /// Every scene value the graph reads: its Scalar inputs and the values repeat counts read.
    pub known_scalars: BTreeSet<String>,
    /// Problems that did not stop compiling (a repeat count capped by its max, a feature or
    /// scalar the graph does not use), located in the graph file.
    pub warnings: crate::diagnostic::Diagnostics,
}

/// One pass instance.
#[derive(Clone, Debug)]
pub struct Step {
    /// Unique instance name: the pass id, or `group[i]/pass` inside a repeat group.
    pub label: String,
    /// The pass id in the graph file.
    pub pass_id: String,
    /// The plugin kind.
    pub kind: String,
    /// (iteration, count) when inside a repeat group.
    pub iteration: Option<(u32, u32)>,
    /// Checked parameters.
    pub params: Params,
    /// Port bindings in port declaration order.
    pub ports: Vec<BoundPort>,
}

impl Step {
    /// The names of the ports the graph wires (what `shaders_wired` and its `#if` names take).
    pub fn wired_ports(&self) -> Vec<&str> {
        self.ports.iter().filter(|bp| bp.binding != Binding::Unbound).map(|bp| bp.port.as_str()).collect()
    }
}

/// What one port of a step is bound to.
#[derive(Clone, Debug)]
pub struct BoundPort {
    /// Port name.
    pub port: String,
    /// Read, write or modify.
    pub access: Access,
    /// The value.
    pub binding: Binding,
}

/// The value bound to a port.
#[derive(Clone, Debug, PartialEq)]
pub enum Binding {
    /// A resource written by a step (for Modify ports: the version read; the version written is
    /// in `written`).
    Resource {
        /// The resource read (Read/Modify) or written (Write).
        id: ResourceId,
        /// For Modify: the new version this step writes (same slot as `id`).
        written: Option<ResourceId>,
    },
    /// A graph input bound by the application.
    Input(String),
    /// A volume input the pass reads as voxels on the CPU ([`crate::decl::PortKind::VolumeVoxels`]):
    /// no texture is made for it.
    InputVoxels(String),
    /// The previous frame's value of a history entry.
    History(String),
    /// An optional input left unwired.
    Unbound,
}

/// What a resource is.
#[derive(Clone, Debug, PartialEq)]
pub enum ResourceDesc {
    /// A 2D target.
    Target {
        /// Pixel format.
        format: TargetFormat,
        /// Declared size.
        size: TargetSize,
        /// Resolved pixel size.
        extent: (u32, u32),
    },
    /// A storage buffer from the pool.
    Buffer {
        /// Its size in bytes.
        size: u64,
    },
    /// A resource owned by its producing pass, shared by type name.
    Owned(String),
}

impl ResourceDesc {
    /// Bytes of a target or buffer (0 for owned resources).
    pub fn bytes(&self) -> u64 {
        match self {
            ResourceDesc::Target { format, extent, .. } => format.bytes_per_pixel() * extent.0 as u64 * extent.1 as u64,
            ResourceDesc::Buffer { size } => *size,
            ResourceDesc::Owned(_) => 0,
        }
    }

    /// What a physical slot holding this resource must be (`None` for owned resources).
    pub fn slot_desc(&self) -> Option<SlotDesc> {
        match self {
            ResourceDesc::Target { format, extent, .. } => Some(SlotDesc::Target { format: *format, extent: *extent }),
            ResourceDesc::Buffer { size } => Some(SlotDesc::Buffer { size: *size }),
            ResourceDesc::Owned(_) => None,
        }
    }
}

/// What a physical slot is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SlotDesc {
    /// A 2D texture.
    Target {
        /// Format.
        format: TargetFormat,
        /// Size in pixels.
        extent: (u32, u32),
    },
    /// A storage buffer.
    Buffer {
        /// Size in bytes.
        size: u64,
    },
}

/// One version of a value.
#[derive(Clone, Debug)]
pub struct Resource {
    /// `pass.port` or `group[i]/pass.port`.
    pub name: String,
    /// Format and size.
    pub desc: ResourceDesc,
    /// The step that writes it.
    pub producer: usize,
    /// The last step that reads it (or any later version in its Modify chain); `usize::MAX`
    /// when it must live to the end of the frame (graph outputs, history sources).
    pub last_use: usize,
    /// The physical slot, for targets.
    pub slot: Option<usize>,
    /// For Modify outputs: the version it was made from (same slot).
    pub modifies: Option<ResourceId>,
}

/// A physical texture or buffer.
#[derive(Clone, Debug)]
pub struct Slot {
    /// What it is.
    pub desc: SlotDesc,
    /// True for a history pair's current-frame texture (kept across frames, never pooled).
    pub persistent: bool,
    /// Resources that use it, in order.
    pub holds: Vec<ResourceId>,
}

impl Slot {
    /// Bytes of the texture or buffer.
    pub fn bytes(&self) -> u64 {
        match self.desc {
            SlotDesc::Target { format, extent } => format.bytes_per_pixel() * extent.0 as u64 * extent.1 as u64,
            SlotDesc::Buffer { size } => size,
        }
    }

    /// The texture format, for a target slot.
    pub fn format(&self) -> Option<TargetFormat> {
        match self.desc {
            SlotDesc::Target { format, .. } => Some(format),
            SlotDesc::Buffer { .. } => None,
        }
    }

    /// The size in pixels, for a target slot.
    pub fn extent(&self) -> Option<(u32, u32)> {
        match self.desc {
            SlotDesc::Target { extent, .. } => Some(extent),
            SlotDesc::Buffer { .. } => None,
        }
    }
}

/// A bypass, in plan terms (`GraphDoc::bypass`): steps the runtime leaves out while the
/// per-pixel mean of buffer `measure` (the sum of its u32 words over the viewport's pixels,
/// read back from the last finished frame) is below `below`; while they are left out, each
/// target in `clears` (written by them, read by steps that run) is cleared to zero where its
/// producer would have run.
#[derive(Clone, Debug, PartialEq)]
pub struct Bypass {
    /// The name the graph gives it.
    pub name: String,
    /// Indices into `Plan::steps` of the steps left out.
    pub steps: Vec<usize>,
    /// Resources those steps write that other steps read.
    pub clears: Vec<ResourceId>,
    /// The step that writes the measure (it runs either way).
    pub measure_step: usize,
    /// The buffer resource it writes.
    pub measure: ResourceId,
    /// The threshold per viewport pixel.
    pub below: f64,
}

/// A history entry.
#[derive(Clone, Debug)]
pub struct History {
    /// The resource whose value is kept for the next frame.
    pub source: ResourceId,
    /// The value before the first frame and after invalidation.
    pub initial: HistoryInitial,
    /// Pass ids whose parameter changes restart this history.
    pub reset_on_params_of: Vec<String>,
    /// The largest camera turn between frames (degrees) this history survives.
    pub max_camera_degrees: Option<f64>,
    /// Restarts whenever the camera moves at all (progressive accumulation).
    pub while_camera_still: bool,
}

/// Transient memory figures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryReport {
    /// Bytes of the pooled transient slots.
    pub pooled_bytes: u64,
    /// Bytes if every transient resource chain had its own texture.
    pub unpooled_bytes: u64,
    /// Bytes kept across frames for history (current + previous).
    pub history_bytes: u64,
}

impl Plan {
    /// Pooled vs unpooled transient memory.
    pub fn memory(&self) -> MemoryReport {
        let pooled_bytes = self.slots.iter().filter(|s| !s.persistent).map(Slot::bytes).sum();
        let history_bytes = self.slots.iter().filter(|s| s.persistent).map(|s| 2 * s.bytes()).sum();
        let unpooled_bytes = self
            .resources
            .iter()
            .filter(|r| r.modifies.is_none())
            .filter(|r| r.slot.is_some_and(|s| !self.slots[s].persistent))
            .map(|r| r.desc.bytes())
            .sum();
        MemoryReport { pooled_bytes, unpooled_bytes, history_bytes }
    }

    /// The human-readable plan `volgraph plan` prints (and the golden files hold).
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        let features = if self.features.is_empty() {
            "none".to_string()
        } else {
            self.features.iter().cloned().collect::<Vec<_>>().join(", ")
        };
        let _ =
            writeln!(s, "plan \"{}\" at {}x{}, features: {}", self.name, self.viewport.0, self.viewport.1, features);
        // What the application binds, each by its name (`volgraph render --volume`, `--tf`).
        let inputs: Vec<String> =
            self.inputs.iter().map(|(name, kind)| format!("{name} ({})", kind.describe())).collect();
        let _ = writeln!(s, "inputs: {}", if inputs.is_empty() { "none".to_string() } else { inputs.join(", ") });
        let _ = writeln!(s, "steps ({}):", self.steps.len());
        for (i, step) in self.steps.iter().enumerate() {
            let _ = writeln!(s, "  {i:>3} {} [{}]", step.label, step.kind);
            for p in &step.ports {
                let what = match &p.binding {
                    Binding::Resource { id, written } => {
                        let r = &self.resources[*id];
                        let slot = r.slot.map_or(String::new(), |s| format!(" @slot{s}"));
                        match (p.access, written) {
                            (Access::Modify, Some(w)) => format!("{}{slot} -> {}", r.name, self.resources[*w].name),
                            _ => format!("{}{slot}", r.name),
                        }
                    }
                    Binding::Input(n) => format!("input.{n}"),
                    Binding::InputVoxels(n) => format!("input.{n} (voxels)"),
                    Binding::History(n) => format!("history.{n}"),
                    Binding::Unbound => "(unbound)".to_string(),
                };
                let arrow = match p.access {
                    Access::Read => "reads ",
                    Access::Write => "writes",
                    Access::Modify => "modify",
                };
                let _ = writeln!(s, "        {arrow} {:<10} {what}", p.port);
            }
        }
        let _ =
            writeln!(s, "culled: {}", if self.culled.is_empty() { "none".to_string() } else { self.culled.join(", ") });
        if !self.gated.is_empty() {
            let g: Vec<String> = self.gated.iter().map(|(p, f)| format!("{p} (needs {})", f.join(", "))).collect();
            let _ = writeln!(s, "off by features: {}", g.join(", "));
        }
        for b in &self.bypass {
            let steps: Vec<&str> = b.steps.iter().map(|&i| self.steps[i].label.as_str()).collect();
            let clears: Vec<&str> = b.clears.iter().map(|&r| self.resources[r].name.as_str()).collect();
            let _ = writeln!(
                s,
                "bypass {}: leaves out {} while {} < {} per pixel (then clears {})",
                b.name,
                if steps.is_empty() { "nothing".to_string() } else { steps.join(", ") },
                self.resources[b.measure].name,
                b.below,
                if clears.is_empty() { "nothing".to_string() } else { clears.join(", ") }
            );
        }
        let _ = writeln!(s, "slots:");
        for (i, slot) in self.slots.iter().enumerate() {
            let names: Vec<&str> = slot.holds.iter().map(|r| self.resources[*r].name.as_str()).collect();
            // A repeat group's carried target holds one version per iteration: show the ends.
            let held = if names.len() > 6 {
                format!("{}, {}, … {} ({} values)", names[0], names[1], names[names.len() - 1], names.len())
            } else {
                names.join(", ")
            };
            let kind = if slot.persistent { "history" } else { "pooled" };
            let what = match slot.desc {
                SlotDesc::Target { format, extent } => format!("{format} {}x{}", extent.0, extent.1),
                SlotDesc::Buffer { size } => format!("buffer {size} B"),
            };
            let _ = writeln!(s, "  slot{i} {what} {kind} {}: {}", mib(slot.bytes()), held);
        }
        for (name, h) in &self.history {
            let _ = writeln!(s, "history {name}: previous frame of {}", self.resources[h.source].name);
        }
        for (name, r) in &self.outputs {
            let _ = writeln!(s, "output {name}: {}", self.resources[*r].name);
        }
        let m = self.memory();
        let saved =
            if m.unpooled_bytes > 0 { 100.0 * (1.0 - m.pooled_bytes as f64 / m.unpooled_bytes as f64) } else { 0.0 };
        let _ = writeln!(
            s,
            "transient memory: pooled {}, unpooled {} ({saved:.0}% saved); history {}",
            mib(m.pooled_bytes),
            mib(m.unpooled_bytes),
            mib(m.history_bytes)
        );
        s
    }
}

/// Bytes as `12.3 MiB`.
pub fn mib(bytes: u64) -> String {
    format!("{:.1} MiB", bytes as f64 / (1024.0 * 1024.0))
}
