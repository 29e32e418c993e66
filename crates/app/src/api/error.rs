//! What the library's calls fail with, by who must act: the graph file's author, the caller
//! (a volume, a transfer function, a camera, a setting), or the GPU — so the Python package
//! raises `GraphError`, `ValueError`/`VolumeError` or `GpuError` by kind, never by the words
//! of a message.

use crate::cli::CliError;

/// Why a library call failed; `Display` is what the command line prints.
#[derive(Debug, thiserror::Error)]
pub enum ApiError {
    /// The graph file's problems, located (see [`super::GraphProblem`]).
    #[error("{0}")]
    Graph(volgraph_core::Diagnostics),
    /// An argument or input the caller gave: a volume, transfer function, scene, camera, size,
    /// parameter, feature or output that cannot be used, with the fix.
    #[error("{0:#}")]
    Input(anyhow::Error),
    /// No GPU adapter, or the GPU refused the work (a texture over its limits, a lost device).
    #[error("{0:#}")]
    Gpu(anyhow::Error),
}

impl ApiError {
    /// A GPU failure.
    pub fn gpu(e: impl std::fmt::Display) -> Self {
        ApiError::Gpu(anyhow::anyhow!("{e}"))
    }
}

impl From<CliError> for ApiError {
    fn from(e: CliError) -> Self {
        match e {
            CliError::Graph(d) => ApiError::Graph(d),
            CliError::Other(e) => ApiError::Input(e),
        }
    }
}

impl From<anyhow::Error> for ApiError {
    fn from(e: anyhow::Error) -> Self {
        ApiError::Input(e)
    }
}
