//! Window output: a graph output drawn onto a surface texture at the end of a frame, in the same
//! command buffer, sRGB-correct whatever the output's and the surface's encodings
//! (`blit.wgsl`). Headless rendering never records it.

use std::collections::HashMap;

use super::gpu::{Gpu, GpuFault};

/// Where and what to present.
pub struct PresentTarget<'a> {
    /// The surface texture's view for this frame.
    pub view: &'a wgpu::TextureView,
    /// The surface format.
    pub format: wgpu::TextureFormat,
    /// The surface size in pixels.
    pub size: (u32, u32),
    /// The graph output to show (`display` when the graph has it).
    pub output: &'a str,
    /// Where on the surface the output goes, (x, y, width, height) in pixels (the viewer's image
    /// beside its panel); `None`: the whole surface.
    pub region: Option<[u32; 4]>,
    /// Draw over what the surface holds (a second output beside the first, the viewer's slice
    /// panes) instead of clearing it to black first.
    pub load: bool,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct BlitParams {
    source_encoded: u32,
    surface_wants_encoded: u32,
    region_origin: [f32; 2],
    region_size: [f32; 2],
    _pad: [f32; 2],
}

struct BlitPipeline {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
}

/// Blit pipelines by surface format.
#[derive(Default)]
pub struct Blitter {
    pipelines: HashMap<wgpu::TextureFormat, BlitPipeline>,
}

impl Blitter {
    fn pipeline(&mut self, gpu: &Gpu, format: wgpu::TextureFormat) -> Result<&BlitPipeline, GpuFault> {
        #[allow(clippy::map_entry, reason = "building can fail; the entry API would hold the map across it")]
        if !self.pipelines.contains_key(&format) {
            let built = gpu.checked(
                || format!("building the window blit for {format:?}"),
                || {
                    let module = gpu.device.create_shader_module(wgpu::ShaderModuleDescriptor {
                        label: Some("blit.wgsl"),
                        source: wgpu::ShaderSource::Wgsl(include_str!("blit.wgsl").into()),
                    });
                    let layout = gpu.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                        label: Some("blit"),
                        entries: &[
                            wgpu::BindGroupLayoutEntry {
                                binding: 0,
                                visibility: wgpu::ShaderStages::FRAGMENT,
                                ty: wgpu::BindingType::Texture {
                                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                                    view_dimension: wgpu::TextureViewDimension::D2,
                                    multisampled: false,
                                },
                                count: None,
                            },
                            wgpu::BindGroupLayoutEntry {
                                binding: 1,
                                visibility: wgpu::ShaderStages::FRAGMENT,
                                ty: wgpu::BindingType::Buffer {
                                    ty: wgpu::BufferBindingType::Uniform,
                                    has_dynamic_offset: false,
                                    min_binding_size: None,
                                },
                                count: None,
                            },
                        ],
                    });
                    let pipeline_layout = gpu.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                        label: Some("blit"),
                        bind_group_layouts: &[Some(&layout)],
                        immediate_size: 0,
                    });
                    let pipeline = gpu.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                        label: Some("blit"),
                        layout: Some(&pipeline_layout),
                        vertex: wgpu::VertexState {
                            module: &module,
                            entry_point: Some("vs_blit"),
                            compilation_options: Default::default(),
                            buffers: &[],
                        },
                        primitive: wgpu::PrimitiveState::default(),
                        depth_stencil: None,
                        multisample: wgpu::MultisampleState::default(),
                        fragment: Some(wgpu::FragmentState {
                            module: &module,
                            entry_point: Some("fs_blit"),
                            compilation_options: Default::default(),
                            targets: &[Some(wgpu::ColorTargetState {
                                format,
                                blend: None,
                                write_mask: wgpu::ColorWrites::ALL,
                            })],
                        }),
                        multiview_mask: None,
                        cache: None,
                    });
                    let params = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("blit params"),
                        size: std::mem::size_of::<BlitParams>() as u64,
                        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    });
                    BlitPipeline { pipeline, layout, params }
                },
            )?;
            self.pipelines.insert(format, built);
        }
        Ok(&self.pipelines[&format])
    }

    /// Records the blit of `source` (sRGB-encoded when `source_encoded`) onto `target`.
    pub(crate) fn record(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        source: &wgpu::TextureView,
        source_encoded: bool,
        target: &PresentTarget<'_>,
    ) -> Result<(), GpuFault> {
        let blit = self.pipeline(gpu, target.format)?;
        // The region, kept on the surface and at least a pixel.
        let (w, h) = (target.size.0.max(1), target.size.1.max(1));
        let region = target.region.map_or([0, 0, w, h], |[x, y, rw, rh]| {
            let (x, y) = (x.min(w - 1), y.min(h - 1));
            [x, y, rw.clamp(1, w - x), rh.clamp(1, h - y)]
        });
        let params = BlitParams {
            source_encoded: source_encoded as u32,
            surface_wants_encoded: (!target.format.is_srgb()) as u32,
            region_origin: [region[0] as f32, region[1] as f32],
            region_size: [region[2] as f32, region[3] as f32],
            _pad: [0.0; 2],
        };
        gpu.queue.write_buffer(&blit.params, 0, bytemuck::bytes_of(&params));
        let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("blit"),
            layout: &blit.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(source) },
                wgpu::BindGroupEntry { binding: 1, resource: blit.params.as_entire_binding() },
            ],
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("present to window"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target.view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: if target.load { wgpu::LoadOp::Load } else { wgpu::LoadOp::Clear(wgpu::Color::BLACK) },
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        pass.set_pipeline(&blit.pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.set_viewport(region[0] as f32, region[1] as f32, region[2] as f32, region[3] as f32, 0.0, 1.0);
        pass.draw(0..3, 0..1);
        Ok(())
    }
}
