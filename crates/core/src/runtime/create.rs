//! What a pass plugin sees when it builds its node: [`CreateContext`]. Pipelines are built through
//! [`CreateContext::render_pipeline`] and [`CreateContext::compute_pipeline`], which reflect the
//! shader, check every binding and fragment output against the pass's ports by name, and look the
//! pipeline up in the runtime's [`PipelineCache`] first: a pipeline is keyed by everything that
//! defines it (module source hash, entry points, override constants, bind group layout, target
//! formats, blend, depth, culling, topology), so rebuilding a node after an edit that did not
//! touch its shaders costs no pipeline compilation.

use std::cell::RefCell;
use std::collections::BTreeSet;

use super::gpu::Gpu;
pub use super::pipeline::{
    ComputePassPipeline, ComputePipelineSpec, DepthSpec, FOOTPRINT_VERTEX, FULLSCREEN_VERTEX, PassPipeline,
    PipelineCache, PipelineKind, RUNTIME_VERTEX_STAGES, RenderPassPipeline, RenderPipelineSpec,
};
use super::reflect::{BindingKind, ReflectedBinding, layout_entry, reflect};
use super::shaders::ShaderLibrary;
use crate::params::Params;
use crate::plugin::{Access, PassPlugin, ShaderUse};
pub use volgraph_compiler::binding_rules::{PortInfo, SYSTEM_BINDINGS, check_bindings, system_sampler_filters};

/// A pass failed to build or record.
#[derive(Clone, Debug, thiserror::Error, PartialEq, Eq)]
#[error("pass \"{pass}\": {message}")]
pub struct PassError {
    /// The pass id or instance label.
    pub pass: String,
    /// What went wrong and how to fix it.
    pub message: String,
}

/// Given to [`crate::plugin::PassPlugin::create`].
pub struct CreateContext<'a> {
    /// The GPU.
    pub gpu: &'a Gpu,
    /// Shader modules.
    pub shaders: &'a ShaderLibrary,
    /// The pass id.
    pub pass_id: &'a str,
    /// Its checked parameters.
    pub params: &'a Params,
    /// Its ports with formats.
    pub ports: &'a [PortInfo],
    pub(crate) pipelines: &'a PipelineCache,
    /// Shader modules this node's pipelines came from (a shader edit rebuilds exactly these nodes).
    pub(crate) modules: RefCell<BTreeSet<String>>,
    /// `(file, entry point)` of every pipeline built, vertex and fragment entries both.
    built: RefCell<BTreeSet<(String, String)>>,
    /// What the plugin declares it builds for these parameters and wired ports
    /// ([`PassPlugin::shaders_wired`]): the one list `volgraph plan` checks bindings with and
    /// the pipelines below are built from — an entry point it lacks is an error, and the names a
    /// node binds itself come from it.
    declared: Vec<ShaderUse>,
    /// `#if` names the frame turns on in every module this node builds (a scene's crop box and
    /// clip planes: [`volgraph_compiler::cut_effects`]), whatever its parameters say.
    frame_defines: Vec<&'static str>,
}

impl<'a> CreateContext<'a> {
    /// A context for building pass `pass_id` of `plugin` (the runtime's, and tools' or plugin
    /// tests' outside one).
    pub fn new(
        gpu: &'a Gpu,
        shaders: &'a ShaderLibrary,
        pipelines: &'a PipelineCache,
        pass_id: &'a str,
        params: &'a Params,
        ports: &'a [PortInfo],
        plugin: &dyn PassPlugin,
    ) -> Self {
        let wired: Vec<&str> = ports.iter().filter(|p| p.bound).map(|p| p.name.as_str()).collect();
        let declared = plugin.shaders_wired(params, &wired);
        Self {
            gpu,
            shaders,
            pass_id,
            params,
            ports,
            pipelines,
            modules: RefCell::new(BTreeSet::new()),
            built: RefCell::new(BTreeSet::new()),
            declared,
            frame_defines: Vec::new(),
        }
    }

    /// The same context with `defines` turned on in every module it builds (the runtime gives
    /// the cut effects to passes that honour them, [`crate::plugin::PassDecl::honours_volume_window`]).
    pub fn with_frame_defines(mut self, defines: Vec<&'static str>) -> Self {
        self.frame_defines = defines;
        self
    }

