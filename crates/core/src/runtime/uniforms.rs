//! The uniform blocks a node uploads, made from its declaration: one buffer per uniform its
//! shader uses declare ([`ShaderUse::uniforms`](crate::plugin::ShaderUse::uniforms)), filled from
//! the pass's parameters by the block's own byte function, bound by the global's name and
//! rewritten in place when a parameter edit only changes uniform values
//! ([`PassDecl::only_uniforms_change`](crate::plugin::PassDecl::only_uniforms_change)). A node
//! that keeps its uniforms here writes no buffer name, size or byte conversion by hand.

use volgraph_compiler::decl::{ShaderUse, UniformLayout};

use super::{CreateContext, Gpu};
use crate::params::Params;

/// One buffer per declared uniform global of a node's shader uses.
pub struct UniformBlocks {
    blocks: Vec<(UniformLayout, wgpu::Buffer)>,
}

impl UniformBlocks {
    /// The buffers of every uniform `uses` declare (a global several uses bind is one buffer),
    /// filled from `ctx.params`.
    pub fn create(ctx: &CreateContext<'_>, uses: &[ShaderUse]) -> Self {
        let mut blocks: Vec<(UniformLayout, wgpu::Buffer)> = Vec::new();
        for layout in uses.iter().flat_map(|u| &u.uniforms) {
            if blocks.iter().any(|(l, _)| l.global == layout.global) {
                continue;
            }
            let buffer = ctx.uniform_from_bytes(layout.global, &(layout.bytes)(ctx.params));
            blocks.push((layout.clone(), buffer));
        }
        Self { blocks }
    }

    /// Rewrites every block from `params` (a node's `update_params`).
    pub fn write(&self, gpu: &Gpu, params: &Params) {
        for (layout, buffer) in &self.blocks {
            gpu.queue.write_buffer(buffer, 0, &(layout.bytes)(params));
        }
    }

    /// `(global, buffer)` of every block, for `RecordContext::bind_group` / `dispatch_over`.
    pub fn bindings(&self) -> Vec<(&'static str, wgpu::BindingResource<'_>)> {
        self.blocks.iter().map(|(l, b)| (l.global, b.as_entire_binding())).collect()
    }

    /// The buffer of `global`, for a node that also writes a computed member itself.
    pub fn buffer(&self, global: &str) -> Option<&wgpu::Buffer> {
        self.blocks.iter().find(|(l, _)| l.global == global).map(|(_, b)| b)
    }
}
