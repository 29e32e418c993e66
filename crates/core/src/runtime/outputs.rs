//! Reading a [`Runtime`]'s last frame back: graph outputs and any target or buffer resource, a
//! capture of what a window would show, and the view of an output the window blit reads.

use super::history::HistoryStore;
use super::live_plan::{LivePlan, SlotTexture};
use super::{Image, PresentTarget, Runtime, RuntimeError, readback};
use crate::plan::ResourceDesc;

impl Runtime {
    /// Reads back a graph output of the last frame (waits for it).
    pub fn read_output(&mut self, name: &str) -> Result<Image, RuntimeError> {
        let live = self.live.as_ref().ok_or(RuntimeError::NoPlan)?;
        let Some(&rid) = live.plan.outputs.get(name) else {
            return Err(RuntimeError::UnknownOutput {
                name: name.to_string(),
                known: live.plan.outputs.keys().cloned().collect::<Vec<_>>().join(", "),
            });
        };
        self.read_resource(rid)
    }

    /// Reads back an 8-bit RGBA output of the last frame (`present`'s `display`: sRGB-encoded
    /// values) as its bytes, rows from the top: `(width, height, bytes)`, without the float
    /// conversion of [`Self::read_output`] (the Python package's images). Waits for the frame.
    pub fn read_output_rgba8(&mut self, name: &str) -> Result<(u32, u32, Vec<u8>), RuntimeError> {
        let live = self.live.as_ref().ok_or(RuntimeError::NoPlan)?;
        let Some(&rid) = live.plan.outputs.get(name) else {
            return Err(RuntimeError::UnknownOutput {
                name: name.to_string(),
                known: live.plan.outputs.keys().cloned().collect::<Vec<_>>().join(", "),
            });
        };
        let (texture, format, extent) = self.resource_texture(rid)?;
        if format != crate::format::TargetFormat::Rgba8Unorm {
            return Err(RuntimeError::Readback(format!("output \"{name}\" is {format:?}, not Rgba8Unorm")));
        }
        let bytes = readback::read_texture_bytes(&self.gpu, &texture).map_err(RuntimeError::Readback)?;
        Ok((extent.0, extent.1, bytes))
    }

    /// Reads back any target resource of the last frame (valid while its slot was not reused
    /// later in the frame: outputs and the last holder of a slot).
    pub fn read_resource(&mut self, rid: usize) -> Result<Image, RuntimeError> {
        let (texture, format, extent) = self.resource_texture(rid)?;
        readback::read_texture(&self.gpu, &texture, format, extent).map_err(RuntimeError::Readback)
    }

    /// The texture, format and extent of target resource `rid` after the last frame (waited for).
    fn resource_texture(
        &mut self,
        rid: usize,
    ) -> Result<(wgpu::Texture, crate::format::TargetFormat, (u32, u32)), RuntimeError> {
        let _ = self.frames.finish(&self.gpu);
        let live = self.live.as_ref().ok_or(RuntimeError::NoPlan)?;
        let r = &live.plan.resources[rid];
        let (Some(slot), ResourceDesc::Target { format, extent, .. }) = (r.slot, &r.desc) else {
            return Err(RuntimeError::Readback(format!("\"{}\" is not a target", r.name)));
        };
        let texture = match &live.slots[slot] {
            SlotTexture::Transient(t) => t.texture.clone(),
            SlotTexture::Buffer(_) => return Err(RuntimeError::Readback(format!("\"{}\" is a buffer", r.name))),
            SlotTexture::History(name) => self
                .history
                .get(name)
                .map(|e| e.current().texture.clone())
                .ok_or_else(|| RuntimeError::Readback(format!("history \"{name}\" is gone")))?,
        };
        Ok((texture, *format, *extent))
    }

    /// Reads back the bytes of a buffer output of the last frame (waits for it).
    pub fn read_buffer_output(&mut self, name: &str) -> Result<Vec<u8>, RuntimeError> {
        let live = self.live.as_ref().ok_or(RuntimeError::NoPlan)?;
        let rid = *live.plan.outputs.get(name).ok_or_else(|| RuntimeError::UnknownOutput {
            name: name.to_string(),
            known: live.plan.outputs.keys().cloned().collect::<Vec<_>>().join(", "),
        })?;
        self.read_buffer_resource(rid)
    }

