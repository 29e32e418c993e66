//! `minmax_grid`: Krüger & Westermann 2003 §2.3's min/max grid of `block_size³` blocks, built
//! on the GPU from the volume texture in a compute pass. Conservative for trilinear
//! interpolation exactly like `volgraph_accel::minmax::MinMaxGrid` (each block's range includes
//! a one-voxel apron), so a block classified empty holds no visible sample. The grid is an
//! Owned `Rg32Float` 3D texture (r = min, g = max) of `ceil(dims / block_size)` texels, created
//! on the first frame (its size comes from the bound volume) and rebuilt only when the volume's
//! content changes (`Rerun::WhenInputsChange`). Shader: `shaders/minmax_grid.wgsl`.

use volgraph_compiler::block::{OnChange, ParamBlock};
use volgraph_compiler::{Params, PassDecl, PortKind, PortSpec, Rerun, ShaderUse};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{ComputePassPipeline, ComputePipelineSpec, CreateContext, PassError, RecordContext};
#[cfg(feature = "gpu")]
use volgraph_core::{PassNode, PassPlugin};

#[cfg(feature = "gpu")]
use crate::grid_tap::GridTap;
use crate::shared::BlockSize;

volgraph_compiler::pass_params! {
    /// Whether the grid covers what the tricubic effect reads.
    pub struct GridApron {
        tricubic: bool = false,
            "widen each block's range by a two-voxel apron, what the tricubic B-spline reads (wire to feature.tricubic)";
    }
}

/// The Owned type name of the grid.
pub const MINMAX_GRID: &str = "minmax_grid";

/// The plugin; [`MinMaxGridPass::tapped`] also hands the grid texture to a [`GridTap`].
#[derive(Default)]
pub struct MinMaxGridPass {
    #[cfg(feature = "gpu")]
    tap: Option<GridTap>,
}

#[cfg(feature = "gpu")]
impl MinMaxGridPass {
    /// A `minmax_grid` pass that stores its texture in `tap` (tests, tools).
    pub fn tapped(tap: GridTap) -> Self {
        Self { tap: Some(tap) }
    }
}

/// Workgroup edge of `cs_minmax` and `cs_classify` (4³ blocks per workgroup).
pub(crate) const GRID_WORKGROUP: u32 = 4;

#[cfg(feature = "gpu")]
/// A 3D float texture usable as a storage output and a sampled input.
pub(crate) fn create_grid_texture(
    ctx: &RecordContext<'_>,
    label: &str,
    format: wgpu::TextureFormat,
    dims: [u32; 3],
) -> wgpu::Texture {
    ctx.gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width: dims[0], height: dims[1], depth_or_array_layers: dims[2] },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D3,
        format,
        usage: wgpu::TextureUsages::STORAGE_BINDING
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

#[cfg(feature = "gpu")]
/// Size of the texture bound to `port` (a 3D input or owned grid).
pub(crate) fn bound_size(ctx: &RecordContext<'_>, port: &str) -> Result<[u32; 3], PassError> {
    let s = ctx.view(port)?.texture().size();
    Ok([s.width, s.height, s.depth_or_array_layers])
}

#[cfg(feature = "gpu")]
/// Records one dispatch of `pipeline` over `dims` texels (4³ per workgroup); `dims = None`
/// records an empty pass, which keeps the step's label and timestamps.
pub(crate) fn dispatch_grid(
    ctx: &mut RecordContext<'_>,
    pipeline: &ComputePassPipeline,
    bind_group: &wgpu::BindGroup,
    dims: [u32; 3],
) {
    let mut pass = ctx.begin_compute_pass();
    pass.set_pipeline(&pipeline.pipeline);
    pass.set_bind_group(0, bind_group, &[]);
    pass.dispatch_workgroups(
        dims[0].div_ceil(GRID_WORKGROUP),
        dims[1].div_ceil(GRID_WORKGROUP),
        dims[2].div_ceil(GRID_WORKGROUP),
    );
}

impl PassDecl for MinMaxGridPass {
    fn honours_volume_window(&self) -> bool {
        true
    }

    fn kind(&self) -> &'static str {
        "minmax_grid"
    }

    fn summary(&self) -> &'static str {
        "GPU min/max grid of the volume's blocks, trilinear-conservative (Krüger–Westermann 2003 §2.3)"
    }

    fn rerun(&self) -> Rerun {
        Rerun::WhenInputsChange
    }

    fn blocks(&self) -> Vec<ParamBlock> {
        vec![
            BlockSize::block(OnChange::Rebuild),
            GridApron::block(OnChange::Rebuild).with_defines(|p| {
                if GridApron::from_params(p).tricubic { vec![crate::defines::TRICUBIC] } else { Vec::new() }
            }),
        ]
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![PortSpec::read("volume", PortKind::Volume), PortSpec::write("grid", PortKind::Owned(MINMAX_GRID))]
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        vec![shader()]
    }
}

/// The pass's one entry point, declared once for `shaders()` and `create`.
fn shader() -> ShaderUse {
    ShaderUse::new("minmax_grid.wgsl", "cs_minmax").uniform(BlockSize::bound_as("minmax"))
}

#[cfg(feature = "gpu")]
impl PassPlugin for MinMaxGridPass {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let defines = self.shader_defines(ctx.params);
        let pipeline =
            ctx.compute_pipeline(&ComputePipelineSpec { defines: &defines, ..ComputePipelineSpec::of(&shader()) })?;
        let block_size = BlockSize::of(ctx.params);
        // `MinMaxParams` of the shader: the block edge, padded to 16 bytes.
        let params = ctx.uniform_from_bytes("minmax", &BlockSize { block_size }.uniform_bytes());
        Ok(Box::new(MinMaxGridNode { pipeline, params, block_size, grid: None, tap: self.tap.clone() }))
    }
}

#[cfg(feature = "gpu")]
struct MinMaxGridNode {
    pipeline: ComputePassPipeline,
    params: wgpu::Buffer,
    block_size: u32,
    /// The grid, the volume size it was built for, and whether it has been built.
    grid: Option<(wgpu::Texture, wgpu::TextureView, [u32; 3])>,
    tap: Option<GridTap>,
}

#[cfg(feature = "gpu")]
impl PassNode for MinMaxGridNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        // Recorded only when the volume changed (`Rerun::WhenInputsChange`); a new texture only
        // when its size did.
        let volume = bound_size(ctx, "volume")?;
        let dims = volume.map(|n| n.div_ceil(self.block_size));
        let (texture, view) = match self.grid.take() {
            Some((texture, view, built_for)) if built_for == volume => (texture, view),
            _ => {
                let texture = create_grid_texture(
                    ctx,
                    &format!("{} min/max grid", ctx.label),
                    wgpu::TextureFormat::Rg32Float,
                    dims,
                );
                let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
                (texture, view)
            }
        };
        if let Some(tap) = &self.tap {
            tap.set(&texture);
        }
        let bg = {
            let grid_view = view.clone();
            ctx.bind_group(
                &self.pipeline,
                &[
                    ("minmax", self.params.as_entire_binding()),
                    ("grid", wgpu::BindingResource::TextureView(&grid_view)),
                ],
            )?
        };
        dispatch_grid(ctx, &self.pipeline, &bg, dims);
        self.grid = Some((texture, view, volume));
        Ok(())
    }

    fn owned_output(&self, port: &str) -> Option<wgpu::TextureView> {
        match port {
            "grid" => self.grid.as_ref().map(|(_, view, _)| view.clone()),
            _ => None,
        }
    }
}
