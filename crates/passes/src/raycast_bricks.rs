//! `raycast_bricks`: DVR through a GPU brick pool with per-brick octrees, after Ruijters &
//! Vilanova 2006, as one compute pass that walks the bricks itself.
//!
//! - §5 **bricks**: the volume is cut into bricks of `brick_cells`³ cells that keep the voxels
//!   of their cells' corners (the one-voxel overlap trilinear samples inside a brick need) and
//!   an apron of more voxels on every side — one, two with shading, three with tricubic, four with both — so that
//!   every filter tap near a brick face (trilinear, gradients, the B-spline) blends exactly the
//!   voxels the whole volume would and images have no seams. Non-empty bricks (for the current
//!   TF) live in a 3D atlas texture, `brick_cells + 1 + 2·apron` voxels per side per slot; empty bricks
//!   are never uploaded. The pool is bounded by a memory budget (`pool_mb`, else the runtime's
//!   `--gpu-memory-mb`, else 2 GiB bounded by the 3D texture limit); a frame streams the bricks it needs
//!   front to back and evicts the least recently used ([`crate::brick_pool`]). A volume larger
//!   than the budget or the 3D texture limit renders in batches: the ray colour carries over.
//! - §7 **octrees**: with `node_cells > 0`, each brick's octree (leaves of `node_cells`³ cells,
//!   the paper's node-size limit) picks the boxes to draw by the ratio rule (`r = 0` skip,
//!   `r ≥ ratio` draw whole, else descend). The boxes are rasterized into the volume's grid of
//!   leaves and its complement into Chebyshev leap distances ([`volgraph_accel::chebyshev`]):
//!   a ray leaves the largest cube of leaves no box covers in one step — the octree's empty
//!   nodes, and empty bricks, as one lookup (without an octree the leaves are the bricks).
//!   Where it stands in a drawn leaf it marches one run: through the cube of drawn leaves
//!   around it ([`volgraph_accel::brick_leaves::leaf_words`]) and on through its brick, up to
//!   `CHECK_EVERY` samples in all, so a thin vessel or a dense brick does not cost a round of
//!   leaps per leaf.
//! - **termination**: a ray stops at `threshold` and skips the bricks behind it (per-brick
//!   early ray termination: with `threshold < 1` a saturated pixel costs nothing in later
//!   batches either).
//!
//! Samples are those of every raycaster (`common/ray_box.wgsl`: k + 0.5 steps from the analytic box entry, same
//! compositing) and so are the scene effects (shading, pre-integration, tricubic, jitter: the
//! shared march's; a leaf's value range takes in a voxel more with tricubic or pre-integration), so the image equals the single-texture raycast up to rounding
//! (crates/passes/tests/ruijters_2006.rs). A TF change re-classifies bricks and octrees
//! (CPU, [`volgraph_accel::octree`]) and uploads only bricks not yet resident.
//! The CPU side (slot words, leaf words, rank slabs) is [`volgraph_accel::brick_leaves`]; the
//! atlas texture and its uploads are `raycast_bricks/atlas.rs`. Shader: `shaders/raycast_bricks.wgsl`.

use crate::effects::effect_block;
use crate::raycast_params::sampling_block;
use std::sync::Arc;
use std::time::Instant;
use volgraph_compiler::block::{OnChange, ParamBlock};

use glam::{DVec3, UVec3};
use volgraph_accel::brick_leaves::{SLOTS_PER_AXIS, classify_leaves, leaf_grid, owns, slot_coord, slot_word};
use volgraph_accel::bricks::{BrickLayout, ViewPoint};
use volgraph_accel::classify::OpacityClassifier;
use volgraph_accel::octree::{OctreeHierarchy, OctreeVisibility};
use volgraph_accel::volume::Volume;
use volgraph_compiler::{Params, PassDecl, PortKind, PortSpec, ShaderUse, TargetFormat};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::upload::VolumeFormat;
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{
    ComputePassPipeline, ComputePipelineSpec, CreateContext, Gpu, PassError, RecordContext, volume_texture_format,
};
#[cfg(feature = "gpu")]
use volgraph_core::{PassNode, PassPlugin};