    /// The declared use of `file`'s `entry` ([`Self::declared`]), or an error saying how to
    /// declare it.
    fn declared_use(&self, file: &str, entry: &str) -> Result<&ShaderUse, PassError> {
        self.declared.iter().find(|u| u.file == file && u.entry_point == entry).ok_or_else(|| {
            self.error(format!(
                "it builds {file} entry point `{entry}`, which its plugin's `shaders()` does not declare for these \
                 parameters (it declares {}); add `ShaderUse::new(\"{file}\", \"{entry}\")` (with \
                 `.uniform(..)` / `.binds(..)` for what the node binds) there, so `volgraph plan` checks its bindings too",
                if self.declared.is_empty() {
                    "none".to_string()
                } else {
                    self.declared.iter().map(|u| format!("{}:{}", u.file, u.entry_point)).collect::<Vec<_>>().join(", ")
                }
            ))
        })
    }

    /// `(file, entry point)` of every pipeline this context built so far (tests compare it with
    /// what the plugin declares in [`crate::plugin::PassDecl::shaders`]).
    pub fn built_entry_points(&self) -> BTreeSet<(String, String)> {
        self.built.borrow().clone()
    }

    fn error(&self, message: String) -> PassError {
        PassError { pass: self.pass_id.to_string(), message }
    }

    /// The names of the ports the graph wires (what `shaders_wired` / `shader_defines_wired`
    /// take).
    pub fn wired(&self) -> Vec<&str> {
        self.ports.iter().filter(|p| p.bound).map(|p| p.name.as_str()).collect()
    }

    /// The port named `name`.
    pub fn port(&self, name: &str) -> Option<&PortInfo> {
        self.ports.iter().find(|p| p.name == name)
    }

    fn check_bindings(&self, shader: &str, bindings: &[ReflectedBinding], extra: &[&str]) -> Result<(), PassError> {
        check_bindings(shader, bindings, extra, self.ports, true).map_err(|m| self.error(m))
    }

    /// The declared uniform blocks of `declared` against the module (a hot reload may have
    /// changed a struct): a disagreement is an error, never a buffer read as zeros.
    fn check_uniforms(&self, file: &str, module: &naga::Module, declared: &ShaderUse) -> Result<(), PassError> {
        volgraph_compiler::declare::check_uniform_layouts(module, &declared.uniforms)
            .map_err(|e| self.error(format!("{file}: {e}")))
    }

    fn layout_entries(
        &self,
        bindings: &[ReflectedBinding],
        stages: wgpu::ShaderStages,
    ) -> Vec<wgpu::BindGroupLayoutEntry> {
        bindings
            .iter()
            .map(|b| {
                let filterable = match (system_sampler_filters(&b.name), self.port(&b.name)) {
                    (Some(filters), _) => filters,
                    (None, Some(p)) if p.owned => false,
                    (None, Some(PortInfo { format: Some(f), .. })) => self.gpu.filterable(*f),
                    _ => true,
                };
                // Writable storage in a vertex stage needs VERTEX_WRITABLE_STORAGE; volgraph's
                // render passes write storage (counters) from fragment shaders only.
                let stages = match b.ty {
                    BindingKind::Storage { read_only: false } => stages - wgpu::ShaderStages::VERTEX,
                    _ => stages,
                };
                layout_entry(b, stages, filterable)
            })
            .collect()
    }

    /// The validated module of `file` (no `#if` names), for a plugin that checks its shader
    /// against its declaration before building ([`crate::plugin::PassDecl::check_module`]).
    pub fn shader_module(&self, file: &str) -> Result<std::sync::Arc<super::shaders::LoadedShader>, PassError> {
        self.shader(file, &[])
    }

    fn shader(&self, file: &str, defines: &[&str]) -> Result<std::sync::Arc<super::shaders::LoadedShader>, PassError> {
        self.modules.borrow_mut().insert(file.to_string());
        let defines = [defines, &self.frame_defines, self.gpu.device_defines()].concat();
        self.shaders.get_with(self.gpu, file, &defines).map_err(|e| self.error(e))
    }

