//! Frames the GPU rejects (a validation error wgpu reports only when the commands run): the last
//! graph, or the last pipelines, that rendered come back by themselves.

use super::*;

/// A pass that builds fine but records a dispatch with no pipeline set: wgpu only rejects it
/// when the frame's commands are finished, after the plan was applied.
struct BadDraw;

struct BadDrawNode {
    pipeline: volgraph_core::runtime::ComputePassPipeline,
}

impl volgraph_core::PassNode for BadDrawNode {
    fn record(
        &mut self,
        ctx: &mut volgraph_core::runtime::RecordContext<'_>,
    ) -> Result<(), volgraph_core::runtime::PassError> {
        let _ = &self.pipeline;
        let mut pass = ctx.begin_compute_pass();
        pass.dispatch_workgroups(1, 1, 1);
        Ok(())
    }
}

fn bad_draw() -> volgraph_core::plugin::ShaderUse {
    volgraph_core::plugin::ShaderUse::new("present.wgsl", "cs_present").binds(&["params"])
}

impl volgraph_core::PassDecl for BadDraw {
    fn kind(&self) -> &'static str {
        "bad_draw"
    }
    fn summary(&self) -> &'static str {
        "test: records an invalid dispatch"
    }
    fn ports(&self, _p: &volgraph_core::Params) -> Vec<volgraph_core::PortSpec> {
        vec![
            volgraph_core::PortSpec::read(
                "color",
                volgraph_core::PortKind::target(&[
                    volgraph_core::TargetFormat::Rgba32Float,
                    volgraph_core::TargetFormat::Rgba16Float,
                ]),
            ),
            volgraph_core::PortSpec::write(
                "display",
                volgraph_core::PortKind::target(&[volgraph_core::TargetFormat::Rgba8Unorm]),
            ),
        ]
    }
    fn shaders(&self, _p: &volgraph_core::Params) -> Vec<volgraph_core::plugin::ShaderUse> {
        vec![bad_draw()]
    }
}

impl volgraph_core::PassPlugin for BadDraw {
    fn create(
        &self,
        ctx: &volgraph_core::runtime::CreateContext<'_>,
    ) -> Result<Box<dyn volgraph_core::PassNode>, volgraph_core::runtime::PassError> {
        let pipeline = ctx.compute_pipeline(&volgraph_core::runtime::ComputePipelineSpec::of(&bad_draw()))?;
        Ok(Box::new(BadDrawNode { pipeline }))
    }
}

#[test]
fn a_frame_the_gpu_rejects_puts_the_last_good_graph_back() {
    let s = scratch("frame-error", "graphs/basic/fragment_raycast.ron");
    let mut registry = volgraph_passes::builtin_registry();
    registry.register(BadDraw);
    let args = session_args(&s, &[], None);
    let (mut session, _) = LiveSession::open_with(gpu(), &args, registry).unwrap_or_else(|_| panic!("loads"));
    let camera = OrbitCamera::default();
    assert!(session.frame(&camera, None).expect("a good frame").is_empty());
    session.runtime.finish();
    let good = session.runtime.read_output("image").expect("image").data;
    // The edit applies (the pass builds), but its frame fails on the GPU.
    edit(&s.graph, "kind: \"present\"", "kind: \"bad_draw\"");
    let events = session.reload_graph();
    assert!(matches!(events.as_slice(), [Event::Reloaded { .. }]), "{events:?}");
    let events = session.frame(&camera, None).expect("recovers by itself");
    let [Event::Error { what, message }] = events.as_slice() else { panic!("{events:?}") };
    assert_eq!(what, "frame");
    assert!(message.contains("the last graph that rendered is back"), "{message}");
    assert!(session.frame(&camera, None).expect("the last good graph renders").is_empty());
    session.runtime.finish();
    assert_eq!(session.runtime.read_output("image").expect("image").data, good);
    assert_eq!(session.plan().expect("plan").steps.iter().filter(|s| s.kind == "present").count(), 1);
    let _ = std::fs::remove_dir_all(&s.dir);
}

/// Issue 19: a hot-reloaded shader that naga accepts but the GPU rejects (a params struct
/// larger than the uniform the pass binds) made the viewer quit: the rollback re-applied the
/// last good graph, which read the bad shader from disk again. The last good *compiled*
/// modules come back instead, and the window keeps rendering the last good image until the
/// file is fixed.
#[test]
fn a_shader_edit_the_gpu_rejects_keeps_the_last_good_pipelines() {
    let s = scratch("gpu-rejects-shader", "graphs/basic/fragment_raycast.ron");
    let mut session = open(&s, None);
    let camera = OrbitCamera::default();
    assert!(session.frame(&camera, None).expect("a good frame").is_empty());
    session.runtime.finish();
    let good = session.runtime.read_output("image").expect("image").data;
    let present = s.shaders.join("present.wgsl");
    // The struct written out in full with trailing padding: the members the pass declares are
    // all there (the layout check accepts it), but the block outgrows the buffer.
    edit(
        &present,
        "#import \"params/PresentParams.wgsl\"",
        "struct PresentParams {\n    background: f32,\n    _pad0: f32,\n    _pad1: f32,\n    _pad2: f32,\n    _pad_larger_than_declared: vec4<f32>,\n}",
    );
    let events = session.files_changed(std::slice::from_ref(&present));
    assert!(matches!(events.as_slice(), [Event::Reloaded { .. }]), "naga accepts the edit: {events:?}");
    let events = session.frame(&camera, None).expect("recovers by itself");
    let [Event::Error { what, message }] = events.as_slice() else { panic!("{events:?}") };
    assert_eq!(what, "frame");
    assert!(message.contains("the last graph that rendered is back"), "{message}");
    // The failure names the pass and the binding, not wgpu's "binding index 1".
    assert!(
        message.contains("pass \"present\": present/cs_present: uniform \"params\" (@binding(1)) is 32 bytes in the shader but the buffer the pass binds holds 16"),
        "{message}"
    );
    for _ in 0..2 {
        assert!(session.frame(&camera, None).expect("the last good pipelines render").is_empty());
    }
    session.runtime.finish();
    assert_eq!(session.runtime.read_output("image").expect("image").data, good);
    // Fixing the file reloads it like any edit.
    edit(&present, "    _pad_larger_than_declared: vec4<f32>,\n", "");
    let events = session.files_changed(std::slice::from_ref(&present));
    assert!(events.iter().any(|e| matches!(e, Event::Reloaded { .. })), "{events:?}");
    assert!(session.frame(&camera, None).expect("the fixed shader renders").is_empty());
    let _ = std::fs::remove_dir_all(&s.dir);
}