#[cfg(feature = "gpu")]
use crate::brick_pool::{Batch, BrickPool};
#[cfg(feature = "gpu")]
use crate::effects::EffectState;
use crate::effects::{EffectFlags, effect_shader_uses};
use crate::raycast_params::{RaycastParamsGpu, SampleLoopChoice, Sampling, Shading, Termination, Workgroup};

#[cfg(feature = "gpu")]
mod atlas;
#[cfg(feature = "gpu")]
use atlas::Atlas;

/// The plugin.
pub struct RaycastBricks;

volgraph_compiler::pass_params! {
    /// The brick pass's own parameters, declared once (the sampling, termination and workgroup
    /// blocks are the other raycasters': `raycast_params`).
    pub struct BrickSettings {
        brick_cells: u32 = 32, 2..=512, "cells per brick side (§5; the paper's best is 64)";
        node_cells: u32 = 8, 0..=512,
            "octree node-size limit in cells (§7; 0: no octree, a brick is drawn whole when it is not empty)";
        ratio: f32 = 0.5, 0.0..=1.0,
            "octree ratio rule: a node whose visible-cell ratio reaches this is drawn whole, below it split (§7)";
        pool_mb: u32 = 0, 0..=1048576,
            "brick pool budget in MiB (0: the runtime's --gpu-memory-mb, else 2 GiB bounded by the 3D texture limit)";
        ranks: u32 = 1, 1..=4096,
            "sort-last rendering (docs/scaling.md): the bricks are split into this many slabs of the brick grid along its longest axis, one per rank";
        rank: u32 = 0, 0..=4095, "with ranks > 1: the slab of bricks this pass draws (0-based)";
    }
}

/// The pool's budget when neither the pass nor the runtime sets one: 2 GiB, within what the
/// atlas's 3D texture limit allows.
const DEFAULT_BUDGET_BYTES: u64 = 2 << 30;

volgraph_compiler::pass_params! {
    /// The `bricks` block of `shaders/raycast_bricks.wgsl` (which imports it): the pool's state,
    /// written by the node each frame.
    struct BrickParams {
        grid: [u32; 4] = computed, "Bricks per axis (xyz); w = cells per brick side.";
        slot_side: [u32; 4] = computed,
            "Voxels per slot and axis (xyz): brick_cells + 1 + 2·apron (voxel lo - apron first), fewer on an axis \
             thinner than a brick; w = the apron: voxels kept on every side of the brick's own, so that every filter \
             tap near a face reads what the whole volume holds (1: trilinear samples; +1 for shading's central \
             differences, +2 for tricubic reconstruction).";
        leaves: [u32; 4] = computed, "x = cells per leaf side, y = leaves per brick side.";
        leaf_grid: [u32; 4] = computed, "Leaves per axis over the whole volume (xyz).";
        atlas: [f32; 4] = computed, "Atlas size in texels (xyz).";
    }
}

impl BrickParams {
    /// Before the pool is sized.
    const EMPTY: Self = Self { grid: [0; 4], slot_side: [0; 4], leaves: [0; 4], leaf_grid: [0; 4], atlas: [0.0; 4] };
}

impl PassDecl for RaycastBricks {
    fn honours_volume_window(&self) -> bool {
        true
    }

    fn kind(&self) -> &'static str {
        "raycast_bricks"
    }

    fn scene_effects(&self) -> &'static [&'static str] {
        &crate::effects::SCENE_EFFECTS
    }

    fn summary(&self) -> &'static str {
        "compute DVR through a GPU brick pool (LRU, memory budget, out of core) with per-brick octrees and early \
         ray termination (Ruijters & Vilanova 2006 §5–7)"
    }

    fn blocks(&self) -> Vec<ParamBlock> {
        // The raycasting values are a uniform; the brick settings shape the pool and the
        // leaves, the workgroup and the sample loop the pipeline.
        vec![
            sampling_block(OnChange::InPlace),
            Termination::block(OnChange::InPlace),
            effect_block(),
            crate::fusion::fusion_block(),
            // The headlight's coefficients, which the shading effect reads.
            Shading::block(OnChange::InPlace),
            BrickSettings::block(OnChange::Rebuild),
            Workgroup::block(OnChange::Rebuild),
            SampleLoopChoice::rebuild_block(),
        ]
    }

    fn uses_gpu_memory_budget(&self) -> bool {
        true
    }

    fn ports(&self, params: &Params) -> Vec<PortSpec> {
        let mut ports =
            vec![PortSpec::read("volume", PortKind::VolumeVoxels), PortSpec::read("tf", PortKind::TransferFunction)];
        ports.extend(crate::fusion::FusionSettings::of(params).ports());
        ports.push(PortSpec::write("color", PortKind::target(&[TargetFormat::Rgba16Float, TargetFormat::Rgba32Float])));
        ports
    }

    fn shaders(&self, params: &Params) -> Vec<ShaderUse> {
        [vec![march_shader(params)], effect_shader_uses(params, false)].concat()
    }
}

