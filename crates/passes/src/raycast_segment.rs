//! `raycast_segment`: Krüger & Westermann 2003 §2.1 "main passes 3 to N" — each pass performs
//! M steps along every ray from where the previous segment stopped and blends the segment into
//! the accumulation target RES front to back. Segment `i` (the repeat group's iteration) covers
//! samples `[i·M, (i+1)·M)` of the single-pass raycaster's sample sequence
//! (`docs/rendering_model.md`), and the blend `RES += (1 - RES.a)·segment` (src factor
//! OneMinusDstAlpha, dst factor One) composites exactly like the single pass, so with no
//! termination the result equals the single-pass raycast.
//!
//! RES is a Modify port (blended in place: the scheduler keeps the whole loop in one texture
//! instead of ping-ponging). When the optional `depth` port is wired, segments are drawn with
//! the depth test GREATER against the early-z buffer that `termination_test` writes, so
//! fragments of terminated rays never run (§2.1; the shader writes no depth, keeping early-z
//! on). Mode `iso` is §2.2: the closest hit of each segment, shaded, alpha 1.
//!
//! The scene effects (shading, pre-integration, tricubic reconstruction, jitter: `effects.rs`)
//! come from the shared march, as in the single-pass raycasters: a segment resumes a ray where
//! the last one stopped, pre-integration included (its first segment takes the sample before).
//!
//! Debugging early-z: [`RaycastSegment::counting`] registers a variant whose fragment shader
//! counts its invocations (`shaders/raycast_segment_counted.wgsl`, forced early depth test).
//! Shader: `shaders/raycast_segment.wgsl`.

use crate::effects::effect_block;
use crate::raycast_params::raycast_blocks;
use std::sync::{Arc, Mutex};
use volgraph_compiler::block::{OnChange, ParamBlock};

use volgraph_compiler::{Params, PassDecl, PortKind, PortSpec, ShaderUse, TargetFormat};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::footprint::FAN_DRAW_VERTICES;
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{
    CreateContext, DepthSpec, Gpu, PassError, RecordContext, RenderPassPipeline, RenderPipelineSpec,
};
#[cfg(feature = "gpu")]
use volgraph_core::{PassNode, PassPlugin};

use crate::defines;
#[cfg(feature = "gpu")]
use crate::effects::EffectState;
use crate::effects::effect_shader_uses;
use crate::empty_space::EMPTY_BLOCKS;
use crate::raycast_params::{RaycastParamsGpu, Sampling, Termination, is_iso};
#[cfg(feature = "gpu")]
use crate::shared::front_to_back_blend;
use crate::shared::{ACCUM_FORMATS, BlockSize, FLOAT_TARGETS, HIT_FORMATS};

/// The plugin. [`Default`] is the production pass; [`RaycastSegment::counting`] adds the debug
/// invocation counter.
#[derive(Default)]
pub struct RaycastSegment {
    #[cfg(feature = "gpu")]
    counter: Option<InvocationCounter>,
}

impl RaycastSegment {
    /// Whether this is the counting variant (a bench tool's; never without the `gpu` feature).
    fn counts(&self) -> bool {
        #[cfg(feature = "gpu")]
        return self.counter.is_some();
        #[cfg(not(feature = "gpu"))]
        false
    }
}

#[cfg(feature = "gpu")]
impl RaycastSegment {
    /// A `raycast_segment` whose fragment shader counts its invocations into `counter` (cleared
    /// at the first segment of every frame). Register it in place of the built-in one.
    pub fn counting(counter: InvocationCounter) -> Self {
        Self { counter: Some(counter) }
    }
}

#[cfg(feature = "gpu")]
/// A handle on the fragment-invocation counter of a counting [`RaycastSegment`]; clone it, give
/// one clone to [`RaycastSegment::counting`], and read it after a frame.
#[derive(Clone, Default)]
pub struct InvocationCounter {
    buffer: Arc<Mutex<Option<wgpu::Buffer>>>,
}

