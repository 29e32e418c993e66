//! What a pass plugin sees: [`CreateContext`] when it builds its pipelines, [`RecordContext`]
//! when it records a frame. Pipelines are built through [`CreateContext::render_pipeline`] and
//! [`CreateContext::compute_pipeline`], which reflect the shader and check every binding and
//! fragment output against the pass's ports by name; bind groups are then assembled by name in
//! [`RecordContext::bind_group`].

use super::gpu::Gpu;
use super::reflect::{BindingKind, ReflectedBinding, layout_entry, reflect};
use super::shaders::ShaderLibrary;
use crate::params::Params;
use crate::plugin::Access;

/// Names the executor binds itself, in every pass that declares them.
pub const SYSTEM_BINDINGS: [&str; 3] = ["frame", "linear_clamp", "nearest_clamp"];

/// A pass failed to build or record.
#[derive(Debug, thiserror::Error)]
#[error("pass \"{pass}\": {message}")]
pub struct PassError {
    /// The pass id or instance label.
    pub pass: String,
    /// What went wrong and how to fix it.
    pub message: String,
}

/// What a port of a pass is, as the executor resolved it.
#[derive(Clone, Debug)]
pub struct PortInfo {
    /// Port name.
    pub name: String,
    /// Read, write or modify.
    pub access: Access,
    /// Texture format, when known at build time (targets; graph inputs are filterable formats).
    pub format: Option<wgpu::TextureFormat>,
    /// A texture another pass owns (a min/max grid): bound as unfilterable float, read with
    /// `textureLoad`, so 32-bit float grids need no FLOAT32_FILTERABLE.
    pub owned: bool,
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
}

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
    /// Shader file under `shaders/`.
    pub shader: &'a str,
    /// Vertex entry point.
    pub vertex: &'a str,
    /// Fragment entry point.
    pub fragment: &'a str,
    /// Names the pass binds itself (its `params` uniform, ...).
    pub extra_bindings: &'a [&'a str],
    /// Face culling.
    pub cull: Option<wgpu::Face>,
    /// Blending for every colour target.
    pub blend: Option<wgpu::BlendState>,
    /// Depth test.
    pub depth: Option<DepthSpec<'a>>,
    /// Pipeline-overridable constants (shader specialization).
    pub constants: &'a [(&'a str, f64)],
}

/// A compute pipeline request.
#[derive(Clone, Debug, Default)]
pub struct ComputePipelineSpec<'a> {
    /// Shader file under `shaders/`.
    pub shader: &'a str,
    /// Entry point.
    pub entry: &'a str,
    /// Names the pass binds itself.
    pub extra_bindings: &'a [&'a str],
    /// Pipeline-overridable constants (workgroup size, features).
    pub constants: &'a [(&'a str, f64)],
}

/// The compiled pipeline of a pass with its reflected bindings.
pub struct PassPipeline {
    /// Debug label (`pass/entry`).
    pub label: String,
    /// Render or compute.
    pub pipeline: PipelineKind,
    /// Layout of bind group 0.
    pub layout: wgpu::BindGroupLayout,
    /// Bindings by name.
    pub bindings: Vec<ReflectedBinding>,
    /// Colour-target ports in location order (render pipelines).
    pub color_ports: Vec<String>,
    /// The depth port, if any.
    pub depth_port: Option<String>,
}

/// A render or compute pipeline.
pub enum PipelineKind {
    /// Render.
    Render(wgpu::RenderPipeline),
    /// Compute.
    Compute(wgpu::ComputePipeline),
}

