//! `volgraph plan` checks shader bindings without a GPU (`check_plan_bindings`): one test per
//! class of binding error that used to surface only when the node was created at run time.
//! The plugins and shaders here are test-local, registered through the public API.

use volgraph_compiler::decl::ShaderUse;
use volgraph_compiler::shader_source::ShaderSources;
use volgraph_compiler::{
    CompileOptions, Kinds, Params, PassDecl, PortKind, PortSpec, TargetFormat, check_plan_bindings, compile,
};

volgraph_compiler::pass_params! {
    /// The probe's uniform block: one float, `struct P { k: f32 }` in the shader.
    pub struct ProbeParams {
        k: f32 = 1.0, 0.0..=2.0, "a knob";
    }
}

/// A pass with a texture input `color`, a buffer input `counts`, an output `out`, and the shader
/// entry point `entry` of `probe.wgsl`; binds the uniform block `params` itself.
struct Probe {
    entry: &'static str,
}

impl PassDecl for Probe {
    fn kind(&self) -> &'static str {
        "probe"
    }
    fn summary(&self) -> &'static str {
        "binding-check test pass"
    }
    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![
            PortSpec::read("color", PortKind::target(&[TargetFormat::Rgba16Float])),
            PortSpec::read("counts", PortKind::buffer(16)).optional(),
            PortSpec::write("out", PortKind::target(&[TargetFormat::Rgba16Float])),
        ]
    }
    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        vec![ShaderUse::new("probe.wgsl", self.entry).uniform(ProbeParams::bound_as("params"))]
    }
}

struct Source;

impl PassDecl for Source {
    fn kind(&self) -> &'static str {
        "source"
    }
    fn summary(&self) -> &'static str {
        "writes a target"
    }
    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        vec![PortSpec::write("color", PortKind::target(&[TargetFormat::Rgba16Float]))]
    }
}

const SHADER: &str = r#"
struct P { k: f32 }
@group(0) @binding(0) var<uniform> params: P;
@group(0) @binding(1) var color: texture_2d<f32>;
@group(0) @binding(2) var out: texture_storage_2d<rgba16float, write>;
@group(0) @binding(3) var colour: texture_2d<f32>;
@group(0) @binding(4) var<storage, read> color_buffer: array<u32>;
@group(0) @binding(5) var counts: texture_2d<f32>;
@group(0) @binding(6) var color_storage: texture_storage_2d<rgba16float, write>;
@group(1) @binding(0) var<uniform> grouped: P;

@compute @workgroup_size(8, 8)
fn cs_ok(@builtin(global_invocation_id) id: vec3<u32>) {
    textureStore(out, vec2<i32>(id.xy), textureLoad(color, vec2<i32>(id.xy), 0) * params.k);
}
// The port is `color`; the shader says `colour`.
@compute @workgroup_size(8, 8)
fn cs_misnamed(@builtin(global_invocation_id) id: vec3<u32>) {
    textureStore(out, vec2<i32>(id.xy), textureLoad(colour, vec2<i32>(id.xy), 0));
}
// `counts` is a storage-buffer port read as a texture.
@compute @workgroup_size(8, 8)
fn cs_buffer_as_texture(@builtin(global_invocation_id) id: vec3<u32>) {
    textureStore(out, vec2<i32>(id.xy), textureLoad(counts, vec2<i32>(id.xy), 0));
}
// A vertex stage (declared like any other, CreateContext requires it) that reads `colour`.
@vertex
fn vs_misnamed(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    return vec4<f32>(textureLoad(colour, vec2<i32>(0, 0), 0).x, 0.0, 0.0, 1.0);
}
// Everything in @group(0).
@compute @workgroup_size(8, 8)
fn cs_group(@builtin(global_invocation_id) id: vec3<u32>) {
    textureStore(out, vec2<i32>(id.xy), vec4<f32>(grouped.k));
}
"#;

const OUT_AS_INPUT: &str = r#"
@group(0) @binding(0) var color: texture_storage_2d<rgba16float, write>;
@group(0) @binding(1) var out: texture_2d<f32>;
@compute @workgroup_size(8, 8)
fn cs_main(@builtin(global_invocation_id) id: vec3<u32>) {
    textureStore(color, vec2<i32>(id.xy), textureLoad(out, vec2<i32>(id.xy), 0));
}
"#;

const GRAPH: &str = r#"Graph(
    name: "probe",
    passes: [
        Pass(id: "src", kind: "source"),
        Pass(id: "p", kind: "probe", inputs: {"color": "src.color"}),
    ],
    outputs: {"image": "p.out"},
)"#;

fn problems(entry: &'static str, shader: &'static str) -> Vec<String> {
    let mut registry = Kinds::new();
    registry.register(Source).register(Probe { entry });
    let plan = compile("probe.ron", GRAPH, &registry, &CompileOptions::new(32, 32)).expect("compiles");
    // Embedded shader tables are 'static; a test leaks its few bytes.
    let table: &'static [(&'static str, &'static str)] = Box::leak(Box::new([("probe.wgsl", shader)]));
    let sources = ShaderSources::new().with_embedded(table);
    check_plan_bindings(&plan, &registry, &sources).into_iter().map(|d| d.message).collect()
}