/// The brick march's entry point and what it binds, declared once for `shaders()` and `create`.
fn march_shader(params: &Params) -> ShaderUse {
    crate::fusion::with_fusion_uniform(
        ShaderUse::new("raycast_bricks.wgsl", "cs_main")
            .binds(&[
                "table",
                "leaf_words",
                "acc",
                "volume",
                "preintegrated",
                "light_volume",
                "label_quads",
                "label_cubes",
            ])
            .uniform(RaycastParamsGpu::bound("params"))
            .uniform(brick_layout()),
        params,
    )
}

/// The `bricks` block, checked against the shader's struct when the graph is planned. The
/// node writes it per frame (the pool's state).
fn brick_layout() -> volgraph_compiler::UniformLayout {
    BrickParams::bound_as_with("bricks", Vec::new(), |_| BrickParams::EMPTY.uniform_bytes())
}

#[cfg(feature = "gpu")]
impl PassPlugin for RaycastBricks {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let settings = BrickSettings::from_params(ctx.params);
        let wg = Workgroup::checked_size(ctx)?;
        let defines = SampleLoopChoice::with_gpu_defines(
            [self.shader_defines(ctx.params), crate::shared::color_precision_defines(ctx)].concat(),
            ctx.params,
            ctx.gpu,
        );
        let pipeline = ctx.compute_pipeline(&ComputePipelineSpec {
            defines: &defines,
            constants: &[("WORKGROUP_X", wg.0 as f64), ("WORKGROUP_Y", wg.1 as f64)],
            ..ComputePipelineSpec::of(&march_shader(ctx.params))
        })?;
        let params = ctx.uniform_from_bytes("params", &RaycastParamsGpu::of(ctx.params).uniform_bytes());
        let uniform = ctx.uniform_from_bytes("bricks", &BrickParams::EMPTY.uniform_bytes());
        let brick_cells = settings.brick_cells;
        let node_cells = match settings.node_cells {
            0 => brick_cells,
            n => n.min(brick_cells),
        };
        if !brick_cells.is_multiple_of(node_cells) {
            return Err(PassError {
                pass: ctx.pass_id.to_string(),
                message: format!(
                    "node_cells {node_cells} does not divide brick_cells {brick_cells}: octree leaves must tile a \
                     brick; use a power of two for both (e.g. 8 and 64)"
                ),
            });
        }
        let (ranks, rank) = (settings.ranks, settings.rank);
        if rank >= ranks {
            return Err(PassError {
                pass: ctx.pass_id.to_string(),
                message: format!("rank {rank} is not below ranks {ranks}; ranks are numbered 0..ranks"),
            });
        }
        let effects = EffectState::new(ctx, false)?;
        // Only the volume's visible bricks are marched (and a label map as the volume would be
        // read through the atlas, voxel by voxel of the volume).
        let fusion =
            crate::fusion::FusionState::bounded_by_the_scan(ctx, self.kind(), "it marches only the visible bricks of")?;
        // Its light volume is made on the CPU from the scan's opacity: the same as the tinted
        // scan's, not the scan's inside the labels.
        let flags = EffectFlags::of(ctx.params);
        if (flags.shadows || flags.ambient_occlusion)
            && crate::fusion::FusionSettings::of(ctx.params).combine() == Some(volgraph_accel::fusion::Combine::Inside)
        {
            return Err(PassError {
                pass: ctx.pass_id.to_string(),
                message: "shadows and ambient occlusion of the scan inside its labels are not made by the brick pool \
                          (its light volume is the scan's alone): use fusion \"tint\" here, or raycast_compute \
                          (graphs/multi/ct_inside_labels.ron)"
                    .to_string(),
            });
        }
        Ok(Box::new(RaycastBricksNode {
            effects,
            fusion,
            step_voxels: Sampling::from_params(ctx.params).step_voxels,
            effects_on: EffectFlags::of(ctx.params),
            ranks: (rank, ranks),
            pipeline,
            params,
            uniform,
            workgroup: wg,
            brick_cells,
            node_cells,
            ratio: settings.ratio,
            pool_mb: settings.pool_mb as u64,
            volume: None,
            acc: None,
            tables: None,
            counters: FrameCounters::default(),
        }))
    }
}

