//! Uploading graph inputs: the volume as a 3D texture, the transfer function as a LUT.
//!
//! The texture format follows what the device offers, with the same normalisation on every path
//! (`docs/rendering_model.md`, "Volume and world space"): 16-bit voxels go up as R16Unorm where
//! `TEXTURE_FORMAT_16BIT_NORM` exists, else as R32Float holding `v / 65535` where 32-bit floats
//! filter, else as R16Float (11 significant bits). Every GPU error comes back as a value.

use super::gpu::{Gpu, GpuFault};

/// The voxel formats a volume texture can have.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VolumeFormat {
    /// 8-bit normalized.
    R8Unorm,
    /// 16-bit normalized (needs `TEXTURE_FORMAT_16BIT_NORM`).
    R16Unorm,
    /// 16-bit float: the fallback where neither 16-bit normalized nor filterable 32-bit float
    /// textures exist (relative precision 2⁻¹¹).
    R16Float,
    /// 32-bit float (linear filtering needs the adapter's FLOAT32_FILTERABLE).
    R32Float,
}

impl VolumeFormat {
    /// The wgpu format.
    pub fn wgpu(self) -> wgpu::TextureFormat {
        match self {
            VolumeFormat::R8Unorm => wgpu::TextureFormat::R8Unorm,
            VolumeFormat::R16Unorm => wgpu::TextureFormat::R16Unorm,
            VolumeFormat::R16Float => wgpu::TextureFormat::R16Float,
            VolumeFormat::R32Float => wgpu::TextureFormat::R32Float,
        }
    }

    /// Bytes per texel.
    pub fn bytes(self) -> u32 {
        match self {
            VolumeFormat::R8Unorm => 1,
            VolumeFormat::R16Unorm | VolumeFormat::R16Float => 2,
            VolumeFormat::R32Float => 4,
        }
    }
}

/// Normalized voxels ready to upload, x fastest.
#[derive(Clone, Debug)]
pub enum VolumeTexels<'a> {
    /// 8-bit values, `v / 255` in the shader.
    Unorm8(&'a [u8]),
    /// 16-bit values, `v / 65535` in the shader (i16 data offset by 32768 first).
    Unorm16(&'a [u16]),
    /// Values already normalized to [0, 1].
    Float(&'a [f32]),
}

impl VolumeTexels<'_> {
    fn len(&self) -> usize {
        match self {
            VolumeTexels::Unorm8(v) => v.len(),
            VolumeTexels::Unorm16(v) => v.len(),
            VolumeTexels::Float(v) => v.len(),
        }
    }
}

/// Why a volume could not be uploaded.
#[derive(Debug, thiserror::Error)]
pub enum UploadError {
    /// A side is zero or beyond the device's 3D texture limit.
    #[error(
        "volume \"{label}\" is {}x{}x{}, but this GPU's 3D textures are limited to 1..={max} per side; \
         render it with bricking, through the brick pool of graphs/ruijters_vilanova_2006/bricks_octree.ron, \
         which has no such limit", .dims[0], .dims[1], .dims[2]
    )]
    TooLarge {
        /// The volume's name.
        label: String,
        /// Its dimensions.
        dims: [u32; 3],
        /// The device limit.
        max: u32,
    },
    /// The voxel count does not match the dimensions.
    #[error("volume \"{label}\": {given} voxels given, {expected} expected")]
    Size {
        /// The volume's name.
        label: String,
        /// Voxels given.
        given: usize,
        /// Voxels the dimensions need.
        expected: u64,
    },
    /// The GPU rejected the texture or the copy.
    #[error(transparent)]
    Gpu(#[from] GpuFault),
}

/// A volume on the GPU.
pub struct UploadedVolume {
    /// The 3D texture.
    pub texture: wgpu::Texture,
    /// The format chosen for this device.
    pub format: VolumeFormat,
}

/// The texture format `texels` get on `gpu` (see the module documentation). On a CPU adapter
/// 8-bit voxels go up as R16Unorm — `v · 257 / 65535` is exactly `v / 255` — because llvmpipe
/// filters them faster than 8-bit texels, whose path works in packed integers with 8-bit
/// weights, and more accurately (bench/one-march.md: hydrogen's `fastest` run 9.8 % fewer
/// instructions and its frame ~7 % faster, the isosurface's mean error against the f64
/// reference ÷2–40). A brick
/// pool stores bricks in the same format, so it renders like the single texture.
pub fn volume_format_for(gpu: &Gpu, texels: &VolumeTexels<'_>) -> VolumeFormat {
    match texels {
        VolumeTexels::Unorm8(_) if gpu.is_cpu && gpu.norm16 => VolumeFormat::R16Unorm,
        VolumeTexels::Unorm8(_) => VolumeFormat::R8Unorm,
        VolumeTexels::Unorm16(_) if gpu.norm16 => VolumeFormat::R16Unorm,
        VolumeTexels::Unorm16(_) | VolumeTexels::Float(_) if gpu.float32_filterable => VolumeFormat::R32Float,
        VolumeTexels::Unorm16(_) | VolumeTexels::Float(_) => VolumeFormat::R16Float,
    }
}

