//! What a pass kind declares — ports, parameters, features, shaders, `#if` defines, rerun
//! policy — as the compiler reads it, without a GPU: [`PassDecl`]. How a kind is created on a
//! device is the runtime's half (`volgraph_core::PassPlugin`, which extends this trait), so the
//! compiler, `volgraph plan` and the golden-plan tests need no wgpu. [`KindLookup`] is what the
//! compiler looks kinds up in: the runtime's `Registry`, or [`Kinds`] for declarations alone.

use std::collections::BTreeMap;
use std::sync::Arc;

use crate::block::{ParamBlock, block_defines, block_params, no_rebuild_block_changed};
use crate::format::TargetFormat;
use crate::params::{ParamKind, ParamSpec, ParamValue, Params};

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
    /// The scalar volume's voxels on the CPU (`RecordContext::voxels` in the runtime), for a
    /// pass that uploads the parts it needs itself (the brick pool of Ruijters & Vilanova 2006
    /// §5): no 3D texture of the whole volume is made for it, so a volume beyond the texture
    /// limit or the memory budget still renders.
    VolumeVoxels,
    /// The transfer-function LUT (a graph input).
    TransferFunction,
    /// A label map's table (a graph input of kind `LabelTable`): a 2D texture, 256 labels per row.
    LabelTable,
    /// A resource a pass owns and shares by name, e.g. `"minmax_grid"` (a 3D texture built from
    /// the volume): producer and consumer must name the same type.
    Owned(&'static str),
    /// A storage buffer from the pool (counters, point lists, brick tables), bound by name as
    /// `var<storage>`: `bytes` plus `bytes_per_pixel` for every viewport pixel. Zeroed with
    /// `RecordContext::clear_buffer` in the runtime where a pass needs it.
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
            PortKind::LabelTable => "a label table".to_string(),
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
    /// An input that reads a target of zeros as "none here", the same as unwired (a graph's
    /// `bypass` clears what a left-out pass would have written; only such ports may read it).
    pub zero_means_none: bool,
}

impl PortSpec {
    /// A required input.
    pub fn read(name: &'static str, kind: PortKind) -> Self {
        Self { name, access: Access::Read, kind, required: true, zero_means_none: false }
    }

    /// An output.
    pub fn write(name: &'static str, kind: PortKind) -> Self {
        Self { name, access: Access::Write, kind, required: true, zero_means_none: false }
    }

    /// A read-modify-write port.
    pub fn modify(name: &'static str, kind: PortKind) -> Self {
        Self { name, access: Access::Modify, kind, required: true, zero_means_none: false }
    }

    /// Marks an input optional.
    pub fn optional(mut self) -> Self {
        self.required = false;
        self
    }

    /// Marks an optional input that reads zeros as if it were unwired, so a graph may bypass
    /// the pass that writes it (see `GraphDoc::bypass`).
    pub fn zero_means_none(mut self) -> Self {
        self.required = false;
        self.zero_means_none = true;
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

/// What a pass kind declares: everything the compiler checks and schedules a graph with. The
/// runtime's `PassPlugin` extends it with `create`, which builds the per-graph node on a device.
pub trait PassDecl: Send + Sync {
    /// The name graph files use in `kind:`.
    fn kind(&self) -> &'static str;

    /// One line saying what the pass does and which paper section it follows.
    fn summary(&self) -> &'static str;

    /// The blocks of settings the kind takes, in order ([`crate::block`]): its parameters,
    /// `#if` names and in-place rule are derived from them unless it says otherwise.
    fn blocks(&self) -> Vec<ParamBlock> {
        Vec::new()
    }

    /// Declared parameters: those of [`Self::blocks`].
    fn params(&self) -> Vec<ParamSpec> {
        block_params(&self.blocks())
    }

    /// Ports, which may depend on parameters (an isosurface raycaster also writes `hit`).
    fn ports(&self, params: &Params) -> Vec<PortSpec>;

    /// Scene features this pass serves: it is only scheduled when all are on.
    fn features(&self) -> Vec<&'static str> {
        Vec::new()
    }

    /// The scene effects this kind can compile in (`scenes/*.ron`'s `effects:`, `--features`),
    /// each a boolean parameter a graph wires to `"feature.NAME"`: what a scene may ask for is
    /// what the registered kinds declare here ([`KindLookup::scene_effects`]), not a list in
    /// the compiler.
    fn scene_effects(&self) -> &'static [&'static str] {
        &[]
    }

