//! What a pass node sees while it records one step of one frame: [`RecordContext`]. Bind groups
//! are assembled by binding name and cached by the exact resources they hold, so a steady frame
//! creates none (history ping-pong simply keeps two).

use std::cell::RefCell;
use std::collections::HashMap;

use super::create::{ComputePassPipeline, PassError, PassPipeline, RenderPassPipeline};
use super::frame::FrameData;
use super::gpu::Gpu;
use crate::plugin::Access;

/// One port of a step as bound for recording.
pub(crate) struct BoundPort<'a> {
    pub name: String,
    pub access: Access,
    pub view: Option<&'a wgpu::TextureView>,
    pub buffer: Option<&'a wgpu::Buffer>,
    pub extent: Option<(u32, u32)>,
    /// Version of a graph input's content or of an Owned resource (equal content, equal
    /// version); `None` for targets, which change every frame.
    pub version: Option<u64>,
    /// A volume input's voxels (ports of kind Volume and VolumeVoxels).
    pub voxels: Option<&'a std::sync::Arc<volgraph_accel::volume::Volume>>,
    /// A volume input bound as a pyramid (streamed brick by brick), instead of `voxels`.
    pub pyramid: Option<&'a std::sync::Arc<dyn volgraph_accel::pyramid::PyramidSource>>,
    /// A transfer-function input's LUT on the CPU.
    pub table: Option<&'a std::sync::Arc<Vec<[f32; 4]>>>,
    /// A graph's bypass left out this input's producer: it holds zeros this frame.
    pub zeroed: bool,
}

/// Samplers and the frame uniform buffer.
pub struct SystemBindings {
    /// `frame`.
    pub frame: wgpu::Buffer,
    /// `linear_clamp`.
    pub linear_clamp: wgpu::Sampler,
    /// `nearest_clamp`.
    pub nearest_clamp: wgpu::Sampler,
    /// `environment_map`: the scene's environment (`Runtime::set_environment`), 1×1 black
    /// without one.
    pub environment_map: wgpu::TextureView,
}

