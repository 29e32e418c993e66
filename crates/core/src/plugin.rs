//! The pass-plugin API: what a pass kind declares ([`PassDecl`], the compiler's half, re-exported
//! from `volgraph_compiler`) and how it is created on a device and records GPU work
//! ([`PassPlugin::create`], [`PassNode`]). Built-in passes register through exactly this API
//! (`volgraph_passes::register_builtin`), so an external crate can add pass kinds the same way.

use std::collections::BTreeMap;
use std::sync::Arc;

pub use volgraph_compiler::decl::{
    Access, KindLookup, Kinds, PassDecl, PortKind, PortSpec, Rerun, ShaderUse, SizeRule, UniformLayout,
};

use crate::params::Params;
use crate::runtime::{CreateContext, Gpu, PassError, RecordContext};

/// A pass kind on a device: its declaration ([`PassDecl`]) and how its per-graph node is built.
/// Long-lived: [`PassPlugin::create`] builds the node that owns pipelines.
pub trait PassPlugin: PassDecl {
    /// Builds the node that records this pass's GPU work for one compiled graph.
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError>;
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
    /// only when [`PassDecl::updates_in_place`] said it can.
    fn update_params(&mut self, _gpu: &Gpu, _params: &Params) {}

    /// Figures of the node's last recorded frame that the CLI, the viewer and benchmarks show
    /// (bytes a brick pool uploaded, its occupancy), as `(name, value)`; see
    /// [`crate::runtime::Runtime::pass_counters`].
    fn counters(&self) -> Vec<(&'static str, f64)> {
        Vec::new()
    }

    /// Waits, up to `timeout`, for work the node has in flight off the GPU — bricks being read
    /// from disk by a streaming raycaster — so a caller that refines an image (`volgraph render`
    /// waiting for the full image) draws its next frame when there is more to show, instead of
    /// drawing frames that take the cores the readers need. Returns at once when nothing is in
    /// flight (the default).
    fn wait_for_background(&self, _timeout: std::time::Duration) {}
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

impl KindLookup for Registry {
    fn decl(&self, kind: &str) -> Option<Arc<dyn PassDecl>> {
        self.plugins.get(kind).map(|p| Arc::clone(p) as Arc<dyn PassDecl>)
    }

    fn kind_names(&self) -> Vec<&'static str> {
        self.kinds()
    }
}

impl std::fmt::Debug for Registry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.plugins.keys()).finish()
    }
}
