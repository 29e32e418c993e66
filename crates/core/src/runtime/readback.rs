//! Reading targets back to the CPU as f32 channels.

use super::gpu::Gpu;
use crate::format::TargetFormat;

/// A target read back: `channels` f32 values per pixel, rows top to bottom.
#[derive(Clone, Debug)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Channels per pixel (1, 2 or 4).
    pub channels: u32,
    /// The values; 8-bit formats are divided by 255, f16 widened.
    pub data: Vec<f32>,
}

impl Image {
    /// Pixel `(x, y)` as RGBA (missing channels 0, alpha 1 for 1–2 channel images).
    pub fn rgba(&self, x: u32, y: u32) -> [f32; 4] {
        let c = self.channels as usize;
        let i = (y as usize * self.width as usize + x as usize) * c;
        let mut out = [0.0, 0.0, 0.0, 1.0];
        let n = c.min(4);
        out[..n].copy_from_slice(&self.data[i..i + n]);
        out
    }

    /// Every pixel as f64 RGBA, row by row from the top: what
    /// [`volgraph_accel::image_diff::image_diff`] compares with a reference.
    pub fn to_rgba_f64(&self) -> Vec<[f64; 4]> {
        (0..self.height)
            .flat_map(|y| (0..self.width).map(move |x| (x, y)))
            .map(|(x, y)| self.rgba(x, y).map(f64::from))
            .collect()
    }
}

fn channels(format: TargetFormat) -> u32 {
    match format {
        TargetFormat::R32Float | TargetFormat::Depth32Float | TargetFormat::R8Unorm => 1,
        TargetFormat::Rg32Float => 2,
        TargetFormat::Rgba16Float | TargetFormat::Rgba32Float | TargetFormat::Rgba8Unorm => 4,
    }
}

/// Waits for `buffer` (MAP_READ) to map and returns `range` of it.
fn map_and_copy(gpu: &Gpu, buffer: &wgpu::Buffer) -> Result<Vec<u8>, String> {
    let slice = buffer.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    gpu.wait_idle();
    match rx.recv() {
        Ok(Ok(())) => {}
        Ok(Err(e)) => return Err(format!("readback failed: {e}")),
        Err(_) => return Err("readback never completed".to_string()),
    }
    let bytes = slice.get_mapped_range().map_err(|e| format!("readback failed: {e}"))?.to_vec();
    buffer.unmap();
    Ok(bytes)
}

/// The one readback of volgraph: the bytes of `buffer[offset..offset + size]`, waiting for the GPU.
pub fn read_buffer(gpu: &Gpu, buffer: &wgpu::Buffer, offset: u64, size: u64) -> Result<Vec<u8>, String> {
    let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: size.max(4).next_multiple_of(4),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("readback") });
    encoder.copy_buffer_to_buffer(buffer, offset, &staging, 0, size.next_multiple_of(4));
    gpu.queue.submit([encoder.finish()]);
    let mut bytes = map_and_copy(gpu, &staging)?;
    bytes.truncate(size as usize);
    Ok(bytes)
}

/// The texels of mip 0 of `texture` (2D or 3D), tightly packed, x fastest, then y, then z.
pub fn read_texture_bytes(gpu: &Gpu, texture: &wgpu::Texture) -> Result<Vec<u8>, String> {
    let format = texture.format();
    let texel = format
        .block_copy_size(Some(wgpu::TextureAspect::All))
        .or_else(|| format.block_copy_size(Some(wgpu::TextureAspect::DepthOnly)));
    let Some(texel) = texel else {
        return Err(format!("cannot read back {format:?} textures"));
    };
    let size = texture.size();
    let layers = if texture.dimension() == wgpu::TextureDimension::D3 { size.depth_or_array_layers } else { 1 };
    let row = size.width * texel;
    let padded = row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: padded as u64 * size.height as u64 * layers as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("readback") });
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: if format.is_depth_stencil_format() {
                wgpu::TextureAspect::DepthOnly
            } else {
                wgpu::TextureAspect::All
            },
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &staging,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(size.height),
            },
        },
        wgpu::Extent3d { width: size.width, height: size.height, depth_or_array_layers: layers },
    );
    gpu.queue.submit([encoder.finish()]);
    let padded_bytes = map_and_copy(gpu, &staging)?;
    let mut out = Vec::with_capacity((row * size.height * layers) as usize);
    for line in 0..(size.height * layers) as usize {
        let start = line * padded as usize;
        out.extend_from_slice(&padded_bytes[start..start + row as usize]);
    }
    Ok(out)
}

/// Copies a target to the CPU and converts it to f32 channels.
pub fn read_texture(
    gpu: &Gpu,
    texture: &wgpu::Texture,
    format: TargetFormat,
    extent: (u32, u32),
) -> Result<Image, String> {
    let bytes = read_texture_bytes(gpu, texture)?;
    let c = channels(format);
    let mut data = Vec::with_capacity((extent.0 * extent.1 * c) as usize);
    match format {
        TargetFormat::Rgba8Unorm | TargetFormat::R8Unorm => data.extend(bytes.iter().map(|b| *b as f32 / 255.0)),
        TargetFormat::Rgba16Float => {
            data.extend(bytes.chunks_exact(2).map(|h| f16_to_f32(u16::from_le_bytes([h[0], h[1]]))))
        }
        _ => data.extend(bytes.chunks_exact(4).map(|f| f32::from_le_bytes([f[0], f[1], f[2], f[3]]))),
    }
    Ok(Image { width: extent.0, height: extent.1, channels: c, data })
}

/// IEEE 754 half → single.
pub fn f16_to_f32(h: u16) -> f32 {
    let sign = ((h >> 15) & 1) as u32;
    let exp = ((h >> 10) & 0x1f) as u32;
    let mant = (h & 0x3ff) as u32;
    let bits = match (exp, mant) {
        (0, 0) => sign << 31,
        (0, m) => {
            // Subnormal: normalize.
            let mut e = 127 - 15 + 1;
            let mut m = m;
            while m & 0x400 == 0 {
                m <<= 1;
                e -= 1;
            }
            (sign << 31) | ((e as u32) << 23) | ((m & 0x3ff) << 13)
        }
        (0x1f, m) => (sign << 31) | (0xff << 23) | (m << 13),
        (e, m) => (sign << 31) | ((e + 127 - 15) << 23) | (m << 13),
    };
    f32::from_bits(bits)
}

#[cfg(test)]
mod tests {
    use super::f16_to_f32;

    #[test]
    fn half_conversion_matches_known_values() {
        assert_eq!(f16_to_f32(0x3c00), 1.0);
        assert_eq!(f16_to_f32(0xc000), -2.0);
        assert_eq!(f16_to_f32(0x3800), 0.5);
        assert_eq!(f16_to_f32(0x0001), 2f32.powi(-24));
        assert!(f16_to_f32(0x7e00).is_nan());
    }
}
