//! `raycast_bricks`: DVR through a GPU brick pool with per-brick octrees, after Ruijters &
//! Vilanova 2006, as one compute pass that walks the bricks itself.
//!
//! - §5 **bricks**: the volume is cut into bricks of `brick_cells`³ cells that keep the voxels
//!   of their cells' corners (the one-voxel overlap trilinear samples inside a brick need) and
//!   one more voxel on every side, so that a filter tap at a brick face blends exactly the
//!   voxels the whole volume would and images have no seams. Non-empty bricks (for the current
//!   TF) live in a 3D atlas texture, `brick_cells + 3` voxels per side per slot; empty bricks
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
//!   around it ([`leaf_words`]) and on through its brick, up to `CHECK_EVERY` samples in all,
//!   so a thin vessel or a dense brick does not cost a round of leaps per leaf.
//! - **termination**: a ray stops at `threshold` and skips the bricks behind it (per-brick
//!   early ray termination: with `threshold < 1` a saturated pixel costs nothing in later
//!   batches either).
//!
//! Samples are those of every raycaster (`common/ray_box.wgsl`: k + 0.5 steps from the analytic box entry, same
//! compositing), so the image equals the single-texture raycast up to rounding
//! (crates/passes/tests/ruijters_2006.rs). A TF change re-classifies bricks and octrees
//! (CPU, [`volgraph_accel::octree`]) and uploads only bricks not yet resident.
//! Shader: `shaders/raycast_bricks.wgsl`.

use std::sync::Arc;
use std::time::Instant;

use glam::{DVec3, UVec3};
use volgraph_accel::bricks::{BrickLayout, ViewPoint};
use volgraph_accel::classify::OpacityClassifier;
use volgraph_accel::octree::{DrawBox, OctreeHierarchy, OctreeVisibility};
use volgraph_accel::volume::Volume;
use volgraph_core::plugin::ShaderUse;
use volgraph_core::runtime::upload::VolumeFormat;
use volgraph_core::runtime::{
    ComputePassPipeline, ComputePipelineSpec, CreateContext, Gpu, PassError, RecordContext, volume_region_bytes,
    volume_texture_format,
};
use volgraph_core::{ParamSpec, Params, PassDecl, PassNode, PassPlugin, PortKind, PortSpec, TargetFormat};
use wgpu::util::DeviceExt;

use crate::brick_pool::{Batch, BrickPool};
use crate::raycast_params::{RaycastParamsGpu, SampleLoopChoice, Sampling, Termination, Workgroup};

/// The plugin.
pub struct RaycastBricks;

volgraph_core::pass_params! {
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

/// Rust twin of `struct BrickParams` in `shaders/raycast_bricks.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct BrickParamsGpu {
    grid: [u32; 4],
    slot_side: [u32; 4],
    leaves: [u32; 4],
    leaf_grid: [u32; 4],
    atlas: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<BrickParamsGpu>() == 80);

/// The largest staging buffer one upload batch uses, whatever the adapter allows: a frame's
/// uploads are split into chunks of at most this many bytes (and at most the device's
/// `max_buffer_size`), so a 1024³ volume never needs a gigabyte of staging at once.
const MAX_STAGING_BYTES: u64 = 64 << 20;

/// Leap distances are capped here: a leap out of a cube of 2·255 − 1 leaves is long enough that a
/// larger one would save little (the cap only shortens leaps, it never skips a drawn leaf).
const MAX_LEAP: u32 = 255;

impl PassDecl for RaycastBricks {
    fn honours_volume_window(&self) -> bool {
        true
    }

