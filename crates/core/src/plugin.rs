//! The pass-plugin API: what a pass kind declares (ports, parameters, features) and how it
//! records GPU work. Built-in passes register through exactly this API (`volgraph_passes::
//! register_builtin`), so an external crate can add pass kinds the same way.

use std::collections::BTreeMap;
use std::sync::Arc;

use crate::format::TargetFormat;
use crate::params::{ParamSpec, Params};
use crate::runtime::{CreateContext, Gpu, PassError, RecordContext};

/// How a pass uses a port.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Access {
    /// Reads a value produced elsewhere.
    Read,
    /// Produces a new value.
    Write,
    /// Reads a value and writes the next version of it in place (blending into an accumulation
    /// target, testing and writing a depth buffer): the output aliases the input's texture.
    Modify,
}

/// What size a target port requires.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SizeRule {
    /// Any size.
    Any,
    /// The same size as the pass's other viewport-sized ports (texel-for-pixel access).
    MatchPass,
}

/// The type of value a port carries.
#[derive(Clone, Debug, PartialEq)]
pub enum PortKind {
    /// A 2D target from the pool. For outputs the first format is the default.
    Target {
        /// Accepted formats.
        formats: Vec<TargetFormat>,
        /// Size requirement.
        size: SizeRule,
    },
    /// The scalar volume (a graph input), bound as a 3D texture.
    Volume,
    /// The scalar volume's voxels on the CPU ([`crate::runtime::RecordContext::voxels`]), for a
    /// pass that uploads the parts it needs itself (the brick pool of Ruijters & Vilanova 2006
    /// §5): no 3D texture of the whole volume is made for it, so a volume beyond the texture
    /// limit or the memory budget still renders.
    VolumeVoxels,
    /// The transfer-function LUT (a graph input).
    TransferFunction,
    /// A resource a pass owns and shares by name, e.g. `"minmax_grid"` (a 3D texture built from
    /// the volume): producer and consumer must name the same type.
    Owned(&'static str),
    /// A storage buffer from the pool (counters, point lists, brick tables), bound by name as
    /// `var<storage>`: `bytes` plus `bytes_per_pixel` for every viewport pixel. Zeroed with
    /// [`crate::runtime::RecordContext::clear_buffer`] where a pass needs it.
    Buffer {
        /// Fixed bytes.
        bytes: u64,
        /// Bytes per viewport pixel.
        bytes_per_pixel: u64,
    },
}

impl PortKind {
    /// A target accepting `formats`, sized like the pass.
    pub fn target(formats: &[TargetFormat]) -> Self {
        PortKind::Target { formats: formats.to_vec(), size: SizeRule::MatchPass }
    }

    /// A buffer of `bytes`.
    pub fn buffer(bytes: u64) -> Self {
        PortKind::Buffer { bytes, bytes_per_pixel: 0 }
    }

    /// The name shown in messages.
    pub fn describe(&self) -> String {
        match self {
            PortKind::Buffer { .. } => "a storage buffer".to_string(),
            PortKind::Target { formats, .. } => {
                let names: Vec<_> = formats.iter().map(|f| f.name()).collect();
                format!("a target ({})", names.join(" or "))
            }
            PortKind::Volume | PortKind::VolumeVoxels => "the volume".to_string(),
            PortKind::TransferFunction => "the transfer function".to_string(),
            PortKind::Owned(t) => format!("a {t}"),
        }
    }
}

/// One declared port.
#[derive(Clone, Debug, PartialEq)]
pub struct PortSpec {
    /// Name, used in graph files and as the WGSL global / fragment-output member name.
    pub name: &'static str,
    /// Read, write or modify.
    pub access: Access,
    /// What it carries.
    pub kind: PortKind,
    /// When false, the graph may leave this input unwired.
    pub required: bool,
}

impl PortSpec {
    /// A required input.
    pub fn read(name: &'static str, kind: PortKind) -> Self {
        Self { name, access: Access::Read, kind, required: true }
    }

    /// An output.
    pub fn write(name: &'static str, kind: PortKind) -> Self {
        Self { name, access: Access::Write, kind, required: true }
    }

    /// A read-modify-write port.
    pub fn modify(name: &'static str, kind: PortKind) -> Self {
        Self { name, access: Access::Modify, kind, required: true }
    }

    /// Marks an input optional.
    pub fn optional(mut self) -> Self {
        self.required = false;
        self
    }

    /// Whether the graph wires this port under `inputs`.
    pub fn is_input(&self) -> bool {
        matches!(self.access, Access::Read | Access::Modify)
    }

    /// Whether this port produces a value others can reference.
    pub fn is_output(&self) -> bool {
        matches!(self.access, Access::Write | Access::Modify)
    }
}

/// When a pass's work is redone.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Rerun {
    /// Every frame: anything that depends on the camera, the frame or a transient target.
    #[default]
    EveryFrame,
    /// Only when something it reads changed since it last ran — a graph input's content, an
    /// Owned resource rebuilt upstream — or its node was built or given new parameters. For a
    /// pass that is a pure function of its inputs and parameters and writes only Owned outputs
    /// (Krüger & Westermann 2003 §2.3: the empty-space grid is rebuilt when the transfer
    /// function changes, not every frame). The runtime falls back to every frame for a pass
    /// that also writes a transient target or whose output a later pass modifies in place.
    WhenInputsChange,
}

/// A pass kind. Long-lived: [`PassPlugin::create`] builds the per-graph node that owns pipelines.
pub trait PassPlugin: Send + Sync {
    /// The name graph files use in `kind:`.
    fn kind(&self) -> &'static str;

