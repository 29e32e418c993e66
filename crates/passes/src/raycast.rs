//! `raycast`: the single-pass fragment raycaster — Krüger & Westermann 2003 §2.1's ray
//! integration in one loop over the whole ray, front-to-back compositing with opacity
//! correction for the step size, early ray termination at a threshold, and §2.2's first-hit
//! isosurface with Blinn–Phong shading from central differences (mode `iso`, which also writes a
//! `hit` target of texture-space hit positions). The march is the shared core
//! (`shaders/common/pixel_march.wgsl`, `common/raymarch.wgsl`; settings in [`crate::march`]),
//! the same as `raycast_compute`'s; the conventions are `docs/rendering_model.md`.
//!
//! Settings of the core: analytic rays instead of the `entry`/`dir` inputs; empty-space leaping
//! over the blocks of a wired `empty` (or `distance`) input — the modern single-pass counterpart
//! of §2.3, which skips empty segments through an extra termination pass; sample counting.
//!
//! Klein et al. 2005 §4.2: with `leap_hits` it also writes `leap_hit` — the first sample that is
//! not fully transparent (DVR) or the isosurface hit, moved back `step_back` samples (or the
//! conservative ⌈|voxel diagonal| / h⌉ with `step_back_rule: "conservative"`), the exit point
//! for a ray that met nothing, w = 0 where there is no ray — and, with its optional `start`
//! input wired, begins each ray at that estimate on the same step grid (common/leap.wgsl).
//! Shader: `shaders/raycast.wgsl`.

use volgraph_compiler::{Params, PassDecl, PortKind, PortSpec, ShaderUse, TargetFormat};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{CreateContext, Gpu, PassError, RecordContext, RenderPassPipeline, RenderPipelineSpec};
#[cfg(feature = "gpu")]
use volgraph_core::{PassNode, PassPlugin};

#[cfg(feature = "gpu")]
use crate::effects::EffectState;
use crate::effects::effect_block;
#[cfg(feature = "gpu")]
use crate::march::Leaping;
use crate::march::{MarchSettings, SAMPLE_ROWS, march_blocks, march_ports, wired_defines};
use crate::raycast_params::{RaycastParamsGpu, is_iso, raycast_blocks};
use crate::shared::BlockSize;
use volgraph_compiler::block::{OnChange, ParamBlock};

/// The plugin.
pub struct Raycast;

/// The inputs a leap march may start its rays from: per-pixel estimates or per-tile bounds.
const START_PORTS: [&str; 2] = ["start", "start_tiles"];

/// The ports of both single-pass raycasters: the shared march's, the volume and TF, `color`
/// in `color` formats and, in mode iso, `hit`.
pub(crate) fn raycast_ports(params: &Params, color: &[TargetFormat], hit: &[TargetFormat]) -> Vec<PortSpec> {
    let mut ports = march_ports(params);
    ports.push(PortSpec::read("volume", PortKind::Volume));
    ports.push(PortSpec::read("tf", PortKind::TransferFunction));
    ports.extend(crate::fusion::FusionSettings::of(params).ports());
    ports.push(PortSpec::write("color", PortKind::target(color)));
    if is_iso(params) {
        ports.push(PortSpec::write("hit", PortKind::target(hit)));
    }
    ports
}

impl PassDecl for Raycast {
    fn honours_volume_window(&self) -> bool {
        true
    }

    fn kind(&self) -> &'static str {
        "raycast"
    }

    fn scene_effects(&self) -> &'static [&'static str] {
        &crate::effects::SCENE_EFFECTS
    }

    fn summary(&self) -> &'static str {
        "single-pass fragment raycaster, DVR or first-hit isosurface, optionally analytic rays, empty-space leaping, \
         Klein's start estimates and leap hits, sample counting (Krüger–Westermann 2003 §2.1–2.3; Klein et al. 2005 §4.2)"
    }

    fn blocks(&self) -> Vec<ParamBlock> {
        // Every value but the effects and the march's settings is a uniform value; a mode or
        // leap switch changes the entry point, the ports or the `#if`s (a rebuild).
        [
            raycast_blocks(OnChange::InPlace),
            vec![effect_block(), crate::fusion::fusion_block()],
            march_blocks(),
            vec![RaycastOwn::block(OnChange::InPlace).with_defines(own_defines)],
        ]
        .concat()
    }

    fn shaders_wired(&self, params: &Params, wired: &[&str]) -> Vec<ShaderUse> {
        let mut uses = self.shaders(params);
        uses[0] = uses[0].clone().defines(wired_defines(params, wired));
        uses
    }

    fn ports(&self, params: &Params) -> Vec<PortSpec> {
        let own = RaycastOwn::from_params(params);
        let mut ports = raycast_ports(
            params,
            &[TargetFormat::Rgba16Float, TargetFormat::Rgba32Float],
            &[TargetFormat::Rgba32Float, TargetFormat::Rgba16Float],
        );
        if own.leaps(params) {
            // The leap variant writes `leap_hit` instead of the exact isosurface `hit`.
            ports.retain(|p| p.name != "hit");
            // Leave unwired, or zero (a bypassed splat), to start every ray at the box (the first
            // frame of Klein's loop): `start_sample` reads w = 0 as no estimate.
            ports.push(PortSpec::read("start", PortKind::target(&[TargetFormat::Rgba32Float])).zero_means_none());
            // Or per-tile depth bounds (`reprojection_tiles`), read the same way.
            ports.push(
                PortSpec::read("start_tiles", PortKind::Buffer { bytes: 16, bytes_per_pixel: 4 }).zero_means_none(),
            );
            ports.push(PortSpec::write("leap_hit", PortKind::target(&[TargetFormat::Rgba32Float])));
        }
        if own.counts_leapable() {
            ports.push(PortSpec::write("leapable", PortKind::buffer(4 * SAMPLE_ROWS)));
        }
        ports
    }

    fn shaders(&self, params: &Params) -> Vec<ShaderUse> {
        [vec![march_shader(params)], crate::effects::effect_shader_uses(params, true)].concat()
    }
}

