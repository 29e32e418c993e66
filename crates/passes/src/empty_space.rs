//! `empty_space`: Krüger & Westermann 2003 §2.3's transfer-function classification of the
//! min/max grid on the GPU — per block, whether any LUT texel reachable by linear interpolation
//! on `[min, max]` has non-zero alpha, mirroring `volgraph_accel::classify::OpacityClassifier`
//! (the paper's "CT" texture, evaluated per block instead of looked up). Output: an Owned
//! `R32Float` 3D texture of empty flags (1 = skip), consumed by `termination_test` (the paper's
//! way) and `raycast` / `raycast_compute` (single-pass empty-block leaping, `empty` wired).
//! Runs (one invocation per block) only when the grid or the transfer function changed, so a
//! new TF takes effect in the next frame and a steady one costs nothing. Shader:
//! `shaders/empty_space.wgsl`.

use volgraph_compiler::block::{OnChange, ParamBlock};
use volgraph_compiler::{Params, PassDecl, PortKind, PortSpec, Rerun, ShaderUse};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{ComputePassPipeline, ComputePipelineSpec, CreateContext, PassError, RecordContext};
#[cfg(feature = "gpu")]
use volgraph_core::{PassNode, PassPlugin};

#[cfg(feature = "gpu")]
use crate::grid_tap::GridTap;
use crate::minmax_grid::MINMAX_GRID;
#[cfg(feature = "gpu")]
use crate::minmax_grid::{bound_size, create_grid_texture, dispatch_grid};
use volgraph_accel::classify::OpacityClassifier;

/// The Owned type name of the empty-block flags.
pub const EMPTY_BLOCKS: &str = "empty_blocks";

/// The plugin; [`EmptySpace::tapped`] also hands the flag texture to a [`GridTap`].
#[derive(Default)]
pub struct EmptySpace {
    #[cfg(feature = "gpu")]
    tap: Option<GridTap>,
}

#[cfg(feature = "gpu")]
impl EmptySpace {
    /// An `empty_space` pass that stores its texture in `tap` (tests, tools).
    pub fn tapped(tap: GridTap) -> Self {
        Self { tap: Some(tap) }
    }
}

#[cfg(feature = "gpu")]
/// Checks that the empty-block grid bound to `port` has `ceil(volume / block_size)` blocks per
/// axis, i.e. that a consumer's `block_size` matches the `minmax_grid` pass's.
pub(crate) fn check_block_grid(
    ctx: &RecordContext<'_>,
    port: &str,
    block_size: u32,
    volume: [u32; 3],
) -> Result<(), PassError> {
    let grid = bound_size(ctx, port)?;
    let expected = volume.map(|n| n.div_ceil(block_size.max(1)));
    if grid != expected {
        return Err(PassError {
            pass: ctx.label.to_string(),
            message: format!(
                "block_size {block_size} gives a {expected:?} block grid for the {volume:?} volume, but \"{port}\" is {grid:?}; \
                 set the same block_size as the minmax_grid pass"
            ),
        });
    }
    Ok(())
}

volgraph_compiler::pass_params! {
    /// The pass's parameters, declared once.
    pub struct ClassifySettings {
        segments: bool = false,
            "classify for pre-integrated segments: a block is empty only if its neighbours' values are invisible too (a segment spans two adjacent blocks; wire to feature.preintegration)";
    }
}

/// The pass's one entry point, declared once for `shaders()` and `create`.
fn shader() -> ShaderUse {
    ShaderUse::new("empty_space.wgsl", "cs_classify").binds(&["visible_before"])
}

impl PassDecl for EmptySpace {
    fn honours_volume_window(&self) -> bool {
        true
    }

