//! The runtime's half of the WGSL-only pass kinds a graph declares (`kinds:`): the declaration
//! ([`WgslKind`], checked and scheduled by the compiler) is created on a device here — its
//! shader read from the shader library and checked against the declaration again (a hot reload
//! can change it), a compute or fullscreen-fragment pipeline, a uniform block of its parameters.

use std::collections::BTreeMap;

pub use volgraph_compiler::wgsl_kind::{GraphKinds, WgslKind, check_kinds, check_kinds_in};

use crate::graph::ast::{WgslForm, WgslKindDoc};
use crate::params::Params;
use crate::plugin::{PassNode, PassPlugin, Registry};
use crate::runtime::{
    ComputePassPipeline, ComputePipelineSpec, CreateContext, Gpu, PassError, RecordContext, RenderPassPipeline,
    RenderPipelineSpec,
};

/// `registry` with a plugin for each WGSL-only kind of `kinds` added: what the runtime creates a
/// graph's nodes from.
pub fn with_graph_kinds(registry: &Registry, kinds: &BTreeMap<String, WgslKindDoc>) -> Registry {
    let mut extended = registry.clone();
    for (name, doc) in kinds {
        extended.register(WgslKind::new(name, doc.clone()));
    }
    extended
}

impl PassPlugin for WgslKind {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let module = ctx.shader_module(&self.doc().shader)?;
        self.check_module_against(&module.module).map_err(|m| PassError { pass: ctx.pass_id.into(), message: m })?;
        let pipeline = match self.doc().form {
            WgslForm::Compute => Pipeline::Compute(ctx.compute_pipeline(&ComputePipelineSpec {
                shader: &self.doc().shader,
                entry: self.doc().entry_point(),
                constants: &[],
                defines: &[],
            })?),
            WgslForm::Fragment => Pipeline::Fragment(ctx.render_pipeline(&RenderPipelineSpec {
                shader: &self.doc().shader,
                vertex: crate::runtime::FULLSCREEN_VERTEX,
                fragment: self.doc().entry_point(),
                ..Default::default()
            })?),
        };
        let uniform = (!self.doc().params.is_empty()).then(|| {
            let buffer = ctx.uniform_buffer("params", self.param_block_size());
            ctx.gpu.queue.write_buffer(&buffer, 0, &self.param_block(ctx.params));
            buffer
        });
        Ok(Box::new(WgslPassNode { pipeline, uniform, kind: self.clone() }))
    }
}

/// The pipeline of a WGSL-only pass, by form.
enum Pipeline {
    Compute(ComputePassPipeline),
    Fragment(RenderPassPipeline),
}

struct WgslPassNode {
    pipeline: Pipeline,
    uniform: Option<wgpu::Buffer>,
    kind: WgslKind,
}

impl PassNode for WgslPassNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let extra: Vec<(&str, wgpu::BindingResource<'_>)> =
            self.uniform.iter().map(|b| ("params", b.as_entire_binding())).collect();
        match &self.pipeline {
            Pipeline::Compute(p) => ctx.dispatch_over(p, &extra, self.kind.first_output(), self.kind.doc().workgroup),
            Pipeline::Fragment(p) => {
                let bind_group = ctx.bind_group(p, &extra)?;
                ctx.draw_fullscreen(p, &bind_group)
            }
        }
    }

    fn update_params(&mut self, gpu: &Gpu, params: &Params) {
        if let Some(buffer) = &self.uniform {
            gpu.queue.write_buffer(buffer, 0, &self.kind.param_block(params));
        }
    }
}