    /// Shader modules and entry points this pass uses with its parameters, so the compiler can
    /// check the shaders' bindings against the ports (see [`crate::reflect`]).
    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        Vec::new()
    }

    /// As [`PassDecl::shaders`], for a pass whose wired optional inputs choose its shader (a
    /// leaping variant when the empty-block flags are wired): `wired` names the ports the graph
    /// binds. What `volgraph plan` checks bindings with.
    fn shaders_wired(&self, params: &Params, wired: &[&str]) -> Vec<ShaderUse> {
        let _ = wired;
        self.shaders(params)
    }

    /// The generated WGSL structs of the uniform blocks its shader uses declare
    /// ([`UniformLayout::import`]), as `(params/NAME.wgsl, text)`: gathered from its uses at the
    /// default parameters, at each value of each choice and flag, with every optional input
    /// wired. A kind whose uses depend on numbers alone adds what those reach.
    fn uniform_imports(&self) -> Vec<(String, String)> {
        let specs = self.params();
        let defaults = Params::defaults(&specs);
        let mut variants = vec![defaults.clone()];
        for spec in &specs {
            let values: Vec<ParamValue> = match &spec.kind {
                ParamKind::Bool { default } => vec![ParamValue::Bool(!default)],
                ParamKind::Choice { options, .. } => {
                    options.iter().map(|o| ParamValue::Choice(o.to_string())).collect()
                }
                _ => Vec::new(),
            };
            for value in values {
                let mut params = defaults.clone();
                params.set(spec.name, value);
                variants.push(params);
            }
        }
        let mut imports: Vec<(String, String)> = Vec::new();
        for params in &variants {
            let optional: Vec<&str> =
                self.ports(params).iter().filter(|p| !p.required && p.is_input()).map(|p| p.name).collect();
            let uses = [self.shaders(params), self.shaders_wired(params, &optional)].concat();
            for uniform in uses.iter().flat_map(|u| &u.uniforms) {
                let import = (uniform.import)();
                if !imports.iter().any(|(path, _)| *path == import.0) {
                    imports.push(import);
                }
            }
        }
        imports
    }

    /// The `#if` names its shaders are assembled with for these parameters (the scene effects it
    /// specializes for), so tools that walk the shaders see exactly what the GPU compiles: those
    /// its [`Self::blocks`] imply.
    fn shader_defines(&self, params: &Params) -> Vec<&'static str> {
        block_defines(&self.blocks(), params)
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

    /// True when the pass is right in a sort-last volume window (`Runtime::set_volume_window`,
    /// docs/scaling.md): it takes no volume samples into its outputs (rays, grids, tables,
    /// display), or exactly the samples of the single-process march that lie in the window's
    /// own box (the raycasters, through the shared sampling core of `shaders/common`), so the
    /// ranks' images composite to the single-process one. `render --distributed` refuses a graph
    /// with any other pass (slice-based rendering, a maximum-intensity projection) rather than
    /// composite a wrong image. The same property makes a scene's crop box and clip planes
    /// right (`crate::cut_effects`: samples are dropped through the same `own_segment`), so it
    /// is [`Self::takes_cuts`]'s default. Default: false.
    fn honours_volume_window(&self) -> bool {
        false
    }

    /// True when the pass takes only what a scene's crop box and clip planes keep
    /// (`crate::cut_effects`): its modules are compiled with `#if CROP`/`#if CLIP` when the
    /// scene cuts, and a graph with a pass that does not is refused with a cut. Default:
    /// [`Self::honours_volume_window`] — a pass right in a rank's box is right in the kept
    /// region through the same `own_segment`. A pass may take cuts without splitting between
    /// ranks: a path tracer's light crosses every rank's box, but the region the cuts keep is
    /// convex, so each path segment is cut like a primary ray (`cut_segment`).
    fn takes_cuts(&self) -> bool {
        self.honours_volume_window()
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

    /// Whether the edit from `old` to `new` only changes values the declared uniform blocks carry:
    /// the same shader uses (files, entry points, uniform layouts), `#if` names and ports, and
    /// every parameter that differs is one a declared uniform block is made of
    /// ([`UniformLayout::params`]). A pass whose node keeps its uniforms in
    /// `volgraph_core::runtime::UniformBlocks` answers [`PassDecl::updates_in_place`] with it and
    /// rewrites them in `update_params`, so neither is written by hand.
    fn only_uniforms_change(&self, old: &Params, new: &Params) -> bool {
        let uses = self.shaders(old);
        if uses != self.shaders(new)
            || self.shader_defines(old) != self.shader_defines(new)
            || self.ports(old) != self.ports(new)
        {
            return false;
        }
        let carried = |name: &str| uses.iter().flat_map(|u| &u.uniforms).any(|u| u.params.contains(&name));
        old.iter().zip(new.iter()).all(|((name, a), (_, b))| a == b || carried(name))
    }

    /// Whether the edit from `old` to `new` changes only values of [`crate::block::OnChange::InPlace`] blocks:
    /// no [`crate::block::OnChange::Rebuild`] block changed, and the shader uses, `#if` names and ports are the
    /// same (a mode switch that picks another entry point or define rebuilds, whatever block
    /// holds it). The default of [`Self::updates_in_place`] for a kind that lists blocks.
    fn only_in_place_blocks_change(&self, old: &Params, new: &Params) -> bool {
        no_rebuild_block_changed(&self.blocks(), old, new)
            && self.shader_defines(old) == self.shader_defines(new)
            && self.ports(old) == self.ports(new)
            && self.shaders(old) == self.shaders(new)
    }

    /// Whether a node built with `old` parameters can take `new` ones through
    /// the node's `update_params` (uniform values) instead of being rebuilt (pipeline changes:
    /// a mode switch, a workgroup size). A parameter edit in the viewer then rebuilds nothing.
    /// Derived from [`Self::blocks`] ([`Self::only_in_place_blocks_change`]); false for a kind
    /// that lists none.
    fn updates_in_place(&self, old: &Params, new: &Params) -> bool {
        !self.blocks().is_empty() && self.only_in_place_blocks_change(old, new)
    }
}