/// What the last frame did, for [`PassNode::counters`].
#[derive(Clone, Copy, Debug, Default)]
struct FrameCounters {
    uploaded_bytes: u64,
    uploaded_bricks: u64,
    batches: u64,
    visible_bricks: u64,
    bricks: u64,
    slots: u64,
    resident: u64,
    pool_bytes: u64,
    classify_ms: f64,
    /// Fraction of the visible bricks' octree leaves that a box to draw covers.
    drawn_leaves: f64,
}

#[cfg(feature = "gpu")]
/// Everything derived from one bound volume.
struct VolumeState {
    version: u64,
    voxels: Arc<Volume>,
    layout: BrickLayout,
    octree: OctreeHierarchy,
    format: VolumeFormat,
    /// Voxels per slot and axis: `brick_cells + 1 + 2·apron`, or fewer on an axis thinner than
    /// a brick (a 1-voxel-thick slab stores 4 layers per brick, not 35, with apron 1).
    side: UVec3,
    /// Voxels kept on every side of a brick's own ([`apron`]).
    apron: u32,
    /// Slots per atlas row and column (fixed), and the most layers the device allows.
    slots_xy: (u32, u32),
    max_layers: u32,
    /// TF version last classified with.
    tf_version: Option<u64>,
    visibility: Option<OctreeVisibility>,
    /// Per brick: visible under the TF.
    visible: Vec<bool>,
    /// Leaves per axis over the whole volume.
    leaf_grid: UVec3,
    leaf_buffer: Option<wgpu::Buffer>,
    /// Fraction of the visible bricks' leaves drawn (the last classification).
    drawn_leaves: f64,
    atlas: Option<Atlas>,
    pool: BrickPool,
    /// Budget in bytes the pool was sized under.
    budget: u64,
}

/// Voxels a slot keeps on every side of its brick's own: what the filter taps near a brick face
/// read beyond it. A trilinear sample reaches one voxel (a border brick's samples run half a
/// voxel past its corner voxels, to the volume's face); shading's central differences one more,
/// the tricubic B-spline (its 4³ support) two more.
fn apron(effects: EffectFlags) -> u32 {
    1 + u32::from(effects.shading) + 2 * u32::from(effects.tricubic)
}

/// Voxels beyond a leaf's cells its value range takes in (`OctreeHierarchy::build_with_apron`):
/// the tricubic B-spline blends a cell's corners and one more voxel on every side, and a
/// pre-integrated segment runs between two samples less than a voxel apart, whose values both
/// lie in the range of either leaf grown by one voxel — so a leaf is empty only where no
/// reconstruction or segment through it can be visible.
fn range_apron(effects: EffectFlags) -> u32 {
    u32::from(effects.tricubic || effects.preintegration)
}

