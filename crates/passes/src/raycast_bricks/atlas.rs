//! The brick atlas of [`super::RaycastBricks`]: Ruijters & Vilanova 2006 §5 loads bricks into
//! texture memory as 3D textures and swaps them least recently used when they do not all fit.
//! Here the resident bricks share one 3D texture of `side`-voxel slots (slot layout and words in
//! [`volgraph_accel::brick_leaves`]), sized for the visible bricks under the memory budget and
//! grown in place; a frame's uploads ([`crate::brick_pool`] plans which) go through staging
//! buffers that hold many bricks side by side.

use glam::UVec3;
use volgraph_accel::brick_leaves::{COPY_ROW_ALIGNMENT, slot_coord, staging_bricks_per_chunk, staging_row_bytes};
use volgraph_core::runtime::volume_region_bytes;
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{PassError, RecordContext};
#[cfg(feature = "gpu")]
use wgpu::util::DeviceExt;

use super::{VolumeState, pass_error};
use crate::brick_pool::BrickPool;

/// The largest staging buffer one upload batch uses, whatever the adapter allows: a frame's
/// uploads are split into chunks of at most this many bytes (and at most the device's
/// `max_buffer_size`), so a 1024³ volume never needs a gigabyte of staging at once.
const MAX_STAGING_BYTES: u64 = 64 << 20;

// The staging rows `brick_leaves` lays out are padded to the alignment copies need.
#[cfg(feature = "gpu")]
const _: () = assert!(COPY_ROW_ALIGNMENT == wgpu::COPY_BYTES_PER_ROW_ALIGNMENT as u64);

#[cfg(feature = "gpu")]
/// The atlas texture and how its slots are laid out.
pub(super) struct Atlas {
    texture: wgpu::Texture,
    pub(super) view: wgpu::TextureView,
    /// Slots per axis (x, y fixed for the volume; z grows).
    pub(super) slots: UVec3,
}

#[cfg(feature = "gpu")]
impl VolumeState {
    /// Sizes the pool for the visible bricks under `budget` bytes: grows the atlas (keeping
    /// resident bricks where they are) or, when the budget changed, starts over.
    pub(super) fn size_pool(&mut self, ctx: &mut RecordContext<'_>, budget: u64) -> Result<(), PassError> {
        if budget != self.budget {
            self.pool = BrickPool::new(0, self.layout.brick_count());
            self.atlas = None;
            self.budget = budget;
        }
        let visible = self.visible.iter().filter(|v| **v).count() as u64;
        let per_layer = self.slots_xy.0 * self.slots_xy.1;
        let most = (budget / self.slot_bytes()).min((per_layer * self.max_layers) as u64);
        if most == 0 {
            return Err(pass_error(
                ctx,
                format!(
                    "the brick pool's budget of {budget} bytes holds no {}-byte brick; raise --gpu-memory-mb (or \
                     pool_mb) or lower brick_cells",
                    self.slot_bytes()
                ),
            ));
        }
        let wanted = visible.min(most).max(1) as u32;
        if wanted <= self.pool.slots() {
            return Ok(());
        }
        let layers = wanted.div_ceil(per_layer);
        let slots = UVec3::new(self.slots_xy.0, self.slots_xy.1, layers);
        let size = slots * self.side;
        let texture = ctx.gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("brick atlas"),
            size: wgpu::Extent3d { width: size.x, height: size.y, depth_or_array_layers: size.z },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D3,
            format: self.format.wgpu(),
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        if let Some(old) = &self.atlas {
            let s = old.slots * self.side;
            ctx.encoder.copy_texture_to_texture(
                old.texture.as_image_copy(),
                texture.as_image_copy(),
                wgpu::Extent3d { width: s.x, height: s.y, depth_or_array_layers: s.z },
            );
        }
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        let slot_count = (slots.x * slots.y * slots.z).min(most as u32);
        self.pool.grow(slot_count - self.pool.slots());
        self.atlas = Some(Atlas { texture, view, slots });
        Ok(())
    }

    /// Records the copies of `uploads` into the atlas, through staging buffers of at most
    /// [`MAX_STAGING_BYTES`] and the device's `max_buffer_size` each; returns the voxel bytes
    /// uploaded.
    pub(super) fn upload(&self, ctx: &mut RecordContext<'_>, uploads: &[(u32, u32)]) -> Result<u64, PassError> {
        let Some(atlas) = &self.atlas else { return Ok(0) };
        let texel = self.format.bytes() as u64;
        let brick_row = self.side.x as u64 * texel;
        let rows = self.side.y as u64 * self.side.z as u64;
        // Chunks of MAX_STAGING_BYTES, or one brick where a brick is larger; never more than
        // the device's largest buffer.
        let one_brick = staging_row_bytes(brick_row, 1) * rows;
        let device = ctx.gpu.limits.max_buffer_size;
        let per_chunk = staging_bricks_per_chunk(brick_row, rows, MAX_STAGING_BYTES.max(one_brick).min(device));
        if per_chunk == 0 {
            return Err(pass_error(
                ctx,
                format!(
                    "one brick of {}x{}x{} voxels needs {one_brick} bytes of staging, more than this device's \
                     largest buffer ({device} bytes); lower brick_cells",
                    self.side.x, self.side.y, self.side.z
                ),
            ));
        }
        for chunk in uploads.chunks(per_chunk) {
            self.upload_chunk(ctx, atlas, chunk, brick_row);
        }
        Ok(uploads.len() as u64 * self.slot_bytes())
    }

    /// One staging buffer for `chunk`: the bricks side by side along x (brick `i`'s row `r` at
    /// `r · row + i · brick_row`), so rows share the 256-byte alignment a buffer-to-texture
    /// copy needs instead of padding every brick's row to it.
    fn upload_chunk(&self, ctx: &mut RecordContext<'_>, atlas: &Atlas, chunk: &[(u32, u32)], brick_row: u64) {
        let side = self.side;
        let row = staging_row_bytes(brick_row, chunk.len());
        let mut staging = vec![0u8; (row * side.y as u64 * side.z as u64) as usize];
        for (i, (brick, _)) in chunk.iter().enumerate() {
            let (lo, _) = self.layout.brick_cells_box(self.layout.brick_coord(*brick as usize));
            let origin = lo.as_ivec3() - glam::IVec3::splat(self.apron as i32);
            let tight = volume_region_bytes(&self.voxels, origin, side, self.format);
            for (r, src) in tight.chunks_exact(brick_row as usize).enumerate() {
                let at = (r as u64 * row + i as u64 * brick_row) as usize;
                staging[at..at + src.len()].copy_from_slice(src);
            }
        }
        let buffer = ctx.gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("brick uploads"),
            contents: &staging,
            usage: wgpu::BufferUsages::COPY_SRC,
        });
        for (i, (_, slot)) in chunk.iter().enumerate() {
            let at = slot_coord(*slot, atlas.slots) * side;
            ctx.encoder.copy_buffer_to_texture(
                wgpu::TexelCopyBufferInfo {
                    buffer: &buffer,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: i as u64 * brick_row,
                        bytes_per_row: Some(row as u32),
                        rows_per_image: Some(side.y),
                    },
                },
                wgpu::TexelCopyTextureInfo {
                    texture: &atlas.texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d { x: at.x, y: at.y, z: at.z },
                    aspect: wgpu::TextureAspect::All,
                },
                wgpu::Extent3d { width: side.x, height: side.y, depth_or_array_layers: side.z },
            );
        }
    }
}
