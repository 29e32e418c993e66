//! Graph inputs bound by the application, held by the runtime rather than by a plan: a volume
//! and a transfer-function LUT are uploaded once and shared by every plan that reads them, and
//! binding the same content again uploads nothing.
//!
//! A volume is kept on the CPU too and becomes a 3D texture only when a plan's pass reads it as
//! one ([`InputStore::ensure_volume_texture`]): a pass that reads its voxels
//! ([`crate::plugin::PortKind::VolumeVoxels`], the brick pool of Ruijters & Vilanova 2006)
//! uploads what it needs itself, so a volume beyond the 3D texture limit or the memory budget
//! still renders through it.

use std::collections::BTreeMap;
use std::hash::{Hash, Hasher};
use std::sync::Arc;

use volgraph_accel::pyramid::{PyramidSource, TexelKind};
use volgraph_accel::volume::{Volume, VoxelData};

use super::frame::VolumeDesc;
use super::gpu::{Gpu, GpuFault};
use super::upload::{
    UploadError, UploadedVolume, VolumeFormat, VolumeTexels, upload_lut, upload_volume, volume_format_for,
};

/// One bound input texture.
pub struct BoundInput {
    /// The texture.
    pub texture: wgpu::Texture,
    /// Its default view.
    pub view: wgpu::TextureView,
    /// Hash of what was uploaded: binding equal content again is free.
    content: u64,
}

/// A bound volume's voxels, kept on the CPU, and the hash of their content.
struct BoundVoxels {
    voxels: Arc<Volume>,
    content: u64,
}

/// A volume bound as a resolution pyramid read brick by brick (an OME-Zarr store larger than
/// memory): only a pass that streams it ([`volgraph_accel::pyramid::PyramidSource`], the
/// `raycast_stream` raycaster) reads it; no texture or CPU copy of it is ever made.
struct BoundPyramid {
    source: Arc<dyn PyramidSource>,
    content: u64,
}

/// The volume input whose description the frame carries when several are bound.
pub const PRIMARY_VOLUME: &str = "volume";

/// Inputs by graph input name, and each bound volume's description.
#[derive(Default)]
pub struct InputStore {
    /// Textures: LUTs, application textures and volumes some pass read as a texture.
    inputs: BTreeMap<String, BoundInput>,
    /// Bound volumes on the CPU (their texture, once made, is in `inputs`).
    volumes: BTreeMap<String, BoundVoxels>,
    /// Volumes bound as pyramids, streamed by the passes that read them.
    pyramids: BTreeMap<String, BoundPyramid>,
    /// Bound LUTs on the CPU (for passes that classify bricks with them).
    tables: BTreeMap<String, Arc<Vec<[f32; 4]>>>,
    /// Each bound volume input's description and texture format, by name.
    descs: BTreeMap<String, (VolumeDesc, VolumeFormat)>,
    uploads: u64,
}

fn content_hash(parts: impl FnOnce(&mut std::collections::hash_map::DefaultHasher)) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    parts(&mut h);
    h.finish()
}

/// Uploads a volume as the 3D texture the shaders sample (normalized values,
/// `docs/rendering_model.md`): u8 → `v / 255`; 16-bit data as [`Volume::unorm16`] (with the
/// type range u16 → `v / 65535`, i16 → `(v + 32768) / 65535`; scanner data over the values it
/// holds); f32 → normalized by the value range; in the device's best format for the data.
pub fn upload_volume_texture(gpu: &Gpu, volume: &Volume) -> Result<UploadedVolume, UploadError> {
    let dims = [volume.dims.x, volume.dims.y, volume.dims.z];
    match &volume.data {
        VoxelData::U8(v) => upload_volume(gpu, &volume.name, dims, &VolumeTexels::Unorm8(v)),
        VoxelData::U16(v) if volume.value_range == (0.0, 65535.0) => {
            upload_volume(gpu, &volume.name, dims, &VolumeTexels::Unorm16(v))
        }
        VoxelData::U16(_) | VoxelData::I16(_) => {
            let texels: Vec<u16> = (0..volume.voxel_count()).map(|i| volume.unorm16(i)).collect();
            upload_volume(gpu, &volume.name, dims, &VolumeTexels::Unorm16(&texels))
        }
        VoxelData::F32(_) => upload_volume(gpu, &volume.name, dims, &VolumeTexels::Float(&volume.normalized_f32())),
    }
}

