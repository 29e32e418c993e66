//! `majorant_grid`: per-block majorants for the path tracer's delta tracking (Novák et al. 2014
//! §3): for each block of the min/max grid, the largest TF opacity its value range can
//! interpolate — the same texel range as `empty_space`'s visibility test — so `path_trace`
//! (`majorant: "blocks"`) steps through empty blocks at once and through thin ones with long
//! free paths, instead of at the rate of the TF's most opaque value everywhere. Output: an Owned
//! `R32Float` 3D texture; runs only when the grid or the TF changed. Shader:
//! `shaders/majorant_grid.wgsl`.

use volgraph_compiler::{Params, PassDecl, PortKind, PortSpec, Rerun, ShaderUse};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{ComputePassPipeline, ComputePipelineSpec, CreateContext, PassError, RecordContext};
#[cfg(feature = "gpu")]
use volgraph_core::{PassNode, PassPlugin};

use crate::minmax_grid::MINMAX_GRID;
#[cfg(feature = "gpu")]
use crate::minmax_grid::{bound_size, create_grid_texture, dispatch_grid};

/// The Owned type name of the per-block majorants.
pub const MAJORANT_GRID: &str = "majorant_grid";

/// The plugin.
pub struct MajorantGrid;

/// The pass's one entry point, declared once for `shaders()` and `create`.
fn shader() -> ShaderUse {
    ShaderUse::new("majorant_grid.wgsl", "cs_majorants")
}

impl PassDecl for MajorantGrid {
    /// A bound per block of the TF's opacity over the block's range: still a bound wherever a
    /// window or the cuts keep part of the block (the path tracer cuts its paths itself).
    fn honours_volume_window(&self) -> bool {
        true
    }

    fn kind(&self) -> &'static str {
        "majorant_grid"
    }

    fn summary(&self) -> &'static str {
        "per-block largest TF opacity from the min/max grid: the path tracer's majorants (Novák et al. 2014 §3)"
    }

    fn rerun(&self) -> Rerun {
        // A function of the grid and the TF.
        Rerun::WhenInputsChange
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read("grid", PortKind::Owned(MINMAX_GRID)),
            PortSpec::read("tf", PortKind::TransferFunction),
            PortSpec::write("majorants", PortKind::Owned(MAJORANT_GRID)),
        ]
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        vec![shader()]
    }
}

#[cfg(feature = "gpu")]
impl PassPlugin for MajorantGrid {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let pipeline = ctx.compute_pipeline(&ComputePipelineSpec::of(&shader()))?;
        Ok(Box::new(MajorantGridNode { pipeline, grid: None }))
    }
}

#[cfg(feature = "gpu")]
struct MajorantGridNode {
    pipeline: ComputePassPipeline,
    grid: Option<(wgpu::TextureView, [u32; 3])>,
}

#[cfg(feature = "gpu")]
impl PassNode for MajorantGridNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let dims = bound_size(ctx, "grid")?;
        if self.grid.as_ref().is_none_or(|(_, d)| *d != dims) {
            let texture =
                create_grid_texture(ctx, &format!("{} majorants", ctx.label), wgpu::TextureFormat::R32Float, dims);
            self.grid = Some((texture.create_view(&wgpu::TextureViewDescriptor::default()), dims));
        }
        let Some((view, _)) = &self.grid else {
            return Err(PassError { pass: ctx.label.to_string(), message: "majorant texture missing".into() });
        };
        let view = view.clone();
        let bg = ctx.bind_group(&self.pipeline, &[("majorants", wgpu::BindingResource::TextureView(&view))])?;
        dispatch_grid(ctx, &self.pipeline, &bg, dims);
        Ok(())
    }

    fn owned_output(&self, port: &str) -> Option<wgpu::TextureView> {
        match port {
            "majorants" => self.grid.as_ref().map(|(view, _)| view.clone()),
            _ => None,
        }
    }
}
