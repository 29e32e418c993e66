//! The streaming raycaster's node: the pool's textures and buffers, the feedback read back,
//! the readers fed and drained, the march dispatched.

use std::sync::Arc;
use std::sync::mpsc::{Receiver, channel};

use glam::{DVec3, UVec3};
use volgraph_accel::brick_leaves::{SLOTS_PER_AXIS, slot_coord};
use volgraph_accel::classify::OpacityClassifier;
use volgraph_accel::pyramid::{BoxTexels, InCorePyramid, PyramidSource};
use volgraph_compiler::PassDecl;
use volgraph_core::runtime::upload::{VolumeFormat, VolumeTexels, texel_bytes, volume_format_for};
use volgraph_core::runtime::{ComputePassPipeline, ComputePipelineSpec, CreateContext, Gpu, PassError, RecordContext};
use volgraph_core::{PassNode, PassPlugin};

use super::{RaycastStream, StreamParams, StreamSettings, apron, march_shader, unoffered_effect};
use crate::effects::EffectFlags;
use crate::raycast_params::{RaycastParamsGpu, SampleLoopChoice, Workgroup};
use crate::stream_cache::{SUB_WORDS, StreamCache, StreamCounts, StreamLayout, occupancy_words, sub_block_ranges};
use crate::stream_loader::{BrickRead, BrickRequest, StreamLoader};

/// The pool's budget when neither the pass nor the runtime sets one.
const DEFAULT_BUDGET_BYTES: u64 = 1 << 30;

impl PassPlugin for RaycastStream {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        if let Some(message) = unoffered_effect(ctx.params) {
            return Err(PassError { pass: ctx.pass_id.to_string(), message });
        }
        let settings = StreamSettings::from_params(ctx.params);
        let wg = Workgroup::checked_size(ctx)?;
        let mut defines = SampleLoopChoice::with_gpu_defines(
            [self.shader_defines(ctx.params), crate::shared::color_precision_defines(ctx)].concat(),
            ctx.params,
            ctx.gpu,
        );
        defines.extend([crate::defines::LEVEL_STEPS, crate::defines::LEAP]);
        let pipeline = ctx.compute_pipeline(&ComputePipelineSpec {
            defines: &defines,
            constants: &[("WORKGROUP_X", wg.0 as f64), ("WORKGROUP_Y", wg.1 as f64)],
            ..ComputePipelineSpec::of(&march_shader())
        })?;
        let params = ctx.uniform_from_bytes("params", &RaycastParamsGpu::of(ctx.params).uniform_bytes());
        let uniform = ctx.uniform_from_bytes("stream", &StreamParams::EMPTY.uniform_bytes());
        Ok(Box::new(RaycastStreamNode {
            settings,
            apron: apron(EffectFlags::of(ctx.params)),
            pipeline,
            params,
            uniform,
            workgroup: wg,
            state: None,
            counters: Counters::default(),
        }))
    }
}

/// What the last frame did, for [`PassNode::counters`].
#[derive(Clone, Copy, Debug, Default)]
struct Counters {
    levels: u64,
    bricks: u64,
    resident: u64,
    pending: u64,
    empty: u64,
    refused: u64,
    slots: u64,
    pool_bytes: u64,
    frame: StreamCounts,
    read_total: u64,
    unreadable: u64,
    uploaded_bytes: u64,
    level_of_detail: f64,
    /// This frame read the last frame's feedback (its `requested` count means something).
    feedback_read: bool,
    /// Bit l: the frame before drew from level l.
    drawn_levels: u32,
    /// Bricks the frame before wanted and lacked.
    missing: u64,
}

/// What a frame draws: its camera, TF version and level of detail.
type View = (volgraph_core::runtime::CameraData, Option<u64>, f32);

