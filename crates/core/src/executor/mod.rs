//! The wgpu executor: runs a [`crate::plan::Plan`] frame by frame.

/// Context given to [`crate::plugin::PassPlugin::create`].
pub struct CreateContext<'a> {
    /// The device.
    pub device: &'a wgpu::Device,
}

/// Context given to [`crate::plugin::PassNode::record`].
pub struct RecordContext<'a> {
    /// The frame's encoder.
    pub encoder: &'a mut wgpu::CommandEncoder,
}

/// A pass failed to build or record.
#[derive(Debug, thiserror::Error)]
#[error("pass \"{pass}\": {message}")]
pub struct PassError {
    /// The pass label.
    pub pass: String,
    /// What went wrong.
    pub message: String,
}
