//! The live runtime honours the graph semantics the scheduler plans and keeps what a plan change
//! does not touch: history carries the previous frame's value (its declared initial value on the
//! first frame, after invalidation and after a descriptor change) and survives a recompile;
//! repeat groups ping-pong their carry between two pooled textures; a parameter edit writes a
//! uniform and builds nothing; a graph edit reuses every pipeline; a resize reallocates only the
//! viewport-sized targets; frames are submitted without waiting; bind groups are cached; a plan
//! that fails to apply leaves the previous one running. The test plugins and their shader
//! (`tests/shaders/add_one.wgsl`) live here and register through the public API.

use std::sync::Arc;

use volgraph_accel::camera::OrbitCamera;
use volgraph_core::plugin::ShaderUse;
use volgraph_core::runtime::{
    CameraData, CreateContext, Gpu, PassError, RecordContext, RenderPassPipeline, RenderPipelineSpec, Runtime,
    ShaderLibrary,
};
use volgraph_core::{
    CompileOptions, ParamSpec, Params, PassDecl, PassNode, PassPlugin, PortKind, PortSpec, Registry, TargetFormat,
    compile,
};

/// `next = value + (amount, 0, 0, 0)`.
struct AddOne;
/// `filled = (100, 0, 0, 0)`.
struct Fill;
/// A kind whose nodes always fail to build (a broken edit).
struct Broken;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct AddParams {
    amount: f32,
    _pad: [f32; 3],
}

struct Node {
    pipeline: RenderPassPipeline,
    params: Option<wgpu::Buffer>,
}

impl PassNode for Node {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let extra: Vec<(&str, wgpu::BindingResource<'_>)> =
            self.params.iter().map(|b| ("params", b.as_entire_binding())).collect();
        let bg = ctx.bind_group(&self.pipeline, &extra)?;
        let mut pass = ctx.begin_render_pass(&self.pipeline, None)?;
        pass.set_pipeline(&self.pipeline.pipeline);
        pass.set_bind_group(0, &bg, &[]);
        pass.draw(0..3, 0..1);
        Ok(())
    }

    fn update_params(&mut self, gpu: &Gpu, params: &Params) {
        if let Some(buffer) = &self.params {
            let p = AddParams { amount: params.float("amount") as f32, _pad: [0.0; 3] };
            gpu.queue.write_buffer(buffer, 0, bytemuck::bytes_of(&p));
        }
    }
}

const ADD_ONE: ShaderUse = ShaderUse::new("add_one.wgsl", "fs_add_one").binds(&["params"]);
const FILL: ShaderUse = ShaderUse::new("add_one.wgsl", "fs_fill");

impl PassDecl for AddOne {
    fn kind(&self) -> &'static str {
        "add_one"
    }
    fn summary(&self) -> &'static str {
        "test: adds `amount` to the red channel"
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec::float("amount", 1.0, -1000.0, 1000.0, "what is added")]
    }
    fn ports(&self, _p: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read("value", PortKind::target(&[TargetFormat::Rgba32Float])),
            PortSpec::write("next", PortKind::target(&[TargetFormat::Rgba32Float])),
        ]
    }
    fn updates_in_place(&self, _old: &Params, _new: &Params) -> bool {
        true
    }
    fn shaders(&self, _p: &Params) -> Vec<ShaderUse> {
        vec![ADD_ONE]
    }
}

impl PassPlugin for AddOne {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let pipeline = ctx.render_pipeline(&RenderPipelineSpec::fullscreen(&ADD_ONE))?;
        let params =
            ctx.uniform_with("params", &AddParams { amount: ctx.params.float("amount") as f32, _pad: [0.0; 3] });
        Ok(Box::new(Node { pipeline, params: Some(params) }))
    }
}

