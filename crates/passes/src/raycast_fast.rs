//! `raycast_fast`: the fastest DVR raycaster of volgraph (issue "the fastest path"), one compute
//! pass that
//! - needs no entry or direction targets: the pixel's ray meets the volume box analytically
//!   (`shaders/common/analytic_ray.wgsl`);
//! - leaps over empty space with `empty_distance`'s Chebyshev map of Krüger & Westermann 2003
//!   §2.3's empty blocks (`leap`: out of the largest cube of empty blocks around the sample, out
//!   of its block, or not at all), looking at the map once per run of `check_every` samples so
//!   the lanes of a SIMD group stay together;
//! - classifies through the TF with the exact per-sample opacity correction (`classify:
//!   "exact"`; a square root, not a `pow`, at the common half-voxel step) or through a
//!   pre-multiplied, corrected table it builds itself from its own step (`"table"`,
//!   [`crate::opacity_lut`]: one filtered lookup, no `pow`; ~14% faster than `pow` at other
//!   steps, but the correction 1 - (1 - α)^step is singular at α = 1, so a TF that reaches
//!   full opacity is off by up to ~1/255 there — bench/peer-ablation.md, tests/fastest.rs);
//! - stops at `threshold` (§2.1's early ray termination, in the loop); and
//! - counts the samples it takes into its `samples` buffer when `count_samples` is on
//!   (benchmarks: `volgraph bench graphs` reads it).
//!
//! Its samples are `raycast`'s (same step, same first sample), so the image equals the plain
//! raycast's up to rounding — a leap skips only samples whose classified alpha is 0
//! (crates/passes/tests/fastest.rs). Variants are pipeline-overridable constants; with leaping
//! off the unwired `distance` input is bound to a 1-texel stand-in the variant never reads.
//! Shader: `shaders/raycast_fast.wgsl`.

use volgraph_core::plugin::ShaderUse;
use volgraph_core::runtime::{ComputePassPipeline, ComputePipelineSpec, CreateContext, Gpu, PassError, RecordContext};
use volgraph_core::{ParamSpec, Params, PassDecl, PassNode, PassPlugin, PortKind, PortSpec, TargetFormat};

use crate::effects::{EffectFlags, EffectState, effect_defines, same_effects};
use crate::empty_distance::EMPTY_DISTANCE;
use crate::minmax_grid::bound_size;
use crate::opacity_lut::{TABLE_SHADERS, opacity_table};
use crate::raycast_params::{RaycastParamsGpu, Sampling, Shading, Termination, Workgroup};
use crate::shared::BlockSize;
use crate::tf_table::TfTable;

/// The plugin.
pub struct RaycastFast;

/// Rows of the `samples` buffer (`SAMPLE_ROWS` in the shader): image row y counts into word
/// y mod SAMPLE_ROWS, so a word holds at most a row's samples.
pub const SAMPLE_ROWS: u64 = 4096;

volgraph_core::param_choice! {
    /// What a run of samples leaps out of when the distance map says it may.
    pub enum Leap {
        /// The largest cube of empty blocks around the sample.
        Cubes = "cubes",
        /// The sample's own block.
        Blocks = "blocks",
        /// Nothing: every sample is taken.
        None = "none",
    }
}

volgraph_core::param_choice! {
    /// How a sample is classified.
    pub enum Classify {
        /// The TF and the exact per-sample opacity correction.
        Exact = "exact",
        /// One lookup in a table pre-corrected for the step.
        Table = "table",
    }
}

volgraph_core::pass_params! {
    /// `raycast_fast`'s own parameters; all of them choose the pipeline (override constants,
    /// ports), so a change rebuilds the node.
    pub struct FastOwn {
        leap: Leap = Cubes,
            "with `distance` wired: leap out of the largest cube of empty blocks, out of one block at a time, or \
             take every sample (unwired: none)";
        check_every: u32 = 16, 1..=1024,
            "samples in a run between two looks at the distance map (all lanes look together)";
        classify: Classify = Exact,
            "exact: the TF and the exact per-sample opacity correction (sqrt at step 0.5, else pow); table: one \
             lookup in a table pre-corrected for the step, rebuilt each frame (faster than pow, up to ~1/255 off \
             where the TF reaches alpha 1)";
        count_samples: bool = false,
            "write the number of samples taken to the `samples` buffer (benchmarks; one atomic per pixel)";
    }
}

