//! The resource kinds the next techniques need, through the public plugin API: storage buffers
//! as graph resources (a counter zeroed and atomically incremented by a compute pass), render
//! passes that draw instanced quads with vertex pulling from a texture (Klein et al. 2005's point
//! splats; WebGPU has no point size), and the typed frame data passes record with.

use std::sync::Arc;

use volgraph_accel::camera::OrbitCamera;
use volgraph_core::plugin::{ShaderUse, SizeRule};
use volgraph_core::runtime::{
    CameraData, ComputePassPipeline, ComputePipelineSpec, CreateContext, Gpu, PassError, RecordContext,
    RenderPassPipeline, RenderPipelineSpec, Runtime, ShaderLibrary,
};
use volgraph_core::{
    CompileOptions, Params, PassDecl, PassNode, PassPlugin, PortKind, PortSpec, Registry, TargetFormat, compile,
};

const SHADER: &str = "splat_count.wgsl";

struct PointList;
struct Splat;
struct CountLit;

struct Draw {
    pipeline: RenderPassPipeline,
    vertices: u32,
    /// Instances per frame: `None` draws one; `Some(port)` one per texel of that port's texture.
    instances_from: Option<&'static str>,
}

impl PassNode for Draw {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let instances = match self.instances_from {
            Some(port) => {
                let size = ctx.view(port)?.texture().size();
                size.width * size.height
            }
            None => 1,
        };
        let bg = ctx.bind_group(&self.pipeline, &[])?;
        let mut pass = ctx.begin_render_pass(&self.pipeline, None)?;
        pass.set_pipeline(&self.pipeline.pipeline);
        pass.set_bind_group(0, &bg, &[]);
        pass.draw(0..self.vertices, 0..instances);
        Ok(())
    }
}

struct Count {
    pipeline: ComputePassPipeline,
}

impl PassNode for Count {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        ctx.clear_buffer("counts")?;
        let (w, h) = ctx.extent("image");
        let bg = ctx.bind_group(&self.pipeline, &[])?;
        let mut pass = ctx.begin_compute_pass();
        pass.set_pipeline(&self.pipeline.pipeline);
        pass.set_bind_group(0, &bg, &[]);
        pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        Ok(())
    }
}

impl PassDecl for PointList {
    fn kind(&self) -> &'static str {
        "point_list"
    }
    fn shaders(&self, _p: &Params) -> Vec<ShaderUse> {
        vec![ShaderUse::new(SHADER, "fs_points")]
    }
    fn summary(&self) -> &'static str {
        "test: four NDC points in an N×1 target"
    }
    fn ports(&self, _p: &Params) -> Vec<PortSpec> {
        vec![PortSpec::write(
            "points",
            PortKind::Target { formats: vec![TargetFormat::Rgba32Float], size: SizeRule::Any },
        )]
    }
}

impl PassPlugin for PointList {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let pipeline = ctx.render_pipeline(&RenderPipelineSpec {
            shader: SHADER,
            vertex: "vs_fullscreen",
            fragment: "fs_points",
            ..Default::default()
        })?;
        Ok(Box::new(Draw { pipeline, vertices: 3, instances_from: None }))
    }
}

impl PassDecl for Splat {
    fn kind(&self) -> &'static str {
        "splat"
    }
    fn shaders(&self, _p: &Params) -> Vec<ShaderUse> {
        vec![ShaderUse::new(SHADER, "vs_splat"), ShaderUse::new(SHADER, "fs_splat")]
    }
    fn summary(&self) -> &'static str {
        "test: a 2×2-pixel quad per point, instanced, vertices pulled from the point texture"
    }
    fn ports(&self, _p: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read(
                "points",
                PortKind::Target { formats: vec![TargetFormat::Rgba32Float], size: SizeRule::Any },
            ),
            PortSpec::write("image", PortKind::target(&[TargetFormat::Rgba32Float])),
        ]
    }
}

impl PassPlugin for Splat {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let pipeline = ctx.render_pipeline(&RenderPipelineSpec {
            shader: SHADER,
            vertex: "vs_splat",
            fragment: "fs_splat",
            topology: wgpu::PrimitiveTopology::TriangleList,
            ..Default::default()
        })?;
        Ok(Box::new(Draw { pipeline, vertices: 6, instances_from: Some("points") }))
    }
}