impl CreateContext<'_> {
    fn error(&self, message: String) -> PassError {
        PassError { pass: self.pass_id.to_string(), message }
    }

    fn port(&self, name: &str) -> Option<&PortInfo> {
        self.ports.iter().find(|p| p.name == name)
    }

    fn check_bindings(&self, shader: &str, bindings: &[ReflectedBinding], extra: &[&str]) -> Result<(), PassError> {
        for b in bindings {
            if b.group != 0 {
                return Err(self.error(format!(
                    "{shader}: global \"{}\" is in @group({}); volgraph binds everything in @group(0)",
                    b.name, b.group
                )));
            }
            if SYSTEM_BINDINGS.contains(&b.name.as_str()) || extra.contains(&b.name.as_str()) {
                continue;
            }
            match self.port(&b.name) {
                Some(p) => {
                    if let BindingKind::StorageTexture { format, .. } = &b.ty {
                        if p.access == Access::Read {
                            return Err(self.error(format!(
                                "{shader}: storage texture \"{}\" is an input port; storage textures are outputs",
                                b.name
                            )));
                        }
                        if let Some(port_format) = p.format
                            && *format != Some(port_format)
                        {
                            let declared = format.map_or("an unsupported format".to_string(), |f| format!("{f:?}"));
                            return Err(self.error(format!(
                                "{shader}: storage texture \"{}\" is declared {declared} but the port's target is \
                                     {port_format:?}; declare the output with the shader's format",
                                b.name
                            )));
                        }
                    } else if p.access == Access::Write {
                        return Err(self.error(format!(
                            "{shader}: global \"{}\" samples output port \"{}\"; outputs are written, not read",
                            b.name, b.name
                        )));
                    }
                }
                None => {
                    let ports: Vec<&str> = self.ports.iter().map(|p| p.name.as_str()).collect();
                    return Err(self.error(format!(
                        "{shader}: global \"{}\" is neither a port of this pass (ports: {}) nor a system binding ({}) \
                         nor one the pass binds itself ({}); rename it to the port it stands for",
                        b.name,
                        ports.join(", "),
                        SYSTEM_BINDINGS.join(", "),
                        if extra.is_empty() { "none".to_string() } else { extra.join(", ") }
                    )));
                }
            }
        }
        Ok(())
    }

    fn layout(&self, label: &str, bindings: &[ReflectedBinding], stages: wgpu::ShaderStages) -> wgpu::BindGroupLayout {
        let entries: Vec<wgpu::BindGroupLayoutEntry> = bindings
            .iter()
            .map(|b| {
                let filterable = match self.port(&b.name) {
                    Some(p) if p.owned => false,
                    Some(PortInfo { format: Some(f), .. }) => self.gpu.filterable(*f),
                    _ => true,
                };
                // Writable storage in a vertex stage needs VERTEX_WRITABLE_STORAGE; volgraph's
                // render passes write storage (debug counters) from fragment shaders only.
                let stages = match b.ty {
                    BindingKind::Storage { read_only: false } => stages - wgpu::ShaderStages::VERTEX,
                    _ => stages,
                };
                layout_entry(b, stages, filterable)
            })
            .collect();
        self.gpu
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries: &entries })
    }

    /// Builds a render pipeline drawing a fragment shader into this pass's output ports, named
    /// by the fragment output struct's members.
    pub fn render_pipeline(&self, spec: &RenderPipelineSpec<'_>) -> Result<PassPipeline, PassError> {
        let shader = self.shaders.get(self.gpu, spec.shader).map_err(|e| self.error(e))?;
        let r = reflect(&shader.module, &shader.info, &[spec.vertex, spec.fragment])
            .map_err(|e| self.error(format!("{} {e}", spec.shader)))?;
        self.check_bindings(spec.shader, &r.bindings, spec.extra_bindings)?;
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
        let label = format!("{}/{}", self.pass_id, spec.fragment);
        let layout = self.layout(&label, &r.bindings, wgpu::ShaderStages::VERTEX_FRAGMENT);
        let pipeline_layout = self.gpu.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(&label),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let scope = self.gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let pipeline = self.gpu.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
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
                topology: wgpu::PrimitiveTopology::TriangleList,
                front_face: wgpu::FrontFace::Ccw,
                cull_mode: spec.cull,
                ..Default::default()
            },
            depth_stencil,
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
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(self.error(format!("{}: wgpu rejected the pipeline: {e}", spec.shader)));
        }
        Ok(PassPipeline {
            label,
            pipeline: PipelineKind::Render(pipeline),
            layout,
            bindings: r.bindings,
            color_ports,
            depth_port: spec.depth.map(|d| d.port.to_string()),
        })
    }

    /// Builds a compute pipeline writing this pass's outputs as storage textures named after
    /// the ports.
    pub fn compute_pipeline(&self, spec: &ComputePipelineSpec<'_>) -> Result<PassPipeline, PassError> {
        let shader = self.shaders.get(self.gpu, spec.shader).map_err(|e| self.error(e))?;
        let r = reflect(&shader.module, &shader.info, &[spec.entry])
            .map_err(|e| self.error(format!("{} {e}", spec.shader)))?;
        self.check_bindings(spec.shader, &r.bindings, spec.extra_bindings)?;
        let label = format!("{}/{}", self.pass_id, spec.entry);
        let layout = self.layout(&label, &r.bindings, wgpu::ShaderStages::COMPUTE);
        let pipeline_layout = self.gpu.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(&label),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let scope = self.gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let pipeline = self.gpu.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(&label),
            layout: Some(&pipeline_layout),
            module: &shader.wgpu,
            entry_point: Some(spec.entry),
            compilation_options: wgpu::PipelineCompilationOptions { constants: spec.constants, ..Default::default() },
            cache: None,
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(self.error(format!("{}: wgpu rejected the pipeline: {e}", spec.shader)));
        }
        Ok(PassPipeline {
            label,
            pipeline: PipelineKind::Compute(pipeline),
            layout,
            bindings: r.bindings,
            color_ports: Vec::new(),
            depth_port: None,
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
}

/// One port of a step as bound for recording.
pub(crate) struct BoundView<'a> {
    pub name: String,
    pub access: Access,
    pub view: Option<&'a wgpu::TextureView>,
    pub extent: Option<(u32, u32)>,
}