/// The blocks `raycast_fast` and `raycast_ess` share: DVR sampling with termination, the
/// shading coefficients (for the shading effect), the block grid and the effects.
pub(crate) fn dvr_leap_specs() -> Vec<ParamSpec> {
    [Sampling::specs(), Termination::specs(), Shading::specs(), BlockSize::specs(), EffectFlags::specs()].concat()
}

impl PassDecl for RaycastFast {
    fn kind(&self) -> &'static str {
        "raycast_fast"
    }

    fn summary(&self) -> &'static str {
        "compute DVR raycaster: analytic ray-box entry, leaping over empty cubes of blocks, pre-corrected TF table, \
         early termination, sample counting (Krüger–Westermann 2003 §2.1–2.3 in one compute pass)"
    }

    fn params(&self) -> Vec<ParamSpec> {
        [dvr_leap_specs(), FastOwn::specs(), Workgroup::specs()].concat()
    }

    fn ports(&self, params: &Params) -> Vec<PortSpec> {
        let mut ports = vec![
            PortSpec::read("volume", PortKind::Volume),
            PortSpec::read("tf", PortKind::TransferFunction),
            // Leave unwired to take every sample.
            PortSpec::read("distance", PortKind::Owned(EMPTY_DISTANCE)).optional(),
            PortSpec::write("color", PortKind::target(&[TargetFormat::Rgba16Float, TargetFormat::Rgba32Float])),
        ];
        if FastOwn::from_params(params).count_samples {
            // One u32 per image row (mod SAMPLE_ROWS): samples taken this frame.
            ports.push(PortSpec::write("samples", PortKind::buffer(4 * SAMPLE_ROWS)));
        }
        ports
    }

    fn shader_defines(&self, params: &Params) -> Vec<&'static str> {
        let mut defines = effect_defines(params);
        let effects = EffectFlags::of(params);
        if effects.shading || effects.preintegration {
            defines.push("EFFECTS");
        }
        defines
    }

    fn shaders(&self, params: &Params) -> Vec<ShaderUse> {
        let own = FastOwn::from_params(params);
        let entry_point = if own.count_samples { "cs_counted" } else { "cs_main" };
        let mut uses = vec![ShaderUse {
            file: "raycast_fast.wgsl",
            entry_point,
            extra: &["params", "fast", "corrected", "preintegrated"],
        }];
        if own.classify == Classify::Table {
            uses.extend(TABLE_SHADERS);
        }
        uses.extend(crate::effects::effect_shader_uses(params));
        uses
    }

    fn updates_in_place(&self, old: &Params, new: &Params) -> bool {
        let half_step = |p: &Params| Sampling::from_params(p).step_voxels == 0.5;
        FastOwn::from_params(old) == FastOwn::from_params(new)
            && Workgroup::from_params(old) == Workgroup::from_params(new)
            && same_effects(old, new)
            && half_step(old) == half_step(new)
    }
}

impl PassPlugin for RaycastFast {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let own = FastOwn::from_params(ctx.params);
        let sampling = Sampling::from_params(ctx.params);
        let wg = Workgroup::checked_size(ctx)?;
        let distance_wired = ctx.port("distance").is_some_and(|p| p.bound);
        let leap = match (distance_wired, own.leap) {
            (false, _) | (true, Leap::None) => 0.0,
            (true, Leap::Blocks) => 1.0,
            (true, Leap::Cubes) => 2.0,
        };
        let table = match own.classify {
            Classify::Table => Some(opacity_table(ctx)?),
            Classify::Exact => None,
        };
        let counted = own.count_samples;
        let mut defines = self.shader_defines(ctx.params);
        if crate::shared::color_is_f32(ctx) {
            defines.push("COLOR_F32");
        }
        let variant = |half_step: bool| {
            ctx.compute_pipeline(&ComputePipelineSpec {
                shader: "raycast_fast.wgsl",
                entry: if counted { "cs_counted" } else { "cs_main" },
                defines: &defines,
                constants: &[
                    ("WORKGROUP_X", wg.0 as f64),
                    ("WORKGROUP_Y", wg.1 as f64),
                    ("LEAP", leap),
                    ("CORRECTED", if table.is_some() { 1.0 } else { 0.0 }),
                    ("CHECK_EVERY", own.check_every.max(1) as f64),
                    ("HALF_STEP", if half_step { 1.0 } else { 0.0 }),
                ],
            })
        };
        let pipeline = variant(false)?;
        // The square-root variant, for frames whose correction exponent is exactly 0.5 (step
        // 0.5 with opacity per voxel); only the exact classification without effects uses it.
        let effects = EffectFlags::of(ctx.params);
        let exact_plain = table.is_none() && !effects.shading && !effects.preintegration;
        let half_step = (exact_plain && sampling.step_voxels == 0.5).then(|| variant(true)).transpose()?;
        let params = ctx.uniform_from_bytes("params", &RaycastParamsGpu::of(ctx.params).uniform_bytes());
        let block_size = BlockSize::of(ctx.params);
        // `FastParams` of the shader: the block edge, padded to 16 bytes.
        let fast = ctx.uniform_from_bytes("fast", &BlockSize { block_size }.uniform_bytes());
        let stand_in = |dimension, format, label: &str| {
            ctx.gpu
                .device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 1 },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension,
                    format,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING,
                    view_formats: &[],
                })
                .create_view(&wgpu::TextureViewDescriptor::default())
        };
        let no_distance = (leap == 0.0)
            .then(|| stand_in(wgpu::TextureDimension::D3, wgpu::TextureFormat::R32Float, "no distance map"));
        let no_table = table
            .is_none()
            .then(|| stand_in(wgpu::TextureDimension::D2, wgpu::TextureFormat::Rgba16Float, "no corrected table"));
        let effects = EffectState::new(ctx)?;
        Ok(Box::new(RaycastFastNode {
            pipeline,
            half_step,
            params,
            fast,
            block_size,
            workgroup: wg,
            counted,
            table,
            no_distance,
            no_table,
            effects,
            step_voxels: sampling.step_voxels,
        }))
    }
}