impl PassDecl for Fill {
    fn kind(&self) -> &'static str {
        "fill"
    }
    fn summary(&self) -> &'static str {
        "test: writes 100 to the red channel"
    }
    fn ports(&self, _p: &Params) -> Vec<PortSpec> {
        vec![PortSpec::write("filled", PortKind::target(&[TargetFormat::Rgba32Float]))]
    }
    fn shaders(&self, _p: &Params) -> Vec<ShaderUse> {
        vec![FILL]
    }
}

impl PassPlugin for Fill {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let pipeline = ctx.render_pipeline(&RenderPipelineSpec::fullscreen(&FILL))?;
        Ok(Box::new(Node { pipeline, params: None }))
    }
}

impl PassDecl for Broken {
    fn kind(&self) -> &'static str {
        "broken"
    }
    fn summary(&self) -> &'static str {
        "test: never builds"
    }
    fn ports(&self, _p: &Params) -> Vec<PortSpec> {
        vec![PortSpec::write("filled", PortKind::target(&[TargetFormat::Rgba32Float]))]
    }
}

impl PassPlugin for Broken {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        Err(PassError { pass: ctx.pass_id.to_string(), message: "this kind never builds".to_string() })
    }
}

fn registry() -> Registry {
    let mut registry = Registry::new();
    registry.register(AddOne).register(Fill).register(Broken);
    registry
}

fn runtime() -> Runtime {
    let gpu = Arc::new(Gpu::new_headless().expect("a Vulkan adapter (lavapipe without a GPU)"));
    // The test's own shader folder first; its `#import "common/fullscreen.wgsl"` comes from
    // volgraph's built-in shaders, as it would for an external plugin crate.
    let sources = volgraph_passes::builtin_shaders()
        .prepend_disk(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/shaders"));
    Runtime::new(gpu, ShaderLibrary::new(sources))
}

fn apply(runtime: &mut Runtime, graph: &str, options: &CompileOptions) -> volgraph_core::runtime::ApplyReport {
    let plan = compile("semantics.ron", graph, &registry(), options).unwrap_or_else(|d| panic!("valid graph:\n{d}"));
    runtime.apply(plan, &registry()).unwrap_or_else(|e| panic!("applies: {e}"))
}

fn camera(runtime: &Runtime) -> CameraData {
    CameraData::from_orbit(&OrbitCamera::default(), runtime.plan().expect("a plan").viewport)
}

fn frame(runtime: &mut Runtime) {
    let c = camera(runtime);
    runtime.render(c).expect("frame");
}

fn red(runtime: &mut Runtime) -> f32 {
    let image = runtime.read_output("image").expect("output");
    let first = image.rgba(0, 0)[0];
    assert!(image.data.chunks(4).all(|p| p[0] == first), "every pixel holds the same value");
    first
}

const HISTORY: &str = r#"Graph(
    name: "history",
    history: {"prev": (of: "count.next", initial: Clear(10.0, 0.0, 0.0, 0.0))},
    passes: [Pass(id: "count", kind: "add_one", inputs: {"value": "history.prev"})],
    outputs: {"image": "count.next"},
)"#;

#[test]
fn history_reads_the_previous_frame_and_restarts_from_its_initial_value() {
    let mut rt = runtime();
    apply(&mut rt, HISTORY, &CompileOptions::new(8, 4));
    let mut seen = Vec::new();
    for _ in 0..3 {
        frame(&mut rt);
        seen.push(red(&mut rt));
    }
    assert_eq!(seen, vec![11.0, 12.0, 13.0], "frame n reads frame n-1's value, frame 0 the initial value");
    rt.invalidate_history();
    frame(&mut rt);
    assert_eq!(red(&mut rt), 11.0, "after invalidation the initial value is read again");
}

