//! Running a plan: pooled targets allocated once per plan, graph inputs bound by the
//! application, one command buffer per frame, per-pass GPU time from timestamp queries.

use std::collections::HashMap;
use std::time::Instant;

use super::context::{BoundView, CreateContext, PassError, PortInfo, RecordContext, SystemBindings};
use super::frame_uniforms::FrameUniforms;
use super::gpu::Gpu;
use super::readback::{Image, read_texture};
use super::shaders::ShaderLibrary;
use crate::format::TargetFormat;
use crate::graph::ast::{HistoryInitial, InputKind};
use crate::plan::{Binding, Plan, ResourceDesc};
use crate::plugin::{Access, PassNode, PortKind, Registry};

/// Why a plan could not be run.
#[derive(Debug, thiserror::Error)]
pub enum ExecutorError {
    /// A pass failed to build or record.
    #[error(transparent)]
    Pass(#[from] PassError),
    /// A step's kind is not in the registry (the plan came from another registry).
    #[error("pass kind \"{0}\" is not registered")]
    UnknownKind(String),
    /// The application did not bind a graph input.
    #[error("graph input \"{name}\" ({kind}) is not bound; {hint}")]
    UnboundInput {
        /// Input name.
        name: String,
        /// Its kind.
        kind: String,
        /// How to bind it.
        hint: String,
    },
    /// A requested output does not exist.
    #[error("the graph has no output \"{name}\" (it has: {known})")]
    UnknownOutput {
        /// Requested name.
        name: String,
        /// Existing names.
        known: String,
    },
    /// Texture upload or readback failed.
    #[error("{0}")]
    Transfer(String),
    /// The GPU rejected work (validation, out of memory), with what was being done.
    #[error(transparent)]
    Gpu(#[from] super::gpu::GpuFault),
}

/// A graph input texture bound by the application.
pub struct InputTexture {
    /// The texture.
    pub texture: wgpu::Texture,
    /// Its default view.
    pub view: wgpu::TextureView,
}

struct SlotTextures {
    current: wgpu::Texture,
    current_view: wgpu::TextureView,
    /// History pairs only: last frame's texture.
    previous: Option<(wgpu::Texture, wgpu::TextureView)>,
}

/// Timing of one frame.
#[derive(Clone, Debug, Default)]
pub struct FrameStats {
    /// GPU milliseconds per step (same order as the plan's steps), when timestamps exist.
    pub step_gpu_ms: Option<Vec<f64>>,
    /// Sum of the steps' GPU time, or wall time from submit to completion as a fallback.
    pub frame_ms: f64,
    /// True when `frame_ms` is wall time because the adapter has no timestamp queries.
    pub wall_time_fallback: bool,
}

/// Runs one compiled plan frame after frame.
pub struct Executor {
    plan: Plan,
    nodes: HashMap<String, Box<dyn PassNode>>,
    slots: Vec<SlotTextures>,
    owned: HashMap<usize, wgpu::TextureView>,
    inputs: HashMap<String, InputTexture>,
    system: SystemBindings,
    frame_index: u32,
    history_valid: bool,
    queries: Option<(wgpu::QuerySet, wgpu::Buffer, wgpu::Buffer)>,
}

fn usage_for(format: TargetFormat) -> wgpu::TextureUsages {
    let mut u = wgpu::TextureUsages::RENDER_ATTACHMENT
        | wgpu::TextureUsages::TEXTURE_BINDING
        | wgpu::TextureUsages::COPY_SRC
        | wgpu::TextureUsages::COPY_DST;
    if matches!(
        format,
        TargetFormat::Rgba16Float
            | TargetFormat::Rgba32Float
            | TargetFormat::R32Float
            | TargetFormat::Rg32Float
            | TargetFormat::Rgba8Unorm
    ) {
        u |= wgpu::TextureUsages::STORAGE_BINDING;
    }
    u
}

fn create_target(
    gpu: &Gpu,
    label: &str,
    format: TargetFormat,
    extent: (u32, u32),
) -> (wgpu::Texture, wgpu::TextureView) {
    let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width: extent.0, height: extent.1, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: format.wgpu(),
        usage: usage_for(format),
        view_formats: &[],
    });
    let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
    (texture, view)
}

