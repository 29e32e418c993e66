//! Parameters shared by the raycasters, declared once as blocks, and their GPU twin.
//!
//! Each block is a [`pass_params!`](volgraph_compiler::pass_params) declaration; a kind lists the
//! blocks it takes whole (`[Sampling::specs(), Termination::specs()].concat()`), and code that
//! serves several kinds reads a block with `try_from_params` (`Some` where the kind declares
//! it). No parameter name is written anywhere else. docs/rendering_model.md gives their meaning.

use volgraph_accel::reference::{Phong, RaycastSettings, RenderMode};
use volgraph_compiler::Params;
use volgraph_compiler::block::{OnChange, ParamBlock};

use crate::defines;
use crate::effects::EffectFlags;

volgraph_compiler::param_choice! {
    /// What a raycaster computes.
    pub enum Mode {
        /// Direct volume rendering: the emission–absorption integral.
        Dvr = "dvr",
        /// The first hit of the isosurface, Blinn–Phong shaded.
        Iso = "iso",
    }
}

volgraph_compiler::pass_params! {
    /// How each ray is sampled: every raycaster.
    pub struct Sampling {
        step_voxels: f64 = 0.5, 0.01..=16.0, "sample distance in units of the smallest voxel side";
        max_steps: u32 = 4096, 1..=1048576, "upper bound on samples per ray";
        jitter: bool = false, "offset each ray's first sample by a per-pixel hash (trades banding for noise)";
        jitter_per_frame: bool = false,
            "with jitter: move the offsets every frame (frame 0 keeps the stable ones), for accumulation";
    }
}

volgraph_compiler::pass_params! {
    /// Early ray termination (Krüger–Westermann 2003 §2.2).
    pub struct Termination {
        threshold: f64 = 1.0, 0.0..=1.0,
            "early ray termination once accumulated alpha reaches this (1 = off, lossless)";
    }
}

volgraph_compiler::pass_params! {
    /// What the raycaster computes: the integral or the first isosurface hit.
    pub struct Surface {
        mode: Mode = Dvr, "direct volume rendering or first-hit isosurface";
        iso_value: f64 = 0.5, 0.0..=1.0, "isovalue in normalized scalar units (mode \"iso\")";
    }
}

volgraph_compiler::pass_params! {
    /// Blinn–Phong headlight coefficients: the isosurface's, and DVR's with the shading effect.
    pub struct Shading {
        ambient: f64 = 0.15, 0.0..=1.0, "Blinn–Phong ambient coefficient (mode \"iso\", or the shading effect)";
        diffuse: f64 = 0.75, 0.0..=1.0, "Blinn–Phong diffuse coefficient (mode \"iso\", or the shading effect)";
        specular: f64 = 0.25, 0.0..=1.0, "Blinn–Phong specular coefficient (mode \"iso\", or the shading effect)";
        shininess: f64 = 32.0, 1.0..=512.0, "Blinn–Phong exponent (mode \"iso\", or the shading effect)";
    }
}

volgraph_compiler::pass_params! {
    /// The compute raycasters' workgroup.
    pub struct Workgroup {
        workgroup_x: u32 = 8, 1..=256, "workgroup width in pixels";
        workgroup_y: u32 = 8, 1..=256, "workgroup height in pixels";
    }
}

volgraph_compiler::param_choice! {
    /// How a compute raycaster's sample loop is built.
    pub enum SampleLoop {
        /// `pipelined` on a GPU, `plain` on a CPU adapter (llvmpipe).
        Auto = "auto",
        /// The TF read from its texture, each sample fetched as it is classified.
        Plain = "plain",
        /// The TF copied into workgroup memory, the next sample fetched before this one is
        /// classified.
        Pipelined = "pipelined",
    }
}

volgraph_compiler::pass_params! {
    /// The compute raycasters' sample loop (`raycast_compute`, `raycast_bricks`).
    pub struct SampleLoopChoice {
        sample_loop: SampleLoop = Auto,
            "pipelined: the TF copied into workgroup memory and interpolated by hand, the next sample fetched before \
             this one is classified (on an H200, 43 % → 94 % of the fetch ceiling: bench/device/README.md; slower on \
             llvmpipe, where workgroup memory and the extra fetch cost more than they hide); plain: neither; auto: \
             pipelined on GPUs, plain on CPU adapters";
    }
}