#[cfg(feature = "gpu")]
struct RaycastBricksNode {
    /// The pre-integration table when that effect is on.
    effects: EffectState,
    /// Several volumes: the fusion uniform and a label map's quads.
    fusion: crate::fusion::FusionState,
    step_voxels: f64,
    /// The effects compiled in ([`apron`], [`range_apron`]).
    effects_on: EffectFlags,
    pipeline: ComputePassPipeline,
    params: wgpu::Buffer,
    uniform: wgpu::Buffer,
    workgroup: (u32, u32),
    brick_cells: u32,
    node_cells: u32,
    ratio: f32,
    pool_mb: u64,
    /// (this rank, ranks): the slab of the brick grid this pass draws (sort-last).
    ranks: (u32, u32),
    volume: Option<VolumeState>,
    /// Per-pixel colour carried between batches, and the viewport it is sized for.
    acc: Option<(wgpu::Buffer, (u32, u32))>,
    /// Per-batch brick tables, and the stride and batch count they hold.
    tables: Option<(wgpu::Buffer, u64, usize)>,
    counters: FrameCounters,
}

#[cfg(feature = "gpu")]
fn pass_error(ctx: &RecordContext<'_>, message: String) -> PassError {
    PassError { pass: ctx.label.to_string(), message }
}

#[cfg(feature = "gpu")]
impl VolumeState {
    fn new(
        ctx: &RecordContext<'_>,
        voxels: Arc<Volume>,
        version: u64,
        brick_cells: u32,
        node_cells: u32,
        apron: u32,
        range_apron: u32,
    ) -> Result<Self, PassError> {
        let layout = BrickLayout::new(voxels.dims, brick_cells, 1).map_err(|e| pass_error(ctx, e.to_string()))?;
        let octree = OctreeHierarchy::build_with_apron(&voxels, &layout, node_cells, range_apron)
            .map_err(|e| pass_error(ctx, e.to_string()))?;
        // The brick's voxels and `apron` more on every side (clamped to the volume like the
        // sampler): a filter tap at a brick face blends exactly what it would in the whole
        // volume, even where the hardware's fixed-point weights give the next texel 1/256.
        // An axis with fewer cells than a brick holds one brick of that many cells.
        let cells = volgraph_accel::bricks::cell_dims(voxels.dims);
        let side = cells.min(UVec3::splat(brick_cells)) + 1 + 2 * apron;
        let max_dim = ctx.gpu.limits.max_texture_dimension_3d;
        if side.max_element() > max_dim {
            return Err(pass_error(
                ctx,
                format!(
                    "brick_cells {brick_cells} needs slots of {}x{}x{} voxels, over this GPU's 3D texture limit \
                     {max_dim}; lower brick_cells",
                    side.x, side.y, side.z
                ),
            ));
        }
        // At most SLOTS_PER_AXIS slots per axis: the table's slot words have 10 bits per axis.
        let per_axis = (UVec3::splat(max_dim) / side).min(UVec3::splat(SLOTS_PER_AXIS));
        let cube = (layout.brick_count() as f64).cbrt().ceil() as u32;
        let row = (cube.clamp(1, per_axis.x), cube.clamp(1, per_axis.y));
        let leaf_grid = leaf_grid(voxels.dims, node_cells);
        Ok(Self {
            version,
            format: volume_texture_format(ctx.gpu, &voxels),
            voxels,
            pool: BrickPool::new(0, layout.brick_count()),
            layout,
            octree,
            side,
            apron,
            slots_xy: row,
            max_layers: per_axis.z,
            tf_version: None,
            visibility: None,
            visible: Vec::new(),
            leaf_grid,
            leaf_buffer: None,
            drawn_leaves: 0.0,
            atlas: None,
            budget: 0,
        })
    }

    fn slot_bytes(&self) -> u64 {
        self.side.as_u64vec3().element_product() * self.format.bytes() as u64
    }

