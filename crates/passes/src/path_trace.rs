//! `path_trace`: a progressive volumetric path tracer (issue "light that scatters", item 2), one
//! path per pixel per frame averaged into a running mean that a graph keeps as history while the
//! view rests (`graphs/cinematic/path_traced.ron`: `while_camera_still`).
//!
//! - Free paths by delta (Woodcock) tracking against a majorant — the extinction of the TF's
//!   largest opacity, recomputed when the TF changes — and the transmittance toward each light by
//!   ratio tracking, or delta tracking's 0-or-1 visibility (`shadow_rays`; Novák et al. 2014, §3
//!   and §5.2);
//! - single and multiple scattering (`bounces`) with a Henyey–Greenstein phase function
//!   (`anisotropy`), or off a Lambertian surface with probability `surface` · (1 − e^(−20 |∇s|))
//!   (Kroes et al. 2012, "Exposure Render", §4.3's hybrid scattering);
//! - the scene's lights (one to three: directional, point or the headlight; at every scattering
//!   event a shadow ray toward each, their direct light summed) and an environment: the scene's map
//!   (`Runtime::set_environment`, bound as `environment_map`), else a generated sky, or a
//!   uniform one (the white furnace);
//! - an interaction scatters with probability `albedo`, tinted by the TF colour, and otherwise
//!   absorbs, emitting `emission` × the TF colour — both in expectation: the path carries the
//!   albedo in its throughput (Russian roulette ends dim paths), and the light toward each light
//!   is weighted by the mixture of the surface and phase lobes, the next direction drawn from
//!   one (docs/accuracy.md "Path tracing");
//! - the pixel's alpha by ratio tracking along the primary ray (`coverage`), over the tentative
//!   collisions its delta tracking draws anyway;
//! - with albedo 0 and emission 1 the estimate is the emission–absorption integral the
//!   raycasters march (tests/path_trace.rs compares it with the f64 reference at a fine step).
//!
//! The TF's opacity α per opacity unit L is the extinction σ = −ln(1 − α) / L: the continuous
//! form of the raycasters' per-step correction 1 − (1 − α)^(Δ/L). Reads last frame's mean
//! (`previous`) and writes the new one (`color`, `Rgba32Float`: an f16 mean stops moving after
//! ~2048 samples). Shader: `shaders/path_trace.wgsl`.

use volgraph_compiler::block::{OnChange, ParamBlock};
use volgraph_compiler::{Params, PassDecl, PortKind, PortSpec, ShaderUse, TargetFormat};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{ComputePassPipeline, ComputePipelineSpec, CreateContext, Gpu, PassError, RecordContext};
#[cfg(feature = "gpu")]
use volgraph_core::{PassNode, PassPlugin};

/// The plugin.
pub struct PathTrace;

volgraph_compiler::param_choice! {
    /// What a path that leaves the volume sees.
    pub enum Environment {
        /// The scene's environment map where it has one (`--environment sky.exr`), else a
        /// generated sky: ground, horizon and zenith along world +y.
        Sky = "sky",
        /// The same radiance from every direction (the white furnace).
        Uniform = "uniform",
    }
}

volgraph_compiler::param_choice! {
    /// What free paths are sampled against.
    pub enum Majorant {
        /// The TF's most opaque value's extinction, everywhere.
        Global = "global",
        /// Each block's own, from a wired `majorants` grid (`majorant_grid`).
        Blocks = "blocks",
    }
}

volgraph_compiler::param_choice! {
    /// How a path estimates the light's transmittance (Novák et al. 2014 §5).
    pub enum ShadowRays {
        /// Ratio tracking: the product of (1 − σ/σ̄) over tentative collisions.
        Ratio = "ratio",
        /// Delta tracking: 1 if the shadow ray reaches the light, else 0.
        Delta = "delta",
    }
}

volgraph_compiler::param_choice! {
    /// How a path estimates its pixel's coverage (alpha): the share of the primary ray's light
    /// the medium stops, 1 − T.
    pub enum Coverage {
        /// Ratio tracking along the primary ray: 1 − the product of (1 − σ/σ̄) over its
        /// tentative collisions (Novák et al. 2014 §5.2) — a value per path, not 0 or 1.
        Ratio = "ratio",
        /// 1 when the path interacted, else 0: the colour's own estimator (a white furnace
        /// sample is then exactly (a, a, a, a)).
        Interaction = "interaction",
    }
}

