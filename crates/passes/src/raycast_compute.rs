//! `raycast_compute`: the single-pass raycaster in a compute shader writing storage textures,
//! one invocation per pixel — the DirectCompute thesis's compute raycaster (`RAYCASTSIMPLE_CS`)
//! and, with its settings turned up, the fastest DVR path volgraph has (`graphs/modern/fastest.ron`):
//! - rays met with the box analytically (`rays: "analytic"`: no entry/direction raster passes);
//! - leaping over empty space with a wired `distance` map (`empty_distance`: out of the largest
//!   cube of empty blocks around the sample) or `empty` flags, looking at it once per run of
//!   `check_every` samples so the lanes of a SIMD group stay together;
//! - classification through the TF with the exact per-sample opacity correction (`classify:
//!   "exact"`; a square root, not a `pow`, at the common half-voxel step) or through a
//!   pre-multiplied, corrected table it builds itself from its own step (`"table"`,
//!   [`crate::opacity_lut`]: one filtered lookup, no `pow`; the correction 1 - (1 - α)^step is
//!   singular at α = 1, so a TF that reaches full opacity is off by up to ~1/255 there —
//!   bench/peer-ablation.md, tests/fastest.rs);
//! - early ray termination at `threshold` (§2.1) and sample counting (`count_samples`);
//! - on GPUs, a pipelined sample loop (`sample_loop`): the TF in workgroup memory, so a sample
//!   takes one texture operation instead of two, and the next sample fetched before this one is
//!   classified (bench/device/README.md: 43 % → 94 % of the fetch ceiling on an H200).
//!
//! The march is the fragment raycaster's (`shaders/common/pixel_march.wgsl`; settings in
//! [`crate::march`]), so the two differ only in how pixels are scheduled. The workgroup size is
//! a parameter (pipeline-overridable constants). Shader: `shaders/raycast_compute.wgsl`.

use volgraph_compiler::{Params, PassDecl, PortSpec, ShaderUse, TargetFormat};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{ComputePassPipeline, ComputePipelineSpec, CreateContext, Gpu, PassError, RecordContext};
#[cfg(feature = "gpu")]
use volgraph_core::{PassNode, PassPlugin};

#[cfg(feature = "gpu")]
use crate::effects::EffectState;
use crate::effects::{EffectFlags, effect_block};
#[cfg(feature = "gpu")]
use crate::march::Leaping;
use crate::march::{MarchSettings, march_blocks, wired_defines};
#[cfg(feature = "gpu")]
use crate::opacity_lut::opacity_table;
use crate::opacity_lut::table_shader_uses;
use crate::raycast::raycast_ports;
use crate::raycast_params::raycast_blocks;
use crate::raycast_params::{RaycastParamsGpu, SampleLoopChoice, Sampling, Workgroup, is_iso};
use crate::shared::BlockSize;
#[cfg(feature = "gpu")]
use crate::shared::color_precision_defines;
#[cfg(feature = "gpu")]
use crate::tf_table::TfTable;
use volgraph_compiler::block::{OnChange, ParamBlock};

/// The plugin.
pub struct RaycastCompute;

volgraph_compiler::param_choice! {
    /// How a sample is classified.
    pub enum Classify {
        /// The TF and the exact per-sample opacity correction.
        Exact = "exact",
        /// One lookup in a table pre-corrected for the step.
        Table = "table",
    }
}

volgraph_compiler::pass_params! {
    /// The compute raycaster's own parameter; it chooses the pipeline.
    pub struct ComputeOwn {
        classify: Classify = Exact,
            "exact: the TF and the exact per-sample opacity correction (sqrt at step 0.5, else pow); table: one \
             lookup in a table pre-corrected for the step, rebuilt each frame (faster than pow, up to ~1/255 off \
             where the TF reaches alpha 1)";
    }
}

fn entry(params: &Params) -> &'static str {
    if is_iso(params) { "cs_iso" } else { "cs_dvr" }
}

/// Whether the pass classifies through the corrected table (pre-integration has its own;
/// fusion classifies each volume through its own TF).
fn uses_table(params: &Params) -> bool {
    ComputeOwn::from_params(params).classify == Classify::Table
        && !EffectFlags::of(params).preintegration
        && crate::fusion::FusionSettings::of(params).combine().is_none()
}

impl PassDecl for RaycastCompute {
    fn honours_volume_window(&self) -> bool {
        true
    }