#[test]
fn history_survives_a_recompile_and_restarts_when_its_descriptor_changes() {
    let mut rt = runtime();
    apply(&mut rt, HISTORY, &CompileOptions::new(8, 4));
    for _ in 0..3 {
        frame(&mut rt);
    }
    assert_eq!(red(&mut rt), 13.0);
    // The same graph with another step size: history keeps its content.
    let report = apply(&mut rt, HISTORY, &CompileOptions::new(8, 4).with_param("count", "amount", 2.0));
    assert_eq!(report.history_kept, vec!["prev".to_string()]);
    frame(&mut rt);
    assert_eq!(red(&mut rt), 15.0, "the recompiled graph continues from the last frame's value");
    // A half-size history target is another descriptor: it starts from its initial value.
    let half = HISTORY.replace(
        r#"Pass(id: "count", kind: "add_one", inputs: {"value": "history.prev"})"#,
        r#"Pass(id: "count", kind: "add_one", inputs: {"value": "history.prev"}, outputs: {"next": (size: Viewport(0.5))})"#,
    );
    let report = apply(&mut rt, &half, &CompileOptions::new(8, 4));
    assert_eq!(report.history_reset, vec!["prev".to_string()]);
    frame(&mut rt);
    assert_eq!(red(&mut rt), 11.0);
}

#[test]
fn repeat_group_feeds_each_iteration_the_previous_output_through_two_slots() {
    let mut rt = runtime();
    apply(
        &mut rt,
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
        &CompileOptions::new(8, 4),
    );
    frame(&mut rt);
    assert_eq!(red(&mut rt), 107.0, "seven iterations each add one to the carried value");
    assert_eq!(rt.plan().expect("plan").slots.len(), 2, "the carried target ping-pongs between two pooled textures");
}

const CHAIN: &str = r#"Graph(
    name: "chain",
    passes: [
        Pass(id: "start", kind: "fill"),
        Pass(id: "a", kind: "add_one", inputs: {"value": "start.filled"}),
        Pass(id: "b", kind: "fill", outputs: {"filled": (size: Absolute(4, 4))}),
        Pass(id: "c", kind: "add_one", inputs: {"value": "a.next"}),
    ],
    outputs: {"image": "c.next", "small": "b.filled"},
)"#;

#[test]
fn a_parameter_edit_writes_a_uniform_and_builds_nothing() {
    let mut rt = runtime();
    let first = apply(&mut rt, CHAIN, &CompileOptions::new(8, 4));
    assert_eq!(first.nodes_created, 4);
    frame(&mut rt);
    assert_eq!(red(&mut rt), 102.0);
    let report = apply(&mut rt, CHAIN, &CompileOptions::new(8, 4).with_param("c", "amount", 7.0));
    assert_eq!((report.nodes_kept, report.nodes_updated, report.nodes_created), (3, 1, 0), "{report:?}");
    assert_eq!((report.pipelines_built, report.textures_created), (0, 0), "{report:?}");
    frame(&mut rt);
    assert_eq!(red(&mut rt), 108.0, "the new amount reached the shader");
}