    /// One line saying what the pass does and which paper section it follows.
    fn summary(&self) -> &'static str;

    /// Declared parameters.
    fn params(&self) -> Vec<ParamSpec> {
        Vec::new()
    }

    /// Ports, which may depend on parameters (an isosurface raycaster also writes `hit`).
    fn ports(&self, params: &Params) -> Vec<PortSpec>;

    /// Scene features this pass serves: it is only scheduled when all are on.
    fn features(&self) -> Vec<&'static str> {
        Vec::new()
    }

    /// Shader modules and entry points this pass uses with its parameters, so the compiler can
    /// check the shaders' bindings against the ports (see [`crate::reflect`]).
    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        Vec::new()
    }

    /// As [`PassPlugin::shaders`], for a pass whose wired optional inputs choose its shader (a
    /// leaping variant when the empty-block flags are wired): `wired` names the ports the graph
    /// binds. What `volgraph plan` checks bindings with.
    fn shaders_wired(&self, params: &Params, wired: &[&str]) -> Vec<ShaderUse> {
        let _ = wired;
        self.shaders(params)
    }

    /// The `#if` names its shaders are assembled with for these parameters (the scene effects it
    /// specializes for), so tools that walk the shaders see exactly what the GPU compiles.
    fn shader_defines(&self, _params: &Params) -> Vec<&'static str> {
        Vec::new()
    }

    /// Checks a module of one of its declared shader uses against what this kind declares
    /// beyond bindings (a workgroup size, the layout of a uniform block), once naga has
    /// validated it: `Err` says what disagrees and how to fix it. `volgraph plan` calls it
    /// ([`crate::compile::check_plan_bindings`]); a plugin calls it from `create` too where a
    /// hot-reloaded shader could disagree (the WGSL-only kinds do), so a disagreement is never
    /// a silent wrong image.
    fn check_module(&self, _params: &Params, _shader: &ShaderUse, _module: &naga::Module) -> Result<(), String> {
        Ok(())
    }

    /// True for passes that hold what they stream within the runtime's GPU memory budget
    /// (`--gpu-memory-mb`): a budget given to a graph without one changes nothing, and the CLI
    /// says so.
    fn uses_gpu_memory_budget(&self) -> bool {
        false
    }

    /// True for passes whose effect is outside the graph (writing a file): never culled.
    fn is_sink(&self) -> bool {
        false
    }

    /// When the runtime records this pass: every frame (the default), or only when what it
    /// reads changed ([`Rerun::WhenInputsChange`]).
    fn rerun(&self) -> Rerun {
        Rerun::EveryFrame
    }

    /// Builds the node that records this pass's GPU work for one compiled graph.
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError>;

    /// Whether a node built with `old` parameters can take `new` ones through
    /// [`PassNode::update_params`] (uniform values) instead of being rebuilt (pipeline changes:
    /// a mode switch, a workgroup size). A parameter edit in the viewer then rebuilds nothing.
    fn updates_in_place(&self, _old: &Params, _new: &Params) -> bool {
        false
    }
}

/// One shader entry point a pass uses.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShaderUse {
    /// File under `shaders/`, e.g. `raycast.wgsl`.
    pub file: &'static str,
    /// Entry point name.
    pub entry_point: &'static str,
    /// Globals the node binds itself (its uniform buffers, tables it owns): with the ports and
    /// the system bindings, every global the entry point uses must be one of these —
    /// `volgraph plan` checks it without a GPU ([`crate::compile::check_plan_bindings`]).
    pub extra: &'static [&'static str],
}

/// The per-graph instance of a pass kind: owns its pipelines, records each frame.
pub trait PassNode: Send {
    /// Records this pass's GPU work into the frame's encoder.
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError>;

    /// For an output port of kind [`PortKind::Owned`]: the texture view this node owns and
    /// fills (a 3D grid built from the volume, ...). Consumers' ports are bound to it. Asked
    /// after [`PassPlugin::create`] and again after every [`PassNode::record`], so a node whose
    /// texture is sized by a graph input (the volume's dims are only known when recording) may
    /// return `None` until its first `record`, which must then create it.
    fn owned_output(&self, _port: &str) -> Option<wgpu::TextureView> {
        None
    }

    /// Takes new parameter values in place (write them to the node's uniform buffer); called
    /// only when [`PassPlugin::updates_in_place`] said it can.
    fn update_params(&mut self, _gpu: &Gpu, _params: &Params) {}

    /// Figures of the node's last recorded frame that the CLI, the viewer and benchmarks show
    /// (bytes a brick pool uploaded, its occupancy), as `(name, value)`; see
    /// [`crate::runtime::Runtime::pass_counters`].
    fn counters(&self) -> Vec<(&'static str, f64)> {
        Vec::new()
    }
}

/// Maps kind names to plugins.
#[derive(Clone, Default)]
pub struct Registry {
    plugins: BTreeMap<&'static str, Arc<dyn PassPlugin>>,
}

impl Registry {
    /// An empty registry.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a plugin; a later registration of the same kind replaces the earlier one.
    pub fn register(&mut self, plugin: impl PassPlugin + 'static) -> &mut Self {
        self.plugins.insert(plugin.kind(), Arc::new(plugin));
        self
    }

    /// The plugin for `kind`.
    pub fn get(&self, kind: &str) -> Option<&Arc<dyn PassPlugin>> {
        self.plugins.get(kind)
    }

    /// All kind names, sorted.
    pub fn kinds(&self) -> Vec<&'static str> {
        self.plugins.keys().copied().collect()
    }
}

impl std::fmt::Debug for Registry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.plugins.keys()).finish()
    }
}