#[cfg(feature = "gpu")]
impl InvocationCounter {
    /// A counter not yet attached to a pass.
    pub fn new() -> Self {
        Self::default()
    }

    /// The number of segment fragment invocations of the last frame, or an error when no
    /// counting pass has been built (or the readback failed).
    pub fn read(&self, gpu: &Gpu) -> Result<u32, String> {
        let guard = self.buffer.lock().map_err(|_| "invocation counter lock poisoned".to_string())?;
        let buffer = guard.as_ref().ok_or("no counting raycast_segment pass has been built")?;
        let bytes = volgraph_core::runtime::readback::read_buffer(gpu, buffer, 0, 4)?;
        let value = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]);
        Ok(value)
    }
}

volgraph_compiler::pass_params! {
    /// The `segment` block of `shaders/common/segment.wgsl` (which imports it), made from the
    /// [`SegmentSteps`], [`BlockSize`] and [`Termination`] blocks.
    pub struct SegmentParams {
        steps: u32 = computed, "M: samples per segment.";
        block_size: u32 = computed,
            "Edge of an empty-space block in voxels (leaping inside a segment, the termination test).";
        threshold: f32 = computed, "T: the termination test stops rays whose accumulated alpha is >= T.";
    }
}

impl SegmentParams {
    /// The block as a shader use declares it (bound as `segment`), so the plan checks the WGSL
    /// struct member by member. The node writes it itself (no parameter is claimed for
    /// in-place updates).
    pub fn layout() -> volgraph_compiler::UniformLayout {
        Self::bound_as_with("segment", Vec::new(), |p| Self::of(p).uniform_bytes())
    }

    /// From the checked parameters of a kind that declares the [`SegmentSteps`], [`BlockSize`]
    /// and [`Termination`] blocks (`raycast_segment`, `termination_test`).
    pub fn of(p: &Params) -> Self {
        Self {
            steps: SegmentSteps::from_params(p).segment_steps,
            block_size: BlockSize::of(p),
            threshold: Termination::from_params(p).threshold as f32,
        }
    }
}

volgraph_compiler::pass_params! {
    /// The segment length, shared with `termination_test` (both must agree).
    pub struct SegmentSteps {
        segment_steps: u32 = 8, 1..=4096,
            "M: samples per segment (Krüger–Westermann used 8); the repeat count divides by it";
    }
}

#[cfg(feature = "gpu")]
/// The segment index this record is for: the repeat iteration (0 outside a repeat group).
pub(crate) fn segment_index(ctx: &RecordContext<'_>) -> u32 {
    ctx.iteration.map_or(0, |(i, _)| i)
}

impl PassDecl for RaycastSegment {
    fn honours_volume_window(&self) -> bool {
        true
    }