/// Everything derived from one bound volume.
struct StreamState {
    version: Option<u64>,
    source: Arc<dyn PyramidSource>,
    cache: StreamCache,
    loader: StreamLoader,
    format: VolumeFormat,
    side: u32,
    atlas: wgpu::Texture,
    atlas_view: wgpu::TextureView,
    atlas_slots: UVec3,
    level_grid: wgpu::Buffer,
    level_scale: wgpu::Buffer,
    page_table: wgpu::Buffer,
    feedback: wgpu::Buffer,
    readback: wgpu::Buffer,
    /// Per slot: SUB_WORDS words of sub-block occupancy, and the sub-blocks' ranges they come from.
    occupancy: wgpu::Buffer,
    sub_ranges: Vec<Vec<[f32; 2]>>,
    /// A copy of the feedback was recorded last frame: read it before this one.
    readback_recorded: bool,
    /// What the frame whose feedback is in `readback` saw: camera, TF and level of detail. A
    /// frame is complete only after the feedback of a frame that saw what it sees.
    feedback_view: Option<View>,
    tf_version: Option<u64>,
    classifier: Option<OpacityClassifier>,
    read_total: u64,
    /// Bricks the source could not read (drawn empty).
    unreadable: u64,
    last_camera: Option<volgraph_core::runtime::CameraData>,
}

struct RaycastStreamNode {
    settings: StreamSettings,
    apron: u32,
    pipeline: ComputePassPipeline,
    params: wgpu::Buffer,
    uniform: wgpu::Buffer,
    workgroup: (u32, u32),
    state: Option<StreamState>,
    counters: Counters,
}

/// The raycasting uniform, its `max_steps` raised to the level-0 steps of the longest ray: the
/// grid is counted in level-0 steps however coarse the levels a ray draws from, so a 4096³
/// volume's rays need 14 000 steps where coarse runs take a few hundred samples — a smaller
/// bound would cut every ray short of the volume's back.
fn params_bytes(params: &volgraph_compiler::Params, longest_ray_voxels: f64) -> Vec<u8> {
    let mut gpu = RaycastParamsGpu::of(params);
    let needed = (longest_ray_voxels / f64::from(gpu.step_voxels)).ceil() + 2.0;
    gpu.max_steps = gpu.max_steps.max(needed.min(f64::from(u32::MAX)) as u32);
    gpu.uniform_bytes()
}

fn pass_error(ctx: &RecordContext<'_>, message: String) -> PassError {
    PassError { pass: ctx.label.to_string(), message }
}

fn texels_of(texels: &BoxTexels) -> VolumeTexels<'_> {
    match texels {
        BoxTexels::Unorm8(v) => VolumeTexels::Unorm8(v),
        BoxTexels::Unorm16(v) => VolumeTexels::Unorm16(v),
        BoxTexels::Float(v) => VolumeTexels::Float(v),
    }
}

fn storage(gpu: &Gpu, label: &str, size: u64, extra: wgpu::BufferUsages) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | extra,
        mapped_at_creation: false,
    })
}

impl RaycastStreamNode {
    fn budget(&self, ctx: &RecordContext<'_>) -> u64 {
        match self.settings.pool_mb {
            0 => ctx.frame.gpu_memory_budget.unwrap_or(DEFAULT_BUDGET_BYTES),
            mb => u64::from(mb) << 20,
        }
    }