/// The bytes of `texels` in `format` (x fastest, tightly packed).
pub fn texel_bytes(texels: &VolumeTexels<'_>, format: VolumeFormat) -> Vec<u8> {
    let as_f32 = |t: &VolumeTexels<'_>| -> Vec<f32> {
        match t {
            VolumeTexels::Unorm8(v) => v.iter().map(|x| *x as f32 / 255.0).collect(),
            VolumeTexels::Unorm16(v) => v.iter().map(|x| *x as f32 / 65535.0).collect(),
            VolumeTexels::Float(v) => v.to_vec(),
        }
    };
    match (format, texels) {
        (VolumeFormat::R8Unorm, VolumeTexels::Unorm8(v)) => v.to_vec(),
        (VolumeFormat::R16Unorm, VolumeTexels::Unorm16(v)) => bytemuck::cast_slice(v).to_vec(),
        (VolumeFormat::R16Unorm, VolumeTexels::Unorm8(v)) => {
            let widened: Vec<u16> = v.iter().map(|x| u16::from(*x) * 257).collect();
            bytemuck::cast_slice(&widened).to_vec()
        }
        (VolumeFormat::R32Float, t) => bytemuck::cast_slice(&as_f32(t)).to_vec(),
        (VolumeFormat::R16Float, t) => {
            let halves: Vec<u16> = as_f32(t).into_iter().map(f32_to_f16).collect();
            bytemuck::cast_slice(&halves).to_vec()
        }
        // Unorm formats only ever hold their own kind (volume_format_for); widen anything else.
        (_, t) => bytemuck::cast_slice(&as_f32(t)).to_vec(),
    }
}

/// Uploads a volume (`dims`, x fastest) as a 3D texture in the format [`volume_format_for`]
/// picks for this device.
pub fn upload_volume(
    gpu: &Gpu,
    label: &str,
    dims: [u32; 3],
    texels: &VolumeTexels<'_>,
) -> Result<UploadedVolume, UploadError> {
    let max = gpu.limits.max_texture_dimension_3d;
    if dims.iter().any(|d| *d == 0 || *d > max) {
        return Err(UploadError::TooLarge { label: label.to_string(), dims, max });
    }
    let expected = dims[0] as u64 * dims[1] as u64 * dims[2] as u64;
    if texels.len() as u64 != expected {
        return Err(UploadError::Size { label: label.to_string(), given: texels.len(), expected });
    }
    let format = volume_format_for(gpu, texels);
    let bytes = texel_bytes(texels, format);
    let texture = texture_with(
        gpu,
        || format!("uploading volume \"{label}\" ({}x{}x{} {format:?})", dims[0], dims[1], dims[2]),
        (label, dims, wgpu::TextureDimension::D3, format.wgpu()),
        &bytes,
    )?;
    Ok(UploadedVolume { texture, format })
}

/// Uploads an RGBA LUT as a 1D texture of `N` texels: Rgba32Float where the adapter filters
/// 32-bit floats, else Rgba16Float. One dimension, not an `N × 1` 2D texture: a linear lookup
/// then reads two texels instead of four (llvmpipe fetches both rows of a bilinear footprint even
/// when the second has weight 0, bench/one-march.md).
pub fn upload_lut(gpu: &Gpu, label: &str, rgba: &[[f32; 4]]) -> Result<wgpu::Texture, GpuFault> {
    let width = rgba.len().max(1) as u32;
    upload_rgba(gpu, ("transfer-function LUT", label), rgba, (width, 1), wgpu::TextureDimension::D1)
}

/// Texels per row of a label table's texture: label `v` is texel `(v % 256, v / 256)`.
pub const LABEL_TABLE_ROW: u32 = 256;

/// Uploads a label table (RGBA by label value, `volgraph_accel::labels::LabelTable::lut`) as the
/// 2D texture a `LabelTable` input binds: [`LABEL_TABLE_ROW`] labels per row, the last row
/// padded with hidden labels. Read with `textureLoad` (no filtering between labels).
pub fn upload_label_table(gpu: &Gpu, label: &str, rgba: &[[f32; 4]]) -> Result<wgpu::Texture, GpuFault> {
    let rows = (rgba.len() as u32).div_ceil(LABEL_TABLE_ROW).max(1);
    let mut padded = rgba.to_vec();
    padded.resize((rows * LABEL_TABLE_ROW) as usize, [0.0; 4]);
    upload_rgba(gpu, ("label table", label), &padded, (LABEL_TABLE_ROW, rows), wgpu::TextureDimension::D2)
}

