//! `raycast`: the single-pass fragment raycaster — Krüger & Westermann 2003 §2.1's ray
//! integration in one loop over the whole ray, front-to-back compositing with opacity
//! correction for the step size, early ray termination at a threshold, and §2.2's first-hit
//! isosurface with Blinn–Phong shading from central differences (mode `iso`, which also writes a
//! `hit` target of texture-space hit positions). The integral itself is
//! `shaders/common/raymarch.wgsl`, shared with `raycast_compute`; the conventions are
//! `docs/rendering_model.md`.
//!
//! Klein et al. 2005 §4.2: with `leap_hits` it also writes `leap_hit` — the first sample that is
//! not fully transparent (DVR) or the isosurface hit, moved back `step_back` samples (or the
//! conservative ⌈|voxel diagonal| / h⌉ with `step_back_rule: "conservative"`), the exit point
//! for a ray that met nothing, w = 0 where there is no ray — and, with its optional `start`
//! input wired, begins each ray at that estimate on the same step grid (common/leap.wgsl). With
//! `count_samples` it adds the samples it takes to its `samples` buffer. Shader:
//! `shaders/raycast.wgsl`.

use volgraph_core::plugin::ShaderUse;
use volgraph_core::runtime::{CreateContext, Gpu, PassError, RecordContext, RenderPassPipeline, RenderPipelineSpec};
use volgraph_core::{ParamSpec, Params, PassDecl, PassNode, PassPlugin, PortKind, PortSpec, TargetFormat};

use crate::effects::{EffectFlags, EffectState, effect_defines, same_effects};
use crate::raycast_params::{RaycastParamsGpu, is_iso, raycast_param_specs};
use crate::shared::FLOAT_TARGETS;

/// The plugin.
pub struct Raycast;

/// The ports shared by both raycasters; `color_formats` differ (compute writes a storage texture
/// of one format).
pub(crate) fn raycast_ports(params: &Params, color: &[TargetFormat], hit: &[TargetFormat]) -> Vec<PortSpec> {
    let mut ports = vec![
        PortSpec::read("entry", PortKind::target(&FLOAT_TARGETS)),
        PortSpec::read("dir", PortKind::target(&FLOAT_TARGETS)),
        PortSpec::read("volume", PortKind::Volume),
        PortSpec::read("tf", PortKind::TransferFunction),
        PortSpec::write("color", PortKind::target(color)),
    ];
    if is_iso(params) {
        ports.push(PortSpec::write("hit", PortKind::target(hit)));
    }
    ports
}

impl PassDecl for Raycast {
    fn kind(&self) -> &'static str {
        "raycast"
    }

    fn summary(&self) -> &'static str {
        "single-pass fragment raycaster, DVR or first-hit isosurface (Krüger–Westermann 2003 §2.1–2.2)"
    }

    fn params(&self) -> Vec<ParamSpec> {
        [raycast_param_specs(), EffectFlags::specs(), RaycastOwn::specs()].concat()
    }

    fn shader_defines(&self, params: &Params) -> Vec<&'static str> {
        let own = RaycastOwn::from_params(params);
        let mut defines = effect_defines(params);
        if own.count_samples {
            defines.push("COUNT");
        }
        if own.analytic() {
            defines.push("ANALYTIC");
        }
        defines
    }

    fn ports(&self, params: &Params) -> Vec<PortSpec> {
        let own = RaycastOwn::from_params(params);
        let mut ports = raycast_ports(
            params,
            &[TargetFormat::Rgba16Float, TargetFormat::Rgba32Float],
            &[TargetFormat::Rgba32Float, TargetFormat::Rgba16Float],
        );
        if own.analytic() {
            ports.retain(|p| p.name != "entry" && p.name != "dir");
        }
        if own.leaps() {
            // The leap variant writes `leap_hit` instead of the exact isosurface `hit`.
            ports.retain(|p| p.name != "hit");
            // Leave unwired to start every ray at the box (the first frame of Klein's loop).
            ports.push(PortSpec::read("start", PortKind::target(&[TargetFormat::Rgba32Float])).optional());
            ports.push(PortSpec::write("leap_hit", PortKind::target(&[TargetFormat::Rgba32Float])));
        }
        if own.count_samples {
            ports.push(PortSpec::write("samples", PortKind::buffer(4 * crate::raycast_fast::SAMPLE_ROWS)));
        }
        ports
    }

    fn shaders(&self, params: &Params) -> Vec<ShaderUse> {
        let own = ShaderUse {
            file: "raycast.wgsl",
            entry_point: fragment_entry(params),
            extra: &["params", "preintegrated"],
        };
        [vec![own], crate::effects::effect_shader_uses(params)].concat()
    }

    fn updates_in_place(&self, old: &Params, new: &Params) -> bool {
        // Every parameter but the mode, the effects and the leap outputs is a uniform value.
        let (a, b) = (RaycastOwn::from_params(old), RaycastOwn::from_params(new));
        is_iso(old) == is_iso(new)
            && same_effects(old, new)
            && a.leaps() == b.leaps()
            && a.analytic() == b.analytic()
            && a.count_samples == b.count_samples
    }
}