    /// Reads back the bytes of buffer resource `rid` after the last frame (valid while its slot
    /// was not reused later in the frame; a pass's unread output keeps its slot).
    pub fn read_buffer_resource(&mut self, rid: usize) -> Result<Vec<u8>, RuntimeError> {
        let _ = self.frames.finish(&self.gpu);
        let live = self.live.as_ref().ok_or(RuntimeError::NoPlan)?;
        let name = live.plan.resources.get(rid).map_or_else(String::new, |r| r.name.clone());
        match live.plan.resources[rid].slot.map(|s| &live.slots[s]) {
            Some(SlotTexture::Buffer(b)) => {
                readback::read_buffer(&self.gpu, &b.buffer, 0, b.size).map_err(RuntimeError::Readback)
            }
            _ => Err(RuntimeError::Readback(format!("\"{name}\" is not a buffer"))),
        }
    }

    /// Draws `target.output` as the last frame left it onto `target` (a window's surface), in a
    /// command buffer of its own after that frame's: a second graph's outputs beside the first's
    /// (`load: true`), without rendering it again. Does not wait.
    pub fn present(&mut self, target: &PresentTarget<'_>) -> Result<(), RuntimeError> {
        let live = self.live.as_ref().ok_or(RuntimeError::NoPlan)?;
        let (source, encoded) = output_view(live, &self.history, target.output)?;
        let mut encoder =
            self.gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("present") });
        self.blitter.record(&self.gpu, &mut encoder, &source, encoded, target)?;
        self.gpu
            .checked(|| format!("presenting \"{}\"", target.output), || self.gpu.queue.submit([encoder.finish()]))?;
        Ok(())
    }

    /// What a window of `format` and `size` shows of `output` after the last frame: the same
    /// blit, drawn into an offscreen texture and read back as `format`'s bytes (a screenshot
    /// without the overlay). Waits for the frame.
    pub fn capture(
        &mut self,
        output: &str,
        format: wgpu::TextureFormat,
        size: (u32, u32),
    ) -> Result<Vec<u8>, RuntimeError> {
        let _ = self.frames.finish(&self.gpu);
        let live = self.live.as_ref().ok_or(RuntimeError::NoPlan)?;
        let (source, encoded) = output_view(live, &self.history, output)?;
        let texture = self.gpu.checked(
            || format!("creating a {}x{} {format:?} capture", size.0, size.1),
            || {
                self.gpu.device.create_texture(&wgpu::TextureDescriptor {
                    label: Some("capture"),
                    size: wgpu::Extent3d { width: size.0.max(1), height: size.1.max(1), depth_or_array_layers: 1 },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                    view_formats: &[],
                })
            },
        )?;
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        let target = PresentTarget { view: &view, format, size, output, region: None, load: false };
        let mut encoder =
            self.gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("capture") });
        self.blitter.record(&self.gpu, &mut encoder, &source, encoded, &target)?;
        self.gpu.queue.submit([encoder.finish()]);
        readback::read_texture_bytes(&self.gpu, &texture).map_err(RuntimeError::Readback)
    }
}

/// The view of output `name` and whether it holds sRGB-encoded values (an 8-bit target).
pub(super) fn output_view(
    live: &LivePlan,
    history: &HistoryStore,
    name: &str,
) -> Result<(wgpu::TextureView, bool), RuntimeError> {
    let Some(&rid) = live.plan.outputs.get(name) else {
        return Err(RuntimeError::UnknownOutput {
            name: name.to_string(),
            known: live.plan.outputs.keys().cloned().collect::<Vec<_>>().join(", "),
        });
    };
    let r = &live.plan.resources[rid];
    let (Some(slot), ResourceDesc::Target { format, .. }) = (r.slot, &r.desc) else {
        return Err(RuntimeError::Readback(format!("output \"{name}\" is not a target")));
    };
    let view = match &live.slots[slot] {
        SlotTexture::Transient(t) => t.view.clone(),
        SlotTexture::Buffer(_) => return Err(RuntimeError::Readback(format!("output \"{name}\" is a buffer"))),
        SlotTexture::History(h) => history
            .get(h)
            .map(|e| e.current().view.clone())
            .ok_or_else(|| RuntimeError::Readback(format!("history \"{h}\" is gone")))?,
    };
    Ok((view, *format == crate::format::TargetFormat::Rgba8Unorm))
}