impl SampleLoopChoice {
    /// The defines of the pipelined loop (`TF_WORKGROUP`, `PREFETCH`) when `params` ask for it
    /// on an adapter that is (`Some(true)`) or is not a CPU; `None` at plan time, where only an
    /// explicit `pipelined` is known.
    pub fn defines(params: &volgraph_compiler::Params, cpu_adapter: Option<bool>) -> Vec<&'static str> {
        let pipelined = match Self::from_params(params).sample_loop {
            SampleLoop::Pipelined => true,
            SampleLoop::Plain => false,
            SampleLoop::Auto => cpu_adapter == Some(false),
        };
        if pipelined { vec![defines::TF_WORKGROUP, defines::PREFETCH] } else { Vec::new() }
    }

    /// The block: its plan-time defines; the pipeline is made with it (a rebuild).
    pub fn rebuild_block() -> ParamBlock {
        Self::block(OnChange::Rebuild).with_defines(|p| Self::defines(p, None))
    }

    /// `defines` at plan time followed by those `gpu` adds: the list a pipeline is built with.
    #[cfg(feature = "gpu")]
    pub fn with_gpu_defines(
        mut defines: Vec<&'static str>,
        params: &volgraph_compiler::Params,
        gpu: &volgraph_core::runtime::Gpu,
    ) -> Vec<&'static str> {
        for define in Self::defines(params, Some(gpu.is_cpu)) {
            if !defines.contains(&define) {
                defines.push(define);
            }
        }
        defines
    }
}

impl Shading {
    /// The coefficients of a kind that declares them, else 0 (what its shader never reads).
    pub fn of(p: &Params) -> Self {
        Self::try_from_params(p).unwrap_or(Self { ambient: 0.0, diffuse: 0.0, specular: 0.0, shininess: 0.0 })
    }
}

impl Workgroup {
    /// `(x, y)`.
    pub fn size(&self) -> (u32, u32) {
        (self.workgroup_x, self.workgroup_y)
    }

    /// The size a compute pass is created with, checked against the device's invocation limit:
    /// the one check every compute pass with a workgroup parameter makes in `create`.
    #[cfg(feature = "gpu")]
    pub fn checked_size(
        ctx: &volgraph_core::runtime::CreateContext<'_>,
    ) -> Result<(u32, u32), volgraph_core::runtime::PassError> {
        let (x, y) = Self::from_params(ctx.params).size();
        let limit = ctx.gpu.limits.max_compute_invocations_per_workgroup;
        let invocations = u64::from(x) * u64::from(y);
        if invocations > u64::from(limit) {
            return Err(volgraph_core::runtime::PassError {
                pass: ctx.pass_id.to_string(),
                message: format!(
                    "workgroup {x}x{y} has {invocations} invocations, over this GPU's limit of {limit}; choose \
                     workgroup_x × workgroup_y ≤ {limit}"
                ),
            });
        }
        Ok((x, y))
    }
}

/// The sampling block: its values travel in the raycasters' uniform, its `jitter` flags
/// compile the jitter in (`JITTER`, `JITTER_PER_FRAME`) — for every kind that takes it.
pub fn sampling_block(on_change: OnChange) -> ParamBlock {
    Sampling::block(on_change).with_defines(crate::effects::jitter_defines)
}

/// Every block of the full raycaster (`raycast`, `raycast_compute`, `raycast_segment`,
/// `antialias`): sampling, termination, isosurface and shading, taken in place by a node that
/// rewrites its [`RaycastParamsGpu`] (`on_change`). The mode picks an entry point, so a mode
/// switch rebuilds whatever the block says.
pub fn raycast_blocks(on_change: OnChange) -> Vec<ParamBlock> {
    vec![sampling_block(on_change), Termination::block(on_change), Surface::block(on_change), Shading::block(on_change)]
}

/// The parameters of [`raycast_blocks`] (what [`RaycastParamsGpu`] carries).
pub fn raycast_param_specs() -> Vec<volgraph_compiler::ParamSpec> {
    volgraph_compiler::block::block_params(&raycast_blocks(OnChange::InPlace))
}

volgraph_compiler::pass_params! {
    /// The raycasters' shared uniform `params`, imported by `shaders/common/raycast_params.wgsl`
    /// as the generated `params/RaycastParamsGpu.wgsl`. It has no
    /// parameters of its own; [`RaycastParamsGpu::of`] fills it from the blocks a kind declares.
    pub struct RaycastParamsGpu {
        step_voxels: f32 = computed, "sample distance in voxels";
        threshold: f32 = computed, "early-termination threshold (1 where the kind has none)";
        max_steps: u32 = computed, "upper bound on samples per ray";
        jitter: u32 = computed, "1: jitter the first sample";
        iso_value: f32 = computed, "isovalue (mode iso)";
        ambient: f32 = computed, "Blinn–Phong ambient";
        diffuse: f32 = computed, "Blinn–Phong diffuse";
        specular: f32 = computed, "Blinn–Phong specular";
        shininess: f32 = computed, "Blinn–Phong exponent";
        step_back: f32 = computed,
            "Klein et al. 2005 §4.2: samples a leap hit is moved back (set by `raycast` and `antialias` from their step back; 0 elsewhere)";
    }
}

