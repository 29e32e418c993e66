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

/// The pixel rectangle `(x, y, w, h)` the volume box of half size `half` covers seen by
/// `camera` in a `viewport`; the whole viewport when a corner is behind the eye: where last
/// frame's hits lie, for both reprojections (`reprojection_splat`, `reprojection_tiles`).
#[cfg(feature = "gpu")]
pub fn screen_rect(camera: &volgraph_core::runtime::CameraData, half: glam::DVec3, viewport: (u32, u32)) -> [u32; 4] {
    let (w, h) = (viewport.0 as f64, viewport.1 as f64);
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for i in 0..8 {
        let corner = glam::DVec3::new(
            if i & 1 != 0 { half.x } else { -half.x },
            if i & 2 != 0 { half.y } else { -half.y },
            if i & 4 != 0 { half.z } else { -half.z },
        );
        let c = camera.clip_from_world * glam::DVec4::new(corner.x, corner.y, corner.z, 1.0);
        if c.w <= 1e-9 {
            return [0, 0, viewport.0, viewport.1];
        }
        let (px, py) = ((c.x / c.w + 1.0) * 0.5 * w, (1.0 - c.y / c.w) * 0.5 * h);
        lo = [lo[0].min(px), lo[1].min(py)];
        hi = [hi[0].max(px), hi[1].max(py)];
    }
    let x0 = lo[0].floor().clamp(0.0, w) as u32;
    let y0 = lo[1].floor().clamp(0.0, h) as u32;
    let x1 = hi[0].ceil().clamp(0.0, w) as u32;
    let y1 = hi[1].ceil().clamp(0.0, h) as u32;
    [x0, y0, x1.saturating_sub(x0), y1.saturating_sub(y0)]
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