    /// Re-classifies bricks and octree leaves for a new TF (§7: only the TF-dependent part)
    /// and uploads the leaves' words ([`volgraph_accel::brick_leaves::leaf_words`]); returns the time it took in ms.
    fn classify(&mut self, ctx: &RecordContext<'_>, lut: &[[f32; 4]], ratio: f32) -> Result<f64, PassError> {
        let started = Instant::now();
        let classifier = OpacityClassifier::new(lut).map_err(|e| pass_error(ctx, e.to_string()))?;
        let visibility = match self.visibility.take() {
            Some(mut v) => {
                self.octree.classify_into(&classifier, &mut v);
                v
            }
            None => self.octree.classify(&classifier),
        };
        let leaves = classify_leaves(&self.octree, &visibility, &self.layout, self.leaf_grid, ratio);
        self.visibility = Some(visibility);
        self.visible = leaves.visible;
        self.drawn_leaves = leaves.drawn_fraction;
        let bits = leaves.words;
        let bytes: &[u8] = bytemuck::cast_slice(&bits);
        let size = (bytes.len() as u64).max(4);
        if self.leaf_buffer.as_ref().is_none_or(|b| b.size() != size) {
            self.leaf_buffer = Some(ctx.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("leaf words"),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }));
        }
        if let Some(buffer) = &self.leaf_buffer
            && !bytes.is_empty()
        {
            ctx.write_buffer(buffer, 0, bytes);
        }
        Ok(started.elapsed().as_secs_f64() * 1e3)
    }
}

#[cfg(feature = "gpu")]
impl RaycastBricksNode {
    fn budget(&self, ctx: &RecordContext<'_>) -> u64 {
        match self.pool_mb {
            0 => ctx.frame.gpu_memory_budget.unwrap_or(DEFAULT_BUDGET_BYTES),
            mb => mb << 20,
        }
    }

    /// The per-batch tables in one buffer, one region per batch at a stride the storage-offset
    /// alignment allows: a header word, then per brick its [`slot_word`] (0: not in this batch).
    fn write_tables(&mut self, ctx: &RecordContext<'_>, batches: &[Batch], bricks: usize, slots: UVec3) -> u64 {
        let align = ctx.gpu.limits.min_storage_buffer_offset_alignment as u64;
        let stride = (4 * (1 + bricks as u64)).div_ceil(align) * align;
        let count = batches.len().max(1);
        if self.tables.as_ref().is_none_or(|(b, s, n)| *s != stride || *n < count || b.size() < stride * count as u64) {
            let buffer = ctx.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("brick tables"),
                size: stride * count as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            self.tables = Some((buffer, stride, count));
        }
        let mut data = vec![0u32; (stride / 4) as usize * count];
        data[0] = 1;
        for (i, batch) in batches.iter().enumerate() {
            let base = i * (stride / 4) as usize;
            data[base] = u32::from(i == 0);
            for (brick, slot) in &batch.bricks {
                data[base + 1 + *brick as usize] = slot_word(slot_coord(*slot, slots));
            }
        }
        if let Some((buffer, _, _)) = &self.tables {
            ctx.write_buffer(buffer, 0, bytemuck::cast_slice(&data));
        }
        stride
    }
}