impl RaycastParamsGpu {
    /// This block as the uniform `global` of a shader use: its bytes are [`Self::of`] the
    /// blocks a kind declares, so every parameter of those blocks is carried by it.
    pub fn bound(global: &'static str) -> volgraph_compiler::UniformLayout {
        let params = raycast_param_specs().iter().map(|s| s.name).collect();
        Self::bound_as_with(global, params, |p| Self::of(p).uniform_bytes())
    }

    /// The block of a raycaster's parameters: the sampling every raycaster declares, and the
    /// termination, isosurface and shading blocks where its kind declares them (else what the
    /// shader never reads: no termination, 0).
    pub fn of(p: &Params) -> Self {
        let sampling = Sampling::from_params(p);
        let threshold = Termination::try_from_params(p).map_or(1.0, |t| t.threshold);
        let iso_value = Surface::try_from_params(p).map_or(0.0, |s| s.iso_value);
        let shading = Shading::of(p);
        Self {
            step_voxels: sampling.step_voxels as f32,
            threshold: threshold as f32,
            max_steps: sampling.max_steps,
            jitter: sampling.jitter as u32,
            iso_value: iso_value as f32,
            ambient: shading.ambient as f32,
            diffuse: shading.diffuse as f32,
            specular: shading.specular as f32,
            shininess: shading.shininess as f32,
            step_back: 0.0,
        }
    }
}

/// Whether the parameters ask for the isosurface (kinds without the [`Surface`] block are DVR).
pub fn is_iso(p: &Params) -> bool {
    Surface::try_from_params(p).is_some_and(|s| s.mode == Mode::Iso)
}

/// The CPU reference settings equivalent to a raycast pass's parameters, so tests render the
/// same integral on both sides.
pub fn reference_settings(p: &Params) -> RaycastSettings {
    let sampling = Sampling::from_params(p);
    let effects = EffectFlags::of(p);
    let shading = Shading::of(p);
    let phong = Phong {
        ambient: shading.ambient,
        diffuse: shading.diffuse,
        specular: shading.specular,
        shininess: shading.shininess,
    };
    let iso = Surface::try_from_params(p).map_or(0.0, |s| s.iso_value);
    RaycastSettings {
        step_voxels: sampling.step_voxels,
        threshold: Termination::try_from_params(p).map_or(1.0, |t| t.threshold),
        max_steps: sampling.max_steps,
        jitter: sampling.jitter,
        effects: volgraph_accel::reference::Effects {
            shading: effects.shading,
            preintegration: effects.preintegration,
            tricubic: effects.tricubic,
            shadows: effects.shadows,
            ambient_occlusion: effects.ambient_occlusion,
        },
        dvr_shading: phong,
        opacity_unit_voxels: 1.0,
        mode: if is_iso(p) { RenderMode::Isosurface { iso, shading: phong } } else { RenderMode::Dvr },
        // Cuts and the lights are the frame's, not a pass's: a test sets the runtime's and the
        // reference's alike.
        cuts: volgraph_accel::cuts::Cuts::NONE,
        lights: volgraph_accel::light::Lights::one(volgraph_accel::light::Light::Headlight),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Rust block and the shader's `RaycastParams` have the same members in the same order.
    #[test]
    fn the_gpu_block_matches_the_shader_struct() {
        RaycastParamsGpu::check_shader(&crate::shared::assembled("raycast.wgsl"), "RaycastParamsGpu")
            .expect("the layouts agree");
        assert_eq!(RaycastParamsGpu::of(&Params::defaults(&raycast_param_specs())).uniform_bytes().len(), 48);
    }

    #[test]
    fn blocks_a_kind_does_not_declare_read_as_what_the_shader_ignores() {
        let params = Params::defaults(&Sampling::specs());
        let gpu = RaycastParamsGpu::of(&params);
        assert_eq!((gpu.threshold, gpu.iso_value, gpu.ambient), (1.0, 0.0, 0.0));
        assert!(!is_iso(&params));
        let full = Params::defaults(&raycast_param_specs());
        assert_eq!(RaycastParamsGpu::of(&full).ambient, 0.15);
    }
}