#[test]
fn a_correct_pass_has_no_problem() {
    assert_eq!(problems("cs_ok", SHADER), Vec::<String>::new());
}

/// A uniform struct that disagrees with the block the pass uploads (a member added in front, the
/// rest shifted) would read its values from the wrong bytes — an image of zeros with exit status
/// 0 at run time; at plan time it is an error naming the member, its offset and the fix.
#[test]
fn a_uniform_struct_that_disagrees_with_the_declaration_is_caught_at_plan_time() {
    let shifted: &'static str =
        Box::leak(SHADER.replace("struct P { k: f32 }", "struct P { j: u32, k: f32 }").into_boxed_str());
    let p = problems("cs_ok", shifted);
    assert!(
        p.len() == 1
            && p[0].contains(
                "uniform \"params\": P member 0 is `j: u32` at offset 0, but the pass declares `k: f32` at 0"
            )
            && p[0].contains("#import \"params/<Struct>.wgsl\""),
        "{p:?}"
    );
}

#[test]
fn a_misnamed_port_is_caught_at_plan_time() {
    let p = problems("cs_misnamed", SHADER);
    assert!(
        p.len() == 1 && p[0].contains("global \"colour\" is neither a port of this pass (ports: color, counts, out)"),
        "{p:?}"
    );
    assert!(p[0].starts_with("pass \"p\" (probe): probe.wgsl"), "{p:?}");
}

/// Vertex stages that bind something are declared too (node creation refuses them otherwise),
/// so their bindings are checked at plan time like the fragment and compute stages'.
#[test]
fn a_misnamed_global_in_a_vertex_stage_is_caught_at_plan_time() {
    let p = problems("vs_misnamed", SHADER);
    assert!(p.len() == 1 && p[0].contains("global \"colour\" is neither a port of this pass"), "{p:?}");
}

#[test]
fn a_buffer_port_read_as_a_texture_is_caught_at_plan_time() {
    let p = problems("cs_buffer_as_texture", SHADER);
    assert!(
        p.len() == 1 && p[0].contains("\"counts\" is not a storage buffer but port \"counts\" is a buffer"),
        "{p:?}"
    );
}

#[test]
fn a_group_other_than_zero_is_caught_at_plan_time() {
    let p = problems("cs_group", SHADER);
    assert!(p.len() == 1 && p[0].contains("global \"grouped\" is in @group(1)"), "{p:?}");
}

#[test]
fn an_entry_point_the_shader_lacks_is_caught_at_plan_time() {
    let p = problems("cs_missing", SHADER);
    assert!(p.len() == 1 && p[0].contains("has no entry point \"cs_missing\""), "{p:?}");
}

#[test]
fn a_storage_texture_on_an_input_and_a_sampled_output_are_caught_at_plan_time() {
    let p = problems("cs_main", OUT_AS_INPUT);
    assert!(p.len() == 1 && p[0].contains("storage texture \"color\" is an input port"), "{p:?}");
}

/// A WGSL error inside an `#import`ed file is reported at that file's own line, not at the line
/// of the assembled text.
#[test]
fn a_shader_error_points_at_the_imported_file_and_line() {
    let mut registry = Kinds::new();
    registry.register(Source).register(Probe { entry: "cs_ok" });
    let plan = compile("probe.ron", GRAPH, &registry, &CompileOptions::new(32, 32)).expect("compiles");
    let table: &'static [(&'static str, &'static str)] = Box::leak(Box::new([
        ("probe.wgsl", "#import \"lib.wgsl\"\n@compute @workgroup_size(1) fn cs_ok() { }\n"),
        ("lib.wgsl", "fn ok() -> f32 { return 1.0; }\nfn broken() -> f32 { return vec2<f32>(1.0); }\n"),
    ]));
    let sources = ShaderSources::new().with_embedded(table);
    let p: Vec<String> = check_plan_bindings(&plan, &registry, &sources).into_iter().map(|d| d.message).collect();
    assert!(p.len() == 1 && p[0].contains("lib.wgsl:2:"), "{p:?}");
}

const SAMPLES_OUTPUT: &str = r#"
@group(0) @binding(0) var color: texture_2d<f32>;
@group(0) @binding(1) var out: texture_2d<f32>;
@compute @workgroup_size(8, 8)
fn cs_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let a = textureLoad(color, vec2<i32>(id.xy), 0) + textureLoad(out, vec2<i32>(id.xy), 0);
}
"#;

#[test]
fn a_sampled_output_is_caught_at_plan_time() {
    let p = problems("cs_main", SAMPLES_OUTPUT);
    assert!(p.len() == 1 && p[0].contains("global \"out\" samples output port \"out\""), "{p:?}");
}
