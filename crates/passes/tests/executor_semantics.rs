//! The executor honours the graph semantics the scheduler plans: history targets carry the
//! previous frame's value (with the declared initial value on the first frame and after
//! invalidation), and repeat groups feed each iteration's output to the next through their
//! carry while ping-ponging between two pooled textures. The test plugins and their shader
//! (`tests/shaders/add_one.wgsl`) live here and register through the public API.

use volgraph_core::executor::{
    CreateContext, Executor, Gpu, PassError, PassPipeline, PipelineKind, RecordContext, RenderPipelineSpec,
    ShaderLibrary,
};
use volgraph_core::{
    CompileOptions, Params, PassNode, PassPlugin, PortKind, PortSpec, Registry, TargetFormat, compile,
};

/// `next = value + (1, 0, 0, 0)`.
struct AddOne;
/// `filled = (100, 0, 0, 0)`.
struct Fill;

struct Node {
    pipeline: PassPipeline,
}

impl PassNode for Node {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let bg = ctx.bind_group(&self.pipeline, &[])?;
        let mut pass = ctx.begin_render_pass(&self.pipeline, None)?;
        if let PipelineKind::Render(p) = &self.pipeline.pipeline {
            pass.set_pipeline(p);
            pass.set_bind_group(0, &bg, &[]);
            pass.draw(0..3, 0..1);
        }
        Ok(())
    }
}

fn node(ctx: &CreateContext<'_>, fragment: &str) -> Result<Box<dyn PassNode>, PassError> {
    let pipeline = ctx.render_pipeline(&RenderPipelineSpec {
        shader: "add_one.wgsl",
        vertex: "vs_fullscreen",
        fragment,
        ..Default::default()
    })?;
    Ok(Box::new(Node { pipeline }))
}

impl PassPlugin for AddOne {
    fn kind(&self) -> &'static str {
        "add_one"
    }
    fn summary(&self) -> &'static str {
        "test: adds one to the red channel"
    }
    fn ports(&self, _p: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read("value", PortKind::target(&[TargetFormat::Rgba32Float])),
            PortSpec::write("next", PortKind::target(&[TargetFormat::Rgba32Float])),
        ]
    }
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        node(ctx, "fs_add_one")
    }
}

impl PassPlugin for Fill {
    fn kind(&self) -> &'static str {
        "fill"
    }
    fn summary(&self) -> &'static str {
        "test: writes 100 to the red channel"
    }
    fn ports(&self, _p: &Params) -> Vec<PortSpec> {
        vec![PortSpec::write("filled", PortKind::target(&[TargetFormat::Rgba32Float]))]
    }
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        node(ctx, "fs_fill")
    }
}

fn setup(graph: &str) -> (Gpu, Executor) {
    let mut registry = Registry::new();
    registry.register(AddOne).register(Fill);
    let plan = compile("semantics.ron", graph, &registry, &CompileOptions::new(8, 4)).expect("valid graph");
    let gpu = Gpu::new_headless().expect("a Vulkan adapter (lavapipe without a GPU)");
    // The test's own shader folder first; its `#import "common/fullscreen.wgsl"` comes from
    // volgraph's, as it would for an external plugin crate.
    let shaders = ShaderLibrary::with_roots(vec![
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/shaders"),
        volgraph_core::shader_source::default_shader_root(),
    ]);
    let exec = Executor::new(&gpu, &shaders, &registry, plan).expect("builds");
    (gpu, exec)
}

fn red(gpu: &Gpu, exec: &Executor) -> f32 {
    let image = exec.read_output(gpu, "image").expect("output");
    let first = image.rgba(0, 0)[0];
    assert!(image.data.chunks(4).all(|p| p[0] == first), "every pixel holds the same value");
    first
}

#[test]
fn history_reads_the_previous_frame_and_restarts_from_its_initial_value() {
    let (gpu, mut exec) = setup(
        r#"Graph(
            name: "history",
            history: {"prev": (of: "count.next", initial: Clear(10.0, 0.0, 0.0, 0.0))},
            passes: [Pass(id: "count", kind: "add_one", inputs: {"value": "history.prev"})],
            outputs: {"image": "count.next"},
        )"#,
    );
    let mut seen = Vec::new();
    for _ in 0..3 {
        exec.run_frame(&gpu).expect("frame");
        seen.push(red(&gpu, &exec));
    }
    assert_eq!(seen, vec![11.0, 12.0, 13.0], "frame n reads frame n-1's value, frame 0 the initial value");
    exec.invalidate_history();
    exec.run_frame(&gpu).expect("frame");
    assert_eq!(red(&gpu, &exec), 11.0, "after invalidation the initial value is read again");
}

#[test]
fn repeat_group_feeds_each_iteration_the_previous_output_through_two_slots() {
    let (gpu, mut exec) = setup(
        r#"Graph(
            name: "repeat",
            passes: [
                Pass(id: "start", kind: "fill"),
                Repeat(
                    id: "loop",
                    count: Fixed(7),
                    carry: {"acc": (init: "start.filled", next: "step.next")},
                    body: [Pass(id: "step", kind: "add_one", inputs: {"value": "loop.acc"})],
                ),
            ],
            outputs: {"image": "loop.acc"},
        )"#,
    );
    exec.run_frame(&gpu).expect("frame");
    assert_eq!(red(&gpu, &exec), 107.0, "seven iterations each add one to the carried value");
    let slots = exec.plan().slots.len();
    assert_eq!(slots, 2, "the carried target ping-pongs between two pooled textures");
}
