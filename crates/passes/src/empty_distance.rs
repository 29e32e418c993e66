//! `empty_distance`: the Chebyshev distance, in blocks, from each block of `empty_space`'s grid
//! to the nearest block that may be visible — the distance map with which a raycaster leaps over
//! many empty blocks at once instead of one at a time (`raycast_compute` wired to `distance`). A
//! separable L∞ distance transform, one compute dispatch per axis and O(n) per line, rebuilt
//! when the flags change (a TF edit). The leap stays lossless: every sample it skips lies in an
//! empty block. Equal cell for cell to `volgraph_accel::chebyshev` (`tests/empty_distance.rs`).
//! Shader: `shaders/empty_distance.wgsl`.

use volgraph_compiler::{Params, PassDecl, PortKind, PortSpec, Rerun, ShaderUse};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{ComputePassPipeline, ComputePipelineSpec, CreateContext, PassError, RecordContext};
#[cfg(feature = "gpu")]
use volgraph_core::{PassNode, PassPlugin};

use crate::empty_space::EMPTY_BLOCKS;
#[cfg(feature = "gpu")]
use crate::grid_tap::GridTap;
#[cfg(feature = "gpu")]
use crate::minmax_grid::{bound_size, create_grid_texture};

/// The Owned type name of the distance map.
pub const EMPTY_DISTANCE: &str = "empty_distance";

/// Longest grid line the shader solves (`MAX_LINE` of `empty_distance.wgsl`).
const MAX_LINE: u32 = 2048;

/// The plugin; [`EmptyDistance::tapped`] also hands the distance texture to a [`GridTap`].
#[derive(Default)]
pub struct EmptyDistance {
    #[cfg(feature = "gpu")]
    tap: Option<GridTap>,
}

#[cfg(feature = "gpu")]
impl EmptyDistance {
    /// An `empty_distance` pass that stores its map in `tap` (tests, tools).
    pub fn tapped(tap: GridTap) -> Self {
        Self { tap: Some(tap) }
    }
}

volgraph_compiler::pass_params! {
    /// The `pass_params` block of `shaders/empty_distance.wgsl` (which imports it): one per
    /// axis, written by the node.
    struct DistanceParams {
        axis: u32 = computed, "0, 1, 2: the axis this dispatch runs along.";
    }
}

/// The pass's one entry point, declared once for `shaders()` and `create`.
fn shader() -> ShaderUse {
    ShaderUse::new("empty_distance.wgsl", "cs_line").binds(&["partial", "distance"]).uniform(
        DistanceParams::bound_as_with("pass_params", Vec::new(), |_| DistanceParams { axis: 0 }.uniform_bytes()),
    )
}

impl PassDecl for EmptyDistance {
    fn honours_volume_window(&self) -> bool {
        true
    }

    fn kind(&self) -> &'static str {
        "empty_distance"
    }

    fn summary(&self) -> &'static str {
        "Chebyshev distance (in blocks) to the nearest visible block, for leaping over many empty blocks at once \
         (Krüger–Westermann 2003 §2.3's grid as a distance map)"
    }

    fn rerun(&self) -> Rerun {
        // A function of the grid and the TF: rebuilt when either changes.
        Rerun::WhenInputsChange
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read("empty", PortKind::Owned(EMPTY_BLOCKS)),
            PortSpec::write("distance", PortKind::Owned(EMPTY_DISTANCE)),
        ]
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        vec![shader()]
    }
}

#[cfg(feature = "gpu")]
impl PassPlugin for EmptyDistance {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let pipeline = ctx.compute_pipeline(&ComputePipelineSpec::of(&shader()))?;
        let axes = [0u32, 1, 2]
            .map(|axis| ctx.uniform_from_bytes(&format!("axis{axis}"), &DistanceParams { axis }.uniform_bytes()));
        Ok(Box::new(EmptyDistanceNode { pipeline, axes, textures: None, tap: self.tap.clone() }))
    }
}

#[cfg(feature = "gpu")]
/// The published map, the scratch texture of the middle pass, and their size in blocks.
struct DistanceTextures {
    out: wgpu::TextureView,
    scratch: wgpu::TextureView,
    dims: [u32; 3],
}

#[cfg(feature = "gpu")]
struct EmptyDistanceNode {
    pipeline: ComputePassPipeline,
    axes: [wgpu::Buffer; 3],
    textures: Option<DistanceTextures>,
    tap: Option<GridTap>,
}

#[cfg(feature = "gpu")]
impl PassNode for EmptyDistanceNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let dims = bound_size(ctx, "empty")?;
        if dims.iter().any(|n| *n > MAX_LINE) {
            return Err(PassError {
                pass: ctx.label.to_string(),
                message: format!(
                    "the block grid is {dims:?}, longer than {MAX_LINE} blocks along an axis; raise block_size"
                ),
            });
        }
        if self.textures.as_ref().is_none_or(|t| t.dims != dims) {
            let make = |what: &str| {
                create_grid_texture(ctx, &format!("{} {what}", ctx.label), wgpu::TextureFormat::R32Float, dims)
            };
            let out = make("distance");
            if let Some(tap) = &self.tap {
                tap.set(&out);
            }
            let view = |t: wgpu::Texture| t.create_view(&wgpu::TextureViewDescriptor::default());
            self.textures = Some(DistanceTextures { out: view(out), scratch: view(make("partial distance")), dims });
        }
        let Some(textures) = &self.textures else {
            return Err(PassError { pass: ctx.label.to_string(), message: "distance textures missing".to_string() });
        };
        // x: flags → out; y: out → scratch; z: scratch → out. Pass x reads the flags, not
        // `partial`, which is bound to a texture it does not write.
        let (out, scratch) = (&textures.out, &textures.scratch);
        let steps = [(scratch, out), (out, scratch), (scratch, out)];
        let mut groups = Vec::with_capacity(3);
        for (axis, (partial, write)) in steps.iter().enumerate() {
            groups.push(ctx.bind_group(
                &self.pipeline,
                &[
                    ("partial", wgpu::BindingResource::TextureView(partial)),
                    ("distance", wgpu::BindingResource::TextureView(write)),
                    ("pass_params", self.axes[axis].as_entire_binding()),
                ],
            )?);
        }
        let mut pass = ctx.begin_compute_pass();
        pass.set_pipeline(&self.pipeline.pipeline);
        for (axis, bg) in groups.iter().enumerate() {
            let across = match axis {
                0 => (dims[1], dims[2]),
                1 => (dims[0], dims[2]),
                _ => (dims[0], dims[1]),
            };
            pass.set_bind_group(0, bg, &[]);
            pass.dispatch_workgroups(across.0.div_ceil(8), across.1.div_ceil(8), 1);
        }
        Ok(())
    }

    fn owned_output(&self, port: &str) -> Option<wgpu::TextureView> {
        match port {
            "distance" => self.textures.as_ref().map(|t| t.out.clone()),
            _ => None,
        }
    }
}