impl PassPlugin for Raycast {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let fragment = fragment_entry(ctx.params);
        let mut defines = self.shader_defines(ctx.params);
        if ctx.port("start").is_some_and(|p| p.bound) {
            defines.push("START");
        }
        let pipeline = ctx.render_pipeline(&RenderPipelineSpec {
            shader: "raycast.wgsl",
            vertex: "vs_fullscreen",
            fragment,
            defines: &defines,
            ..Default::default()
        })?;
        let own = RaycastOwn::from_params(ctx.params);
        let settings = gpu_block(ctx.params);
        let params = ctx.uniform_from_bytes("params", &settings.uniform_bytes());
        let effects = EffectState::new(ctx)?;
        Ok(Box::new(RaycastNode {
            pipeline,
            params,
            effects,
            settings,
            conservative: own.step_back_rule == StepBackRule::Conservative,
            counted: own.count_samples,
            written_step_back: None,
        }))
    }
}

volgraph_core::param_choice! {
    /// Where a ray's entry and direction come from.
    pub enum Rays {
        /// The `entry` and `dir` inputs (K-W 2003 §2.1).
        Raster = "raster",
        /// Met with the box in the shader, no inputs needed.
        Analytic = "analytic",
    }
}

volgraph_core::param_choice! {
    /// How far a leap hit is moved back along the ray (Klein et al. 2005 §4.2).
    pub enum StepBackRule {
        /// `step_back` samples.
        Fixed = "fixed",
        /// ⌈|voxel diagonal| / step⌉, never missing a voxel.
        Conservative = "conservative",
    }
}

volgraph_core::pass_params! {
    /// The raycaster's own parameters: its rays and Klein et al. 2005's leap hits.
    pub struct RaycastOwn {
        rays: Rays = Raster,
            "raster: entry and direction from the `entry` and `dir` inputs (K-W 2003 §2.1); analytic: met with the box in \
             the shader, no inputs needed";
        leap_hits: bool = false,
            "write `leap_hit` (where the next frame's ray starts) and read the optional `start` estimate (Klein et al. 2005 §4.2)";
        step_back: u32 = 2, 0..=64, "samples a leap hit is moved back along the ray (the paper: one to three suffice)";
        step_back_rule: StepBackRule = Fixed,
            "fixed: step_back samples; conservative: ⌈|voxel diagonal| / step⌉, never missing a voxel (Klein et al. 2005 §4.2)";
        count_samples: bool = false, "add the samples taken to the `samples` buffer (benchmarks)";
    }
}

impl RaycastOwn {
    /// Whether the rays meet the box analytically (no `entry` / `dir` inputs).
    fn analytic(&self) -> bool {
        self.rays == Rays::Analytic
    }

    /// Whether the pass runs Klein's variant (leap hits written, or samples counted).
    fn leaps(&self) -> bool {
        self.leap_hits || self.count_samples
    }
}

fn fragment_entry(params: &Params) -> &'static str {
    match (is_iso(params), RaycastOwn::from_params(params).leaps()) {
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

/// ⌈|voxel diagonal| / h⌉ for the bound volume (Klein et al. 2005 §4.2's conservative bound).
fn conservative_step_back(volume: &volgraph_core::runtime::VolumeDesc, step_voxels: f64) -> f32 {
    let voxel = 2.0 * volume.half_extent / volume.dims.as_dvec3();
    (voxel.length() / (step_voxels * volume.unit_step)).ceil() as f32
}

struct RaycastNode {
    pipeline: RenderPassPipeline,
    params: wgpu::Buffer,
    effects: EffectState,
    /// What `params` holds (the conservative step back is filled in per volume).
    settings: RaycastParamsGpu,
    conservative: bool,
    counted: bool,
    written_step_back: Option<f32>,
}

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
        self.effects.update(ctx, &self.params, self.settings.step_voxels as f64)?;
        let mut extra = vec![("params", self.params.as_entire_binding())];
        extra.extend(self.effects.bindings());
        let bg = ctx.bind_group(&self.pipeline, &extra)?;
        let mut pass = ctx.begin_render_pass(&self.pipeline, None)?;
        crate::draw(&mut pass, &self.pipeline, &bg, 0..3);
        Ok(())
    }

    fn update_params(&mut self, gpu: &Gpu, params: &Params) {
        self.settings = gpu_block(params);
        self.conservative = RaycastOwn::from_params(params).step_back_rule == StepBackRule::Conservative;
        self.written_step_back = None;
        gpu.queue.write_buffer(&self.params, 0, &self.settings.uniform_bytes());
        self.effects.invalidate();
    }
}