    fn kind(&self) -> &'static str {
        "raycast_bricks"
    }

    fn summary(&self) -> &'static str {
        "compute DVR through a GPU brick pool (LRU, memory budget, out of core) with per-brick octrees and early \
         ray termination (Ruijters & Vilanova 2006 §5–7)"
    }

    fn params(&self) -> Vec<ParamSpec> {
        [Sampling::specs(), Termination::specs(), BrickSettings::specs(), Workgroup::specs(), SampleLoopChoice::specs()]
            .concat()
    }

    fn shader_defines(&self, params: &Params) -> Vec<&'static str> {
        [crate::effects::jitter_defines(params), SampleLoopChoice::defines(params, None)].concat()
    }

    fn uses_gpu_memory_budget(&self) -> bool {
        true
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read("volume", PortKind::VolumeVoxels),
            PortSpec::read("tf", PortKind::TransferFunction),
            PortSpec::write("color", PortKind::target(&[TargetFormat::Rgba16Float, TargetFormat::Rgba32Float])),
        ]
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        vec![march_shader()]
    }

    fn updates_in_place(&self, old: &Params, new: &Params) -> bool {
        // Only the raycasting parameters (a uniform) change in place; the brick settings
        // shape the pool and the leaves.
        BrickSettings::from_params(old) == BrickSettings::from_params(new)
            && Workgroup::from_params(old) == Workgroup::from_params(new)
            && SampleLoopChoice::from_params(old) == SampleLoopChoice::from_params(new)
            && self.shader_defines(old) == self.shader_defines(new)
    }
}

/// The brick march's entry point and what it binds, declared once for `shaders()` and `create`.
fn march_shader() -> ShaderUse {
    ShaderUse::new("raycast_bricks.wgsl", "cs_main")
        .binds(&["table", "leaf_words", "acc", "volume"])
        .uniform(RaycastParamsGpu::bound("params"))
        .uniform(brick_layout())
}