volgraph_compiler::pass_params! {
    /// The parameters, declared once: spec, typed values and `PathTraceParams` of
    /// `shaders/path_trace.wgsl` (`max_alpha` the node computes from the TF).
    pub struct PathTraceParams {
        albedo: f32 = 0.9, 0.0..=1.0,
            "probability that an interaction scatters (tinted by the TF colour); otherwise it absorbs and emits";
        emission: f32 = 0.0, 0.0..=100.0,
            "radiance an absorbing interaction emits, times the TF colour (albedo 0, emission 1: the DVR integral)";
        anisotropy: f32 = 0.0, -0.95..=0.95, "Henyey–Greenstein g: < 0 back-scatters, > 0 forward-scatters";
        surface: f32 = 0.5, 0.0..=1.0,
            "how much a strong gradient scatters as a Lambertian surface instead of the phase function (Kroes et al. 2012)";
        bounces: u32 = 4, 0..=64, "scattering events a path may take before it ends";
        russian_roulette: bool = true,
            "from the second scattering on, a path whose largest throughput channel c is below 1/4 goes on with probability 4c, its throughput divided by it (unbiased)";
        light_intensity: f32 = 2.0, 0.0..=1000.0, "irradiance of each of the scene's lights (a point light's one world unit away)";
        environment: Environment = Sky,
            "what paths leaving the volume see: the scene's environment map where it has one, else a generated sky; or a uniform radiance";
        environment_intensity: f32 = 0.6, 0.0..=1000.0, "radiance scale of the environment";
        seed: u32 = 0, 0..=4294967295, "seed of the random sequence (each frame and pixel draws its own stream)";
        majorant: Majorant = Global,
            "free paths against the TF's largest extinction (global) or each block's (blocks: wire `majorants`)";
        block_size: u32 = 8, 1..=256, "with majorant blocks: the minmax_grid pass's block size";
        leap: bool = false,
            "with majorant blocks: cross the largest cube of empty blocks around a path at once, by the Chebyshev distance map (wire `distance` from empty_distance)";
        reproject: bool = false,
            "keep each pixel's mean across camera moves, found where its surface was last frame (wire previous_aux/aux)";
        reproject_keep: u32 = 32, 1..=65536, "after a camera move, a reprojected pixel keeps at most this many samples";
        reproject_tolerance: f32 = 2.0, 0.0..=1000.0,
            "voxels between this frame's surface point and last frame's mean point for a pixel to continue its mean";
        shadow_rays: ShadowRays = Ratio,
            "the light's transmittance by ratio tracking (smooth) or delta tracking (0 or 1: cheaper, noisier)";
        coverage: Coverage = Ratio,
            "the pixel's alpha by ratio tracking along the primary ray (smooth) or whether the path interacted (0 or 1)";
        max_alpha: f32 = computed, "the TF's largest opacity: the majorant's";
        environment_map: u32 = computed, "1: paths leaving see the scene's environment map (bound as environment_map)";
    }
}

/// Whether free paths step block by block (`majorant: "blocks"`).
fn by_blocks(params: &Params) -> bool {
    PathTraceParams::from_params(params).majorant == Majorant::Blocks
}

/// Whether free paths cross cubes of empty blocks at once (`leap`, with block majorants).
fn leaps(params: &Params) -> bool {
    by_blocks(params) && PathTraceParams::from_params(params).leap
}

/// Whether each pixel's mean follows its surface across camera moves (`reproject`).
fn reprojects(params: &Params) -> bool {
    PathTraceParams::from_params(params).reproject
}

/// Its one pipeline, declared once; with several volumes (`fusion`) it reads their combination
/// through the `fusion` uniform and label quads, as the raycasters do.
fn shader(params: &Params) -> ShaderUse {
    crate::fusion::with_fusion_uniform(
        ShaderUse::new("path_trace.wgsl", "cs_path_trace")
            .binds(&["label_quads"])
            .uniform(PathTraceParams::bound_as("trace")),
        params,
    )
}

/// The workgroup (`@workgroup_size`).
const WORKGROUP: (u32, u32) = (8, 8);