    fn kind(&self) -> &'static str {
        "raycast_compute"
    }

    fn scene_effects(&self) -> &'static [&'static str] {
        &crate::effects::SCENE_EFFECTS
    }

    fn summary(&self) -> &'static str {
        "compute-shader raycaster, DVR or first-hit isosurface, optionally analytic rays, empty-space leaping, \
         pre-corrected TF table, sample counting (DirectCompute thesis RAYCASTSIMPLE_CS; Krüger–Westermann 2003 §2.1–2.3)"
    }

    fn blocks(&self) -> Vec<ParamBlock> {
        // The workgroup, the sample loop and the classification shape the pipeline.
        [
            raycast_blocks(OnChange::InPlace),
            vec![effect_block(), crate::fusion::fusion_block()],
            march_blocks(),
            vec![
                ComputeOwn::block(OnChange::Rebuild)
                    .with_defines(|p| if uses_table(p) { vec![crate::defines::CORRECTED_TABLE] } else { vec![] }),
                Workgroup::block(OnChange::Rebuild),
                SampleLoopChoice::rebuild_block(),
            ],
        ]
        .concat()
    }

    fn shaders_wired(&self, params: &Params, wired: &[&str]) -> Vec<ShaderUse> {
        // The march's own use gets the wired leap; the table shaders do not march.
        let mut uses = self.shaders(params);
        uses[0] = uses[0].clone().defines(wired_defines(params, wired));
        uses
    }

    fn ports(&self, params: &Params) -> Vec<PortSpec> {
        // Storage formats: rgba16float or (a scene's f32 precision) rgba32float colour, chosen by
        // a shader define; rgba32float hits.
        raycast_ports(params, &[TargetFormat::Rgba16Float, TargetFormat::Rgba32Float], &[TargetFormat::Rgba32Float])
    }

    fn shaders(&self, params: &Params) -> Vec<ShaderUse> {
        let mut uses = vec![march_shader(params)];
        if uses_table(params) {
            uses.extend(table_shader_uses());
        }
        uses.extend(crate::effects::effect_shader_uses(params, true));
        uses
    }

    fn updates_in_place(&self, old: &Params, new: &Params) -> bool {
        // The blocks' rule: the step is a uniform value, and the node holds the half-voxel
        // variant whenever it may be picked, so a step change (the viewer's level of detail
        // doubles it while the camera moves) rebuilds nothing.
        self.only_in_place_blocks_change(old, new)
    }
}

/// The march's entry point for `params` and what it binds, declared once for `shaders()` and
/// `create`.
fn march_shader(params: &Params) -> ShaderUse {
    crate::fusion::with_fusion_uniform(
        ShaderUse::new("raycast_compute.wgsl", entry(params))
            .binds(crate::effects::MARCH_BINDINGS)
            .uniform(RaycastParamsGpu::bound("params"))
            .uniform(BlockSize::bound_as("blocks")),
        params,
    )
}

#[cfg(feature = "gpu")]
impl PassPlugin for RaycastCompute {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let wg = Workgroup::checked_size(ctx)?;
        let sampling = Sampling::from_params(ctx.params);
        let leaping = Leaping::new(ctx)?;
        let table = uses_table(ctx.params).then(|| opacity_table(ctx)).transpose()?;
        let own = march_shader(ctx.params).defines(wired_defines(ctx.params, &ctx.wired()));
        let defines = SampleLoopChoice::with_gpu_defines(
            [self.shader_defines(ctx.params), own.defines.clone(), color_precision_defines(ctx)].concat(),
            ctx.params,
            ctx.gpu,
        );
        let variant = |half_step: bool| {
            let mut constants = vec![("WORKGROUP_X", wg.0 as f64), ("WORKGROUP_Y", wg.1 as f64)];
            constants.extend(leaping.constants());
            if half_step {
                constants.push(("HALF_STEP", 1.0));
            }
            ctx.compute_pipeline(&ComputePipelineSpec {
                constants: &constants,
                defines: &defines,
                ..ComputePipelineSpec::of(&own)
            })
        };
        let pipeline = variant(false)?;
        // The square-root variant, for frames whose correction exponent is exactly 0.5 (step
        // 0.5 with opacity per voxel): DVR through the exact correction only. Built whatever the
        // step now, so the step can change in place (`updates_in_place`): a rebuilt node would
        // also remake what it derives from its inputs (a label map's quads, made on the CPU
        // from the whole map).
        let exact = table.is_none() && !EffectFlags::of(ctx.params).preintegration && !is_iso(ctx.params);
        let half_step = exact.then(|| variant(true)).transpose()?;
        let params = ctx.uniform_from_bytes("params", &RaycastParamsGpu::of(ctx.params).uniform_bytes());
        let effects = EffectState::new(ctx, true)?;
        let fusion = crate::fusion::FusionState::new(ctx)?;
        Ok(Box::new(RaycastComputeNode {
            fusion,
            pipeline,
            half_step,
            params,
            workgroup: wg,
            counted: MarchSettings::from_params(ctx.params).count_samples,
            table,
            leaping,
            effects,
            step_voxels: sampling.step_voxels,
        }))
    }
}

#[cfg(feature = "gpu")]
struct RaycastComputeNode {
    pipeline: ComputePassPipeline,
    /// The HALF_STEP variant, when the step is 0.5 voxel.
    half_step: Option<ComputePassPipeline>,
    params: wgpu::Buffer,
    workgroup: (u32, u32),
    counted: bool,
    table: Option<TfTable>,
    leaping: Leaping,
    effects: EffectState,
    fusion: crate::fusion::FusionState,
    step_voxels: f64,
}

#[cfg(feature = "gpu")]
impl PassNode for RaycastComputeNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        self.leaping.check(ctx)?;
        if self.counted {
            ctx.clear_buffer("samples")?;
        }
        if let Some(table) = &self.table {
            table.fill(ctx, &self.params, "tf")?;
        }
        self.fusion.update(ctx)?;
        self.effects.update(ctx, &self.params, self.step_voxels, &self.fusion.bindings())?;
        let mut extra = vec![("params", self.params.as_entire_binding())];
        if let Some(t) = &self.table {
            extra.push(("corrected", wgpu::BindingResource::TextureView(&t.view)));
        }
        extra.extend(self.leaping.bindings());
        extra.extend(self.effects.bindings());
        extra.extend(self.fusion.bindings());
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
        self.leaping.update(gpu, params);
        self.effects.invalidate();
    }
}