/// The `bricks` block as `BrickParamsGpu` lays it out, checked against the shader's
/// `BrickParams` when the graph is planned. The node writes it per frame (the pool's state).
fn brick_layout() -> volgraph_core::UniformLayout {
    volgraph_core::UniformLayout {
        global: "bricks",
        fields: vec![
            ("grid", "vec4<u32>"),
            ("slot_side", "vec4<u32>"),
            ("leaves", "vec4<u32>"),
            ("leaf_grid", "vec4<u32>"),
            ("atlas", "vec4<f32>"),
        ],
        params: Vec::new(),
        bytes: |_| bytemuck::bytes_of(&BrickParamsGpu::default()).to_vec(),
    }
}

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
            ..ComputePipelineSpec::of(&march_shader())
        })?;
        let params = ctx.uniform_from_bytes("params", &RaycastParamsGpu::of(ctx.params).uniform_bytes());
        let uniform = ctx.uniform_buffer("bricks", std::mem::size_of::<BrickParamsGpu>() as u64);
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
        Ok(Box::new(RaycastBricksNode {
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

/// The atlas texture and how its slots are laid out.
struct Atlas {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    /// Slots per axis (x, y fixed for the volume; z grows).
    slots: UVec3,
}

/// Everything derived from one bound volume.
struct VolumeState {
    version: u64,
    voxels: Arc<Volume>,
    layout: BrickLayout,
    octree: OctreeHierarchy,
    format: VolumeFormat,
    /// Voxels per slot and axis: `brick_cells + 3`, or fewer on an axis thinner than a brick
    /// (a 1-voxel-thick slab stores 4 layers per brick, not 35).
    side: UVec3,
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

struct RaycastBricksNode {
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

fn pass_error(ctx: &RecordContext<'_>, message: String) -> PassError {
    PassError { pass: ctx.label.to_string(), message }
}

impl VolumeState {
    fn new(
        ctx: &RecordContext<'_>,
        voxels: Arc<Volume>,
        version: u64,
        brick_cells: u32,
        node_cells: u32,
    ) -> Result<Self, PassError> {
        let layout = BrickLayout::new(voxels.dims, brick_cells, 1).map_err(|e| pass_error(ctx, e.to_string()))?;
        let octree =
            OctreeHierarchy::build(&voxels, &layout, node_cells).map_err(|e| pass_error(ctx, e.to_string()))?;
        // The brick's voxels and one more on every side (clamped to the volume like the
        // sampler): a filter tap at a brick face blends exactly what it would in the whole
        // volume, even where the hardware's fixed-point weights give the next texel 1/256.
        // An axis with fewer cells than a brick holds one brick of that many cells.
        let cells = volgraph_accel::bricks::cell_dims(voxels.dims);
        let side = cells.min(UVec3::splat(brick_cells)) + 3;
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
        let leaf_grid =
            UVec3::new(cells.x.div_ceil(node_cells), cells.y.div_ceil(node_cells), cells.z.div_ceil(node_cells));
        Ok(Self {
            version,
            format: volume_texture_format(ctx.gpu, &voxels),
            voxels,
            pool: BrickPool::new(0, layout.brick_count()),
            layout,
            octree,
            side,
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
    /// and uploads the leaves' words ([`leaf_words`]); returns the time it took in ms.
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

    /// Sizes the pool for the visible bricks under `budget` bytes: grows the atlas (keeping
    /// resident bricks where they are) or, when the budget changed, starts over.
    fn size_pool(&mut self, ctx: &mut RecordContext<'_>, budget: u64) -> Result<(), PassError> {
        if budget != self.budget {
            self.pool = BrickPool::new(0, self.layout.brick_count());
            self.atlas = None;
            self.budget = budget;
        }
        let visible = self.visible.iter().filter(|v| **v).count() as u64;
        let per_layer = self.slots_xy.0 * self.slots_xy.1;
        let most = (budget / self.slot_bytes()).min((per_layer * self.max_layers) as u64);
        if most == 0 {
            return Err(pass_error(
                ctx,
                format!(
                    "the brick pool's budget of {budget} bytes holds no {}-byte brick; raise --gpu-memory-mb (or \
                     pool_mb) or lower brick_cells",
                    self.slot_bytes()
                ),
            ));
        }
        let wanted = visible.min(most).max(1) as u32;
        if wanted <= self.pool.slots() {
            return Ok(());
        }
        let layers = wanted.div_ceil(per_layer);
        let slots = UVec3::new(self.slots_xy.0, self.slots_xy.1, layers);
        let size = slots * self.side;
        let texture = ctx.gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("brick atlas"),
            size: wgpu::Extent3d { width: size.x, height: size.y, depth_or_array_layers: size.z },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D3,
            format: self.format.wgpu(),
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        if let Some(old) = &self.atlas {
            let s = old.slots * self.side;
            ctx.encoder.copy_texture_to_texture(
                old.texture.as_image_copy(),
                texture.as_image_copy(),
                wgpu::Extent3d { width: s.x, height: s.y, depth_or_array_layers: s.z },
            );
        }
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        let slot_count = (slots.x * slots.y * slots.z).min(most as u32);
        self.pool.grow(slot_count - self.pool.slots());
        self.atlas = Some(Atlas { texture, view, slots });
        Ok(())
    }

    /// Records the copies of `uploads` into the atlas, through staging buffers of at most
    /// [`MAX_STAGING_BYTES`] and the device's `max_buffer_size` each; returns the voxel bytes
    /// uploaded.
    fn upload(&self, ctx: &mut RecordContext<'_>, uploads: &[(u32, u32)]) -> Result<u64, PassError> {
        let Some(atlas) = &self.atlas else { return Ok(0) };
        let texel = self.format.bytes() as u64;
        let brick_row = self.side.x as u64 * texel;
        let rows = self.side.y as u64 * self.side.z as u64;
        // Chunks of MAX_STAGING_BYTES, or one brick where a brick is larger; never more than
        // the device's largest buffer.
        let one_brick = staging_row_bytes(brick_row, 1) * rows;
        let device = ctx.gpu.limits.max_buffer_size;
        let per_chunk = staging_bricks_per_chunk(brick_row, rows, MAX_STAGING_BYTES.max(one_brick).min(device));
        if per_chunk == 0 {
            return Err(pass_error(
                ctx,
                format!(
                    "one brick of {}x{}x{} voxels needs {one_brick} bytes of staging, more than this device's \
                     largest buffer ({device} bytes); lower brick_cells",
                    self.side.x, self.side.y, self.side.z
                ),
            ));
        }
        for chunk in uploads.chunks(per_chunk) {
            self.upload_chunk(ctx, atlas, chunk, brick_row);
        }
        Ok(uploads.len() as u64 * self.slot_bytes())
    }

    /// One staging buffer for `chunk`: the bricks side by side along x (brick `i`'s row `r` at
    /// `r · row + i · brick_row`), so rows share the 256-byte alignment a buffer-to-texture
    /// copy needs instead of padding every brick's row to it.
    fn upload_chunk(&self, ctx: &mut RecordContext<'_>, atlas: &Atlas, chunk: &[(u32, u32)], brick_row: u64) {
        let side = self.side;
        let row = staging_row_bytes(brick_row, chunk.len());
        let mut staging = vec![0u8; (row * side.y as u64 * side.z as u64) as usize];
        for (i, (brick, _)) in chunk.iter().enumerate() {
            let (lo, _) = self.layout.brick_cells_box(self.layout.brick_coord(*brick as usize));
            let origin = lo.as_ivec3() - glam::IVec3::ONE;
            let tight = volume_region_bytes(&self.voxels, origin, side, self.format);
            for (r, src) in tight.chunks_exact(brick_row as usize).enumerate() {
                let at = (r as u64 * row + i as u64 * brick_row) as usize;
                staging[at..at + src.len()].copy_from_slice(src);
            }
        }
        let buffer = ctx.gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("brick uploads"),
            contents: &staging,
            usage: wgpu::BufferUsages::COPY_SRC,
        });
        for (i, (_, slot)) in chunk.iter().enumerate() {
            let at = slot_coord(*slot, atlas.slots) * side;
            ctx.encoder.copy_buffer_to_texture(
                wgpu::TexelCopyBufferInfo {
                    buffer: &buffer,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: i as u64 * brick_row,
                        bytes_per_row: Some(row as u32),
                        rows_per_image: Some(side.y),
                    },
                },
                wgpu::TexelCopyTextureInfo {
                    texture: &atlas.texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d { x: at.x, y: at.y, z: at.z },
                    aspect: wgpu::TextureAspect::All,
                },
                wgpu::Extent3d { width: side.x, height: side.y, depth_or_array_layers: side.z },
            );
        }
    }
}

/// Slots per atlas axis, at most: a slot word ([`slot_word`]) has 10 bits per axis. (A slot is
/// at least 4 voxels wide, so a 3D texture limit of 4096 or less never meets it.)
const SLOTS_PER_AXIS: u32 = 1 << 10;

/// Where slot `slot` lies in an atlas of `slots` slots per axis, in slots: x fastest.
fn slot_coord(slot: u32, slots: UVec3) -> UVec3 {
    UVec3::new(slot % slots.x, (slot / slots.x) % slots.y, slot / (slots.x * slots.y))
}

/// A drawn brick's word in the batch table (`raycast_bricks.wgsl`'s `table`): bit 31 set (0 is
/// "not in this batch") and its slot's coordinates, 10 bits per axis, x lowest — so the march
/// finds the slot's origin with a multiply instead of three integer divisions per brick entered,
/// which llvmpipe runs one lane at a time (2 % of the `bricks` graph's time on the engine,
/// bench/one-march-final.md "Brick runs").
pub fn slot_word(coord: UVec3) -> u32 {
    debug_assert!(coord.max_element() < SLOTS_PER_AXIS);
    1 << 31 | coord.x | coord.y << 10 | coord.z << 20
}

/// Bytes per staging row for `bricks` bricks of `brick_row` bytes side by side, padded to the
/// copy alignment.
fn staging_row_bytes(brick_row: u64, bricks: usize) -> u64 {
    let align = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT as u64;
    (brick_row * bricks as u64).div_ceil(align) * align
}

/// How many bricks (`rows` rows of `brick_row` bytes each) one staging buffer of at most
/// `limit` bytes holds (0: not even one). Row pitch stays within `u32`, as copies need.
pub fn staging_bricks_per_chunk(brick_row: u64, rows: u64, limit: u64) -> usize {
    let fits = |n: u64| {
        let row = staging_row_bytes(brick_row, n as usize);
        row <= u64::from(u32::MAX) && row * rows <= limit
    };
    if !fits(1) {
        return 0;
    }
    // The largest n that fits: rows grow monotonically with n.
    let (mut lo, mut hi) = (1u64, (limit / (brick_row * rows).max(1)).max(1) + 1);
    while lo + 1 < hi {
        let mid = lo + (hi - lo) / 2;
        if fits(mid) { lo = mid } else { hi = mid }
    }
    lo as usize
}

/// Leaves of `node_cells`³ cells per axis over a volume of `volume_dims` voxels.
pub fn leaf_grid(volume_dims: UVec3, node_cells: u32) -> UVec3 {
    let cells = volgraph_accel::bricks::cell_dims(volume_dims);
    UVec3::new(cells.x.div_ceil(node_cells), cells.y.div_ceil(node_cells), cells.z.div_ceil(node_cells))
}

/// The CPU work of a TF change after the octrees' visible counts are rebuilt: which bricks are
/// visible, and every leaf's word ([`leaf_words`]).
pub struct LeafClassification {
    /// Per brick: visible under the TF.
    pub visible: Vec<bool>,
    /// Per leaf of the volume (x fastest), what the march reads ([`leaf_word`]): where no box
    /// to draw covers it, the Chebyshev distance in leaves to the nearest such leaf (capped at
    /// 255); where one does, how far the drawn leaves around it reach within its brick.
    pub words: Vec<u32>,
    /// Fraction of the leaves drawn.
    pub drawn_fraction: f64,
}

/// Rasterizes every visible brick's boxes to draw (§7's ratio rule at `ratio`) into the leaf
/// grid and turns them into the march's words ([`leaf_words`]: leap distances, drawn cubes).
pub fn classify_leaves(
    octree: &OctreeHierarchy,
    visibility: &OctreeVisibility,
    layout: &BrickLayout,
    grid: UVec3,
    ratio: f32,
) -> LeafClassification {
    let count = layout.brick_count();
    let visible: Vec<bool> = (0..count).map(|b| visibility.brick_visible_cells(b) > 0).collect();
    let mut drawn = vec![false; (grid.x * grid.y * grid.z) as usize];
    let mut boxes: Vec<DrawBox> = Vec::new();
    let leaf = octree.min_node_cells();
    for b in (0..count).filter(|b| visible[*b]) {
        boxes.clear();
        octree.draw_boxes(visibility, b, ratio, ViewPoint::Direction(DVec3::Z), &mut boxes);
        for d in &boxes {
            let lo = d.cells_lo / leaf;
            let hi = UVec3::new(d.cells_hi.x.div_ceil(leaf), d.cells_hi.y.div_ceil(leaf), d.cells_hi.z.div_ceil(leaf))
                .min(grid);
            for z in lo.z..hi.z {
                for y in lo.y..hi.y {
                    for x in lo.x..hi.x {
                        drawn[(x + grid.x * (y + grid.y * z)) as usize] = true;
                    }
                }
            }
        }
    }
    let drawn_fraction = drawn.iter().filter(|d| **d).count() as f64 / drawn.len().max(1) as f64;
    let words = leaf_words(&drawn, grid, layout.brick_cells().div_ceil(leaf).max(1));
    LeafClassification { visible, words, drawn_fraction }
}

/// Every leaf's [`leaf_word`] for the drawn leaves `drawn` (x fastest in `grid`), in bricks of
/// `leaves_per_brick` leaves per side.
pub fn leaf_words(drawn: &[bool], grid: UVec3, leaves_per_brick: u32) -> Vec<u32> {
    let to_drawn = volgraph_accel::chebyshev::chebyshev_distance(drawn, grid, MAX_LEAP);
    let not_drawn: Vec<bool> = drawn.iter().map(|d| !d).collect();
    let to_not_drawn = volgraph_accel::chebyshev::chebyshev_distance(&not_drawn, grid, leaves_per_brick);
    let mut words = Vec::with_capacity(drawn.len());
    for z in 0..grid.z {
        for y in 0..grid.y {
            for x in 0..grid.x {
                let i = (x + grid.x * (y + grid.y * z)) as usize;
                let reach = to_not_drawn[i].min(reach_within_brick(UVec3::new(x, y, z), leaves_per_brick, grid));
                words.push(leaf_word(drawn[i], to_drawn[i], reach));
            }
        }
    }
    words
}

/// The word `raycast_bricks.wgsl` reads per leaf (`empty_region_at`): the leap distance
/// `to_drawn` (1..=255) of a leaf no box covers; `reach << 8` for a drawn one, whose cube of
/// `2·reach − 1` leaves around it is drawn and inside its brick, so one run of samples crosses it
/// (a dense brick in a few runs, not one per leaf).
pub fn leaf_word(drawn: bool, to_drawn: u32, reach: u32) -> u32 {
    if drawn { reach.clamp(1, 0x00ff_ffff) << 8 } else { to_drawn.clamp(1, MAX_LEAP) }
}

/// How far a cube around leaf `l` may reach and stay inside its brick (of `leaves_per_brick`
/// leaves per side, fewer in the last brick of an axis): 1 next to another brick. The volume's
/// faces do not bound it: the march clamps the cube to the leaf grid.
fn reach_within_brick(l: UVec3, leaves_per_brick: u32, grid: UVec3) -> u32 {
    let lo = l / leaves_per_brick * leaves_per_brick;
    let hi = (lo + leaves_per_brick).min(grid) - 1;
    let to_lo = UVec3::select(lo.cmpeq(UVec3::ZERO), UVec3::MAX, l - lo);
    let to_hi = UVec3::select(hi.cmpeq(grid - 1), UVec3::MAX, hi - l);
    to_lo.min(to_hi).min_element().saturating_add(1)
}

/// Whether rank `ranks.0` of `ranks.1` draws brick `brick`: the brick grid is cut into
/// `ranks.1` slabs along its longest axis (a one-level kd-tree; docs/scaling.md).
pub fn owns(layout: &BrickLayout, brick: u32, (rank, ranks): (u32, u32)) -> bool {
    if ranks <= 1 {
        return true;
    }
    let grid = layout.grid_dims();
    let axis = if grid.x >= grid.y && grid.x >= grid.z {
        0
    } else if grid.y >= grid.z {
        1
    } else {
        2
    };
    let c = layout.brick_coord(brick as usize)[axis] as u64;
    (c * ranks as u64 / grid[axis] as u64) as u32 == rank
}

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

impl PassNode for RaycastBricksNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let voxels = ctx.voxels("volume")?.clone();
        let version = ctx.input_version("volume").unwrap_or(0);
        if self.volume.as_ref().is_none_or(|v| v.version != version) {
            self.volume = Some(VolumeState::new(ctx, voxels, version, self.brick_cells, self.node_cells)?);
        }
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
        let uniform = BrickParamsGpu {
            grid: [grid.x, grid.y, grid.z, self.brick_cells],
            slot_side: [state.side.x, state.side.y, state.side.z, 0],
            leaves: [state.octree.min_node_cells(), self.brick_cells / state.octree.min_node_cells(), 0, 0],
            leaf_grid: [state.leaf_grid.x, state.leaf_grid.y, state.leaf_grid.z, 0],
            atlas: [atlas_size.x, atlas_size.y, atlas_size.z, 0.0],
        };
        ctx.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));

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
            let extra = [
                ("params", self.params.as_entire_binding()),
                ("bricks", self.uniform.as_entire_binding()),
                ("table", wgpu::BindingResource::Buffer(table)),
                ("leaf_words", leaf_buffer.as_entire_binding()),
                ("acc", acc.as_entire_binding()),
                ("volume", wgpu::BindingResource::TextureView(&atlas.view)),
            ];
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Chunks fill the limit without passing it; rows are padded to the copy alignment once per
    /// chunk, not once per brick.
    #[test]
    fn staging_chunks_fit_the_limit() {
        // 35-voxel u8 rows, 35·35 rows per brick.
        let (brick_row, rows) = (35u64, 35 * 35u64);
        for limit in [64 << 20, 512 << 10, 400_000, 256 * rows] {
            let n = staging_bricks_per_chunk(brick_row, rows, limit);
            assert!(n >= 1, "{limit}");
            assert!(staging_row_bytes(brick_row, n) * rows <= limit, "{limit}: {n} bricks");
            assert!(staging_row_bytes(brick_row, n + 1) * rows > limit, "{limit}: {n} is the most");
        }
        // Padding: 64 MiB holds ~1561 bricks of 42875 bytes, not the 214 a 256-byte row each allows.
        assert!(staging_bricks_per_chunk(brick_row, rows, 64 << 20) > 1500);
        assert_eq!(staging_bricks_per_chunk(brick_row, rows, 1000), 0, "not even one brick");
    }

    /// The words the march leaps and runs by, against brute force on random leaf masks: an
    /// empty leaf's distance is the Chebyshev distance to the nearest drawn leaf; a drawn leaf's
    /// reach is the largest cube around it that is all drawn and inside its brick (the last
    /// brick of an axis is thinner).
    #[test]
    fn leaf_words_are_leap_distances_and_drawn_cubes_within_a_brick() {
        let grid = UVec3::new(9, 8, 7);
        let per_brick = 4;
        let index = |l: UVec3| (l.x + grid.x * (l.y + grid.y * l.z)) as usize;
        let leaves = || {
            (0..grid.z).flat_map(move |z| (0..grid.y).flat_map(move |y| (0..grid.x).map(move |x| UVec3::new(x, y, z))))
        };
        let cube = |l: UVec3, r: u32| {
            let lo = l.saturating_sub(UVec3::splat(r));
            let hi = (l + r).min(grid - 1);
            leaves().filter(move |m| m.cmpge(lo).all() && m.cmple(hi).all())
        };
        let mut rng = volgraph_accel::generate::SplitMix64(7);
        for density in [0.1, 0.6, 0.95, 1.0] {
            let drawn: Vec<bool> =
                (0..grid.element_product()).map(|_| (rng.next_u64() as f64 / u64::MAX as f64) < density).collect();
            let words = leaf_words(&drawn, grid, per_brick);
            for l in leaves() {
                let word = words[index(l)];
                if !drawn[index(l)] {
                    let want = leaves()
                        .filter(|m| drawn[index(*m)])
                        .map(|m| (m.as_ivec3() - l.as_ivec3()).abs().max_element() as u32)
                        .min();
                    assert_eq!(word, want.unwrap_or(MAX_LEAP).clamp(1, MAX_LEAP), "{density}: empty leaf {l}");
                    continue;
                }
                assert_eq!(word & 0xff, 0, "{density}: drawn leaf {l}");
                let fits = |r: u32| cube(l, r).all(|m| drawn[index(m)] && m / per_brick == l / per_brick);
                let reach = word >> 8;
                assert!(reach >= 1 && fits(reach - 1), "{density}: leaf {l} reach {reach}");
                assert!(
                    !fits(reach) || cube(l, reach).count() == cube(l, reach - 1).count(),
                    "{density}: leaf {l}: reach {reach} is the largest"
                );
            }
        }
    }
}
