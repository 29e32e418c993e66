//! A handle through which tests and tools read a pass-owned 3D grid (the GPU min/max grid, the
//! empty-block flags) back to the CPU: a pass built "tapped" stores a clone of its texture in
//! the handle whenever it (re)creates it.

use std::sync::{Arc, Mutex};

use volgraph_core::runtime::Gpu;

/// Shared access to one owned 3D texture; cheap to clone.
#[derive(Clone, Default)]
pub struct GridTap {
    texture: Arc<Mutex<Option<wgpu::Texture>>>,
}

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
        let row = size.width * texel_bytes;
        let padded = row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("grid tap readback"),
            size: padded as u64 * size.height as u64 * size.depth_or_array_layers as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder =
            gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("grid tap readback") });
        encoder.copy_texture_to_buffer(
            texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded),
                    rows_per_image: Some(size.height),
                },
            },
            size,
        );
        gpu.queue.submit([encoder.finish()]);
        let slice = buffer.slice(..);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        gpu.wait_idle();
        let mut values =
            Vec::with_capacity((size.width * size.height * size.depth_or_array_layers * channels) as usize);
        {
            let data = slice.get_mapped_range().map_err(|e| format!("grid tap readback: {e}"))?;
            for z in 0..size.depth_or_array_layers {
                for y in 0..size.height {
                    let start = ((z * size.height + y) * padded) as usize;
                    let bytes = &data[start..start + row as usize];
                    values.extend(bytes.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])));
                }
            }
        }
        buffer.unmap();
        Ok(([size.width, size.height, size.depth_or_array_layers], values))
    }
}