/// Klein's `#if`s: the leap hits (and the first visible sample they need), the leapable count.
fn own_defines(params: &Params) -> Vec<&'static str> {
    let own = RaycastOwn::from_params(params);
    let mut defines = Vec::new();
    if own.leaps(params) {
        defines.extend([crate::defines::LEAP_HITS, crate::defines::FIRST_VISIBLE]);
    }
    if own.counts_leapable() {
        defines.push(crate::defines::COUNT_LEAPABLE);
    }
    defines
}

/// The march's entry point for `params` (DVR or iso, leap hits or not) and what it binds,
/// declared once for `shaders()` and `create`.
fn march_shader(params: &Params) -> ShaderUse {
    crate::fusion::with_fusion_uniform(
        ShaderUse::new("raycast.wgsl", fragment_entry(params))
            .binds(crate::effects::MARCH_BINDINGS)
            .uniform(RaycastParamsGpu::bound("params"))
            .uniform(BlockSize::bound_as("blocks")),
        params,
    )
}

#[cfg(feature = "gpu")]
impl PassPlugin for Raycast {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let leaping = Leaping::new(ctx)?;
        let pipeline_for = |wired: &[&str]| {
            let own = march_shader(ctx.params).defines(wired_defines(ctx.params, wired));
            let defines = [self.shader_defines(ctx.params), own.defines.clone()].concat();
            ctx.render_pipeline(&RenderPipelineSpec {
                defines: &defines,
                constants: &leaping.constants(),
                ..RenderPipelineSpec::footprint(&own)
            })
        };
        let wired = ctx.wired();
        let pipeline = pipeline_for(&wired)?;
        if wired.contains(&"start") && wired.contains(&"start_tiles") {
            return Err(PassError {
                pass: ctx.pass_id.to_string(),
                message: "both \"start\" and \"start_tiles\" are wired; wire one source of start estimates".into(),
            });
        }
        // A graph's bypass may leave the estimates out (zeros): then the march runs as if they
        // were unwired, without reading them.
        let without_start = match START_PORTS.iter().filter_map(|&name| ctx.port(name)).find(|p| p.bound) {
            Some(p) if p.bound && p.may_read_zeros => {
                let wired: Vec<&str> = wired.iter().copied().filter(|w| !START_PORTS.contains(w)).collect();
                Some(pipeline_for(&wired)?)
            }
            _ => None,
        };
        let own = RaycastOwn::from_params(ctx.params);
        let settings = gpu_block(ctx.params);
        let params = ctx.uniform_from_bytes("params", &settings.uniform_bytes());
        let effects = EffectState::new(ctx, true)?;
        let fusion = crate::fusion::FusionState::new(ctx)?;
        Ok(Box::new(RaycastNode {
            fusion,
            pipeline,
            without_start,
            params,
            effects,
            leaping,
            settings,
            conservative: own.step_back_rule == StepBackRule::Conservative,
            counted: MarchSettings::from_params(ctx.params).count_samples,
            counts_leapable: own.counts_leapable(),
            written_step_back: None,
        }))
    }
}

volgraph_compiler::param_choice! {
    /// How far a leap hit is moved back along the ray (Klein et al. 2005 §4.2).
    pub enum StepBackRule {
        /// `step_back` samples.
        Fixed = "fixed",
        /// ⌈|voxel diagonal| / step⌉, never missing a voxel.
        Conservative = "conservative",
    }
}