    /// The state for the bound volume: a pyramid the application bound, else the voxels as an
    /// in-memory pyramid halving down to one brick.
    fn state_for(&mut self, ctx: &RecordContext<'_>) -> Result<(), PassError> {
        let version = ctx.input_version("volume");
        if self.state.as_ref().is_some_and(|s| s.version == version) {
            return Ok(());
        }
        self.state = None;
        let source: Arc<dyn PyramidSource> = match ctx.pyramid("volume") {
            Some(p) => p.clone(),
            None => Arc::new(InCorePyramid::new(ctx.voxels("volume")?.clone(), self.settings.brick_cells)),
        };
        let layout = StreamLayout::new(source.levels(), self.settings.brick_cells).map_err(|e| pass_error(ctx, e))?;
        let format = volume_format_for(
            ctx.gpu,
            &match source.texel_kind() {
                volgraph_accel::pyramid::TexelKind::Unorm8 => VolumeTexels::Unorm8(&[]),
                volgraph_accel::pyramid::TexelKind::Unorm16 => VolumeTexels::Unorm16(&[]),
                volgraph_accel::pyramid::TexelKind::Float => VolumeTexels::Float(&[]),
            },
        );
        let side = self.settings.brick_cells + 2 * self.apron;
        let max_dim = ctx.gpu.limits.max_texture_dimension_3d;
        if side > max_dim {
            return Err(pass_error(
                ctx,
                format!(
                    "brick_cells {} needs slots of {side}³ voxels, over this GPU's 3D texture limit {max_dim}",
                    self.settings.brick_cells
                ),
            ));
        }
        let slot_bytes = u64::from(side).pow(3) * format.bytes() as u64;
        let per_axis = (max_dim / side).min(SLOTS_PER_AXIS);
        let budget = self.budget(ctx);
        let most = (budget / slot_bytes).min(u64::from(per_axis).pow(3)).min(u64::from(layout.entries()));
        let coarsest = layout.level_entries(layout.levels.len() - 1).len() as u64;
        // The coarsest level, pinned, and room for one finer brick where there are any.
        let needed = (coarsest + 1).min(u64::from(layout.entries()));
        if most < needed {
            return Err(pass_error(
                ctx,
                format!(
                    "the brick pool's budget of {} MiB holds {most} bricks of {slot_bytes} bytes, fewer than the \
                     {needed} it needs (the coarsest level's {coarsest}, and one more where there are finer levels); raise --gpu-memory-mb (or pool_mb)",
                    budget >> 20
                ),
            ));
        }
        let edge = ((most as f64).cbrt().ceil() as u32).clamp(1, per_axis);
        let layers = (most as u32).div_ceil(edge * edge).min(per_axis);
        let atlas_slots = UVec3::new(edge, edge, layers);
        let size = atlas_slots * side;
        let atlas = ctx.gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("stream atlas"),
            size: wgpu::Extent3d { width: size.x, height: size.y, depth_or_array_layers: size.z },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D3,
            format: format.wgpu(),
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let atlas_view = atlas.create_view(&wgpu::TextureViewDescriptor::default());
        let n0 = layout.levels[0].dims.as_dvec3();
        let grids: Vec<[u32; 4]> = layout.levels.iter().map(|l| [l.grid.x, l.grid.y, l.grid.z, l.first]).collect();
        let scales: Vec<[f32; 4]> = layout
            .levels
            .iter()
            .map(|l| {
                let s = n0 / l.factor;
                [s.x as f32, s.y as f32, s.z as f32, l.factor.min_element() as f32]
            })
            .collect();
        let level_grid = storage(ctx.gpu, "stream level grids", 16 * grids.len() as u64, wgpu::BufferUsages::empty());
        let level_scale =
            storage(ctx.gpu, "stream level scales", 16 * scales.len() as u64, wgpu::BufferUsages::empty());
        ctx.write_buffer(&level_grid, 0, bytemuck::cast_slice(&grids));
        ctx.write_buffer(&level_scale, 0, bytemuck::cast_slice(&scales));
        let entries = u64::from(layout.entries());
        let page_table = storage(ctx.gpu, "stream page table", 4 * entries, wgpu::BufferUsages::empty());
        let feedback = storage(ctx.gpu, "stream feedback", 4 * entries, wgpu::BufferUsages::COPY_SRC);
        let readback = ctx.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("stream feedback readback"),
            size: (4 * entries).max(16),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let slot_count = u64::from(atlas_slots.element_product());
        let occupancy =
            storage(ctx.gpu, "stream occupancy", 4 * SUB_WORDS as u64 * slot_count, wgpu::BufferUsages::empty());
        let readers = match self.settings.readers {
            0 => std::thread::available_parallelism().map_or(2, |n| n.get()).max(2),
            n => n as usize,
        };
        self.state = Some(StreamState {
            version,
            loader: StreamLoader::new(source.clone(), readers),
            source,
            cache: StreamCache::new(layout, atlas_slots),
            format,
            side,
            atlas,
            atlas_view,
            atlas_slots,
            level_grid,
            level_scale,
            page_table,
            feedback,
            readback,
            occupancy,
            sub_ranges: vec![Vec::new(); slot_count as usize],
            readback_recorded: false,
            feedback_view: None,
            tf_version: None,
            classifier: None,
            read_total: 0,
            unreadable: 0,
            last_camera: None,
        });
        Ok(())
    }
}