/// Samplers and the frame uniform buffer.
pub struct SystemBindings {
    /// `frame`.
    pub frame: wgpu::Buffer,
    /// `linear_clamp`.
    pub linear_clamp: wgpu::Sampler,
    /// `nearest_clamp`.
    pub nearest_clamp: wgpu::Sampler,
}

/// Given to [`crate::plugin::PassNode::record`] for one step of one frame.
pub struct RecordContext<'a> {
    /// The GPU.
    pub gpu: &'a Gpu,
    /// The frame's encoder.
    pub encoder: &'a mut wgpu::CommandEncoder,
    /// Instance label (debug label of every GPU pass recorded).
    pub label: &'a str,
    /// `(iteration, count)` inside a repeat group.
    pub iteration: Option<(u32, u32)>,
    /// The pass's parameters.
    pub params: &'a Params,
    /// The viewport.
    pub viewport: (u32, u32),
    pub(crate) ports: Vec<BoundView<'a>>,
    pub(crate) system: &'a SystemBindings,
    pub(crate) timestamps: Option<(&'a wgpu::QuerySet, u32)>,
    pub(crate) began_pass: bool,
}

impl<'a> RecordContext<'a> {
    fn error(&self, message: String) -> PassError {
        PassError { pass: self.label.to_string(), message }
    }