/// The TF's largest opacity: every interpolated value lies between two texels, so the majorant
/// made from it bounds the extinction everywhere (a NaN texel counts as opaque).
pub fn max_alpha(lut: &[[f32; 4]]) -> f32 {
    lut.iter().map(|t| if t[3].is_nan() { 1.0 } else { t[3].clamp(0.0, 1.0) }).fold(0.0, f32::max)
}

impl PassDecl for PathTrace {
    /// Paths are cut like the raycasters' rays (`world_segment` → `cut_segment`): the primary
    /// ray's, each scattered path's and each shadow ray's (material cut away casts no shadow).
    /// The kept region is convex, so a path from inside leaves it once. No sort-last window:
    /// scattered light crosses every rank's box.
    fn takes_cuts(&self) -> bool {
        true
    }

    fn kind(&self) -> &'static str {
        "path_trace"
    }

    fn summary(&self) -> &'static str {
        "progressive volumetric path tracer: delta tracking, ratio-tracked shadow rays, Henyey–Greenstein and \
         gradient-surface scattering, a light and an environment, a running mean over still frames \
         (Novák et al. 2014; Kroes et al. 2012)"
    }

    fn blocks(&self) -> Vec<ParamBlock> {
        // Every value is a uniform (a change restarts the accumulation: the graph's history);
        // block majorants add a port and a define.
        vec![
            crate::fusion::fusion_block(),
            PathTraceParams::block(OnChange::InPlace).with_defines(|p| {
                let mut defines = Vec::new();
                if by_blocks(p) {
                    defines.push(crate::defines::BLOCK_MAJORANTS);
                }
                if leaps(p) {
                    defines.push(crate::defines::MAJORANT_LEAP);
                }
                if reprojects(p) {
                    defines.push(crate::defines::REPROJECT);
                }
                defines
            }),
        ]
    }

    fn updates_in_place(&self, old: &Params, new: &Params) -> bool {
        by_blocks(old) == by_blocks(new)
            && leaps(old) == leaps(new)
            && reprojects(old) == reprojects(new)
            && crate::fusion::FusionSettings::of(old) == crate::fusion::FusionSettings::of(new)
    }

    fn ports(&self, params: &Params) -> Vec<PortSpec> {
        let mut ports = vec![
            PortSpec::read("volume", PortKind::Volume),
            PortSpec::read("tf", PortKind::TransferFunction),
            PortSpec::read("previous", PortKind::target(&[TargetFormat::Rgba32Float])),
            PortSpec::write("color", PortKind::target(&[TargetFormat::Rgba32Float])),
        ];
        if by_blocks(params) {
            ports.push(PortSpec::read("majorants", PortKind::Owned(crate::majorant_grid::MAJORANT_GRID)));
        }
        if leaps(params) {
            ports.push(PortSpec::read("distance", PortKind::Owned(crate::empty_distance::EMPTY_DISTANCE)));
        }
        if reprojects(params) {
            ports.push(PortSpec::read("previous_aux", PortKind::target(&[TargetFormat::Rgba32Float])));
            ports.push(PortSpec::write("aux", PortKind::target(&[TargetFormat::Rgba32Float])));
        }
        ports.extend(crate::fusion::FusionSettings::of(params).ports());
        ports
    }

    fn shaders(&self, params: &Params) -> Vec<ShaderUse> {
        vec![shader(params)]
    }
}

#[cfg(feature = "gpu")]
impl PassPlugin for PathTrace {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let settings = PathTraceParams::from_params(ctx.params);
        let fusion_settings = crate::fusion::FusionSettings::of(ctx.params);
        let refuse = |message: String| PassError { pass: ctx.pass_id.to_string(), message };
        match fusion_settings.combine() {
            Some(volgraph_accel::fusion::Combine::Labels) => {
                return Err(refuse(
                    "fusion \"labels\" (a label map alone) is not path traced: the path tracer's medium is a scan \
                     through its TF; use fusion \"tint\" or \"inside\" with the scan as the volume"
                        .to_string(),
                ));
            }
            Some(combine) if !combine.bounded_by_first() && settings.majorant == Majorant::Blocks => {
                return Err(refuse(format!(
                    "fusion \"{}\" can be opaque where the volume is empty, so the volume's block majorants do not \
                     bound it; use majorant \"global\" (graphs/multi/pet_ct_path_traced.ron)",
                    volgraph_compiler::declare::ParamChoice::name(fusion_settings.fusion)
                )));
            }
            _ => {}
        }
        let fusion = crate::fusion::FusionState::new(ctx)?;
        let defines = self.shader_defines(ctx.params);
        let pipeline = ctx.compute_pipeline(&ComputePipelineSpec {
            defines: &defines,
            ..ComputePipelineSpec::of(&shader(ctx.params))
        })?;
        let uniform = ctx.uniform_from_bytes("trace", &settings.uniform_bytes());
        let partners = fusion_settings.scalar_partners().iter().map(|(_, tf)| *tf).collect();
        Ok(Box::new(PathTraceNode { pipeline, uniform, settings, written: None, fusion, partners, fusion_settings }))
    }
}