/// `rgba` as a `width × height` texture of `dimension` (1D: height 1), in f32 where the device
/// filters it, else f16; `(what, label)` name it in a fault.
fn upload_rgba(
    gpu: &Gpu,
    (what, label): (&str, &str),
    rgba: &[[f32; 4]],
    (width, height): (u32, u32),
    dimension: wgpu::TextureDimension,
) -> Result<wgpu::Texture, GpuFault> {
    let (format, bytes): (wgpu::TextureFormat, Vec<u8>) = if gpu.float32_filterable {
        (wgpu::TextureFormat::Rgba32Float, bytemuck::cast_slice(rgba).to_vec())
    } else {
        let halves: Vec<u16> = rgba.iter().flatten().map(|v| f32_to_f16(*v)).collect();
        (wgpu::TextureFormat::Rgba16Float, bytemuck::cast_slice(&halves).to_vec())
    };
    texture_with(
        gpu,
        || format!("uploading the {what} \"{label}\" ({} entries)", rgba.len()),
        (label, [width, height, 1], dimension, format),
        &bytes,
    )
}

/// A label map's [`LabelQuads`](volgraph_accel::labels::sample::LabelQuads) as an unsigned
/// integer 3D texture of its channels' width (`Rgba8Uint`, `Rgba16Uint` or `Rgba32Uint`; read as
/// `texture_3d<u32>` alike): smooth label sampling's two reads a sample.
pub fn upload_label_quads(
    gpu: &Gpu,
    label: &str,
    dims: [u32; 3],
    quads: &volgraph_accel::labels::sample::LabelQuads,
) -> Result<wgpu::Texture, GpuFault> {
    use volgraph_accel::labels::sample::LabelQuads;
    let (format, bytes): (_, &[u8]) = match quads {
        LabelQuads::U8(q) => (wgpu::TextureFormat::Rgba8Uint, bytemuck::cast_slice(q)),
        LabelQuads::U16(q) => (wgpu::TextureFormat::Rgba16Uint, bytemuck::cast_slice(q)),
        LabelQuads::U32(q) => (wgpu::TextureFormat::Rgba32Uint, bytemuck::cast_slice(q)),
    };
    texture_with(
        gpu,
        || format!("uploading \"{label}\" ({}x{}x{} {format:?})", dims[0], dims[1], dims[2]),
        (label, dims, wgpu::TextureDimension::D3, format),
        bytes,
    )
}

/// A label map's [`LabelCubes`](volgraph_accel::labels::cubes::LabelCubes) as an `Rg32Uint` 3D
/// texture, a texel a block (label, distance): where a march takes samples without reading the
/// label map (`shaders/common/label_cubes.wgsl`).
pub fn upload_label_cubes(
    gpu: &Gpu,
    label: &str,
    cubes: &volgraph_accel::labels::cubes::LabelCubes,
) -> Result<wgpu::Texture, GpuFault> {
    let dims = cubes.dims.to_array();
    texture_with(
        gpu,
        || format!("uploading \"{label}\" ({}x{}x{} rg32uint)", dims[0], dims[1], dims[2]),
        (label, dims, wgpu::TextureDimension::D3, wgpu::TextureFormat::Rg32Uint),
        bytemuck::cast_slice(&cubes.texels),
    )
}

/// `texels` (x fastest) as a filterable `Rgba16Float` 3D texture: derived fields in \[0, 1\] whose
/// f16 step (≤ 2⁻¹¹ there) is below a 255th (the illumination volume of the `shadows` and
/// `ambient_occlusion` effects, as the GPU's own dispatch writes it).
pub fn upload_rgba16f_3d(
    gpu: &Gpu,
    label: &str,
    dims: [u32; 3],
    texels: &[[f32; 4]],
) -> Result<wgpu::Texture, GpuFault> {
    let halves: Vec<u16> = texels.iter().flatten().map(|v| f32_to_f16(*v)).collect();
    texture_with(
        gpu,
        || format!("uploading \"{label}\" ({}x{}x{} rgba16float)", dims[0], dims[1], dims[2]),
        (label, dims, wgpu::TextureDimension::D3, wgpu::TextureFormat::Rgba16Float),
        bytemuck::cast_slice(&halves),
    )
}

/// The one way a sampled input texture is made: `(label, dims, dimension, format)` created and
/// `bytes` (x fastest, tightly packed rows) written, a GPU error coming back as a fault named by
/// `what`.
fn texture_with(
    gpu: &Gpu,
    what: impl Fn() -> String,
    (label, dims, dimension, format): (&str, [u32; 3], wgpu::TextureDimension, wgpu::TextureFormat),
    bytes: &[u8],
) -> Result<wgpu::Texture, GpuFault> {
    let size = wgpu::Extent3d { width: dims[0], height: dims[1], depth_or_array_layers: dims[2] };
    let texel = format.block_copy_size(None).unwrap_or(4);
    gpu.checked(what, || {
        let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size,
            mip_level_count: 1,
            sample_count: 1,
            dimension,
            format,
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
                bytes_per_row: Some(dims[0] * texel),
                rows_per_image: Some(dims[1]),
            },
            size,
        );
        texture
    })
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