    fn kind(&self) -> &'static str {
        "raycast_segment"
    }

    fn scene_effects(&self) -> &'static [&'static str] {
        &crate::effects::SCENE_EFFECTS
    }

    fn summary(&self) -> &'static str {
        "M raycasting steps per pass blended into an accumulation target, early-z tested (Krüger–Westermann 2003 §2.1–2.2)"
    }

    fn blocks(&self) -> Vec<ParamBlock> {
        // The node writes its uniforms once, when built: every change rebuilds it.
        [
            raycast_blocks(OnChange::Rebuild),
            vec![
                effect_block(),
                crate::fusion::fusion_block(),
                SegmentSteps::block(OnChange::Rebuild),
                BlockSize::block(OnChange::Rebuild),
            ],
        ]
        .concat()
    }

    fn ports(&self, params: &Params) -> Vec<PortSpec> {
        let mut ports = vec![
            PortSpec::read("entry", PortKind::target(&FLOAT_TARGETS)),
            PortSpec::read("dir", PortKind::target(&FLOAT_TARGETS)),
            PortSpec::read("volume", PortKind::Volume),
            PortSpec::read("tf", PortKind::TransferFunction),
            PortSpec::modify("accum", PortKind::target(&ACCUM_FORMATS)),
            PortSpec::read("depth", PortKind::target(&[TargetFormat::Depth32Float])).optional(),
            // With the block flags wired, a DVR segment leaps over empty blocks inside its M
            // samples (§2.3's skipping done in the segment instead of by the depth test).
            PortSpec::read("empty", PortKind::Owned(EMPTY_BLOCKS)).optional(),
        ];
        ports.extend(crate::fusion::FusionSettings::of(params).ports());
        if is_iso(params) {
            // §2.2: the closest hit's texture-space position, blended like the colour.
            ports.push(PortSpec::modify("hit", PortKind::target(&HIT_FORMATS)));
        }
        ports
    }

    fn shaders(&self, params: &Params) -> Vec<ShaderUse> {
        let (file, entry_point) = self.entry(params);
        // The counting variant (a bench tool's) binds the invocation counter too.
        // The pre-integration table's (an effect's), and the counting variant's counter.
        let binds: &'static [&'static str] = if self.counts() {
            &["invocations", "preintegrated", "light_volume", "label_quads", "label_cubes"]
        } else {
            &["preintegrated", "light_volume", "label_quads", "label_cubes"]
        };
        let mut uses = [ShaderUse::new(file, "vs_segment"), ShaderUse::new(file, entry_point)]
            .map(|u| {
                crate::fusion::with_fusion_uniform(
                    u.binds(binds).uniform(RaycastParamsGpu::bound("params")).uniform(SegmentParams::layout()),
                    params,
                )
            })
            .to_vec();
        uses.extend(effect_shader_uses(params, true));
        uses
    }

    fn shaders_wired(&self, params: &Params, wired: &[&str]) -> Vec<ShaderUse> {
        // §2.3 inside the segment: the shared march leaps over the wired block flags.
        let leap: Vec<&'static str> =
            if wired.contains(&"empty") { vec![defines::LEAP, defines::LEAP_BLOCKS] } else { vec![] };
        // The segment's own two stages only: the effects' table pipelines do not march.
        let mut uses = self.shaders(params);
        for u in uses.iter_mut().take(2) {
            *u = u.clone().defines(leap.clone());
        }
        uses
    }
}

