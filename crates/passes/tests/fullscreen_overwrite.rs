//! `RecordContext::draw_fullscreen` leaves a pass's Write targets uncleared only where its
//! draw writes every pixel (`PassPipeline::covers_viewport`): a fullscreen stage that can
//! `discard` still starts from zeros, not from what the pooled texture held (here: the
//! previous frame's image).

use std::sync::{Arc, Mutex};

use volgraph_accel::camera::OrbitCamera;
use volgraph_core::plugin::ShaderUse;
use volgraph_core::runtime::{
    CameraData, CreateContext, PassError, RecordContext, RenderPassPipeline, RenderPipelineSpec, Runtime, ShaderLibrary,
};
use volgraph_core::{
    CompileOptions, Params, PassDecl, PassNode, PassPlugin, PortKind, PortSpec, Registry, TargetFormat, compile,
};

mod support;

const SHADER: &str = "fullscreen_cover.wgsl";

/// A fullscreen pass drawing `entry` of the test shader into `image`; `covers` records the
/// built pipeline's `covers_viewport`.
struct Fullscreen {
    kind: &'static str,
    entry: &'static str,
    covers: Arc<Mutex<Option<bool>>>,
}

struct Draw {
    pipeline: RenderPassPipeline,
}

impl PassNode for Draw {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let bg = ctx.bind_group(&self.pipeline, &[])?;
        ctx.draw_fullscreen(&self.pipeline, &bg)
    }
}

impl PassDecl for Fullscreen {
    fn kind(&self) -> &'static str {
        self.kind
    }
    fn shaders(&self, _p: &Params) -> Vec<ShaderUse> {
        vec![ShaderUse::new(SHADER, self.entry)]
    }
    fn summary(&self) -> &'static str {
        "test: one fullscreen fragment stage"
    }
    fn ports(&self, _p: &Params) -> Vec<PortSpec> {
        vec![PortSpec::write("image", PortKind::target(&[TargetFormat::Rgba32Float]))]
    }
}

impl PassPlugin for Fullscreen {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let pipeline = ctx.render_pipeline(&RenderPipelineSpec::fullscreen(&ShaderUse::new(SHADER, self.entry)))?;
        *self.covers.lock().expect("not poisoned") = Some(pipeline.covers_viewport);
        Ok(Box::new(Draw { pipeline }))
    }
}

/// Whether `kind`'s pipeline covers the viewport, and row 1's red channel after `frames` frames
/// of a graph of one `kind` pass.
fn run(kind: &'static str, frames: u32) -> (bool, Vec<f32>) {
    let gpu = support::gpu();
    let covers = Arc::new(Mutex::new(None));
    let sources = volgraph_passes::builtin_shaders()
        .prepend_disk(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/shaders"));
    let mut registry = Registry::new();
    registry.register(Fullscreen {
        kind,
        entry: if kind == "cover" { "fs_cover" } else { "fs_half" },
        covers: covers.clone(),
    });
    let mut rt = Runtime::new(gpu, ShaderLibrary::new(sources));
    let graph =
        format!(r#"Graph(name: "t", passes: [Pass(id: "draw", kind: "{kind}")], outputs: {{"image": "draw.image"}})"#);
    let plan = compile("t.ron", &graph, &registry, &CompileOptions::new(8, 2)).expect("valid graph");
    rt.apply(plan, &registry).expect("applies");
    let camera = CameraData::from_orbit(&OrbitCamera::default(), (8, 2));
    for _ in 0..frames {
        rt.render(camera).expect("frame");
    }
    let image = rt.read_output("image").expect("image");
    let covers = covers.lock().expect("not poisoned").expect("the pass was built");
    (covers, (0..8).map(|x| image.rgba(x, 1)[0]).collect())
}

#[test]
fn a_draw_over_every_pixel_overwrites_without_a_clear() {
    let (covers, red) = run("cover", 3);
    assert!(covers, "the fullscreen triangle without discard, depth test or blending covers the viewport");
    assert_eq!(red, vec![3.0; 8], "frame 2 writes 3 everywhere");
}

#[test]
fn a_fullscreen_stage_that_can_discard_still_starts_from_zeros() {
    let (covers, red) = run("half", 2);
    assert!(!covers, "a fragment stage that calls a function with a discard may leave pixels unwritten");
    // Frame 1 discards the left half: cleared, not frame 0's 1.0.
    assert_eq!(red, vec![0.0, 0.0, 0.0, 0.0, 2.0, 2.0, 2.0, 2.0]);
}
