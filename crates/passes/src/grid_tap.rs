//! A handle through which tests and tools read a pass-owned 3D grid (the GPU min/max grid, the
//! empty-block flags) back to the CPU: a pass built "tapped" stores a clone of its texture in
//! the handle whenever it (re)creates it.

use std::sync::{Arc, Mutex};

#[cfg(feature = "gpu")]
use volgraph_core::runtime::Gpu;

#[cfg(feature = "gpu")]
/// Shared access to one owned 3D texture; cheap to clone.
#[derive(Clone, Default)]
pub struct GridTap {
    texture: Arc<Mutex<Option<wgpu::Texture>>>,
}

#[cfg(feature = "gpu")]
impl GridTap {
    /// An empty tap (nothing built yet).
    pub fn new() -> Self {
        Self::default()
    }

    pub(crate) fn set(&self, texture: &wgpu::Texture) {
        if let Ok(mut slot) = self.texture.lock() {
            *slot = Some(texture.clone());
        }
    }

    /// Reads the texture as rows of `f32` channels: `(dims, values)` with `channels` floats per
    /// texel, x fastest. Errors when nothing has been built yet or the texture is not a 32-bit
    /// float format with that many channels.
    pub fn read_f32(&self, gpu: &Gpu, channels: u32) -> Result<([u32; 3], Vec<f32>), String> {
        let texture = self
            .texture
            .lock()
            .map_err(|_| "grid tap lock poisoned".to_string())?
            .clone()
            .ok_or("the tapped pass has not built its grid yet (run a frame first)")?;
        let texel_bytes = 4 * channels;
        if texture.format().block_copy_size(None) != Some(texel_bytes) {
            return Err(format!("the tapped texture is {:?}, not {channels} f32 channels", texture.format()));
        }
        let size = texture.size();
        let bytes = volgraph_core::runtime::readback::read_texture_bytes(gpu, &texture)?;
        let values: Vec<f32> = bytes.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
        Ok(([size.width, size.height, size.depth_or_array_layers], values))
    }
}
