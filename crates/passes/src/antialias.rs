//! `antialias`: Klein et al. 2005 §5's selective super-sampling. A pixel whose colour differs
//! from a 4-neighbour by more than `contrast` is re-rendered from sub-pixel rays — `pattern` 2x
//! (diagonal pair), 4x (regular grid) or rgss (4x rotated grid) — with directions interpolated
//! from its own and its neighbours' ray directions (`directions`: linear from two neighbours as
//! in the paper's Fig. 7 left, bilinear from three, or the camera's exact ones), each starting
//! from the nearest leap hit of the pixel and its neighbours on its own step grid; the colour is
//! their mean. `selection: "full"` re-renders every pixel: full-scene super-sampling, the
//! baseline. Its raycast parameters (step, threshold, mode, isovalue, shading, step back) must
//! be the raycaster's: share them through Scalar inputs. Shader: `shaders/antialias.wgsl`.

use crate::effects::effect_block;
use crate::raycast_params::raycast_blocks;
use volgraph_compiler::block::{OnChange, ParamBlock};
use volgraph_compiler::{Params, PassDecl, PortKind, PortSpec, ShaderUse, TargetFormat};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{CreateContext, Gpu, PassError, RecordContext, RenderPassPipeline, RenderPipelineSpec};
#[cfg(feature = "gpu")]
use volgraph_core::{PassNode, PassPlugin};

use volgraph_compiler::declare::ParamChoice;

#[cfg(feature = "gpu")]
use crate::effects::EffectState;
use crate::effects::effect_shader_uses;
use crate::raycast_params::{RaycastParamsGpu, Sampling, is_iso};
use crate::shared::FLOAT_TARGETS;

/// The plugin.
pub struct Antialias;

volgraph_compiler::pass_params! {
    /// The `aa` block of `shaders/antialias.wgsl` (which imports it), made from [`AaOwn`].
    struct AaParams {
        contrast: f32 = computed, "Colour difference to a 4-neighbour that flags a pixel.";
        pattern: u32 = computed, "2: 2x, 4: 4x regular, 5: 4x rotated grid.";
        directions: u32 = computed, "0: linear, 1: bilinear, 2: exact.";
        full: u32 = computed, "1: every pixel (full-scene super-sampling).";
    }
}

/// The block as the shader use declares it (bound as `aa`), so the plan checks the WGSL struct
/// member by member; the node writes it itself.
fn aa_layout() -> volgraph_compiler::UniformLayout {
    AaParams::bound_as_with("aa", Vec::new(), |p| AaParams::of(p).uniform_bytes())
}

volgraph_compiler::param_choice! {
    /// The sub-pixel pattern.
    pub enum Pattern { Two = "2x", Four = "4x", RotatedGrid = "rgss" }
}

volgraph_compiler::param_choice! {
    /// Where the sub-pixel rays' directions come from.
    pub enum Directions { Linear = "linear", Bilinear = "bilinear", Exact = "exact" }
}

volgraph_compiler::param_choice! {
    /// Which pixels are re-rendered.
    pub enum Selection { Selective = "selective", Full = "full" }
}

volgraph_compiler::pass_params! {
    /// The antialiasing pass's own parameters (Klein et al. 2005 §5).
    pub struct AaOwn {
        step_back: u32 = 2, 0..=64, "the raycaster's step back (sub-pixel rays start like its rays)";
        contrast: f32 = 0.05, 0.0..=1.0, "colour difference to a 4-neighbour (any channel) that flags a pixel";
        pattern: Pattern = Four, "sub-pixel pattern: 2 diagonal, 4 regular, 4 rotated grid";
        directions: Directions = Linear, "sub-pixel directions from two neighbours (the paper), three, or the camera";
        selection: Selection = Selective, "re-render flagged pixels only, or every pixel (full-scene super-sampling)";
    }
}

impl AaParams {
    fn of(p: &Params) -> Self {
        let own = AaOwn::from_params(p);
        Self {
            contrast: own.contrast,
            // The shader's pattern code: its sample count, 5 for the rotated grid's 4.
            pattern: match own.pattern {
                Pattern::Two => 2,
                Pattern::Four => 4,
                Pattern::RotatedGrid => 5,
            },
            directions: own.directions.index() as u32,
            full: (own.selection == Selection::Full) as u32,
        }
    }
}