impl Executor {
    /// Builds every pass's node and allocates the plan's pooled targets.
    pub fn new(gpu: &Gpu, shaders: &ShaderLibrary, registry: &Registry, plan: Plan) -> Result<Self, ExecutorError> {
        let mut nodes: HashMap<String, Box<dyn PassNode>> = HashMap::new();
        for step in &plan.steps {
            if nodes.contains_key(&step.pass_id) {
                continue;
            }
            let plugin = registry.get(&step.kind).ok_or_else(|| ExecutorError::UnknownKind(step.kind.clone()))?;
            let specs = plugin.ports(&step.params);
            let ports: Vec<PortInfo> = step
                .ports
                .iter()
                .map(|bp| {
                    let format = match &bp.binding {
                        Binding::Resource { id, .. } => match &plan.resources[*id].desc {
                            ResourceDesc::Target { format, .. } => Some(format.wgpu()),
                            ResourceDesc::Owned(_) => None,
                        },
                        Binding::History(name) => {
                            plan.history.get(name).and_then(|h| match &plan.resources[h.source].desc {
                                ResourceDesc::Target { format, .. } => Some(format.wgpu()),
                                ResourceDesc::Owned(_) => None,
                            })
                        }
                        _ => specs.iter().find(|s| s.name == bp.port).and_then(|s| match &s.kind {
                            PortKind::Target { formats, .. } => formats.first().map(|f| f.wgpu()),
                            _ => None,
                        }),
                    };
                    let owned = matches!(
                        &bp.binding,
                        Binding::Resource { id, .. } if matches!(plan.resources[*id].desc, ResourceDesc::Owned(_))
                    );
                    PortInfo { name: bp.port.clone(), access: bp.access, format, owned }
                })
                .collect();
            let ctx = CreateContext { gpu, shaders, pass_id: &step.pass_id, params: &step.params, ports: &ports };
            let node = plugin.create(&ctx)?;
            nodes.insert(step.pass_id.clone(), node);
        }
        let mut owned = HashMap::new();
        for step in &plan.steps {
            for bp in &step.ports {
                if let Binding::Resource { id, written: None } = &bp.binding
                    && bp.access == Access::Write
                    && matches!(plan.resources[*id].desc, ResourceDesc::Owned(_))
                {
                    let node = nodes.get(&step.pass_id).ok_or_else(|| ExecutorError::UnknownKind(step.kind.clone()))?;
                    // A node whose texture depends on a graph input (a grid sized by the
                    // volume) creates it in its first `record`; `run_frame` picks it up then.
                    if let Some(view) = node.owned_output(&bp.port) {
                        owned.insert(*id, view);
                    }
                }
            }
        }
        let mut slots = Vec::with_capacity(plan.slots.len());
        for (i, s) in plan.slots.iter().enumerate() {
            let label = format!("slot{i} {}", s.format);
            let held = s.holds.first().map_or(String::new(), |r| format!(" for \"{}\"", plan.resources[*r].name));
            let textures = gpu.checked(
                || format!("creating target {label} {}x{}{held}", s.extent.0, s.extent.1),
                || {
                    let (current, current_view) = create_target(gpu, &label, s.format, s.extent);
                    let previous = s
                        .persistent
                        .then(|| create_target(gpu, &format!("{label} (previous frame)"), s.format, s.extent));
                    SlotTextures { current, current_view, previous }
                },
            )?;
            slots.push(textures);
        }
        let sampler = |label: &str, filter: wgpu::FilterMode| {
            gpu.device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some(label),
                address_mode_u: wgpu::AddressMode::ClampToEdge,
                address_mode_v: wgpu::AddressMode::ClampToEdge,
                address_mode_w: wgpu::AddressMode::ClampToEdge,
                mag_filter: filter,
                min_filter: filter,
                ..Default::default()
            })
        };
        let system = SystemBindings {
            frame: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("frame uniforms"),
                size: std::mem::size_of::<FrameUniforms>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            linear_clamp: sampler("linear_clamp", wgpu::FilterMode::Linear),
            nearest_clamp: sampler("nearest_clamp", wgpu::FilterMode::Nearest),
        };
        let queries = (gpu.has_timestamps && !plan.steps.is_empty()).then(|| {
            let count = (2 * plan.steps.len()) as u32;
            let set = gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("step timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count,
            });
            let size = count as u64 * 8;
            let resolve = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp resolve"),
                size,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let read = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp readback"),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            (set, resolve, read)
        });
        Ok(Self {
            plan,
            nodes,
            slots,
            owned,
            inputs: HashMap::new(),
            system,
            frame_index: 0,
            history_valid: false,
            queries,
        })
    }

    /// The plan being run.
    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    /// Binds a graph input texture (volume, transfer-function LUT) by input name.
    pub fn bind_input(&mut self, name: &str, texture: wgpu::Texture) {
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        self.inputs.insert(name.to_string(), InputTexture { texture, view });
    }

    /// Uploads this frame's uniforms.
    pub fn set_frame(&mut self, gpu: &Gpu, mut uniforms: FrameUniforms) {
        uniforms.frame_index = self.frame_index;
        gpu.queue.write_buffer(&self.system.frame, 0, bytemuck::bytes_of(&uniforms));
    }

    /// Forgets history: the next frame reads every history entry's initial value (call on
    /// resize, transfer-function or isovalue change, or a camera jump; Klein et al. 2005 §4).
    pub fn invalidate_history(&mut self) {
        self.history_valid = false;
    }

    fn check_inputs(&self) -> Result<(), ExecutorError> {
        for (name, kind) in &self.plan.inputs {
            let used =
                self.plan.steps.iter().any(|s| s.ports.iter().any(|p| p.binding == Binding::Input(name.clone())));
            if used && !self.inputs.contains_key(name) {
                let (kind, hint) = match kind {
                    InputKind::Volume => ("Volume", "bind a 3D texture with Executor::bind_input"),
                    InputKind::TransferFunction => {
                        ("TransferFunction", "bind the LUT texture with Executor::bind_input")
                    }
                    InputKind::Scalar(_) => ("Scalar", "scalars are compile-time scene values"),
                };
                return Err(ExecutorError::UnboundInput {
                    name: name.clone(),
                    kind: kind.to_string(),
                    hint: hint.to_string(),
                });
            }
        }
        Ok(())
    }

    /// Records, submits and waits for one frame. An error the GPU reports for the frame comes
    /// back as [`ExecutorError::Gpu`] naming the graph (wgpu's message names the pass label).
    pub fn run_frame(&mut self, gpu: &Gpu) -> Result<FrameStats, ExecutorError> {
        self.check_inputs()?;
        let what = || format!("frame {} of graph \"{}\"", self.frame_index, self.plan.name);
        let what = what();
        let wall_ms = gpu.checked(
            || what,
            || -> Result<f64, ExecutorError> {
                let commands = self.record_frame(gpu)?;
                let start = Instant::now();
                gpu.queue.submit([commands]);
                gpu.wait_idle();
                Ok(start.elapsed().as_secs_f64() * 1e3)
            },
        )??;
        self.frame_index += 1;
        self.history_valid = true;
        let step_gpu_ms = match &self.queries {
            Some((_, _, read)) => Some(read_timestamps(gpu, read, self.plan.steps.len())?),
            None => None,
        };
        let frame_ms = step_gpu_ms.as_ref().map_or(wall_ms, |v| v.iter().sum());
        Ok(FrameStats { wall_time_fallback: step_gpu_ms.is_none(), step_gpu_ms, frame_ms })
    }

    fn record_frame(&mut self, gpu: &Gpu) -> Result<wgpu::CommandBuffer, ExecutorError> {
        let mut encoder =
            gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(&self.plan.name) });
        // History pairs: swap, and clear "previous" when there is no previous frame.
        for textures in &mut self.slots {
            if let Some(prev) = textures.previous.as_mut() {
                std::mem::swap(&mut textures.current, &mut prev.0);
                std::mem::swap(&mut textures.current_view, &mut prev.1);
            }
        }
        if !self.history_valid {
            for h in self.plan.history.values() {
                let Some(slot) = self.plan.resources[h.source].slot else { continue };
                let Some((_, view)) = &self.slots[slot].previous else { continue };
                let HistoryInitial::Clear((r, g, b, a)) = h.initial;
                let _ = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("history initial value"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color { r, g, b, a }),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    ..Default::default()
                });
            }
        }
        let plan = &self.plan;
        for (i, step) in plan.steps.iter().enumerate() {
            let mut ports = Vec::new();
            for bp in &step.ports {
                let (view, extent) = match &bp.binding {
                    Binding::Resource { id, written } => {
                        let rid = if bp.access == Access::Modify { written.unwrap_or(*id) } else { *id };
                        let r = &plan.resources[rid];
                        let extent = match &r.desc {
                            ResourceDesc::Target { extent, .. } => Some(*extent),
                            ResourceDesc::Owned(_) => None,
                        };
                        let view = match r.slot {
                            Some(s) => Some(&self.slots[s].current_view),
                            None => self.owned.get(&super::run::root_owned(plan, rid)),
                        };
                        (view, extent)
                    }
                    Binding::Input(name) => (self.inputs.get(name).map(|t| &t.view), None),
                    Binding::History(name) => {
                        let slot = plan.history.get(name).and_then(|h| plan.resources[h.source].slot);
                        (slot.and_then(|s| self.slots[s].previous.as_ref().map(|p| &p.1)), None)
                    }
                    Binding::Unbound => (None, None),
                };
                ports.push(BoundView { name: bp.port.clone(), access: bp.access, view, extent });
            }
            let node =
                self.nodes.get_mut(&step.pass_id).ok_or_else(|| ExecutorError::UnknownKind(step.kind.clone()))?;
            let mut ctx = RecordContext {
                gpu,
                encoder: &mut encoder,
                label: &step.label,
                iteration: step.iteration,
                params: &step.params,
                viewport: plan.viewport,
                ports,
                system: &self.system,
                timestamps: self.queries.as_ref().map(|(set, _, _)| (set, 2 * i as u32)),
                began_pass: false,
            };
            node.record(&mut ctx)?;
            // Owned outputs created or replaced while recording (sized by a graph input).
            for bp in &step.ports {
                if let Binding::Resource { id, written: None } = &bp.binding
                    && bp.access == Access::Write
                    && matches!(plan.resources[*id].desc, ResourceDesc::Owned(_))
                {
                    let view = node.owned_output(&bp.port).ok_or_else(|| {
                        ExecutorError::Pass(PassError {
                            pass: step.label.clone(),
                            message: format!(
                                "declares owned output \"{}\" but its node provides no texture for it",
                                bp.port
                            ),
                        })
                    })?;
                    self.owned.insert(*id, view);
                }
            }
        }
        if let Some((set, resolve, read)) = &self.queries {
            let count = 2 * plan.steps.len() as u32;
            encoder.resolve_query_set(set, 0..count, resolve, 0);
            encoder.copy_buffer_to_buffer(resolve, 0, read, 0, count as u64 * 8);
        }
        Ok(encoder.finish())
    }

    /// Reads back a graph output after a frame.
    pub fn read_output(&self, gpu: &Gpu, name: &str) -> Result<Image, ExecutorError> {
        let Some(&rid) = self.plan.outputs.get(name) else {
            return Err(ExecutorError::UnknownOutput {
                name: name.to_string(),
                known: self.plan.outputs.keys().cloned().collect::<Vec<_>>().join(", "),
            });
        };
        self.read_resource(gpu, rid)
    }

    /// Reads back any target resource after a frame (valid while its slot was not reused, i.e.
    /// for outputs and the last holder of a slot).
    pub fn read_resource(&self, gpu: &Gpu, rid: usize) -> Result<Image, ExecutorError> {
        let r = &self.plan.resources[rid];
        let (Some(slot), ResourceDesc::Target { format, extent, .. }) = (r.slot, &r.desc) else {
            return Err(ExecutorError::Transfer(format!("\"{}\" is not a target", r.name)));
        };
        read_texture(gpu, &self.slots[slot].current, *format, *extent).map_err(ExecutorError::Transfer)
    }
}

fn read_timestamps(gpu: &Gpu, read: &wgpu::Buffer, steps: usize) -> Result<Vec<f64>, ExecutorError> {
    let slice = read.slice(..);
    slice.map_async(wgpu::MapMode::Read, |_| {});
    gpu.wait_idle();
    let period_ns = gpu.queue.get_timestamp_period() as f64;
    let values: Vec<u64> = {
        let data = slice.get_mapped_range().map_err(|e| ExecutorError::Transfer(format!("timestamp readback: {e}")))?;
        data.chunks_exact(8).map(|c| u64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]])).collect()
    };
    read.unmap();
    Ok((0..steps)
        .map(|i| {
            let (a, b) = (values[2 * i], values[2 * i + 1]);
            if b > a { (b - a) as f64 * period_ns / 1e6 } else { 0.0 }
        })
        .collect())
}

/// The resource an Owned value's chain starts at (Modify ports on owned resources keep the
/// producer's texture).
pub(crate) fn root_owned(plan: &Plan, mut rid: usize) -> usize {
    while let Some(prev) = plan.resources[rid].modifies {
        rid = prev;
    }
    rid
}