/// An environment map as an `Rgba32Float` 2D texture (read with `textureLoad`).
pub(crate) fn environment_view(gpu: &Gpu, map: &volgraph_accel::environment::EnvironmentMap) -> wgpu::TextureView {
    use wgpu::util::DeviceExt as _;
    gpu.device
        .create_texture_with_data(
            &gpu.queue,
            &wgpu::TextureDescriptor {
                label: Some("environment map"),
                size: wgpu::Extent3d { width: map.width, height: map.height, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba32Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            bytemuck::cast_slice(&map.texels),
        )
        .create_view(&wgpu::TextureViewDescriptor::default())
}

impl SystemBindings {
    pub(crate) fn new(gpu: &Gpu) -> Self {
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
        Self {
            frame: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("frame uniforms"),
                size: std::mem::size_of::<super::frame::FrameUniforms>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            linear_clamp: sampler("linear_clamp", wgpu::FilterMode::Linear),
            nearest_clamp: sampler("nearest_clamp", wgpu::FilterMode::Nearest),
            environment_map: environment_view(gpu, &volgraph_accel::environment::EnvironmentMap::uniform([0.0; 3])),
        }
    }
}

/// The identity of one bound resource (wgpu handles compare by identity).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
enum ResourceKey {
    View(wgpu::TextureView),
    Buffer(wgpu::Buffer, u64, Option<u64>),
    Sampler(wgpu::Sampler),
}

type BindKey = (wgpu::BindGroupLayout, Vec<(u32, ResourceKey)>);

/// Bind groups by layout and resources, with the frame each was last used in.
#[derive(Default)]
pub(crate) struct BindGroupCache {
    groups: HashMap<BindKey, (wgpu::BindGroup, u64)>,
    created: u64,
}

impl BindGroupCache {
    /// Drops groups not used in the last `frames` frames (their resources were replaced).
    pub(crate) fn evict_older_than(&mut self, frame: u64, frames: u64) {
        self.groups.retain(|_, (_, used)| *used + frames >= frame);
    }

    pub(crate) fn created(&self) -> u64 {
        self.created
    }
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
    pub params: &'a crate::params::Params,
    /// The viewport.
    pub viewport: (u32, u32),
    /// The frame contract: cameras (this and the previous frame), counters, the volume.
    pub frame: &'a FrameData,
    /// The volume's screen footprint this frame (`super::footprint`), computed once for the
    /// frame block: what a footprint draw covers, and row spans for a pass that needs them.
    pub footprint: &'a super::footprint::Footprint,
    pub(crate) ports: Vec<BoundPort<'a>>,
    pub(crate) system: &'a SystemBindings,
    pub(crate) timestamps: Option<(&'a wgpu::QuerySet, u32)>,
    pub(crate) began_pass: bool,
    pub(crate) bind_groups: &'a RefCell<BindGroupCache>,
}

impl<'a> RecordContext<'a> {
    fn error(&self, message: String) -> PassError {
        PassError { pass: self.label.to_string(), message }
    }

    fn port(&self, name: &str) -> Option<&BoundPort<'a>> {
        self.ports.iter().find(|p| p.name == name)
    }

    /// The content version of what `port` reads — a graph input (the volume, the transfer
    /// function) or an Owned resource — so a node can keep data derived from it until it changes
    /// (a pre-integration table rebuilt when the TF changes); `None` for targets and unwired ports.
    pub fn input_version(&self, port: &str) -> Option<u64> {
        self.port(port).and_then(|p| p.version)
    }

    /// Whether input `port` holds zeros this frame because a graph's bypass left out the pass
    /// that writes it (its port reads zeros as "none"): a node may draw with a variant that
    /// does without it (built when `PortInfo::may_read_zeros`), as if it were unwired.
    pub fn reads_zeros(&self, port: &str) -> bool {
        self.port(port).is_some_and(|p| p.zeroed)
    }

    /// The texture view bound to `port` (an input's value, or the target an output writes).
    pub fn view(&self, port: &str) -> Result<&'a wgpu::TextureView, PassError> {
        self.port(port)
            .and_then(|p| p.view)
            .ok_or_else(|| self.error(format!("port \"{port}\" is not bound to a texture")))
    }

    /// The voxels of the volume bound to `port` (a port of kind
    /// [`crate::plugin::PortKind::VolumeVoxels`], or `Volume`: its texture's voxels), on the CPU.
    pub fn voxels(&self, port: &str) -> Result<&'a std::sync::Arc<volgraph_accel::volume::Volume>, PassError> {
        self.port(port)
            .and_then(|p| p.voxels)
            .ok_or_else(|| self.error(format!("port \"{port}\" is not bound to a volume's voxels")))
    }

    /// The pyramid bound to volume port `port`, when the application bound one (a volume
    /// larger than memory) instead of voxels; `None` for voxels or nothing.
    pub fn pyramid(&self, port: &str) -> Option<&'a std::sync::Arc<dyn volgraph_accel::pyramid::PyramidSource>> {
        self.port(port).and_then(|p| p.pyramid)
    }

    /// The transfer-function LUT bound to `port`, on the CPU (classifying bricks).
    pub fn table(&self, port: &str) -> Result<&'a std::sync::Arc<Vec<[f32; 4]>>, PassError> {
        self.port(port)
            .and_then(|p| p.table)
            .ok_or_else(|| self.error(format!("port \"{port}\" is not bound to a transfer function")))
    }

    /// The storage buffer bound to `port`.
    pub fn buffer(&self, port: &str) -> Result<&'a wgpu::Buffer, PassError> {
        self.port(port)
            .and_then(|p| p.buffer)
            .ok_or_else(|| self.error(format!("port \"{port}\" is not bound to a buffer")))
    }

    /// Whether an optional port is bound.
    pub fn is_bound(&self, port: &str) -> bool {
        self.port(port).is_some_and(|p| p.view.is_some() || p.buffer.is_some() || p.voxels.is_some())
    }

    /// Pixel size of the target bound to `port`.
    pub fn extent(&self, port: &str) -> (u32, u32) {
        self.port(port).and_then(|p| p.extent).unwrap_or(self.viewport)
    }

    /// Zeroes the buffer bound to `port` (a counter at the start of a frame).
    pub fn clear_buffer(&mut self, port: &str) -> Result<(), PassError> {
        let buffer = self.buffer(port)?;
        self.encoder.clear_buffer(buffer, 0, None);
        Ok(())
    }

    /// Clears the target bound to `port` to zero (a compute pass that scatters into part of
    /// it starts from "nothing here"), labelled and timed with the step. On lavapipe this
    /// clears a 128-bit target one `memcpy` per texel; a compute round writing zeros is far
    /// cheaper there (`reprojection_splat`'s `cs_splat_clear`).
    pub fn clear_target(&mut self, port: &str) -> Result<(), PassError> {
        let view = self.view(port)?;
        let ts = self.render_pass_timestamps();
        let label = format!("{}: clear {port}", self.label);
        clear_view(self.encoder, view, false, &label, ts);
        Ok(())
    }

    /// Uploads `data` into `buffer` at `offset` before this frame's work runs (per-frame CPU
    /// data: brick tables, streamed bricks).
    pub fn write_buffer(&self, buffer: &wgpu::Buffer, offset: u64, data: &[u8]) {
        self.gpu.queue.write_buffer(buffer, offset, data);
    }

    /// Bind group 0 of `pipeline`, every binding resolved by name: system bindings, then `extra`
    /// (the pass's own buffers), then ports. Cached by the resources it holds.
    pub fn bind_group<K>(
        &self,
        pipeline: &PassPipeline<K>,
        extra: &[(&str, wgpu::BindingResource<'_>)],
    ) -> Result<wgpu::BindGroup, PassError> {
        let mut entries = Vec::with_capacity(pipeline.bindings.len());
        let mut key = Vec::with_capacity(pipeline.bindings.len());
        for b in &pipeline.bindings {
            let resource = match b.name.as_str() {
                "frame" => self.system.frame.as_entire_binding(),
                "linear_clamp" => wgpu::BindingResource::Sampler(&self.system.linear_clamp),
                "nearest_clamp" => wgpu::BindingResource::Sampler(&self.system.nearest_clamp),
                "environment_map" => wgpu::BindingResource::TextureView(&self.system.environment_map),
                name => match extra.iter().find(|(n, _)| *n == name) {
                    Some((_, r)) => r.clone(),
                    None => match self.port(name).and_then(|p| p.buffer) {
                        Some(buffer) => buffer.as_entire_binding(),
                        None => wgpu::BindingResource::TextureView(self.view(name)?),
                    },
                },
            };
            // A uniform buffer smaller than the shader's struct is rejected by the GPU when the
            // pass runs, as "binding index N"; say which binding and what disagrees.
            if let (Some(want), wgpu::BindingResource::Buffer(bb)) = (b.uniform_size, &resource) {
                let have = bb.size.map_or_else(|| bb.buffer.size().saturating_sub(bb.offset), |s| s.get());
                if have < want {
                    return Err(PassError {
                        pass: self.label.to_string(),
                        message: format!(
                            "{}: uniform \"{}\" (@binding({})) is {want} bytes in the shader but the buffer the pass \
                             binds holds {have}; the shader's struct and the pass's parameter block disagree (check \
                             the struct against its pass_params! declaration)",
                            pipeline.label, b.name, b.binding
                        ),
                    });
                }
            }
            let resource_key = match &resource {
                wgpu::BindingResource::TextureView(v) => Some(ResourceKey::View((*v).clone())),
                wgpu::BindingResource::Sampler(s) => Some(ResourceKey::Sampler((*s).clone())),
                wgpu::BindingResource::Buffer(bb) => {
                    Some(ResourceKey::Buffer(bb.buffer.clone(), bb.offset, bb.size.map(|s| s.get())))
                }
                _ => None,
            };
            match resource_key {
                Some(k) => key.push((b.binding, k)),
                None => key.clear(),
            }
            entries.push(wgpu::BindGroupEntry { binding: b.binding, resource });
        }
        let cacheable = key.len() == entries.len();
        let frame = self.frame.frame_index;
        let key = (pipeline.layout.clone(), key);
        if cacheable && let Some((group, used)) = self.bind_groups.borrow_mut().groups.get_mut(&key) {
            *used = frame;
            return Ok(group.clone());
        }
        let group = self.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&pipeline.label),
            layout: &pipeline.layout,
            entries: &entries,
        });
        let mut cache = self.bind_groups.borrow_mut();
        cache.created += 1;
        if cacheable {
            cache.groups.insert(key, (group.clone(), frame));
        }
        Ok(group)
    }

    fn timestamp_indices(&mut self) -> Option<(&'a wgpu::QuerySet, Option<u32>, u32)> {
        let (set, base) = self.timestamps?;
        let begin = (!self.began_pass).then_some(base);
        self.began_pass = true;
        Some((set, begin, base + 1))
    }

    /// This step's timestamps for a render pass (the first pass of a step writes the beginning).
    fn render_pass_timestamps(&mut self) -> Option<wgpu::RenderPassTimestampWrites<'a>> {
        self.timestamp_indices().map(|(query_set, b, e)| wgpu::RenderPassTimestampWrites {
            query_set,
            beginning_of_pass_write_index: b,
            end_of_pass_write_index: Some(e),
        })
    }

    /// Begins a render pass into `pipeline`'s colour ports (Write ports cleared to 0, Modify
    /// ports loaded) and its depth port (`depth_clear`: Some(value) clears, None loads),
    /// labelled and timed.
    pub fn begin_render_pass(
        &mut self,
        pipeline: &RenderPassPipeline,
        depth_clear: Option<f32>,
    ) -> Result<wgpu::RenderPass<'static>, PassError> {
        self.begin_render_pass_over(pipeline, depth_clear, false)
    }

    /// The common fragment pass in one call: the fullscreen triangle of `pipeline` with
    /// `bind_group`. Where the pipeline writes every pixel (`PassPipeline::covers_viewport`) its
    /// Write ports are not cleared first: on lavapipe a clear of a 128-bit target is a `memcpy`
    /// per texel, 5 % of a Klein `leap_iso` frame (bench/one-march-final.md, "Clears").
    pub fn draw_fullscreen(
        &mut self,
        pipeline: &RenderPassPipeline,
        bind_group: &wgpu::BindGroup,
    ) -> Result<(), PassError> {
        let mut pass = self.begin_render_pass_over(pipeline, None, pipeline.covers_viewport)?;
        pass.set_pipeline(&pipeline.pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        pass.draw(0..3, 0..1);
        Ok(())
    }

    /// Draws a pipeline of [`RenderPipelineSpec::footprint`](super::RenderPipelineSpec::footprint)
    /// over this frame's screen footprint of the volume ([`super::footprint`]): its Write ports
    /// are cleared to zeros (on lavapipe a 128-bit target costs a `memcpy` per texel, less than
    /// the fragments left out where measured) and only the
    /// fragments inside the footprint (grown by a pixel) run — the same image as the fullscreen
    /// triangle for a fragment stage that writes zeros where a pixel's ray misses the box.
    pub fn draw_footprint(
        &mut self,
        pipeline: &RenderPassPipeline,
        bind_group: &wgpu::BindGroup,
    ) -> Result<(), PassError> {
        let mut pass = self.begin_render_pass_over(pipeline, None, false)?;
        pass.set_pipeline(&pipeline.pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        pass.draw(0..super::footprint::FAN_DRAW_VERTICES, 0..1);
        Ok(())
    }

    /// `begin_render_pass`; `overwritten`: the draw writes every pixel of the Write ports, so
    /// they are loaded (their old content never shows) instead of cleared.
    fn begin_render_pass_over(
        &mut self,
        pipeline: &RenderPassPipeline,
        depth_clear: Option<f32>,
        overwritten: bool,
    ) -> Result<wgpu::RenderPass<'static>, PassError> {
        let mut colors = Vec::new();
        for port in &pipeline.color_ports {
            let p = self.port(port).ok_or_else(|| self.error(format!("no port {port}")))?;
            let view = p.view.ok_or_else(|| self.error(format!("port \"{port}\" is not bound")))?;
            let load = if p.access == Access::Modify || overwritten {
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
        let ts = self.render_pass_timestamps();
        let label = self.label.to_string();
        let pass = self.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(&label),
            color_attachments: &colors,
            depth_stencil_attachment: depth,
            timestamp_writes: ts,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        Ok(pass.forget_lifetime())
    }

    /// The common compute pass in one call: bind group 0 of `pipeline` (with `extra`), one
    /// dispatch of `workgroup`-sized groups covering the target bound to `port`.
    pub fn dispatch_over(
        &mut self,
        pipeline: &ComputePassPipeline,
        extra: &[(&str, wgpu::BindingResource<'_>)],
        port: &str,
        workgroup: (u32, u32),
    ) -> Result<(), PassError> {
        let bind_group = self.bind_group(pipeline, extra)?;
        let (w, h) = self.extent(port);
        let mut pass = self.begin_compute_pass();
        pass.set_pipeline(&pipeline.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(w.div_ceil(workgroup.0.max(1)), h.div_ceil(workgroup.1.max(1)), 1);
        Ok(())
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

/// Clears `view` to zero in a render pass of its own (a depth target when `depth`), labelled and,
/// with `timestamps`, timed: what a pass clears before scattering into part of a target
/// (`RecordContext::clear_target`) and what a bypassed pass would have written
/// (`bypass::clear_for_left_out`).
pub(crate) fn clear_view(
    encoder: &mut wgpu::CommandEncoder,
    view: &wgpu::TextureView,
    depth: bool,
    label: &str,
    timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
) {
    let zero = wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT), store: wgpu::StoreOp::Store };
    let color = [Some(wgpu::RenderPassColorAttachment { view, depth_slice: None, resolve_target: None, ops: zero })];
    let depth_attachment = wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(0.0), store: wgpu::StoreOp::Store }),
        stencil_ops: None,
    };
    drop(encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: if depth { &[] } else { &color },
        depth_stencil_attachment: depth.then_some(depth_attachment),
        timestamp_writes: timestamps,
        occlusion_query_set: None,
        multiview_mask: None,
    }));
}