#[cfg(feature = "gpu")]
impl PassPlugin for RaycastSegment {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let error = |message: String| PassError { pass: ctx.pass_id.to_string(), message };
        let accum_format = ctx.ports.iter().find(|p| p.name == "accum").and_then(|p| p.format);
        if accum_format == Some(wgpu::TextureFormat::Rgba32Float) && !ctx.gpu.float32_blendable {
            return Err(error(format!(
                "the accumulation target is Rgba32Float, which {} cannot blend into; declare it Rgba16Float \
                 (outputs: {{\"accum\": (format: Rgba16Float)}} on the pass that creates it)",
                ctx.gpu.adapter_name
            )));
        }
        if self.counter.is_some() && !ctx.gpu.early_depth_test {
            return Err(error(format!(
                "the invocation counter needs forced early depth tests (SHADER_EARLY_DEPTH_TEST), which {} lacks",
                ctx.gpu.adapter_name
            )));
        }
        let leap = ctx.ports.iter().any(|p| p.name == "empty" && p.bound);
        let (shader, fragment) = match (leap, self.entry(ctx.params)) {
            // §2.3 inside the segment: with the empty-block flags wired, the shared march leaps.
            (true, ("raycast_segment.wgsl", "fs_dvr")) => ("raycast_segment.wgsl", "fs_dvr"),
            (true, (_, entry)) => {
                return Err(error(format!(
                    "empty-block leaping is implemented for the DVR segment shader only, not {entry}; \
                     leave \"empty\" unwired"
                )));
            }
            (false, entry) => entry,
        };
        let mut defines = self.shader_defines(ctx.params);
        if leap {
            defines.extend([defines::LEAP, defines::LEAP_BLOCKS]);
        }
        let spec = |depth: Option<DepthSpec<'static>>| RenderPipelineSpec {
            shader,
            vertex: "vs_segment",
            fragment,
            blend: Some(front_to_back_blend()),
            depth,
            defines: &defines,
            ..Default::default()
        };
        let free = ctx.render_pipeline(&spec(None))?;
        let early_z = ctx.render_pipeline(&spec(Some(DepthSpec {
            port: "depth",
            write: false,
            compare: wgpu::CompareFunction::Greater,
        })))?;
        let params = ctx.uniform_from_bytes("params", &RaycastParamsGpu::of(ctx.params).uniform_bytes());
        let segment = ctx.uniform_from_bytes("segment", &SegmentParams::of(ctx.params).uniform_bytes());
        let invocations = match &self.counter {
            Some(counter) => {
                let buffer = ctx.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(&format!("{}.invocations", ctx.pass_id)),
                    size: 4,
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                let mut slot =
                    counter.buffer.lock().map_err(|_| error("invocation counter lock poisoned".to_string()))?;
                *slot = Some(buffer.clone());
                Some(buffer)
            }
            None => None,
        };
        let effects = EffectState::new(ctx, true)?;
        let fusion = crate::fusion::FusionState::bounded_by_the_scan(
            ctx,
            self.kind(),
            "the termination test and empty-space classification beside its segments read",
        )?;
        let step_voxels = Sampling::from_params(ctx.params).step_voxels;
        Ok(Box::new(RaycastSegmentNode { free, early_z, params, segment, invocations, effects, fusion, step_voxels }))
    }
}

impl RaycastSegment {
    fn entry(&self, params: &Params) -> (&'static str, &'static str) {
        match (self.counts(), is_iso(params)) {
            (false, false) => ("raycast_segment.wgsl", "fs_dvr"),
            (false, true) => ("raycast_segment.wgsl", "fs_iso"),
            (true, false) => ("raycast_segment_counted.wgsl", "fs_dvr_counted"),
            (true, true) => ("raycast_segment_counted.wgsl", "fs_iso_counted"),
        }
    }
}

#[cfg(feature = "gpu")]
struct RaycastSegmentNode {
    /// Without the depth test (RC: no termination pass wired).
    free: RenderPassPipeline,
    /// With the early-z test against `depth`.
    early_z: RenderPassPipeline,
    params: wgpu::Buffer,
    segment: wgpu::Buffer,
    invocations: Option<wgpu::Buffer>,
    /// The pre-integration table when that effect is on.
    effects: EffectState,
    /// Several volumes: the fusion uniform and a label map's quads.
    fusion: crate::fusion::FusionState,
    step_voxels: f64,
}

#[cfg(feature = "gpu")]
impl PassNode for RaycastSegmentNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let index = segment_index(ctx);
        let pipeline = if ctx.is_bound("depth") { &self.early_z } else { &self.free };
        self.fusion.update(ctx)?;
        self.effects.update(ctx, &self.params, self.step_voxels, &self.fusion.bindings())?;
        let mut extra =
            vec![("params", self.params.as_entire_binding()), ("segment", self.segment.as_entire_binding())];
        extra.extend(self.effects.bindings());
        extra.extend(self.fusion.bindings());
        if let Some(counter) = &self.invocations {
            if index == 0 {
                ctx.encoder.clear_buffer(counter, 0, None);
            }
            extra.push(("invocations", counter.as_entire_binding()));
        }
        let bg = ctx.bind_group(pipeline, &extra)?;
        let mut pass = ctx.begin_render_pass(pipeline, None)?;
        pass.set_pipeline(&pipeline.pipeline);
        pass.set_bind_group(0, &bg, &[]);
        pass.draw(0..FAN_DRAW_VERTICES, index..index + 1);
        Ok(())
    }
}
