//! The runtime's texture pool: transient targets keyed by descriptor. A live plan acquires its
//! slots' textures here and gives them back when a new plan replaces it, so a graph edit that
//! keeps a target's format and size keeps its texture, and a resize reallocates only the
//! viewport-sized targets. Textures nobody took back within one further plan change are freed,
//! so resizing a window never accumulates memory.

use std::collections::HashMap;

use super::gpu::{Gpu, GpuFault};
use crate::format::TargetFormat;

/// What defines a pooled texture.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct TextureKey {
    /// Pixel format.
    pub format: TargetFormat,
    /// Size in pixels.
    pub extent: (u32, u32),
}

/// A 2D target texture with its default view.
#[derive(Clone, Debug)]
pub struct PooledTexture {
    /// The texture.
    pub texture: wgpu::Texture,
    /// Its default view.
    pub view: wgpu::TextureView,
    /// Its descriptor.
    pub key: TextureKey,
}

/// Usage of every target: drawn into, sampled, copied (readback), and stored to where the
/// format allows (compute passes).
pub(crate) fn usage_for(format: TargetFormat) -> wgpu::TextureUsages {
    let mut u = wgpu::TextureUsages::RENDER_ATTACHMENT
        | wgpu::TextureUsages::TEXTURE_BINDING
        | wgpu::TextureUsages::COPY_SRC
        | wgpu::TextureUsages::COPY_DST;
    if matches!(
        format,
        TargetFormat::Rgba16Float
            | TargetFormat::Rgba32Float
            | TargetFormat::R32Float
            | TargetFormat::Rg32Float
            | TargetFormat::Rgba8Unorm
    ) {
        u |= wgpu::TextureUsages::STORAGE_BINDING;
    }
    u
}

/// A storage buffer from the pool.
#[derive(Clone, Debug)]
pub struct PooledBuffer {
    /// The buffer.
    pub buffer: wgpu::Buffer,
    /// Its size in bytes.
    pub size: u64,
}

/// Free textures and buffers by descriptor, each with the plan generation it was given back in.
#[derive(Default)]
pub struct TexturePool {
    free: HashMap<TextureKey, Vec<(PooledTexture, u64)>>,
    free_buffers: HashMap<u64, Vec<(PooledBuffer, u64)>>,
    generation: u64,
    created: u64,
}

impl TexturePool {
    /// A texture of `key`: a free one, or a new one (creation errors come back as values).
    pub fn acquire(&mut self, gpu: &Gpu, key: TextureKey, label: &str) -> Result<PooledTexture, GpuFault> {
        if let Some(list) = self.free.get_mut(&key)
            && let Some((t, _)) = list.pop()
        {
            return Ok(t);
        }
        let texture = gpu.checked(
            || format!("creating target {label} ({} {}x{})", key.format, key.extent.0, key.extent.1),
            || {
                gpu.device.create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d { width: key.extent.0, height: key.extent.1, depth_or_array_layers: 1 },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: key.format.wgpu(),
                    usage: usage_for(key.format),
                    view_formats: &[],
                })
            },
        )?;
        self.created += 1;
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        Ok(PooledTexture { texture, view, key })
    }

    /// Gives a texture back.
    pub fn release(&mut self, texture: PooledTexture) {
        self.free.entry(texture.key).or_default().push((texture, self.generation));
    }

    /// A storage buffer of `size` bytes: a free one, or a new one.
    pub fn acquire_buffer(&mut self, gpu: &Gpu, size: u64, label: &str) -> Result<PooledBuffer, GpuFault> {
        if let Some(list) = self.free_buffers.get_mut(&size)
            && let Some((b, _)) = list.pop()
        {
            return Ok(b);
        }
        let buffer = gpu.checked(
            || format!("creating buffer {label} ({size} bytes)"),
            || {
                gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size,
                    usage: wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_SRC
                        | wgpu::BufferUsages::COPY_DST
                        | wgpu::BufferUsages::INDIRECT
                        | wgpu::BufferUsages::VERTEX,
                    mapped_at_creation: false,
                })
            },
        )?;
        self.created += 1;
        Ok(PooledBuffer { buffer, size })
    }

    /// Gives a buffer back.
    pub fn release_buffer(&mut self, buffer: PooledBuffer) {
        self.free_buffers.entry(buffer.size).or_default().push((buffer, self.generation));
    }

    /// Called after each plan change: frees what was given back before the previous change and
    /// not taken since.
    pub fn next_generation(&mut self) {
        let generation = self.generation;
        for list in self.free.values_mut() {
            list.retain(|(_, g)| *g + 1 >= generation);
        }
        self.free.retain(|_, l| !l.is_empty());
        for list in self.free_buffers.values_mut() {
            list.retain(|(_, g)| *g + 1 >= generation);
        }
        self.free_buffers.retain(|_, l| !l.is_empty());
        self.generation += 1;
    }

    /// Textures created since the runtime started.
    pub fn created(&self) -> u64 {
        self.created
    }

    /// Bytes held by free textures.
    pub fn free_bytes(&self) -> u64 {
        let textures: u64 = self
            .free
            .iter()
            .map(|(k, l)| k.format.bytes_per_pixel() * k.extent.0 as u64 * k.extent.1 as u64 * l.len() as u64)
            .sum();
        textures + self.free_buffers.iter().map(|(size, l)| size * l.len() as u64).sum::<u64>()
    }
}