struct RaycastFastNode {
    pipeline: ComputePassPipeline,
    /// The HALF_STEP variant, when the step is 0.5 voxel.
    half_step: Option<ComputePassPipeline>,
    params: wgpu::Buffer,
    fast: wgpu::Buffer,
    block_size: u32,
    workgroup: (u32, u32),
    counted: bool,
    table: Option<TfTable>,
    no_distance: Option<wgpu::TextureView>,
    no_table: Option<wgpu::TextureView>,
    effects: EffectState,
    step_voxels: f64,
}

impl RaycastFastNode {
    /// The distance map must be `block_size`'s grid of the bound volume.
    fn check_grid(&self, ctx: &RecordContext<'_>) -> Result<(), PassError> {
        let volume = bound_size(ctx, "volume")?;
        let grid = bound_size(ctx, "distance")?;
        let expected = volume.map(|n| n.div_ceil(self.block_size));
        if grid == expected {
            return Ok(());
        }
        Err(PassError {
            pass: ctx.label.to_string(),
            message: format!(
                "block_size {} gives a {expected:?} block grid for the {volume:?} volume, but \"distance\" is \
                 {grid:?}; set the same block_size as the minmax_grid pass (share a Scalar input)",
                self.block_size
            ),
        })
    }
}

impl PassNode for RaycastFastNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        if self.no_distance.is_none() {
            self.check_grid(ctx)?;
        }
        if self.counted {
            ctx.clear_buffer("samples")?;
        }
        if let Some(table) = &self.table {
            table.fill(ctx, &self.params)?;
        }
        self.effects.update(ctx, &self.params, self.step_voxels)?;
        let corrected = self.table.as_ref().map_or(self.no_table.as_ref(), |t| Some(&t.view));
        let mut extra = vec![("params", self.params.as_entire_binding()), ("fast", self.fast.as_entire_binding())];
        if let Some(v) = corrected {
            extra.push(("corrected", wgpu::BindingResource::TextureView(v)));
        }
        if let Some(v) = &self.no_distance {
            extra.push(("distance", wgpu::BindingResource::TextureView(v)));
        }
        extra.extend(self.effects.bindings());
        let unit = ctx.frame.volume.map_or(1.0, |v| v.opacity_unit_voxels);
        let pipeline = match &self.half_step {
            Some(half) if self.step_voxels / unit == 0.5 => half,
            _ => &self.pipeline,
        };
        ctx.dispatch_over(pipeline, &extra, "color", (self.workgroup.0, self.workgroup.1))
    }

    fn update_params(&mut self, gpu: &Gpu, params: &Params) {
        gpu.queue.write_buffer(&self.params, 0, &RaycastParamsGpu::of(params).uniform_bytes());
        self.step_voxels = Sampling::from_params(params).step_voxels;
        self.effects.invalidate();
        self.block_size = BlockSize::of(params);
        gpu.queue.write_buffer(&self.fast, 0, &BlockSize { block_size: self.block_size }.uniform_bytes());
    }
}