#[test]
fn a_graph_edit_reuses_every_pipeline() {
    let mut rt = runtime();
    apply(&mut rt, CHAIN, &CompileOptions::new(8, 4));
    frame(&mut rt);
    // Another graph of the same kinds: new nodes, no new pipeline.
    let edited = CHAIN
        .replace(
            r#"Pass(id: "c", kind: "add_one", inputs: {"value": "a.next"})"#,
            r#"Pass(id: "d", kind: "add_one", inputs: {"value": "start.filled"})"#,
        )
        .replace(r#""image": "c.next""#, r#""image": "d.next""#);
    assert_ne!(edited, CHAIN);
    let report = apply(&mut rt, &edited, &CompileOptions::new(8, 4));
    assert_eq!(report.pipelines_built, 0, "{report:?}");
    assert!(report.pipelines_reused > 0, "{report:?}");
    frame(&mut rt);
    assert_eq!(red(&mut rt), 101.0);
}

#[test]
fn a_resize_reallocates_only_viewport_sized_targets() {
    let mut rt = runtime();
    apply(&mut rt, CHAIN, &CompileOptions::new(8, 4));
    frame(&mut rt);
    let plan = rt.plan().expect("plan").clone();
    let viewport_slots = plan.slots.iter().filter(|s| s.extent() == Some((8, 4))).count();
    let report = apply(&mut rt, CHAIN, &CompileOptions::new(16, 8));
    assert_eq!(report.pipelines_built, 0, "{report:?}");
    assert_eq!(report.nodes_created, 0, "no node depends on the viewport: {report:?}");
    assert_eq!(
        report.textures_created as usize, viewport_slots,
        "only the {viewport_slots} viewport-sized slots: {report:?}"
    );
    frame(&mut rt);
    let image = rt.read_output("image").expect("image");
    assert_eq!((image.width, image.height), (16, 8));
    assert_eq!(rt.read_output("small").expect("small").width, 4);
}

#[test]
fn frames_are_submitted_without_waiting_and_timed_in_order() {
    let mut rt = runtime();
    apply(&mut rt, HISTORY, &CompileOptions::new(8, 4));
    let c = camera(&rt);
    for _ in 0..5 {
        rt.submit(c, None).expect("submit");
        assert!(rt.in_flight() <= volgraph_core::runtime::MAX_FRAMES_IN_FLIGHT);
    }
    let mut stats = rt.poll();
    stats.extend(rt.finish());
    let indices: Vec<u64> = stats.iter().map(|s| s.frame_index).collect();
    assert_eq!(indices, vec![0, 1, 2, 3, 4], "every frame reports once, in order");
    assert!(stats.iter().all(|s| s.frame_ms >= 0.0 && s.pass_ids.len() == 1));
    assert_eq!(red(&mut rt), 15.0, "five frames each added one");
}

#[test]
fn bind_groups_are_made_once_and_reused() {
    let mut rt = runtime();
    apply(&mut rt, HISTORY, &CompileOptions::new(8, 4));
    for _ in 0..4 {
        frame(&mut rt);
    }
    let warm = rt.memory().bind_groups_created;
    for _ in 0..20 {
        frame(&mut rt);
    }
    assert_eq!(rt.memory().bind_groups_created, warm, "a steady frame creates no bind group");
    assert!(warm <= 2, "history ping-pong needs two: {warm}");
}

#[test]
fn a_plan_that_fails_to_apply_leaves_the_previous_one_running() {
    let mut rt = runtime();
    apply(&mut rt, CHAIN, &CompileOptions::new(8, 4));
    frame(&mut rt);
    let broken = CHAIN.replace(r#"Pass(id: "start", kind: "fill")"#, r#"Pass(id: "start", kind: "broken")"#);
    let plan = compile("semantics.ron", &broken, &registry(), &CompileOptions::new(8, 4)).expect("valid graph");
    let err = rt.apply(plan, &registry()).expect_err("the broken pass cannot build");
    assert!(err.to_string().contains("this kind never builds"), "{err}");
    assert_eq!(rt.plan().expect("still a plan").name, "chain");
    frame(&mut rt);
    assert_eq!(red(&mut rt), 102.0, "the last good graph keeps rendering");
}

#[test]
fn step_profiling_times_every_step_and_renders_the_same() {
    let mut rt = runtime();
    apply(&mut rt, CHAIN, &CompileOptions::new(8, 4));
    frame(&mut rt);
    let plain = red(&mut rt);
    rt.set_step_profiling(true);
    let c = camera(&rt);
    let stats = rt.render(c).expect("profiled frame");
    assert!(stats.steps_serialised, "the stats say the steps were submitted one by one");
    let ms = stats.step_gpu_ms.as_ref().expect("a time per step");
    assert_eq!(ms.len(), stats.pass_ids.len(), "one time per step: {:?}", stats.pass_ids);
    assert!(ms.iter().all(|t| t.is_finite() && *t >= 0.0), "wall times: {ms:?}");
    assert_eq!(stats.per_pass_ms().len(), 4, "start, a, b, c");
    assert_eq!(red(&mut rt), plain, "submitting step by step renders what one submit does");
    rt.set_step_profiling(false);
    let stats = rt.render(c).expect("frame");
    assert!(!stats.steps_serialised, "profiling off again");
}
