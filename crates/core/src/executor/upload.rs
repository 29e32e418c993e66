//! Uploading graph inputs: the volume as a 3D texture, the transfer function as a LUT.

use super::gpu::Gpu;

/// The voxel formats a volume texture can have.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VolumeFormat {
    /// 8-bit normalized.
    R8Unorm,
    /// 16-bit normalized.
    R16Unorm,
    /// 32-bit float (linear filtering needs the adapter's FLOAT32_FILTERABLE).
    R32Float,
}

impl VolumeFormat {
    fn wgpu(self) -> wgpu::TextureFormat {
        match self {
            VolumeFormat::R8Unorm => wgpu::TextureFormat::R8Unorm,
            VolumeFormat::R16Unorm => wgpu::TextureFormat::R16Unorm,
            VolumeFormat::R32Float => wgpu::TextureFormat::R32Float,
        }
    }

    fn bytes(self) -> u32 {
        match self {
            VolumeFormat::R8Unorm => 1,
            VolumeFormat::R16Unorm => 2,
            VolumeFormat::R32Float => 4,
        }
    }
}

/// Uploads a volume (`dims`, x fastest, little-endian texels) as a 3D texture.
pub fn upload_volume(
    gpu: &Gpu,
    label: &str,
    dims: [u32; 3],
    format: VolumeFormat,
    bytes: &[u8],
) -> Result<wgpu::Texture, String> {
    let max = gpu.limits.max_texture_dimension_3d;
    if dims.iter().any(|d| *d == 0 || *d > max) {
        return Err(format!(
            "volume \"{label}\" is {}x{}x{}, but this GPU's 3D textures are limited to 1..={max} per side; \
             bricking (Ruijters–Vilanova) lifts this limit",
            dims[0], dims[1], dims[2]
        ));
    }
    if format == VolumeFormat::R32Float && !gpu.float32_filterable {
        return Err(format!(
            "volume \"{label}\" is float32, but this GPU cannot filter 32-bit float textures; convert it to 16-bit"
        ));
    }
    let expected = dims[0] as u64 * dims[1] as u64 * dims[2] as u64 * format.bytes() as u64;
    if bytes.len() as u64 != expected {
        return Err(format!("volume \"{label}\": {} bytes given, {expected} expected", bytes.len()));
    }
    let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width: dims[0], height: dims[1], depth_or_array_layers: dims[2] },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D3,
        format: format.wgpu(),
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    gpu.queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: &texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        bytes,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(dims[0] * format.bytes()),
            rows_per_image: Some(dims[1]),
        },
        wgpu::Extent3d { width: dims[0], height: dims[1], depth_or_array_layers: dims[2] },
    );
    Ok(texture)
}

/// Uploads an RGBA LUT as an `N × 1` texture: Rgba32Float where the adapter filters 32-bit
/// floats, else Rgba16Float.
pub fn upload_lut(gpu: &Gpu, label: &str, rgba: &[[f32; 4]]) -> wgpu::Texture {
    let width = rgba.len().max(1) as u32;
    let (format, bytes): (wgpu::TextureFormat, Vec<u8>) = if gpu.float32_filterable {
        (wgpu::TextureFormat::Rgba32Float, bytemuck::cast_slice(rgba).to_vec())
    } else {
        let halves: Vec<u16> = rgba.iter().flatten().map(|v| f32_to_f16(*v)).collect();
        (wgpu::TextureFormat::Rgba16Float, bytemuck::cast_slice(&halves).to_vec())
    };
    let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width, height: 1, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let bpp = format.block_copy_size(None).unwrap_or(16);
    gpu.queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: &texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        &bytes,
        wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(width * bpp), rows_per_image: Some(1) },
        wgpu::Extent3d { width, height: 1, depth_or_array_layers: 1 },
    );
    texture
}

/// IEEE single → half, round to nearest even (for the f16 LUT fallback).
pub fn f32_to_f16(v: f32) -> u16 {
    let bits = v.to_bits();
    let sign = ((bits >> 16) & 0x8000) as u16;
    let exp = ((bits >> 23) & 0xff) as i32;
    let mant = bits & 0x7f_ffff;
    if exp == 0xff {
        return sign | 0x7c00 | if mant != 0 { 0x200 } else { 0 };
    }
    let e = exp - 127 + 15;
    if e >= 0x1f {
        return sign | 0x7c00;
    }
    if e <= 0 {
        if e < -10 {
            return sign;
        }
        let m = (mant | 0x80_0000) >> (1 - e);
        let round = (m >> 12) & 1;
        return sign | ((m >> 13) + round) as u16;
    }
    let m = mant >> 13;
    let round_bits = mant & 0x1fff;
    let mut h = sign as u32 | ((e as u32) << 10) | m;
    if round_bits > 0x1000 || (round_bits == 0x1000 && (m & 1) == 1) {
        h += 1;
    }
    h as u16
}