/// The voxels `origin .. origin + dims` of `volume` (clamped to it per axis, so a box reaching
/// past a face repeats the face: clamp-to-edge, as the sampler does) as texels of `format`, x
/// fastest, with the same normalisation as [`upload_volume_texture`]: what a brick pool uploads
/// for one brick.
pub fn volume_region_bytes(volume: &Volume, origin: glam::IVec3, dims: glam::UVec3, format: VolumeFormat) -> Vec<u8> {
    let n = volume.dims.as_ivec3();
    let count = dims.x as usize * dims.y as usize * dims.z as usize;
    let mut indices = Vec::with_capacity(count);
    for z in 0..dims.z as i32 {
        let zz = (origin.z + z).clamp(0, n.z - 1) as usize;
        for y in 0..dims.y as i32 {
            let yy = (origin.y + y).clamp(0, n.y - 1) as usize;
            let row = (zz * n.y as usize + yy) * n.x as usize;
            for x in 0..dims.x as i32 {
                indices.push(row + (origin.x + x).clamp(0, n.x - 1) as usize);
            }
        }
    }
    match &volume.data {
        VoxelData::U8(v) => {
            let t: Vec<u8> = indices.iter().map(|i| v[*i]).collect();
            super::upload::texel_bytes(&VolumeTexels::Unorm8(&t), format)
        }
        VoxelData::U16(_) | VoxelData::I16(_) => {
            let t: Vec<u16> = indices.iter().map(|i| volume.unorm16(*i)).collect();
            super::upload::texel_bytes(&VolumeTexels::Unorm16(&t), format)
        }
        VoxelData::F32(_) => {
            let t: Vec<f32> = indices.iter().map(|i| volume.normalized(*i) as f32).collect();
            super::upload::texel_bytes(&VolumeTexels::Float(&t), format)
        }
    }
}