/// The raycaster's block with its step back, so sub-pixel rays start like its rays.
fn ray_block(p: &Params) -> RaycastParamsGpu {
    RaycastParamsGpu { step_back: AaOwn::from_params(p).step_back as f32, ..RaycastParamsGpu::of(p) }
}

/// Its pipeline for these parameters.
fn shader(params: &Params) -> ShaderUse {
    ShaderUse::new("antialias.wgsl", if is_iso(params) { "fs_aa_iso" } else { "fs_aa_dvr" })
        .binds(&["preintegrated", "light_volume"])
        .uniform(aa_layout())
        .uniform(RaycastParamsGpu::bound("params"))
}

impl PassDecl for Antialias {
    fn honours_volume_window(&self) -> bool {
        true
    }

    fn kind(&self) -> &'static str {
        "antialias"
    }

    fn scene_effects(&self) -> &'static [&'static str] {
        &crate::effects::SCENE_EFFECTS
    }

    fn summary(&self) -> &'static str {
        "selective super-sampling where a pixel differs from a 4-neighbour; 2x, 4x, rotated grid (Klein et al. 2005 §5)"
    }

    fn blocks(&self) -> Vec<ParamBlock> {
        // The sub-pixel rays march like the raycaster's, scene effects included (wire the same
        // features to both); the node rewrites both uniforms in place.
        [raycast_blocks(OnChange::InPlace), vec![effect_block(), AaOwn::block(OnChange::InPlace)]].concat()
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read("color", PortKind::target(&FLOAT_TARGETS)),
            PortSpec::read("hits", PortKind::target(&[TargetFormat::Rgba32Float])),
            PortSpec::read("volume", PortKind::Volume),
            PortSpec::read("tf", PortKind::TransferFunction),
            PortSpec::write("color_aa", PortKind::target(&[TargetFormat::Rgba16Float, TargetFormat::Rgba32Float])),
        ]
    }

    fn shaders(&self, params: &Params) -> Vec<ShaderUse> {
        [vec![shader(params)], effect_shader_uses(params, true)].concat()
    }
}

#[cfg(feature = "gpu")]
impl PassPlugin for Antialias {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let defines = self.shader_defines(ctx.params);
        let pipeline = ctx.render_pipeline(&RenderPipelineSpec {
            defines: &defines,
            ..RenderPipelineSpec::fullscreen(&shader(ctx.params))
        })?;
        let params = ctx.uniform_from_bytes("params", &ray_block(ctx.params).uniform_bytes());
        let aa = ctx.uniform_from_bytes("aa", &AaParams::of(ctx.params).uniform_bytes());
        let effects = EffectState::new(ctx, true)?;
        let step_voxels = Sampling::from_params(ctx.params).step_voxels;
        Ok(Box::new(AntialiasNode { pipeline, params, aa, effects, step_voxels }))
    }
}

#[cfg(feature = "gpu")]
struct AntialiasNode {
    pipeline: RenderPassPipeline,
    params: wgpu::Buffer,
    aa: wgpu::Buffer,
    /// The pre-integration table when that effect is on.
    effects: EffectState,
    step_voxels: f64,
}

#[cfg(feature = "gpu")]
impl PassNode for AntialiasNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        self.effects.update(ctx, &self.params, self.step_voxels, &[])?;
        let mut bindings = vec![("params", self.params.as_entire_binding()), ("aa", self.aa.as_entire_binding())];
        bindings.extend(self.effects.bindings());
        let bg = ctx.bind_group(&self.pipeline, &bindings)?;
        ctx.draw_fullscreen(&self.pipeline, &bg)
    }

    fn update_params(&mut self, gpu: &Gpu, params: &Params) {
        gpu.queue.write_buffer(&self.params, 0, &ray_block(params).uniform_bytes());
        gpu.queue.write_buffer(&self.aa, 0, &AaParams::of(params).uniform_bytes());
        self.step_voxels = Sampling::from_params(params).step_voxels;
        self.effects.invalidate();
    }
}
