//! volgraph as a library: a graph kept on a GPU, a volume handed over in memory, images back —
//! what the Python package (`crates/python`) wraps and any Rust program may use. Every step is
//! the command line's (`render.rs`): the graph read by name or file, the transfer function by
//! preset, file or fitted to the data, the scene values of the volume, the camera (the anterior
//! view for a volume in the patient frame), the same runtime and output — so an image equals
//! `volgraph render`'s of the same voxels bit for bit (`crates/python/tests/test_volgraph.py`).
//! Effects, crop and clip, the light and scene files are set as `--features`, `--crop`, `--clip`,
//! `--light` and `--scene` set them; [`Renderer::reference`] gives the converged f64 image of the
//! graph's raycast model, so what accuracy costs in time can be measured from a script.

mod camera;
mod error;
mod renderer;

use anyhow::anyhow;
use volgraph_accel::volume::Volume;
use volgraph_core::runtime::Image;

pub use camera::Camera;
pub use error::ApiError;
pub use renderer::{Renderer, TfChoice};

/// Where a graph problem lies: the file as given, 1-based line and column where the graph text
/// has one, the message and the help — what `volgraph.GraphError` carries.
#[derive(Clone, Debug, PartialEq)]
pub struct GraphProblem {
    /// The graph file as named.
    pub path: String,
    /// 1-based line, where the problem has a place in the text.
    pub line: Option<usize>,
    /// 1-based column (characters).
    pub column: Option<usize>,
    /// Every problem, as the command line prints them (located, with their fixes).
    pub message: String,
}

impl GraphProblem {
    /// The first problem's place of `diagnostics`, and all of them as text.
    pub fn of(diagnostics: &volgraph_core::Diagnostics) -> Self {
        let place = diagnostics.items.iter().find_map(|d| match &d.location {
            volgraph_core::Location::Span(s) => Some(volgraph_core::graph::spans::line_col(&diagnostics.text, s.start)),
            _ => None,
        });
        Self {
            path: diagnostics.file.clone(),
            line: place.map(|p| p.0),
            column: place.map(|p| p.1),
            message: diagnostics.to_string(),
        }
    }
}

/// A rendered output, rows from the top.
pub enum Rendered {
    /// An 8-bit RGBA output (`present`'s `display`): sRGB-encoded bytes, as the PNG holds them.
    Srgb8 {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
        /// RGBA bytes.
        bytes: Vec<u8>,
    },
    /// Any other target: linear float values.
    Linear(Image),
}

/// A volume handed over in memory, as a raw file of the same voxels is read (`load::from_memory`).
pub fn volume_from_memory(
    name: &str,
    dims: glam::UVec3,
    spacing: glam::DVec3,
    data: volgraph_accel::volume::VoxelData,
) -> Result<Volume, ApiError> {
    Ok(volgraph_accel::load::from_memory(name, dims, spacing, data).map_err(|e| ApiError::Input(anyhow!(e)))?.volume)
}
