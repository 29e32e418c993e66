//! Shader bindings are reflected with naga and checked against the pass's declared ports when
//! the graph loads: a mismatch is a clear error naming the pass, the shader, the global and the
//! ports, never a wgpu panic or a silently unbound texture. The plugins here live outside
//! crates/passes' registry on purpose: they register through the public API.

use volgraph_core::plugin::ShaderUse;
use volgraph_core::runtime::{
    ComputePipelineSpec, CreateContext, Gpu, PassError, RecordContext, RenderPipelineSpec, Runtime, ShaderLibrary,
};
use volgraph_core::{
    CompileOptions, Params, PassDecl, PassNode, PassPlugin, PortKind, PortSpec, Registry, TargetFormat, compile,
};

const FLOATS: [TargetFormat; 3] = [TargetFormat::Rgba32Float, TargetFormat::Rgba16Float, TargetFormat::Rgba8Unorm];

/// A raycaster whose ports are misnamed relative to `raycast.wgsl`.
struct Misnamed {
    kind: &'static str,
    dir_port: &'static str,
    color_port: &'static str,
    compute_color: Option<TargetFormat>,
}

struct NoOp;

impl PassNode for NoOp {
    fn record(&mut self, _ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        Ok(())
    }
}

impl PassDecl for Misnamed {
    fn kind(&self) -> &'static str {
        self.kind
    }

    fn summary(&self) -> &'static str {
        "test plugin with ports that do not match its shader"
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        let color = match self.compute_color {
            Some(f) => PortKind::target(&[f]),
            None => PortKind::target(&FLOATS),
        };
        vec![
            PortSpec::read("entry", PortKind::target(&FLOATS)),
            PortSpec::read(self.dir_port, PortKind::target(&FLOATS)),
            PortSpec::read("volume", PortKind::Volume),
            PortSpec::read("tf", PortKind::TransferFunction),
            PortSpec::write(self.color_port, color),
        ]
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        match (self.compute_color, self.kind) {
            // Declares the fragment entry it does not build (`fs_iso`), not the one it does.
            (_, "undeclared") => vec![ShaderUse::new("raycast.wgsl", "fs_iso").binds(&["params"])],
            // Declares the fragment stage but not the vertex stage, which binds the frame.
            (_, "undeclared_vertex") => {
                vec![ShaderUse::new("entry_points.wgsl", "fs_entry")]
            }
            (Some(_), _) => vec![ShaderUse::new("raycast_compute.wgsl", "cs_dvr").binds(&["params"])],
            (None, _) => vec![ShaderUse::new("raycast.wgsl", "fs_dvr").binds(&["params"])],
        }
    }
}

impl PassPlugin for Misnamed {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        if self.kind == "undeclared_vertex" {
            ctx.render_pipeline(&RenderPipelineSpec {
                shader: "entry_points.wgsl",
                vertex: "vs_box",
                fragment: "fs_entry",
                ..Default::default()
            })?;
        } else if self.compute_color.is_some() {
            ctx.compute_pipeline(&ComputePipelineSpec {
                shader: "raycast_compute.wgsl",
                entry: "cs_dvr",
                constants: &[],
                defines: &[],
            })?;
        } else {
            ctx.render_pipeline(&RenderPipelineSpec {
                shader: "raycast.wgsl",
                vertex: "vs_fullscreen",
                fragment: "fs_dvr",
                ..Default::default()
            })?;
        }
        Ok(Box::new(NoOp))
    }
}

fn build_error(plugin: Misnamed) -> String {
    let kind = plugin.kind;
    let dir = plugin.dir_port;
    let color = plugin.color_port;
    let mut registry = Registry::new();
    volgraph_passes::register_builtin(&mut registry);
    registry.register(plugin);
    let graph = format!(
        r#"Graph(
    name: "reflection test",
    inputs: {{"volume": Volume, "tf": TransferFunction}},
    passes: [
        Pass(id: "entry", kind: "entry_points"),
        Pass(id: "dirs", kind: "ray_directions", inputs: {{"entry": "entry.entry"}}),
        Pass(id: "march", kind: "{kind}", inputs: {{
            "entry": "entry.entry", "{dir}": "dirs.dir", "volume": "input.volume", "tf": "input.tf"}}),
    ],
    outputs: {{"image": "march.{color}"}},
)"#
    );
    let plan =
        compile("reflection.ron", &graph, &registry, &CompileOptions::new(16, 16)).expect("the graph itself is valid");
    let gpu = std::sync::Arc::new(Gpu::new_headless().expect("a Vulkan adapter (lavapipe without a GPU)"));
    let mut runtime = Runtime::new(gpu, ShaderLibrary::new(volgraph_passes::builtin_shaders()));
    match runtime.apply(plan, &registry) {
        Ok(_) => panic!("a pass whose ports do not match its shader must not build"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn shader_global_without_a_port_is_named() {
    let msg = build_error(Misnamed {
        kind: "misnamed_input",
        dir_port: "direction",
        color_port: "color",
        compute_color: None,
    });
    assert_eq!(
        msg,
        "pass \"march\": raycast.wgsl: global \"dir\" is neither a port of this pass (ports: entry, direction, volume, tf, color) \
         nor a system binding (frame, linear_clamp, nearest_clamp, environment_map) nor one the pass binds itself (params); \
         rename it to the port it stands for, or, when the node binds it itself, declare it in the pass's \
         ShaderUse (`.uniform(..)` for a uniform block, else `.binds(&[\"dir\"])`)"
    );
}

/// Node creation builds from the declared list: a pipeline `shaders()` does not declare (so
/// `volgraph plan` never checked its bindings) is an error, not a silent extra.
#[test]
fn an_entry_point_the_plugin_does_not_declare_is_not_built() {
    let msg = build_error(Misnamed { kind: "undeclared", dir_port: "dir", color_port: "color", compute_color: None });
    assert_eq!(
        msg,
        "pass \"march\": it builds raycast.wgsl entry point `fs_dvr`, which its plugin's `shaders()` does not \
         declare for these parameters (it declares raycast.wgsl:fs_iso); add `ShaderUse::new(\"raycast.wgsl\", \
         \"fs_dvr\")` (with `.uniform(..)` / `.binds(..)` for what the node binds) there, so `volgraph plan` checks \
         its bindings too"
    );
}

/// A vertex stage that binds something (here the frame) is declared like the fragment stage.
#[test]
fn a_vertex_stage_that_binds_something_must_be_declared() {
    let msg =
        build_error(Misnamed { kind: "undeclared_vertex", dir_port: "dir", color_port: "color", compute_color: None });
    assert!(
        msg.contains(
            "it builds entry_points.wgsl entry point `vs_box`, which its plugin's `shaders()` does not declare"
        ),
        "{msg}"
    );
}

#[test]
fn fragment_output_without_a_port_is_named() {
    let msg =
        build_error(Misnamed { kind: "misnamed_output", dir_port: "dir", color_port: "colour", compute_color: None });
    assert_eq!(
        msg,
        "pass \"march\": raycast.wgsl: fragment output \"color\" (@location(0)) of fs_dvr is not an output port of this pass"
    );
}

#[test]
fn storage_texture_format_must_match_the_target() {
    let msg = build_error(Misnamed {
        kind: "wrong_storage_format",
        dir_port: "dir",
        color_port: "color",
        compute_color: Some(TargetFormat::Rgba32Float),
    });
    assert_eq!(
        msg,
        "pass \"march\": raycast_compute.wgsl: storage texture \"color\" is declared Rgba16Float but the port's target is \
         Rgba32Float; declare the output with the shader's format"
    );
}