impl StreamState {
    /// The request for page-table entry `entry`.
    fn request(&self, entry: u32, apron: u32) -> BrickRequest {
        let layout = self.cache.layout();
        let (level, brick) = layout.locate(entry);
        let (lo, dims) = layout.slot_box(brick, apron);
        BrickRequest { entry, level, lo, dims }
    }

    /// Re-classifies every brick whose range is known for a new transfer function.
    fn classify(&mut self, ctx: &RecordContext<'_>, lut: &[[f32; 4]], apron: u32) -> Result<(), String> {
        let classifier = OpacityClassifier::new(lut).map_err(|e| e.to_string())?;
        let source = self.source.clone();
        let layout = self.cache.layout().clone();
        self.cache.classify(
            |lo, hi| classifier.is_visible(lo, hi),
            |e| {
                let (level, brick) = layout.locate(e);
                let (lo, dims) = layout.slot_box(brick, apron);
                source.box_range(level, lo, lo + dims.as_ivec3())
            },
        );
        // Resident bricks keep their slots; their sub-blocks are classified anew.
        let words: Vec<u32> =
            self.sub_ranges.iter().flat_map(|r| occupancy_words(r, |lo, hi| classifier.is_visible(lo, hi))).collect();
        ctx.write_buffer(&self.occupancy, 0, bytemuck::cast_slice(&words));
        self.classifier = Some(classifier);
        Ok(())
    }