    /// Builds (or takes from the cache) a render pipeline drawing a fragment shader into this
    /// pass's output ports, named by the fragment output struct's members.
    pub fn render_pipeline(&self, spec: &RenderPipelineSpec<'_>) -> Result<RenderPassPipeline, PassError> {
        let declared = self.declared_use(spec.shader, spec.fragment)?;
        let shader = self.shader(spec.shader, spec.defines)?;
        let mut built = self.built.borrow_mut();
        built.insert((spec.shader.to_string(), spec.vertex.to_string()));
        built.insert((spec.shader.to_string(), spec.fragment.to_string()));
        drop(built);
        let r = reflect(&shader.module, &shader.info, &[spec.vertex, spec.fragment])
            .map_err(|e| self.error(format!("{} {e}", spec.shader)))?;
        // A vertex stage that binds anything (the frame, a point texture) is declared like the
        // fragment stage, so `volgraph plan` checks it too; the runtime's own need no
        // declaration (`RUNTIME_VERTEX_STAGES`).
        let vertex = reflect(&shader.module, &shader.info, &[spec.vertex])
            .map_err(|e| self.error(format!("{} {e}", spec.shader)))?;
        let mut extra: Vec<&str> = declared.node_bindings();
        self.check_uniforms(spec.shader, &shader.module, declared)?;
        if !vertex.bindings.is_empty() && !RUNTIME_VERTEX_STAGES.contains(&spec.vertex) {
            let vertex_use = self.declared_use(spec.shader, spec.vertex)?;
            extra.extend(vertex_use.node_bindings());
            self.check_uniforms(spec.shader, &shader.module, vertex_use)?;
        }
        self.check_bindings(spec.shader, &r.bindings, &extra)?;
        let mut outputs = r.fragment_outputs.clone();
        outputs.sort_by_key(|(_, loc)| *loc);
        let mut targets = Vec::new();
        let mut color_ports = Vec::new();
        for (name, location) in &outputs {
            let Some(port) = self.port(name).filter(|p| p.access != Access::Read) else {
                return Err(self.error(format!(
                    "{}: fragment output \"{name}\" (@location({location})) of {} is not an output port of this pass",
                    spec.shader, spec.fragment
                )));
            };
            if *location as usize != targets.len() {
                return Err(
                    self.error(format!("{}: fragment outputs must use consecutive locations from 0", spec.shader))
                );
            }
            let Some(format) = port.format else {
                return Err(self.error(format!("output port \"{name}\" has no target format")));
            };
            targets.push(Some(wgpu::ColorTargetState {
                format,
                blend: spec.blend,
                write_mask: wgpu::ColorWrites::ALL,
            }));
            color_ports.push(name.clone());
        }
        let depth_stencil = match &spec.depth {
            Some(d) => {
                let port = self
                    .port(d.port)
                    .ok_or_else(|| self.error(format!("depth port \"{}\" is not a port of this pass", d.port)))?;
                Some(wgpu::DepthStencilState {
                    format: port.format.unwrap_or(wgpu::TextureFormat::Depth32Float),
                    depth_write_enabled: Some(d.write),
                    depth_compare: Some(d.compare),
                    stencil: wgpu::StencilState::default(),
                    bias: wgpu::DepthBiasState::default(),
                })
            }
            None => None,
        };
        let entries = self.layout_entries(&r.bindings, wgpu::ShaderStages::VERTEX_FRAGMENT);
        let key = format!(
            "render|{}|{:016x}|{}|{}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}",
            spec.shader,
            shader.hash,
            spec.vertex,
            spec.fragment,
            spec.constants,
            entries,
            targets,
            depth_stencil,
            spec.cull,
            spec.topology
        );
        let label = format!("{}/{}", self.pass_id, spec.fragment);
        let covers_viewport = spec.vertex == FULLSCREEN_VERTEX
            && spec.topology == wgpu::PrimitiveTopology::TriangleList
            && spec.depth.is_none()
            && spec.blend.is_none()
            && !r.may_discard;
        self.pipelines
            .get_or_build(key, || {
                let device = &self.gpu.device;
                let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some(&label),
                    entries: &entries,
                });
                let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some(&label),
                    bind_group_layouts: &[Some(&layout)],
                    immediate_size: 0,
                });
                let pipeline = self
                    .gpu
                    .checked(
                        || format!("{}: building the pipeline {}/{}", spec.shader, spec.vertex, spec.fragment),
                        || {
                            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                                label: Some(&label),
                                layout: Some(&pipeline_layout),
                                vertex: wgpu::VertexState {
                                    module: &shader.wgpu,
                                    entry_point: Some(spec.vertex),
                                    compilation_options: wgpu::PipelineCompilationOptions {
                                        constants: spec.constants,
                                        ..Default::default()
                                    },
                                    buffers: &[],
                                },
                                primitive: wgpu::PrimitiveState {
                                    topology: spec.topology,
                                    front_face: wgpu::FrontFace::Ccw,
                                    cull_mode: spec.cull,
                                    ..Default::default()
                                },
                                depth_stencil: depth_stencil.clone(),
                                multisample: wgpu::MultisampleState::default(),
                                fragment: Some(wgpu::FragmentState {
                                    module: &shader.wgpu,
                                    entry_point: Some(spec.fragment),
                                    compilation_options: wgpu::PipelineCompilationOptions {
                                        constants: spec.constants,
                                        ..Default::default()
                                    },
                                    targets: &targets,
                                }),
                                multiview_mask: None,
                                cache: None,
                            })
                        },
                    )
                    .map_err(|e| self.error(e.to_string()))?;
                Ok(PassPipeline {
                    label: label.clone(),
                    pipeline: PipelineKind::Render(pipeline),
                    layout,
                    bindings: r.bindings.clone(),
                    color_ports: color_ports.clone(),
                    depth_port: spec.depth.map(|d| d.port.to_string()),
                    covers_viewport,
                })
            })
            .map(|mut p| {
                p.label = label.clone();
                p
            })
            .and_then(|p| {
                p.typed(|k| match k {
                    PipelineKind::Render(r) => Some(r),
                    PipelineKind::Compute(_) => None,
                })
                .ok_or_else(|| self.error("the pipeline cache returned a compute pipeline for a render key".into()))
            })
    }

    /// Builds (or takes from the cache) a compute pipeline writing this pass's outputs as storage
    /// textures or buffers named after the ports.
    pub fn compute_pipeline(&self, spec: &ComputePipelineSpec<'_>) -> Result<ComputePassPipeline, PassError> {
        let declared = self.declared_use(spec.shader, spec.entry)?;
        let shader = self.shader(spec.shader, spec.defines)?;
        self.built.borrow_mut().insert((spec.shader.to_string(), spec.entry.to_string()));
        let r = reflect(&shader.module, &shader.info, &[spec.entry])
            .map_err(|e| self.error(format!("{} {e}", spec.shader)))?;
        self.check_bindings(spec.shader, &r.bindings, &declared.node_bindings())?;
        self.check_uniforms(spec.shader, &shader.module, declared)?;
        let entries = self.layout_entries(&r.bindings, wgpu::ShaderStages::COMPUTE);
        let key =
            format!("compute|{}|{:016x}|{}|{:?}|{:?}", spec.shader, shader.hash, spec.entry, spec.constants, entries);
        let label = format!("{}/{}", self.pass_id, spec.entry);
        self.pipelines
            .get_or_build(key, || {
                let device = &self.gpu.device;
                let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some(&label),
                    entries: &entries,
                });
                let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some(&label),
                    bind_group_layouts: &[Some(&layout)],
                    immediate_size: 0,
                });
                let pipeline = self
                    .gpu
                    .checked(
                        || format!("{}: building the compute pipeline {}", spec.shader, spec.entry),
                        || {
                            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                                label: Some(&label),
                                layout: Some(&pipeline_layout),
                                module: &shader.wgpu,
                                entry_point: Some(spec.entry),
                                compilation_options: wgpu::PipelineCompilationOptions {
                                    constants: spec.constants,
                                    ..Default::default()
                                },
                                cache: None,
                            })
                        },
                    )
                    .map_err(|e| self.error(e.to_string()))?;
                Ok(PassPipeline {
                    label: label.clone(),
                    pipeline: PipelineKind::Compute(pipeline),
                    layout,
                    bindings: r.bindings.clone(),
                    color_ports: Vec::new(),
                    depth_port: None,
                    covers_viewport: false,
                })
            })
            .map(|mut p| {
                p.label = label.clone();
                p
            })
            .and_then(|p| {
                p.typed(|k| match k {
                    PipelineKind::Compute(c) => Some(c),
                    PipelineKind::Render(_) => None,
                })
                .ok_or_else(|| self.error("the pipeline cache returned a render pipeline for a compute key".into()))
            })
    }

    /// A uniform buffer for this pass (e.g. its `params`).
    pub fn uniform_buffer(&self, name: &str, size: u64) -> wgpu::Buffer {
        self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(&format!("{}.{name}", self.pass_id)),
            size,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// A uniform buffer named `name` holding `bytes` (a `pass_params!` block's `uniform_bytes()`).
    pub fn uniform_from_bytes(&self, name: &str, bytes: &[u8]) -> wgpu::Buffer {
        let buffer = self.uniform_buffer(name, bytes.len() as u64);
        self.gpu.queue.write_buffer(&buffer, 0, bytes);
        buffer
    }

    /// A uniform buffer holding `value` (a `#[repr(C)]` twin of a WGSL struct).
    pub fn uniform_with<T: bytemuck::Pod>(&self, name: &str, value: &T) -> wgpu::Buffer {
        let buffer = self.uniform_buffer(name, std::mem::size_of::<T>() as u64);
        self.gpu.queue.write_buffer(&buffer, 0, bytemuck::bytes_of(value));
        buffer
    }
}
