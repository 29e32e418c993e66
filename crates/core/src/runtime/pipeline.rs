//! Pipelines of passes: the requests a pass makes ([`RenderPipelineSpec`], [`ComputePipelineSpec`],
//! [`DepthSpec`]), the runtime's own vertex stages, the compiled [`PassPipeline`] with its
//! reflected bindings, and the [`PipelineCache`] that keys each pipeline by everything that
//! defines it. They are built through [`CreateContext`](super::CreateContext) (`create.rs`); all
//! of them are re-exported there and from `volgraph_core::runtime`.

use std::collections::{BTreeSet, HashMap};
use std::sync::Mutex;

use super::create::PassError;
use super::reflect::ReflectedBinding;
use crate::plugin::ShaderUse;

/// Depth test of a render pipeline.
#[derive(Clone, Copy, Debug)]
pub struct DepthSpec<'a> {
    /// The port holding the depth target (Read: test only; Modify/Write: test and write).
    pub port: &'a str,
    /// Whether fragments write depth.
    pub write: bool,
    /// The comparison.
    pub compare: wgpu::CompareFunction,
}

/// A render pipeline request.
#[derive(Clone, Debug, Default)]
pub struct RenderPipelineSpec<'a> {
    /// Shader file, e.g. `raycast.wgsl`.
    pub shader: &'a str,
    /// Vertex entry point.
    pub vertex: &'a str,
    /// Fragment entry point.
    pub fragment: &'a str,
    /// Face culling.
    pub cull: Option<wgpu::Face>,
    /// Blending for every colour target.
    pub blend: Option<wgpu::BlendState>,
    /// Depth test.
    pub depth: Option<DepthSpec<'a>>,
    /// Pipeline-overridable constants (shader specialization).
    pub constants: &'a [(&'a str, f64)],
    /// Primitive topology (instanced quads, point lists drawn as triangles, lines).
    pub topology: wgpu::PrimitiveTopology,
    /// `#if` names the module is assembled with (effects a scene turned on).
    pub defines: &'a [&'a str],
}

/// A compute pipeline request.
#[derive(Clone, Debug, Default)]
pub struct ComputePipelineSpec<'a> {
    /// Shader file.
    pub shader: &'a str,
    /// Entry point.
    pub entry: &'a str,
    /// Pipeline-overridable constants (workgroup size, features).
    pub constants: &'a [(&'a str, f64)],
    /// `#if` names the module is assembled with (effects a scene turned on).
    pub defines: &'a [&'a str],
}

impl<'a> ComputePipelineSpec<'a> {
    /// The pipeline of a declared entry point (a pass's `const` [`ShaderUse`], listed by its
    /// `shaders()`), so the file and entry are named once.
    pub fn of(declared: &ShaderUse) -> Self {
        Self { shader: declared.file, entry: declared.entry_point, ..Default::default() }
    }
}

impl<'a> RenderPipelineSpec<'a> {
    /// The pipeline of a declared vertex and fragment entry point (two of a pass's
    /// `shaders()`, of one file), so the file and entry points are named once.
    pub fn drawing(vertex: &ShaderUse, fragment: &ShaderUse) -> Self {
        debug_assert_eq!(vertex.file, fragment.file, "a render pipeline's stages come from one shader file");
        Self { shader: vertex.file, vertex: vertex.entry_point, fragment: fragment.entry_point, ..Default::default() }
    }

    /// The pipeline drawing a declared fragment entry point over the fullscreen triangle of
    /// `shaders/common/fullscreen.wgsl` (`vs_fullscreen`); override `vertex` for other draws.
    pub fn fullscreen(declared: &ShaderUse) -> Self {
        Self {
            shader: declared.file,
            vertex: FULLSCREEN_VERTEX,
            fragment: declared.entry_point,
            topology: wgpu::PrimitiveTopology::TriangleList,
            ..Default::default()
        }
    }

    /// The pipeline drawing a declared fragment entry point over the volume's screen footprint
    /// (`vs_footprint` of `shaders/common/footprint.wgsl`, which the shader file imports), for
    /// [`RecordContext::draw_footprint`](super::RecordContext::draw_footprint): the fragment
    /// stage must write zeros wherever a pixel's ray misses the box, as the pixels outside the
    /// fan read the targets' clear value.
    pub fn footprint(declared: &ShaderUse) -> Self {
        Self { vertex: FOOTPRINT_VERTEX, cull: None, ..Self::fullscreen(declared) }
    }
}

/// The vertex entry point of the screen-covering triangle (`shaders/common/fullscreen.wgsl`).
pub const FULLSCREEN_VERTEX: &str = "vs_fullscreen";

/// The vertex entry point of the volume's screen footprint, a fan of triangles
/// (`shaders/common/footprint.wgsl`, [`super::footprint`]).
pub const FOOTPRINT_VERTEX: &str = "vs_footprint";

/// The runtime's own vertex stages, which a pass uses without declaring them in `shaders()`: the
/// fullscreen triangle binds nothing, the footprint fan only the system binding `frame`.
pub const RUNTIME_VERTEX_STAGES: [&str; 2] = [FULLSCREEN_VERTEX, FOOTPRINT_VERTEX];