    /// Places brick reads: the slot's voxels uploaded and its word set (transparent or
    /// unreadable bricks take no slot).
    fn place(&mut self, ctx: &RecordContext<'_>, reads: Vec<BrickRead>, counts: &mut StreamCounts) -> u64 {
        let mut bytes = 0;
        for read in reads {
            self.read_total += 1;
            let range = read.texels.as_ref().ok().and_then(BoxTexels::range);
            // The source keeps what it could not read for the application to report
            // (`PyramidSource::notes`); the brick is drawn empty.
            self.unreadable += u64::from(read.texels.is_err());
            let visible = range.is_some_and(|(lo, hi)| self.classifier.as_ref().is_none_or(|c| c.is_visible(lo, hi)));
            let Some(slot) = self.cache.arrived(read.request.entry, range, visible, counts) else { continue };
            let Ok(texels) = &read.texels else { continue };
            let data = texel_bytes(&texels_of(texels), self.format);
            let brick_cells = self.cache.layout().brick_cells;
            let ranges = sub_block_ranges(|i| texels.value(i), brick_cells, (self.side - brick_cells) / 2);
            let words =
                occupancy_words(&ranges, |lo, hi| self.classifier.as_ref().is_none_or(|c| c.is_visible(lo, hi)));
            ctx.write_buffer(&self.occupancy, 4 * SUB_WORDS as u64 * u64::from(slot), bytemuck::cast_slice(&words));
            self.sub_ranges[slot as usize] = ranges;
            let at = slot_coord(slot, self.atlas_slots) * self.side;
            ctx.gpu.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &self.atlas,
                    mip_level: 0,
                    origin: wgpu::Origin3d { x: at.x, y: at.y, z: at.z },
                    aspect: wgpu::TextureAspect::All,
                },
                &data,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.side * self.format.bytes() as u32),
                    rows_per_image: Some(self.side),
                },
                wgpu::Extent3d { width: self.side, height: self.side, depth_or_array_layers: self.side },
            );
            bytes += data.len() as u64;
        }
        bytes
    }

    /// Reads every brick of the coarsest level the page table has no word for, here and now:
    /// what a ray falls back to must be there.
    fn ensure_coarsest(&mut self, ctx: &RecordContext<'_>, apron: u32, counts: &mut StreamCounts) -> u64 {
        let layout = self.cache.layout();
        let last = layout.levels.len() - 1;
        let missing: Vec<u32> = layout.level_entries(last).filter(|e| self.cache.table()[*e as usize] == 0).collect();
        if missing.is_empty() {
            return 0;
        }
        let reads: Vec<BrickRead> = missing
            .into_iter()
            .map(|e| {
                let request = self.request(e, apron);
                BrickRead { request, texels: self.source.read_box(request.level, request.lo, request.dims) }
            })
            .collect();
        self.place(ctx, reads, counts)
    }

    /// Last frame's feedback, read back (the frame is done: this waits for no disk).
    fn read_feedback(&mut self, gpu: &Gpu) -> Option<Vec<u32>> {
        if !std::mem::replace(&mut self.readback_recorded, false) {
            return None;
        }
        let slice = self.readback.slice(..);
        let (tx, rx): (_, Receiver<Result<(), wgpu::BufferAsyncError>>) = channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        gpu.wait_idle();
        let flags = match rx.recv() {
            Ok(Ok(())) => slice.get_mapped_range().ok().map(|view| bytemuck::pod_collect_to_vec::<u8, u32>(&view)),
            _ => None,
        };
        self.readback.unmap();
        flags
    }
}