#[cfg(feature = "gpu")]
struct PathTraceNode {
    pipeline: ComputePassPipeline,
    uniform: wgpu::Buffer,
    settings: PathTraceParams,
    /// The block last written, with the TF versions its majorant came from and whether the
    /// scene had an environment map.
    written: Option<(PathTraceParams, (Vec<Option<u64>>, bool))>,
    /// Several volumes: their combination's uniform and bindings.
    fusion: crate::fusion::FusionState,
    /// The TF ports of the scalar volumes fused with the volume (`fuse`, `add`).
    partners: Vec<&'static str>,
    fusion_settings: crate::fusion::FusionSettings,
}

#[cfg(feature = "gpu")]
impl PathTraceNode {
    /// The largest opacity of the medium: the TF's, or the combination's of several volumes
    /// (`volgraph_accel::fusion::max_alpha`, as the f64 tracer takes it).
    fn max_alpha(&self, ctx: &RecordContext<'_>) -> Result<f32, PassError> {
        let first = max_alpha(ctx.table("tf")?);
        let Some(combine) = self.fusion_settings.combine() else { return Ok(first) };
        let mut maxima = vec![f64::from(first)];
        for port in &self.partners {
            maxima.push(f64::from(max_alpha(ctx.table(port)?)));
        }
        Ok(volgraph_accel::fusion::max_alpha(combine, &maxima) as f32)
    }
}

#[cfg(feature = "gpu")]
impl PassNode for PathTraceNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        if self.settings.majorant == Majorant::Blocks {
            let dims = ctx.voxels("volume")?.dims;
            crate::empty_space::check_block_grid(ctx, "majorants", self.settings.block_size, dims.to_array())?;
            if self.settings.leap {
                crate::empty_space::check_block_grid(ctx, "distance", self.settings.block_size, dims.to_array())?;
            }
        }
        self.fusion.update(ctx)?;
        let tfs = std::iter::once("tf").chain(self.partners.iter().copied()).map(|port| ctx.input_version(port));
        let version = (tfs.collect::<Vec<_>>(), ctx.frame.environment);
        if self.written.as_ref().is_none_or(|(_, v)| *v != version) {
            // The scene's map stands in for the generated sky (a uniform environment stays one).
            let environment_map = u32::from(ctx.frame.environment && self.settings.environment == Environment::Sky);
            let block = PathTraceParams { max_alpha: self.max_alpha(ctx)?, environment_map, ..self.settings };
            ctx.write_buffer(&self.uniform, 0, &block.uniform_bytes());
            self.written = Some((block, version));
        }
        let mut bindings = vec![("trace", self.uniform.as_entire_binding())];
        bindings.extend(self.fusion.bindings());
        ctx.dispatch_over(&self.pipeline, &bindings, "color", WORKGROUP)
    }

    fn update_params(&mut self, _gpu: &Gpu, params: &Params) {
        // Written with the TF's majorant when the pass next records.
        self.settings = PathTraceParams::from_params(params);
        self.written = None;
    }
}

#[cfg(test)]
mod tests {
    use super::max_alpha;

    /// The majorant's opacity is the LUT's largest, clamped; a NaN texel counts as opaque so
    /// delta tracking never under-estimates it.
    #[test]
    fn the_majorant_bounds_every_texel() {
        assert_eq!(max_alpha(&[[0.0; 4], [1.0, 1.0, 1.0, 0.25], [0.0, 0.0, 0.0, 0.5]]), 0.5);
        assert_eq!(max_alpha(&[[0.0, 0.0, 0.0, f32::NAN]]), 1.0);
        assert_eq!(max_alpha(&[[0.0, 0.0, 0.0, 7.0]]), 1.0);
        assert_eq!(max_alpha(&[]), 0.0);
    }
}