#[cfg(feature = "gpu")]
impl PassNode for RaycastBricksNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let voxels = ctx.voxels("volume")?.clone();
        let version = ctx.input_version("volume").unwrap_or(0);
        if self.volume.as_ref().is_none_or(|v| v.version != version) {
            let (apron, range_apron) = (apron(self.effects_on), range_apron(self.effects_on));
            self.volume =
                Some(VolumeState::new(ctx, voxels, version, self.brick_cells, self.node_cells, apron, range_apron)?);
        }
        self.fusion.update(ctx)?;
        self.effects.update(ctx, &self.params, self.step_voxels, &self.fusion.bindings())?;
        let tf_version = ctx.input_version("tf");
        let lut = ctx.table("tf")?.clone();
        let budget = self.budget(ctx);
        let Some(state) = self.volume.as_mut() else { return Ok(()) };
        let mut counters = FrameCounters { classify_ms: self.counters.classify_ms, ..Default::default() };
        if state.tf_version != tf_version || state.visibility.is_none() {
            counters.classify_ms = state.classify(ctx, &lut, self.ratio)?;
            state.tf_version = tf_version;
        }
        state.size_pool(ctx, budget)?;

        // Front to back from the eye (texture space), visible bricks only.
        let camera = &ctx.frame.camera;
        let half = ctx.frame.volume.map_or(DVec3::splat(0.5), |v| v.half_extent);
        let eye = camera.eye / (2.0 * half) + DVec3::splat(0.5);
        let order: Vec<u32> = state
            .layout
            .front_to_back(ViewPoint::Eye(eye))
            .into_iter()
            .filter(|b| state.visible[*b as usize] && owns(&state.layout, *b, self.ranks))
            .collect();
        let batches = state.pool.plan_frame(&order);
        let bricks = state.layout.brick_count();

        let atlas_slots = state.atlas.as_ref().map_or(UVec3::ONE, |a| a.slots);
        let atlas_size = (atlas_slots * state.side).as_vec3();
        let grid = state.layout.grid_dims();
        let uniform = BrickParams {
            grid: [grid.x, grid.y, grid.z, self.brick_cells],
            slot_side: [state.side.x, state.side.y, state.side.z, state.apron],
            leaves: [state.octree.min_node_cells(), self.brick_cells / state.octree.min_node_cells(), 0, 0],
            leaf_grid: [state.leaf_grid.x, state.leaf_grid.y, state.leaf_grid.z, 0],
            atlas: [atlas_size.x, atlas_size.y, atlas_size.z, 0.0],
        };
        ctx.write_buffer(&self.uniform, 0, &uniform.uniform_bytes());

        let (w, h) = ctx.extent("color");
        if self.acc.as_ref().is_none_or(|(_, size)| *size != (w, h)) {
            let buffer = ctx.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("brick ray colour"),
                size: 16 * w.max(1) as u64 * h.max(1) as u64,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            });
            self.acc = Some((buffer, (w, h)));
        }
        let stride = self.write_tables(ctx, &batches, bricks, atlas_slots);
        let state = self.volume.as_ref().expect("set above");
        let (Some(atlas), Some(leaf_buffer), Some((acc, _)), Some((tables, _, _))) =
            (&state.atlas, &state.leaf_buffer, &self.acc, &self.tables)
        else {
            return Err(pass_error(ctx, "brick pool not ready".to_string()));
        };
        for i in 0..batches.len().max(1) {
            if let Some(batch) = batches.get(i) {
                counters.uploaded_bytes += state.upload(ctx, &batch.uploads)?;
                counters.uploaded_bricks += batch.uploads.len() as u64;
            }
            let table = wgpu::BufferBinding {
                buffer: tables,
                offset: i as u64 * stride,
                size: std::num::NonZeroU64::new(stride),
            };
            let mut extra = vec![
                ("params", self.params.as_entire_binding()),
                ("bricks", self.uniform.as_entire_binding()),
                ("table", wgpu::BindingResource::Buffer(table)),
                ("leaf_words", leaf_buffer.as_entire_binding()),
                ("acc", acc.as_entire_binding()),
                ("volume", wgpu::BindingResource::TextureView(&atlas.view)),
            ];
            extra.extend(self.effects.bindings());
            extra.extend(self.fusion.bindings());
            ctx.dispatch_over(&self.pipeline, &extra, "color", self.workgroup)?;
        }
        counters.batches = batches.len() as u64;
        counters.visible_bricks = order.len() as u64;
        counters.bricks = bricks as u64;
        counters.slots = state.pool.slots() as u64;
        counters.resident = state.pool.resident() as u64;
        counters.pool_bytes = state.pool.slots() as u64 * state.slot_bytes();
        counters.drawn_leaves = state.drawn_leaves;
        self.counters = counters;
        Ok(())
    }

    fn update_params(&mut self, gpu: &Gpu, params: &Params) {
        gpu.queue.write_buffer(&self.params, 0, &RaycastParamsGpu::of(params).uniform_bytes());
        self.step_voxels = Sampling::from_params(params).step_voxels;
        self.effects.invalidate();
    }

    fn counters(&self) -> Vec<(&'static str, f64)> {
        let c = &self.counters;
        vec![
            ("uploaded_bytes", c.uploaded_bytes as f64),
            ("uploaded_bricks", c.uploaded_bricks as f64),
            ("batches", c.batches as f64),
            ("visible_bricks", c.visible_bricks as f64),
            ("bricks", c.bricks as f64),
            ("pool_slots", c.slots as f64),
            ("resident_bricks", c.resident as f64),
            ("pool_bytes", c.pool_bytes as f64),
            ("classify_ms", c.classify_ms),
            ("drawn_leaves", c.drawn_leaves),
        ]
    }
}