volgraph_compiler::pass_params! {
    /// The fragment raycaster's own parameters: Klein et al. 2005's leap hits.
    pub struct RaycastOwn {
        leap_hits: bool = false,
            "write `leap_hit` (where the next frame's ray starts) and read the optional `start` estimate (Klein et al. 2005 §4.2)";
        step_back: u32 = 2, 0..=64, "samples a leap hit is moved back along the ray (the paper: one to three suffice)";
        step_back_rule: StepBackRule = Fixed,
            "fixed: step_back samples; conservative: ⌈|voxel diagonal| / step⌉, never missing a voxel (Klein et al. 2005 §4.2)";
        count_leapable: bool = false,
            "with leap_hits: add to the `leapable` buffer the samples a perfect start estimate would leap over (one atomic \
             per pixel), what a graph's `bypass` weighs reprojection's fixed cost against";
    }
}

impl RaycastOwn {
    /// Whether the pass runs Klein's variant (leap hits written, or samples counted).
    fn leaps(&self, params: &Params) -> bool {
        self.leap_hits || MarchSettings::from_params(params).count_samples
    }

    /// Whether the pass writes `leapable` (only with leap hits: the count is of their samples).
    fn counts_leapable(&self) -> bool {
        self.leap_hits && self.count_leapable
    }
}

fn fragment_entry(params: &Params) -> &'static str {
    match (is_iso(params), RaycastOwn::from_params(params).leaps(params)) {
        (false, false) => "fs_dvr",
        (true, false) => "fs_iso",
        (false, true) => "fs_dvr_leap",
        (true, true) => "fs_iso_leap",
    }
}

/// The shared block with the fixed step back (the conservative one is computed per volume).
fn gpu_block(params: &Params) -> RaycastParamsGpu {
    RaycastParamsGpu { step_back: RaycastOwn::from_params(params).step_back as f32, ..RaycastParamsGpu::of(params) }
}

#[cfg(feature = "gpu")]
/// ⌈|voxel diagonal| / h⌉ for the bound volume (Klein et al. 2005 §4.2's conservative bound).
fn conservative_step_back(volume: &volgraph_core::runtime::VolumeDesc, step_voxels: f64) -> f32 {
    let voxel = 2.0 * volume.half_extent / volume.dims.as_dvec3();
    (voxel.length() / (step_voxels * volume.unit_step)).ceil() as f32
}

#[cfg(feature = "gpu")]
struct RaycastNode {
    pipeline: RenderPassPipeline,
    /// The same march without the `start` input, for frames whose estimates a bypass left out.
    without_start: Option<RenderPassPipeline>,
    params: wgpu::Buffer,
    effects: EffectState,
    fusion: crate::fusion::FusionState,
    leaping: Leaping,
    /// What `params` holds (the conservative step back is filled in per volume).
    settings: RaycastParamsGpu,
    conservative: bool,
    counted: bool,
    counts_leapable: bool,
    written_step_back: Option<f32>,
}

#[cfg(feature = "gpu")]
impl PassNode for RaycastNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        if self.conservative
            && let Some(volume) = &ctx.frame.volume
        {
            let n = conservative_step_back(volume, self.settings.step_voxels as f64);
            if self.written_step_back != Some(n) {
                self.settings.step_back = n;
                ctx.write_buffer(&self.params, 0, &self.settings.uniform_bytes());
                self.written_step_back = Some(n);
            }
        }
        if self.counted {
            ctx.clear_buffer("samples")?;
        }
        if self.counts_leapable {
            ctx.clear_buffer("leapable")?;
        }
        self.leaping.check(ctx)?;
        self.fusion.update(ctx)?;
        self.effects.update(ctx, &self.params, self.settings.step_voxels as f64, &self.fusion.bindings())?;
        let mut extra = vec![("params", self.params.as_entire_binding())];
        extra.extend(self.leaping.bindings());
        extra.extend(self.effects.bindings());
        extra.extend(self.fusion.bindings());
        let pipeline = match &self.without_start {
            Some(without) if START_PORTS.iter().any(|&p| ctx.reads_zeros(p)) => without,
            _ => &self.pipeline,
        };
        let bg = ctx.bind_group(pipeline, &extra)?;
        ctx.draw_footprint(pipeline, &bg)
    }

    fn update_params(&mut self, gpu: &Gpu, params: &Params) {
        self.settings = gpu_block(params);
        self.conservative = RaycastOwn::from_params(params).step_back_rule == StepBackRule::Conservative;
        self.written_step_back = None;
        gpu.queue.write_buffer(&self.params, 0, &self.settings.uniform_bytes());
        self.leaping.update(gpu, params);
        self.effects.invalidate();
    }
}