    fn kind(&self) -> &'static str {
        "empty_space"
    }

    fn summary(&self) -> &'static str {
        "per-block empty flags from the min/max grid and the transfer function (Krüger–Westermann 2003 §2.3)"
    }

    fn rerun(&self) -> Rerun {
        // A function of the grid and the TF: rebuilt when either changes.
        Rerun::WhenInputsChange
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read("grid", PortKind::Owned(MINMAX_GRID)),
            PortSpec::read("tf", PortKind::TransferFunction),
            PortSpec::write("empty", PortKind::Owned(EMPTY_BLOCKS)),
        ]
    }

    fn blocks(&self) -> Vec<ParamBlock> {
        vec![ClassifySettings::block(OnChange::Rebuild).with_defines(|p| {
            if ClassifySettings::from_params(p).segments { vec![crate::defines::SEGMENTS] } else { Vec::new() }
        })]
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        vec![shader()]
    }
}

#[cfg(feature = "gpu")]
impl PassPlugin for EmptySpace {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let defines = self.shader_defines(ctx.params);
        let pipeline =
            ctx.compute_pipeline(&ComputePipelineSpec { defines: &defines, ..ComputePipelineSpec::of(&shader()) })?;
        Ok(Box::new(EmptySpaceNode { pipeline, flags: None, visible_before: None, tap: self.tap.clone() }))
    }
}

#[cfg(feature = "gpu")]
struct EmptySpaceNode {
    pipeline: ComputePassPipeline,
    flags: Option<(wgpu::Texture, wgpu::TextureView, [u32; 3])>,
    /// The LUT's visible-texel prefix counts (`visible_before` of the shader) and their length.
    visible_before: Option<(wgpu::Buffer, usize)>,
    tap: Option<GridTap>,
}

#[cfg(feature = "gpu")]
impl PassNode for EmptySpaceNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let dims = bound_size(ctx, "grid")?;
        if self.flags.as_ref().is_none_or(|(_, _, d)| *d != dims) {
            let texture =
                create_grid_texture(ctx, &format!("{} empty blocks", ctx.label), wgpu::TextureFormat::R32Float, dims);
            let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
            if let Some(tap) = &self.tap {
                tap.set(&texture);
            }
            self.flags = Some((texture, view, dims));
        }
        let view = self.flags.as_ref().map(|(_, v, _)| v.clone()).ok_or_else(|| PassError {
            pass: ctx.label.to_string(),
            message: "empty-block texture missing right after creation".to_string(),
        })?;
        let classifier = OpacityClassifier::new(ctx.table("tf")?)
            .map_err(|e| PassError { pass: ctx.label.to_string(), message: format!("transfer function: {e}") })?;
        let counts = classifier.visible_before();
        let texels = ctx.view("tf")?.texture().width() as usize;
        if counts.len() != texels + 1 {
            return Err(PassError {
                pass: ctx.label.to_string(),
                message: format!(
                    "the transfer function's CPU table has {} texels but its texture {texels}; bind the LUT with \
                     Runtime::bind_lut (a texture bound by hand has no table to classify with)",
                    counts.len() - 1
                ),
            });
        }
        if self.visible_before.as_ref().is_none_or(|(_, n)| *n != counts.len()) {
            let buffer = ctx.gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(&format!("{} visible texels before", ctx.label)),
                size: (counts.len() * 4) as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            self.visible_before = Some((buffer, counts.len()));
        }
        let Some((counts_buffer, _)) = &self.visible_before else {
            return Err(PassError { pass: ctx.label.to_string(), message: "prefix buffer missing".to_string() });
        };
        ctx.write_buffer(counts_buffer, 0, bytemuck::cast_slice(counts));
        let bg = ctx.bind_group(
            &self.pipeline,
            &[
                ("empty", wgpu::BindingResource::TextureView(&view)),
                ("visible_before", counts_buffer.as_entire_binding()),
            ],
        )?;
        dispatch_grid(ctx, &self.pipeline, &bg, dims);
        Ok(())
    }

    fn owned_output(&self, port: &str) -> Option<wgpu::TextureView> {
        match port {
            "empty" => self.flags.as_ref().map(|(_, view, _)| view.clone()),
            _ => None,
        }
    }
}