/// The compiled pipeline of a pass with its reflected bindings; cheap to clone. Typed by what
/// it is: [`RenderPassPipeline`] from [`CreateContext::render_pipeline`](super::CreateContext::render_pipeline), [`ComputePassPipeline`]
/// from [`CreateContext::compute_pipeline`](super::CreateContext::compute_pipeline), so a render pipeline cannot be dispatched (or a
/// compute one drawn) by mistake; `PassPipeline` alone is the cache's either-kind form.
#[derive(Clone, Debug)]
pub struct PassPipeline<K = PipelineKind> {
    /// Debug label (`pass/entry`).
    pub label: String,
    /// The wgpu pipeline.
    pub pipeline: K,
    /// Layout of bind group 0.
    pub layout: wgpu::BindGroupLayout,
    /// Bindings by name.
    pub bindings: Vec<ReflectedBinding>,
    /// Colour-target ports in location order (render pipelines).
    pub color_ports: Vec<String>,
    /// The depth port, if any.
    pub depth_port: Option<String>,
    /// True when drawing vertices 0..3 writes every pixel of every colour target: the
    /// fullscreen triangle, no depth test, no blending, a fragment stage that cannot discard.
    /// [`RecordContext::draw_fullscreen`](super::RecordContext::draw_fullscreen) then skips
    /// clearing the targets it would overwrite anyway.
    pub covers_viewport: bool,
}

/// A render pipeline of a pass.
pub type RenderPassPipeline = PassPipeline<wgpu::RenderPipeline>;

/// A compute pipeline of a pass.
pub type ComputePassPipeline = PassPipeline<wgpu::ComputePipeline>;

impl PassPipeline {
    /// The typed form, if this is a `T` pipeline.
    pub(super) fn typed<T>(self, pick: impl FnOnce(PipelineKind) -> Option<T>) -> Option<PassPipeline<T>> {
        let PassPipeline { label, pipeline, layout, bindings, color_ports, depth_port, covers_viewport } = self;
        pick(pipeline).map(|pipeline| PassPipeline {
            label,
            pipeline,
            layout,
            bindings,
            color_ports,
            depth_port,
            covers_viewport,
        })
    }
}

/// A render or compute pipeline (the pipeline cache holds both).
#[derive(Clone, Debug)]
pub enum PipelineKind {
    /// Render.
    Render(wgpu::RenderPipeline),
    /// Compute.
    Compute(wgpu::ComputePipeline),
}

/// Pipelines by the key of everything that defines them. Lives as long as the runtime.
#[derive(Default)]
pub struct PipelineCache {
    pipelines: Mutex<HashMap<String, PassPipeline>>,
    counts: Mutex<(u64, u64)>,
}

impl PipelineCache {
    /// `(hits, misses)` since creation: a graph edit that changes no shader should only hit.
    pub fn counts(&self) -> (u64, u64) {
        self.counts.lock().map(|c| *c).unwrap_or_default()
    }

    /// Cached pipelines.
    pub fn len(&self) -> usize {
        self.pipelines.lock().map(|p| p.len()).unwrap_or(0)
    }

    /// True when nothing is cached.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// For each pipeline whose label (`pass/entry`) a wgpu message quotes, one line naming its
    /// bindings by number: wgpu reports `binding 3`, the graph author thinks in port names.
    pub fn binding_names_in(&self, message: &str) -> Vec<String> {
        let Ok(pipelines) = self.pipelines.lock() else { return Vec::new() };
        let mut seen = BTreeSet::new();
        let mut lines: Vec<String> = pipelines
            .values()
            .filter(|p| message.contains(&format!("'{}'", p.label)) && seen.insert(p.label.clone()))
            .map(|p| {
                let names: Vec<String> =
                    p.bindings.iter().map(|b| format!("@binding({}) = \"{}\"", b.binding, b.name)).collect();
                format!("pipeline '{}' binds {}", p.label, names.join(", "))
            })
            .collect();
        lines.sort();
        lines
    }

    /// Drops the pipelines built from a module whose source hash is no longer current.
    pub fn retain(&self, keep: impl Fn(&str) -> bool) {
        if let Ok(mut p) = self.pipelines.lock() {
            p.retain(|k, _| keep(k));
        }
    }

    pub(super) fn get_or_build(
        &self,
        key: String,
        build: impl FnOnce() -> Result<PassPipeline, PassError>,
    ) -> Result<PassPipeline, PassError> {
        if let Some(p) = self.pipelines.lock().ok().and_then(|p| p.get(&key).cloned()) {
            if let Ok(mut c) = self.counts.lock() {
                c.0 += 1;
            }
            return Ok(p);
        }
        let built = build()?;
        if let Ok(mut c) = self.counts.lock() {
            c.1 += 1;
        }
        if let Ok(mut p) = self.pipelines.lock() {
            p.insert(key, built.clone());
        }
        Ok(built)
    }
}