/// The texture format [`upload_volume_texture`] gives `volume` on `gpu` (without uploading).
pub fn volume_texture_format(gpu: &Gpu, volume: &Volume) -> VolumeFormat {
    match &volume.data {
        VoxelData::U8(_) => volume_format_for(gpu, &VolumeTexels::Unorm8(&[])),
        VoxelData::U16(_) | VoxelData::I16(_) => volume_format_for(gpu, &VolumeTexels::Unorm16(&[])),
        VoxelData::F32(_) => volume_format_for(gpu, &VolumeTexels::Float(&[])),
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
    /// Binds `volume` to input `name`. Returns whether the content is new; the texture is made
    /// by [`InputStore::ensure_volume_texture`] when a pass reads it as one.
    pub fn bind_volume(&mut self, gpu: &Gpu, name: &str, volume: &Volume) -> Result<bool, UploadError> {
        let content = content_hash(|h| {
            volume.dims.to_array().hash(h);
            volume.spacing.to_array().map(f64::to_bits).hash(h);
            volume.value_range.0.to_bits().hash(h);
            volume.value_range.1.to_bits().hash(h);
            let bytes: &[u8] = match &volume.data {
                VoxelData::U8(v) => v,
                VoxelData::U16(v) => bytemuck::cast_slice(v),
                VoxelData::I16(v) => bytemuck::cast_slice(v),
                VoxelData::F32(v) => bytemuck::cast_slice(v),
            };
            // The voxels by a fast fingerprint (every recompile binds them again), and their type.
            std::mem::discriminant(&volume.data).hash(h);
            super::fingerprint::fingerprint(bytes).hash(h);
        });
        let desc = VolumeDesc::of(volume);
        let format = volume_texture_format(gpu, volume);
        if self.volumes.get(name).is_some_and(|v| v.content == content) {
            self.descs.insert(name.to_string(), (desc, format));
            return Ok(false);
        }
        let expected = volume.dims.x as u64 * volume.dims.y as u64 * volume.dims.z as u64;
        if volume.data.len() as u64 != expected {
            return Err(UploadError::Size { label: volume.name.clone(), given: volume.data.len(), expected });
        }
        self.inputs.remove(name);
        self.pyramids.remove(name);
        self.volumes.insert(name.to_string(), BoundVoxels { voxels: Arc::new(volume.clone()), content });
        self.descs.insert(name.to_string(), (desc, format));
        Ok(true)
    }

    /// Binds a pyramid to volume input `name` (a volume read brick by brick by the pass that
    /// streams it); the frame's volume description is its finest level's. Binding the same
    /// source again (the same `Arc`) is no new content.
    pub fn bind_pyramid(&mut self, gpu: &Gpu, name: &str, source: Arc<dyn PyramidSource>) {
        let level = source.levels()[0];
        let content = content_hash(|h| {
            "pyramid".hash(h);
            (Arc::as_ptr(&source) as *const () as usize).hash(h);
        });
        let format = volume_format_for(
            gpu,
            &match source.texel_kind() {
                TexelKind::Unorm8 => VolumeTexels::Unorm8(&[]),
                TexelKind::Unorm16 => VolumeTexels::Unorm16(&[]),
                TexelKind::Float => VolumeTexels::Float(&[]),
            },
        );
        self.descs.insert(name.to_string(), (VolumeDesc::of_box(level.dims, source.spacing()), format));
        self.inputs.remove(name);
        self.volumes.remove(name);
        self.pyramids.insert(name.to_string(), BoundPyramid { source, content });
    }

    /// The pyramid bound to volume input `name`, if one is (not a volume in memory).
    pub fn pyramid(&self, name: &str) -> Option<&Arc<dyn PyramidSource>> {
        self.pyramids.get(name).map(|p| &p.source)
    }

    /// Makes the 3D texture of volume input `name` if it has none yet (a pass reads it as a
    /// texture). Returns whether it uploaded.
    pub fn ensure_volume_texture(&mut self, gpu: &Gpu, name: &str) -> Result<bool, UploadError> {
        if self.inputs.contains_key(name) {
            return Ok(false);
        }
        let Some(bound) = self.volumes.get(name) else { return Ok(false) };
        let content = bound.content;
        let uploaded = upload_volume_texture(gpu, &bound.voxels)?;
        self.insert(name, uploaded.texture, content);
        Ok(true)
    }

    /// The voxels bound to volume input `name`.
    pub fn voxels(&self, name: &str) -> Option<&Arc<Volume>> {
        self.volumes.get(name).map(|v| &v.voxels)
    }

    /// The LUT bound to input `name`, on the CPU.
    pub fn table(&self, name: &str) -> Option<&Arc<Vec<[f32; 4]>>> {
        self.tables.get(name)
    }

    /// The content version of input `name` (texture or CPU volume).
    pub fn version(&self, name: &str) -> Option<u64> {
        self.inputs
            .get(name)
            .map(|i| i.content)
            .or_else(|| self.volumes.get(name).map(|v| v.content))
            .or_else(|| self.pyramids.get(name).map(|p| p.content))
    }

    /// Whether input `name` is bound (as a texture or as a volume on the CPU).
    pub fn is_bound(&self, name: &str) -> bool {
        self.inputs.contains_key(name) || self.volumes.contains_key(name) || self.pyramids.contains_key(name)
    }

    /// Binds an RGBA LUT to input `name`; uploads only when it differs from what is bound.
    pub fn bind_lut(&mut self, gpu: &Gpu, name: &str, lut: &[[f32; 4]]) -> Result<bool, GpuFault> {
        let content = content_hash(|h| lut.iter().flatten().map(|x| x.to_bits()).for_each(|b| b.hash(h)));
        if self.inputs.get(name).is_some_and(|i| i.content == content) {
            return Ok(false);
        }
        let texture = upload_lut(gpu, "transfer function", lut)?;
        self.insert(name, texture, content);
        self.tables.insert(name.to_string(), Arc::new(lut.to_vec()));
        Ok(true)
    }

    /// Binds a label table (RGBA by label value) to input `name` as its 2D texture
    /// ([`super::upload::upload_label_table`]); uploads only when it differs from what is bound.
    pub fn bind_label_table(&mut self, gpu: &Gpu, name: &str, table: &[[f32; 4]]) -> Result<bool, GpuFault> {
        let content = content_hash(|h| {
            "label table".hash(h);
            table.iter().flatten().map(|x| x.to_bits()).for_each(|b| b.hash(h))
        });
        if self.inputs.get(name).is_some_and(|i| i.content == content) {
            return Ok(false);
        }
        let texture = super::upload::upload_label_table(gpu, "label table", table)?;
        self.insert(name, texture, content);
        self.tables.insert(name.to_string(), Arc::new(table.to_vec()));
        Ok(true)
    }

    /// Binds a texture the application made to input `name` (always counts as new content).
    pub fn bind_texture(&mut self, name: &str, texture: wgpu::Texture) {
        let content = self.uploads.wrapping_add(0x9e37_79b9_7f4a_7c15);
        self.insert(name, texture, content);
        // Whatever LUT was bound here before is not what the texture holds.
        self.tables.remove(name);
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

    /// The frame's volume — the description and texture format of the volume input named
    /// `volume`, else of the first bound by name — which sets the box rays meet and the voxel
    /// unit. A graph with several volume inputs binds volumes on one grid (`volgraph render`
    /// checks it), so any of them describes the same box.
    pub fn volume(&self) -> Option<(VolumeDesc, VolumeFormat)> {
        self.descs.get(PRIMARY_VOLUME).or_else(|| self.descs.values().next()).copied()
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