/// One shader entry point a pass uses, declared once: the file, the entry point, the globals the
/// node binds itself and the layout of each uniform block it uploads. `volgraph plan` checks
/// the bindings and the uniform layouts against the shader without a GPU
/// ([`crate::compile::check_plan_bindings`]); node creation checks them again (a hot-reloaded
/// shader can change) and builds pipelines only for declared uses.
///
/// ```
/// # use volgraph_compiler::ShaderUse;
/// volgraph_compiler::pass_params! {
///     /// Parameters of a pass; the shader imports the WGSL struct this generates.
///     pub struct GlowParams { gain: f32 = 1.0, 0.0..=4.0, "how bright"; }
/// }
/// let shader = ShaderUse::new("glow.wgsl", "cs_glow").uniform(GlowParams::bound_as("glow"));
/// assert_eq!(shader.node_bindings(), ["glow"]);
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShaderUse {
    /// File under `shaders/`, e.g. `raycast.wgsl`.
    pub file: &'static str,
    /// Entry point name.
    pub entry_point: &'static str,
    /// Globals the node binds itself besides its uniform blocks (tables it owns, storage it
    /// keeps): with the ports, the system bindings and [`Self::uniforms`], every global the entry
    /// point uses must be one of these.
    pub extra: &'static [&'static str],
    /// The uniform blocks the node uploads, by global name, with their layout: the shader's
    /// struct for each must have these members in this order (a swapped struct is an error, not
    /// an image of zeros).
    pub uniforms: Vec<UniformLayout>,
    /// `#if` names this use is assembled with beyond the pass's
    /// [`PassDecl::shader_defines`]: code a wired input compiles into this entry point alone
    /// (the raycasters' leap over a wired `empty` or `distance`, Klein's `start`), declared in
    /// `shaders_wired` so `volgraph plan` checks the code the node builds.
    pub defines: Vec<&'static str>,
}

impl ShaderUse {
    /// Entry point `entry_point` of `file`, binding nothing of its own yet.
    pub const fn new(file: &'static str, entry_point: &'static str) -> Self {
        Self { file, entry_point, extra: &[], uniforms: Vec::new(), defines: Vec::new() }
    }