    /// The texture view bound to `port` (an input's value, or the target an output writes).
    pub fn view(&self, port: &str) -> Result<&'a wgpu::TextureView, PassError> {
        self.ports
            .iter()
            .find(|p| p.name == port)
            .and_then(|p| p.view)
            .ok_or_else(|| self.error(format!("port \"{port}\" is not bound to a texture")))
    }

    /// Whether an optional port is bound.
    pub fn is_bound(&self, port: &str) -> bool {
        self.ports.iter().any(|p| p.name == port && p.view.is_some())
    }

    /// Pixel size of the target bound to `port`.
    pub fn extent(&self, port: &str) -> (u32, u32) {
        self.ports.iter().find(|p| p.name == port).and_then(|p| p.extent).unwrap_or(self.viewport)
    }

    /// Builds bind group 0 of `pipeline`, resolving every binding by name: system bindings,
    /// then `extra` (the pass's own buffers), then ports.
    pub fn bind_group(
        &self,
        pipeline: &PassPipeline,
        extra: &[(&str, wgpu::BindingResource<'_>)],
    ) -> Result<wgpu::BindGroup, PassError> {
        let mut entries = Vec::new();
        for b in &pipeline.bindings {
            let resource = match b.name.as_str() {
                "frame" => self.system.frame.as_entire_binding(),
                "linear_clamp" => wgpu::BindingResource::Sampler(&self.system.linear_clamp),
                "nearest_clamp" => wgpu::BindingResource::Sampler(&self.system.nearest_clamp),
                name => match extra.iter().find(|(n, _)| *n == name) {
                    Some((_, r)) => r.clone(),
                    None => wgpu::BindingResource::TextureView(self.view(name)?),
                },
            };
            entries.push(wgpu::BindGroupEntry { binding: b.binding, resource });
        }
        Ok(self.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&pipeline.label),
            layout: &pipeline.layout,
            entries: &entries,
        }))
    }

    fn timestamp_indices(&mut self) -> Option<(&'a wgpu::QuerySet, Option<u32>, u32)> {
        let (set, base) = self.timestamps?;
        let begin = (!self.began_pass).then_some(base);
        self.began_pass = true;
        Some((set, begin, base + 1))
    }

    /// Begins a render pass into `pipeline`'s colour ports (Write ports cleared to 0, Modify
    /// ports loaded) and its depth port (`depth_clear`: Some(value) clears, None loads),
    /// labelled and timed.
    pub fn begin_render_pass(
        &mut self,
        pipeline: &PassPipeline,
        depth_clear: Option<f32>,
    ) -> Result<wgpu::RenderPass<'static>, PassError> {
        let mut colors = Vec::new();
        for port in &pipeline.color_ports {
            let p = self.ports.iter().find(|p| &p.name == port).ok_or_else(|| self.error(format!("no port {port}")))?;
            let view = p.view.ok_or_else(|| self.error(format!("port \"{port}\" is not bound")))?;
            let load = if p.access == Access::Modify {
                wgpu::LoadOp::Load
            } else {
                wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)
            };
            colors.push(Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load, store: wgpu::StoreOp::Store },
            }));
        }
        let depth = match &pipeline.depth_port {
            Some(port) => {
                let view = self.view(port)?;
                Some(wgpu::RenderPassDepthStencilAttachment {
                    view,
                    depth_ops: Some(wgpu::Operations {
                        load: depth_clear.map_or(wgpu::LoadOp::Load, wgpu::LoadOp::Clear),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                })
            }
            None => None,
        };
        let ts = self.timestamp_indices();
        let label = self.label.to_string();
        let pass = self.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(&label),
            color_attachments: &colors,
            depth_stencil_attachment: depth,
            timestamp_writes: ts.map(|(query_set, b, e)| wgpu::RenderPassTimestampWrites {
                query_set,
                beginning_of_pass_write_index: b,
                end_of_pass_write_index: Some(e),
            }),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        Ok(pass.forget_lifetime())
    }

    /// Begins a compute pass, labelled and timed.
    pub fn begin_compute_pass(&mut self) -> wgpu::ComputePass<'static> {
        let ts = self.timestamp_indices();
        let label = self.label.to_string();
        self.encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(&label),
                timestamp_writes: ts.map(|(query_set, b, e)| wgpu::ComputePassTimestampWrites {
                    query_set,
                    beginning_of_pass_write_index: b,
                    end_of_pass_write_index: Some(e),
                }),
            })
            .forget_lifetime()
    }
}
