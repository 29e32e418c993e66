//! Graph inputs bound by the application, held by the runtime rather than by a plan: a volume
//! and a transfer-function LUT are uploaded once and shared by every plan that reads them, and
//! binding the same content again uploads nothing.

use std::collections::BTreeMap;
use std::hash::{Hash, Hasher};

use volgraph_accel::volume::{Volume, VoxelData};

use super::frame::VolumeDesc;
use super::gpu::{Gpu, GpuFault};
use super::upload::{UploadError, UploadedVolume, VolumeFormat, VolumeTexels, upload_lut, upload_volume};

/// One bound input texture.
pub struct BoundInput {
    /// The texture.
    pub texture: wgpu::Texture,
    /// Its default view.
    pub view: wgpu::TextureView,
    /// Hash of what was uploaded: binding equal content again is free.
    content: u64,
}

/// Inputs by graph input name, and the bound volume's description.
#[derive(Default)]
pub struct InputStore {
    inputs: BTreeMap<String, BoundInput>,
    volume: Option<(VolumeDesc, VolumeFormat)>,
    uploads: u64,
}

fn content_hash(parts: impl FnOnce(&mut std::collections::hash_map::DefaultHasher)) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    parts(&mut h);
    h.finish()
}

/// Uploads a volume as the 3D texture the shaders sample (normalized values,
/// `docs/rendering_model.md`): u8 → `v / 255`, u16 → `v / 65535`, i16 → `(v + 32768) / 65535`,
/// f32 → normalized by the value range, in the device's best format for the data.
pub fn upload_volume_texture(gpu: &Gpu, volume: &Volume) -> Result<UploadedVolume, UploadError> {
    let dims = [volume.dims.x, volume.dims.y, volume.dims.z];
    match &volume.data {
        VoxelData::U8(v) => upload_volume(gpu, &volume.name, dims, &VolumeTexels::Unorm8(v)),
        VoxelData::U16(v) => upload_volume(gpu, &volume.name, dims, &VolumeTexels::Unorm16(v)),
        VoxelData::I16(v) => {
            let shifted: Vec<u16> = v.iter().map(|x| (*x as i32 + 32768) as u16).collect();
            upload_volume(gpu, &volume.name, dims, &VolumeTexels::Unorm16(&shifted))
        }
        VoxelData::F32(_) => upload_volume(gpu, &volume.name, dims, &VolumeTexels::Float(&volume.normalized_f32())),
    }
}

impl BoundInput {
    /// A version of the content: equal content, equal version (passes that run only when their
    /// inputs change compare it).
    pub fn version(&self) -> u64 {
        self.content
    }
}

impl InputStore {
    /// Binds `volume` to input `name`; uploads only when its content differs from what is bound.
    /// Returns whether it uploaded.
    pub fn bind_volume(&mut self, gpu: &Gpu, name: &str, volume: &Volume) -> Result<bool, UploadError> {
        let content = content_hash(|h| {
            volume.dims.to_array().hash(h);
            volume.spacing.to_array().map(f64::to_bits).hash(h);
            volume.value_range.0.to_bits().hash(h);
            volume.value_range.1.to_bits().hash(h);
            match &volume.data {
                VoxelData::U8(v) => v.hash(h),
                VoxelData::U16(v) => v.hash(h),
                VoxelData::I16(v) => v.hash(h),
                VoxelData::F32(v) => v.iter().map(|x| x.to_bits()).for_each(|b| b.hash(h)),
            }
        });
        let desc = VolumeDesc::of(volume);
        if self.inputs.get(name).is_some_and(|i| i.content == content) {
            if let Some((_, format)) = self.volume {
                self.volume = Some((desc, format));
            }
            return Ok(false);
        }
        let uploaded = upload_volume_texture(gpu, volume)?;
        self.volume = Some((desc, uploaded.format));
        self.insert(name, uploaded.texture, content);
        Ok(true)
    }

    /// Binds an RGBA LUT to input `name`; uploads only when it differs from what is bound.
    pub fn bind_lut(&mut self, gpu: &Gpu, name: &str, lut: &[[f32; 4]]) -> Result<bool, GpuFault> {
        let content = content_hash(|h| lut.iter().flatten().map(|x| x.to_bits()).for_each(|b| b.hash(h)));
        if self.inputs.get(name).is_some_and(|i| i.content == content) {
            return Ok(false);
        }
        let texture = upload_lut(gpu, "transfer function", lut)?;
        self.insert(name, texture, content);
        Ok(true)
    }

    /// Binds a texture the application made to input `name` (always counts as new content).
    pub fn bind_texture(&mut self, name: &str, texture: wgpu::Texture) {
        let content = self.uploads.wrapping_add(0x9e37_79b9_7f4a_7c15);
        self.insert(name, texture, content);
    }

    fn insert(&mut self, name: &str, texture: wgpu::Texture, content: u64) {
        self.uploads += 1;
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        self.inputs.insert(name.to_string(), BoundInput { texture, view, content });
    }

    /// The input `name`.
    pub fn get(&self, name: &str) -> Option<&BoundInput> {
        self.inputs.get(name)
    }

    /// The bound volume's description and texture format.
    pub fn volume(&self) -> Option<(VolumeDesc, VolumeFormat)> {
        self.volume
    }

    /// Uploads done since the runtime started (binding unchanged content does none).
    pub fn uploads(&self) -> u64 {
        self.uploads
    }

    /// Bytes of bound input textures.
    pub fn bytes(&self) -> u64 {
        self.inputs
            .values()
            .map(|i| {
                let s = i.texture.size();
                let texel = i.texture.format().block_copy_size(None).unwrap_or(4) as u64;
                s.width as u64 * s.height as u64 * s.depth_or_array_layers as u64 * texel
            })
            .sum()
    }
}
