//! Helpers several technique modules share, kept out of the modules themselves: the target
//! format sets ports accept, the block-size rule of the empty-space passes, the front-to-back
//! blend, and how a node tells which colour precision its graph picked.

use volgraph_compiler::TargetFormat;
#[cfg(feature = "gpu")]
use volgraph_core::runtime::CreateContext;

/// Float RGBA targets a ray pass reads or writes (entry points, directions, hits); the first is
/// the default for outputs.
pub const FLOAT_TARGETS: [TargetFormat; 2] = [TargetFormat::Rgba32Float, TargetFormat::Rgba16Float];

/// Formats of an accumulation target blended into segment by segment (Krüger & Westermann 2003
/// §2.1).
pub const ACCUM_FORMATS: [TargetFormat; 2] = FLOAT_TARGETS;

/// Formats of the isosurface hit target blended like the colour (§2.2).
pub const HIT_FORMATS: [TargetFormat; 2] = FLOAT_TARGETS;

volgraph_compiler::pass_params! {
    /// The `block_size` parameter of the min/max grid and everything that reads it (Krüger &
    /// Westermann 2003 §2.3): one declaration, so the passes that must agree cannot drift.
    pub struct BlockSize {
        block_size: u32 = 8, 1..=256, "edge of an empty-space block in voxels (Krüger–Westermann used 8)";
    }
}

impl BlockSize {
    /// The block edge of `params` (at least 1).
    pub fn of(params: &volgraph_compiler::Params) -> u32 {
        Self::from_params(params).block_size.max(1)
    }
}

#[cfg(feature = "gpu")]
/// The front-to-back blend `dst + (1 - dst.a)·src` for colour and alpha.
pub fn front_to_back_blend() -> wgpu::BlendState {
    let c = wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::OneMinusDstAlpha,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    };
    wgpu::BlendState { color: c, alpha: c }
}

#[cfg(feature = "gpu")]
/// Whether the graph (or the scene's precision) made `color` an Rgba32Float target: the node
/// then compiles its shader with `COLOR_F32`.
fn color_is_f32(ctx: &CreateContext<'_>) -> bool {
    ctx.port("color").and_then(|p| p.format) == Some(wgpu::TextureFormat::Rgba32Float)
}

#[cfg(feature = "gpu")]
/// The `#if` names of the colour target's precision (`shaders/common/color_target.wgsl`): the
/// one place a compute march learns whether it writes f16 or f32.
pub fn color_precision_defines(ctx: &CreateContext<'_>) -> Vec<&'static str> {
    if color_is_f32(ctx) { vec![crate::defines::COLOR_F32] } else { Vec::new() }
}

/// A built-in shader assembled as the GPU gets it (imports resolved, bindings numbered), for
/// tests that compare a `pass_params!` declaration with its WGSL struct (`check_shader`).
#[cfg(test)]
pub(crate) fn assembled(file: &str) -> String {
    assembled_with(file, &[])
}

/// [`assembled`] with `defines` on.
#[cfg(test)]
pub(crate) fn assembled_with(file: &str, defines: &[&str]) -> String {
    let defines = defines.iter().map(|d| d.to_string()).collect();
    volgraph_compiler::shader_source::assemble_with(&crate::builtin_shaders(), file, &defines).expect("assembles").text
}

#[cfg(test)]
mod tests {
    use super::{BlockSize, assembled, assembled_with};

    /// The min/max grid's and the leaping raycasters' block-edge uniforms are `BlockSize`'s
    /// bytes (the generated struct).
    #[test]
    fn the_block_size_uniforms_match_their_shader_structs() {
        BlockSize::check_shader(&assembled("minmax_grid.wgsl"), "BlockSize").unwrap_or_else(|e| panic!("{e}"));
        for file in ["raycast.wgsl", "raycast_compute.wgsl"] {
            let text = assembled_with(file, &[crate::defines::LEAP, crate::defines::LEAP_CUBES]);
            BlockSize::check_shader(&text, "BlockSize").unwrap_or_else(|e| panic!("{file}: {e}"));
        }
        assert_eq!(BlockSize { block_size: 8 }.uniform_bytes().len(), 16);
    }
}