impl PassNode for RaycastStreamNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        self.state_for(ctx)?;
        let tf_version = ctx.input_version("tf");
        let lut = ctx.table("tf")?.clone();
        let apron = self.apron;
        let settings = self.settings;
        let Some(state) = self.state.as_mut() else { return Ok(()) };
        let mut counts = StreamCounts::default();
        if state.tf_version != tf_version || state.classifier.is_none() {
            state.classify(ctx, &lut, apron).map_err(|e| pass_error(ctx, e))?;
            state.tf_version = tf_version;
        }
        let mut uploaded = state.ensure_coarsest(ctx, apron, &mut counts);

        // The camera in level-0 voxels, and whether it moved since the last frame.
        let camera = ctx.frame.camera;
        let moving = state.last_camera.is_some_and(|c| c != camera);
        if moving {
            state.cache.view_changed();
        }
        state.last_camera = Some(camera);
        let half = ctx.frame.volume.map_or(DVec3::splat(0.5), |v| v.half_extent);
        let n0 = state.cache.layout().levels[0].dims.as_dvec3();
        let eye_voxels = (camera.eye / (2.0 * half) + DVec3::splat(0.5)) * n0;

        // Last frame's requests to the readers; what they finished into the pool.
        let lod = if moving { settings.lod_moving } else { settings.lod };
        let view: View = (camera, tf_version, lod);
        let feedback = state.read_feedback(ctx.gpu);
        let feedback_read = feedback.is_some() && state.feedback_view == Some(view);
        if let Some(flags) = feedback {
            let wanted = state.cache.feedback(&flags, eye_voxels);
            counts.requested = wanted.len() as u64;
            let requests: Vec<BrickRequest> = wanted.iter().map(|e| state.request(*e, apron)).collect();
            state.loader.enqueue(requests);
        }
        for entry in state.loader.take_dropped() {
            state.cache.dropped(entry);
        }
        let finished = state.loader.take_finished(settings.uploads_per_frame as usize);
        uploaded += state.place(ctx, finished, &mut counts);
        if state.cache.take_dirty() {
            ctx.write_buffer(&state.page_table, 0, bytemuck::cast_slice(state.cache.table()));
        }

        let levels = state.cache.layout().levels.len() as u32;
        let atlas = (state.atlas_slots * state.side).as_vec3();
        let uniform = StreamParams {
            brick: [settings.brick_cells, apron, state.side, levels],
            atlas: [atlas.x, atlas.y, atlas.z, 0.0],
            lod: [lod, 0.0, 0.0, 0.0],
        };
        ctx.write_buffer(&self.uniform, 0, &uniform.uniform_bytes());
        let longest = ctx.frame.volume.map_or(0.0, |v| v.longest_ray_voxels());
        ctx.write_buffer(&self.params, 0, &params_bytes(ctx.params, longest));
        ctx.encoder.clear_buffer(&state.feedback, 0, None);
        let extra = [
            ("params", self.params.as_entire_binding()),
            ("stream", self.uniform.as_entire_binding()),
            ("level_grid", state.level_grid.as_entire_binding()),
            ("level_scale", state.level_scale.as_entire_binding()),
            ("page_table", state.page_table.as_entire_binding()),
            ("feedback", state.feedback.as_entire_binding()),
            ("occupancy", state.occupancy.as_entire_binding()),
            ("volume", wgpu::BindingResource::TextureView(&state.atlas_view)),
        ];
        ctx.dispatch_over(&self.pipeline, &extra, "color", self.workgroup)?;
        let state = self.state.as_mut().expect("set above");
        ctx.encoder.copy_buffer_to_buffer(&state.feedback, 0, &state.readback, 0, state.feedback.size());
        state.readback_recorded = true;
        state.feedback_view = Some(view);

        let cache = &state.cache;
        self.counters = Counters {
            levels: u64::from(levels),
            bricks: u64::from(cache.layout().entries()),
            resident: cache.resident() as u64,
            pending: cache.pending() as u64,
            empty: cache.empty() as u64,
            refused: cache.refused() as u64,
            slots: u64::from(cache.slots()),
            pool_bytes: u64::from(cache.slots()) * u64::from(state.side).pow(3) * state.format.bytes() as u64,
            frame: counts,
            read_total: state.read_total,
            unreadable: state.unreadable,
            uploaded_bytes: uploaded,
            level_of_detail: f64::from(lod),
            feedback_read,
            drawn_levels: cache.drawn_levels(),
            missing: cache.missing() as u64,
        };
        Ok(())
    }

    fn wait_for_background(&self, timeout: std::time::Duration) {
        if let Some(state) = &self.state {
            state.loader.wait_idle(timeout);
        }
    }

    fn update_params(&mut self, gpu: &Gpu, params: &volgraph_compiler::Params) {
        gpu.queue.write_buffer(&self.params, 0, &RaycastParamsGpu::of(params).uniform_bytes());
    }

    fn counters(&self) -> Vec<(&'static str, f64)> {
        let c = &self.counters;
        vec![
            ("levels", c.levels as f64),
            ("bricks", c.bricks as f64),
            ("resident_bricks", c.resident as f64),
            ("pending_bricks", c.pending as f64),
            ("empty_bricks", c.empty as f64),
            ("refused_bricks", c.refused as f64),
            ("requested_bricks", c.frame.requested as f64),
            ("placed_bricks", c.frame.placed as f64),
            ("read_bricks", c.read_total as f64),
            ("unreadable_bricks", c.unreadable as f64),
            ("pool_slots", c.slots as f64),
            ("pool_bytes", c.pool_bytes as f64),
            ("uploaded_bytes", c.uploaded_bytes as f64),
            ("level_of_detail", c.level_of_detail),
            ("feedback_read", f64::from(u8::from(c.feedback_read))),
            ("drawn_levels", f64::from(c.drawn_levels)),
            ("missing_bricks", c.missing as f64),
        ]
    }
}
