//! Named history resources: last frame's value of a target (Klein et al. 2005's hit points),
//! kept by the runtime, not by a plan, so a recompile that leaves a history entry's descriptor
//! unchanged keeps its content, and one that changes it starts over from the declared initial
//! value.

use std::collections::BTreeMap;

use super::gpu::{Gpu, GpuFault};
use super::textures::{PooledTexture, TextureKey, TexturePool};
use crate::graph::ast::HistoryInitial;

/// One history entry: two textures that swap roles every frame.
pub struct HistoryEntry {
    key: TextureKey,
    textures: [PooledTexture; 2],
    /// Index of the texture written this frame; the other holds the previous frame.
    current: usize,
    initial: HistoryInitial,
    /// False until a frame has written it (and after invalidation).
    valid: bool,
}

impl HistoryEntry {
    /// The texture this frame writes.
    pub fn current(&self) -> &PooledTexture {
        &self.textures[self.current]
    }

    /// The texture holding the previous frame's value.
    pub fn previous(&self) -> &PooledTexture {
        &self.textures[1 - self.current]
    }
}

/// History entries by name.
#[derive(Default)]
pub struct HistoryStore {
    entries: BTreeMap<String, HistoryEntry>,
}

impl HistoryStore {
    /// Makes `name` an entry of `key`: kept with its content when it already exists with the
    /// same descriptor (returns true), created fresh and invalid otherwise.
    pub(crate) fn ensure(
        &mut self,
        gpu: &Gpu,
        pool: &mut TexturePool,
        name: &str,
        key: TextureKey,
        initial: &HistoryInitial,
    ) -> Result<bool, GpuFault> {
        if let Some(e) = self.entries.get_mut(name)
            && e.key == key
        {
            if e.initial != *initial {
                e.initial = initial.clone();
                e.valid = false;
            }
            return Ok(true);
        }
        let a = pool.acquire(gpu, key, &format!("history {name}"))?;
        let b = pool.acquire(gpu, key, &format!("history {name} (previous)"))?;
        if let Some(old) = self.entries.insert(
            name.to_string(),
            HistoryEntry { key, textures: [a, b], current: 0, initial: initial.clone(), valid: false },
        ) {
            let [a, b] = old.textures;
            pool.release(a);
            pool.release(b);
        }
        Ok(false)
    }

    /// Drops every entry not in `keep`, giving its textures back.
    pub(crate) fn retain(&mut self, pool: &mut TexturePool, keep: &[&str]) {
        let gone: Vec<String> = self.entries.keys().filter(|k| !keep.contains(&k.as_str())).cloned().collect();
        for name in gone {
            if let Some(e) = self.entries.remove(&name) {
                let [a, b] = e.textures;
                pool.release(a);
                pool.release(b);
            }
        }
    }

    /// The entry `name`.
    pub fn get(&self, name: &str) -> Option<&HistoryEntry> {
        self.entries.get(name)
    }

    /// Starts a frame: what was written last frame becomes "previous"; an invalid entry's
    /// previous texture is cleared to its initial value (recorded into `encoder`).
    pub(crate) fn begin_frame(&mut self, encoder: &mut wgpu::CommandEncoder) {
        for e in self.entries.values_mut() {
            e.current = 1 - e.current;
            if !e.valid {
                let HistoryInitial::Clear((r, g, b, a)) = e.initial;
                let _ = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("history initial value"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &e.textures[1 - e.current].view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color { r, g, b, a }),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    ..Default::default()
                });
            }
        }
    }

    /// Ends a frame: every entry now holds a written value.
    pub(crate) fn end_frame(&mut self) {
        for e in self.entries.values_mut() {
            e.valid = true;
        }
    }

    /// Forgets every entry's content: the next frame reads initial values.
    pub fn invalidate(&mut self) {
        for e in self.entries.values_mut() {
            e.valid = false;
        }
    }

    /// True when every entry holds a previous frame's value.
    pub fn all_valid(&self) -> bool {
        self.entries.values().all(|e| e.valid)
    }

    /// Bytes held (both textures of every entry).
    pub fn bytes(&self) -> u64 {
        self.entries
            .values()
            .map(|e| 2 * e.key.format.bytes_per_pixel() * e.key.extent.0 as u64 * e.key.extent.1 as u64)
            .sum()
    }
}