    /// With `names` bound by the node that are not uniform blocks (tables, storage it owns).
    pub const fn binds(mut self, names: &'static [&'static str]) -> Self {
        self.extra = names;
        self
    }

    /// With the uniform block `layout` (from a `pass_params!` struct's `bound_as`).
    pub fn uniform(mut self, layout: UniformLayout) -> Self {
        self.uniforms.push(layout);
        self
    }

    /// With the `#if` names `defines` on for this use ([`Self::defines`]).
    pub fn defines(mut self, defines: Vec<&'static str>) -> Self {
        self.defines = defines;
        self
    }

    /// Every global the node binds itself: [`Self::extra`] and the uniform blocks.
    pub fn node_bindings(&self) -> Vec<&'static str> {
        self.extra.iter().copied().chain(self.uniforms.iter().map(|u| u.global)).collect()
    }
}

/// A uniform block as a node uploads it: the global it is bound to, its members `(name, WGSL
/// type)` at WGSL's uniform offsets in order, the parameters it is made of and how its bytes
/// are made from them — what a `pass_params!` struct declares (`Name::bound_as(global)`).
/// Enough for the runtime to create, fill and rewrite the buffer
/// (`volgraph_core::runtime::UniformBlocks`) and to tell an edit that only changes uniform
/// values ([`PassDecl::only_uniforms_change`]).
#[derive(Clone, Debug)]
pub struct UniformLayout {
    /// The WGSL global, e.g. `params`.
    pub global: &'static str,
    /// The members, in order.
    pub fields: Vec<(&'static str, &'static str)>,
    /// The parameters the bytes are made of.
    pub params: Vec<&'static str>,
    /// The block's bytes for a pass's parameters (padded to 16).
    pub bytes: fn(&Params) -> Vec<u8>,
    /// The WGSL struct as a generated shader file `(params/NAME.wgsl, text)` the shader may
    /// import: what [`KindLookup::uniform_imports`] gathers from the kinds that declare it.
    pub import: fn() -> (String, String),
}

impl PartialEq for UniformLayout {
    /// The same global, members and parameters (the byte function is the declaration's).
    fn eq(&self, other: &Self) -> bool {
        self.global == other.global && self.fields == other.fields && self.params == other.params
    }
}

impl Eq for UniformLayout {}

/// Where the compiler looks pass kinds up: the runtime's `Registry` (every plugin is a
/// declaration too) or [`Kinds`], declarations alone.
pub trait KindLookup {
    /// The declaration of `kind`.
    fn decl(&self, kind: &str) -> Option<Arc<dyn PassDecl>>;

    /// All kind names, sorted.
    fn kind_names(&self) -> Vec<&'static str>;

    /// The scene effects some kind declares ([`PassDecl::scene_effects`]), sorted.
    fn scene_effects(&self) -> Vec<&'static str> {
        let mut effects: Vec<&'static str> = self
            .kind_names()
            .into_iter()
            .filter_map(|kind| self.decl(kind))
            .flat_map(|decl| decl.scene_effects().iter().copied())
            .collect();
        effects.sort_unstable();
        effects.dedup();
        effects
    }

    /// The generated WGSL structs every kind's uniform blocks declare
    /// ([`PassDecl::uniform_imports`]), sorted by path, each once: the `params/NAME.wgsl` files
    /// shaders import (`ShaderSources::with_generated`), from what the kinds declare.
    fn uniform_imports(&self) -> Vec<(String, String)> {
        let mut imports: Vec<(String, String)> = self
            .kind_names()
            .into_iter()
            .filter_map(|kind| self.decl(kind))
            .flat_map(|decl| decl.uniform_imports())
            .collect();
        imports.sort();
        imports.dedup_by(|a, b| a.0 == b.0);
        imports
    }
}

/// Pass kinds by name, as declarations only: what a compiler-only tool registers.
#[derive(Clone, Default)]
pub struct Kinds {
    decls: BTreeMap<&'static str, Arc<dyn PassDecl>>,
}

impl Kinds {
    /// No kinds.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a declaration; a later one of the same kind replaces the earlier.
    pub fn register(&mut self, decl: impl PassDecl + 'static) -> &mut Self {
        self.decls.insert(decl.kind(), Arc::new(decl));
        self
    }
}

impl KindLookup for Kinds {
    fn decl(&self, kind: &str) -> Option<Arc<dyn PassDecl>> {
        self.decls.get(kind).cloned()
    }

    fn kind_names(&self) -> Vec<&'static str> {
        self.decls.keys().copied().collect()
    }
}

impl std::fmt::Debug for Kinds {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.decls.keys()).finish()
    }
}