impl PassDecl for CountLit {
    fn kind(&self) -> &'static str {
        "count_lit"
    }
    fn shaders(&self, _p: &Params) -> Vec<ShaderUse> {
        vec![ShaderUse::new(SHADER, "cs_count")]
    }
    fn summary(&self) -> &'static str {
        "test: counts lit pixels into a storage buffer"
    }
    fn ports(&self, _p: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read("image", PortKind::target(&[TargetFormat::Rgba32Float])),
            PortSpec::write("counts", PortKind::buffer(16)),
        ]
    }
}

impl PassPlugin for CountLit {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let pipeline =
            ctx.compute_pipeline(&ComputePipelineSpec { shader: SHADER, entry: "cs_count", ..Default::default() })?;
        Ok(Box::new(Count { pipeline }))
    }
}

const GRAPH: &str = r#"Graph(
    name: "splat and count",
    passes: [
        Pass(id: "points", kind: "point_list", outputs: {"points": (size: Absolute(4, 1))}),
        Pass(id: "splat", kind: "splat", inputs: {"points": "points.points"}),
        Pass(id: "count", kind: "count_lit", inputs: {"image": "splat.image"}),
    ],
    outputs: {"image": "splat.image", "counts": "count.counts"},
)"#;

fn runtime() -> (Runtime, Registry) {
    let gpu = Arc::new(Gpu::new_headless().expect("a Vulkan adapter (lavapipe without a GPU)"));
    let sources = volgraph_passes::builtin_shaders()
        .prepend_disk(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/shaders"));
    let mut registry = Registry::new();
    registry.register(PointList).register(Splat).register(CountLit);
    (Runtime::new(gpu, ShaderLibrary::new(sources)), registry)
}

fn counts(runtime: &mut Runtime) -> [u32; 4] {
    let bytes = runtime.read_buffer_output("counts").expect("the counter buffer reads back");
    std::array::from_fn(|i| u32::from_le_bytes([bytes[4 * i], bytes[4 * i + 1], bytes[4 * i + 2], bytes[4 * i + 3]]))
}

#[test]
fn instanced_quads_pulled_from_a_texture_are_counted_into_a_buffer() {
    let (mut rt, registry) = runtime();
    let plan = compile("splat.ron", GRAPH, &registry, &CompileOptions::new(40, 12)).expect("valid graph");
    assert!(plan.to_text().contains("buffer 16 B pooled"), "{}", plan.to_text());
    rt.apply(plan, &registry).expect("applies");
    let camera = CameraData::from_orbit(&OrbitCamera::default(), (40, 12));
    for frame in 0..3u32 {
        rt.render(camera).expect("frame");
        let c = counts(&mut rt);
        // Four points, each a 2×2-pixel quad; the counter is zeroed every frame.
        assert_eq!(c[0], 16, "lit pixels in frame {frame}");
        assert_eq!(c[1], frame, "the frame contract's index reached the shader");
    }
    let image = rt.read_output("image").expect("image");
    let lit: Vec<(u32, u32)> =
        (0..12).flat_map(|y| (0..40).map(move |x| (x, y))).filter(|&(x, y)| image.rgba(x, y)[0] > 0.5).collect();
    // Each point sits on pixel centre (4 + 8i, 5); its quad covers pixels x in {3 + 8i, 4 + 8i}, y in {4, 5}.
    let expected: Vec<(u32, u32)> =
        [4u32, 5].iter().flat_map(|&y| (0..4).flat_map(move |i| [(3 + 8 * i, y), (4 + 8 * i, y)])).collect();
    let mut lit_sorted = lit.clone();
    lit_sorted.sort();
    let mut expected_sorted = expected;
    expected_sorted.sort();
    assert_eq!(lit_sorted, expected_sorted);
}

#[test]
fn a_buffer_where_a_texture_is_expected_is_a_located_error() {
    let (_, registry) = runtime();
    let wrong = GRAPH.replace(r#"inputs: {"image": "splat.image"}"#, r#"inputs: {"image": "count.counts"}"#);
    let err = compile("splat.ron", &wrong, &registry, &CompileOptions::new(40, 12)).expect_err("type error");
    let text = err.to_string();
    assert!(text.contains("accepts Rgba32Float") || text.contains("needs a target"), "{text}");
}
