//! The scheduler, seen through compiled plans: ordering, culling, pooling, repeat unrolling with
//! ping-pong, Modify chains, history, feature gating and scene-derived repeat counts.
//!
//! The pass kinds are defined here, outside `volgraph-passes`, through the public
//! [`PassDecl`] API: this is also the proof that a crate other than the built-in one can add
//! pass kinds and have them scheduled. They are declarations only: this test links no GPU stack.

use volgraph_compiler::plan::{Binding, ResourceDesc};
use volgraph_compiler::{
    Access, CompileOptions, Kinds, ParamSpec, Params, PassDecl, Plan, PortKind, PortSpec, TargetFormat, compile,
};

/// A pass kind described as data: a name, ports, parameters and features.
struct Kind {
    name: &'static str,
    ports: Vec<PortSpec>,
    params: Vec<ParamSpec>,
    features: Vec<&'static str>,
}

impl Kind {
    fn new(name: &'static str) -> Self {
        Self { name, ports: Vec::new(), params: Vec::new(), features: Vec::new() }
    }

    fn read(mut self, port: &'static str, format: TargetFormat) -> Self {
        self.ports.push(PortSpec::read(port, PortKind::target(&[format])));
        self
    }

    fn write(mut self, port: &'static str, format: TargetFormat) -> Self {
        self.ports.push(PortSpec::write(port, PortKind::target(&[format])));
        self
    }

    fn modify(mut self, port: &'static str, format: TargetFormat) -> Self {
        self.ports.push(PortSpec::modify(port, PortKind::target(&[format])));
        self
    }

    fn feature(mut self, feature: &'static str) -> Self {
        self.features.push(feature);
        self
    }

    fn param(mut self, spec: ParamSpec) -> Self {
        self.params.push(spec);
        self
    }
}

/// A declaration only: scheduling tests never run a frame.
impl PassDecl for Kind {
    fn kind(&self) -> &'static str {
        self.name
    }

    fn summary(&self) -> &'static str {
        "scheduler test pass"
    }

    fn params(&self) -> Vec<ParamSpec> {
        self.params.clone()
    }

    fn ports(&self, _params: &Params) -> Vec<PortSpec> {
        self.ports.clone()
    }

    fn features(&self) -> Vec<&'static str> {
        self.features.clone()
    }
}

const RGBA32: TargetFormat = TargetFormat::Rgba32Float;
const RGBA16: TargetFormat = TargetFormat::Rgba16Float;
const DEPTH: TargetFormat = TargetFormat::Depth32Float;

fn registry() -> Kinds {
    let mut r = Kinds::new();
    r.register(Kind::new("source").write("out", RGBA32));
    r.register(Kind::new("source16").write("out", RGBA16));
    r.register(Kind::new("filter").read("src", RGBA32).write("out", RGBA32));
    r.register(Kind::new("to16").read("src", RGBA32).write("out", RGBA16));
    r.register(Kind::new("blend").read("a", RGBA32).read("b", RGBA32).write("out", RGBA32));
    r.register(Kind::new("clear").write("color", RGBA32).write("depth", DEPTH));
    r.register(
        Kind::new("segment")
            .read("accum", RGBA32)
            .modify("depth", DEPTH)
            .write("color", RGBA32)
            .param(ParamSpec::uint("steps", 8, 1, 1024, "samples per segment")),
    );
    r.register(Kind::new("depth_peek").read("depth", DEPTH).write("out", RGBA32));
    r.register(Kind::new("terminate").read("color", RGBA32).modify("depth", DEPTH));
    r.register(Kind::new("antialias").read("src", RGBA32).write("out", RGBA32).feature("antialias"));
    r
}

fn plan(source: &str) -> Plan {
    plan_with(source, &CompileOptions::new(64, 32))
}

fn plan_with(source: &str, options: &CompileOptions) -> Plan {
    compile("test.ron", source, &registry(), options).unwrap_or_else(|d| panic!("does not compile:\n{d}"))
}

fn labels(plan: &Plan) -> Vec<&str> {
    plan.steps.iter().map(|s| s.label.as_str()).collect()
}

/// The binding of `port` on the step labelled `label`.
fn binding<'a>(plan: &'a Plan, label: &str, port: &str) -> &'a Binding {
    let step = plan.steps.iter().find(|s| s.label == label).unwrap_or_else(|| panic!("no step {label}"));
    &step.ports.iter().find(|p| p.port == port).unwrap_or_else(|| panic!("{label} has no port {port}")).binding
}

/// The name of the resource `port` of step `label` reads (or writes, for Write ports).
fn resource_of(plan: &Plan, label: &str, port: &str) -> String {
    match binding(plan, label, port) {
        Binding::Resource { id, .. } => plan.resources[*id].name.clone(),
        other => panic!("{label}.{port} is bound to {other:?}"),
    }
}

fn slot_of(plan: &Plan, resource: &str) -> usize {
    let r = plan.resources.iter().find(|r| r.name == resource).unwrap_or_else(|| panic!("no resource {resource}"));
    r.slot.unwrap_or_else(|| panic!("{resource} has no slot"))
}

/// Pooling's safety property: in every slot, each resource chain is written only after the
/// previous chain's last read, and every holder has the slot's format and size.
fn assert_slots_never_overlap(plan: &Plan) {
    for (s, slot) in plan.slots.iter().enumerate() {
        let mut previous_end: Option<usize> = None;
        for &id in &slot.holds {
            let r = &plan.resources[id];
            let ResourceDesc::Target { format, extent, .. } = r.desc else { panic!("{} is not a target", r.name) };
            assert_eq!((Some(format), Some(extent)), (slot.format(), slot.extent()), "{} in slot{s}", r.name);
            if r.modifies.is_some() {
                continue; // the next version of a chain already holding the slot
            }
            if let Some(end) = previous_end {
                assert!(
                    end < r.producer,
                    "slot{s}: {} written at step {} while still read until {end}",
                    r.name,
                    r.producer
                );
            }
            let chain_end = chain_end(plan, id);
            previous_end = Some(chain_end);
        }
    }
}

fn chain_end(plan: &Plan, root: usize) -> usize {
    let mut end = plan.resources[root].last_use;
    for (id, r) in plan.resources.iter().enumerate() {
        let mut cur = id;
        while let Some(prev) = plan.resources[cur].modifies {
            cur = prev;
        }
        if cur == root {
            end = end.max(r.last_use);
        }
    }
    end
}

#[test]
fn order_is_topological_with_ties_in_document_order() {
    let p = plan(
        r#"Graph(name: "order", passes: [
            Pass(id: "mix", kind: "blend", inputs: {"a": "late.out", "b": "early.out"}),
            Pass(id: "late", kind: "filter", inputs: {"src": "early.out"}),
            Pass(id: "other", kind: "source"),
            Pass(id: "early", kind: "source"),
            Pass(id: "final", kind: "blend", inputs: {"a": "mix.out", "b": "other.out"}),
        ], outputs: {"image": "final.out"})"#,
    );
    // "other" and "early" are both ready first: "other" comes first in the document.
    assert_eq!(labels(&p), ["other", "early", "late", "mix", "final"]);
    assert_slots_never_overlap(&p);
}

#[test]
fn culling_drops_passes_no_output_needs_and_reports_them() {
    let p = plan(
        r#"Graph(name: "cull", passes: [
            Pass(id: "src", kind: "source"),
            Pass(id: "unused", kind: "filter", inputs: {"src": "src.out"}),
            Pass(id: "also_unused", kind: "filter", inputs: {"src": "unused.out"}),
            Pass(id: "used", kind: "filter", inputs: {"src": "src.out"}),
        ], outputs: {"image": "used.out"})"#,
    );
    assert_eq!(labels(&p), ["src", "used"]);
    assert_eq!(p.culled, ["unused", "also_unused"]);
    assert!(p.to_text().contains("culled: unused, also_unused\n"));
}

#[test]
fn chain_of_eight_passes_needs_two_targets() {
    let mut passes = vec![r#"Pass(id: "p0", kind: "source")"#.to_string()];
    for i in 1..8 {
        passes.push(format!(r#"Pass(id: "p{i}", kind: "filter", inputs: {{"src": "p{}.out"}})"#, i - 1));
    }
    let src = format!(r#"Graph(name: "chain", passes: [{}], outputs: {{"image": "p7.out"}})"#, passes.join(",\n"));
    let p = plan(&src);
    assert_eq!(p.steps.len(), 8);
    assert_eq!(p.slots.len(), 2, "{}", p.to_text());
    // Each pass reads the slot the previous one wrote and writes the other.
    for i in 1..8 {
        assert_ne!(slot_of(&p, &format!("p{}.out", i - 1)), slot_of(&p, &format!("p{i}.out")));
    }
    let m = p.memory();
    assert_eq!(m.unpooled_bytes, 8 * 64 * 32 * 16);
    assert_eq!(m.pooled_bytes, 2 * 64 * 32 * 16);
    assert_slots_never_overlap(&p);
}

#[test]
fn differing_formats_and_sizes_never_share_a_slot() {
    let p = plan(
        r#"Graph(name: "formats", passes: [
            Pass(id: "a", kind: "source"),
            Pass(id: "b", kind: "to16", inputs: {"src": "a.out"}),
            Pass(id: "c", kind: "source", outputs: {"out": (size: Viewport(0.5))}),
            Pass(id: "d", kind: "source", outputs: {"out": (size: Absolute(64, 32))}),
            Pass(id: "e", kind: "blend", inputs: {"a": "d.out", "b": "d.out"}, outputs: {"out": (size: Absolute(64, 32))}),
        ], outputs: {"half": "c.out", "small": "b.out", "image": "e.out"})"#,
    );
    // a (dead after b) and d (64x32 = the viewport, same format) may share; c is half size and b
    // another format, so neither shares with anything.
    let (a, b, c, d) = (slot_of(&p, "a.out"), slot_of(&p, "b.out"), slot_of(&p, "c.out"), slot_of(&p, "d.out"));
    assert_eq!(a, d, "Absolute(64, 32) at a 64x32 viewport is the same descriptor:\n{}", p.to_text());
    assert!(b != a && b != c && c != a, "{}", p.to_text());
    assert_eq!(p.slots[c].extent(), Some((32, 16)));
    assert_eq!(p.slots[b].format(), Some(RGBA16));
    assert_slots_never_overlap(&p);
}

#[test]
fn target_read_by_the_final_step_is_not_overwritten() {
    let p = plan(
        r#"Graph(name: "tail", passes: [
            Pass(id: "a", kind: "source"),
            Pass(id: "b", kind: "filter", inputs: {"src": "a.out"}),
            Pass(id: "c", kind: "filter", inputs: {"src": "b.out"}),
        ], outputs: {"image": "c.out", "early": "a.out"})"#,
    );
    // c reads b while writing: they cannot share. a is a graph output: alive to the end.
    assert_ne!(slot_of(&p, "b.out"), slot_of(&p, "c.out"));
    let a = slot_of(&p, "a.out");
    assert_eq!(p.slots[a].holds.len(), 1, "{}", p.to_text());
    assert_eq!(p.resources[p.outputs["early"]].last_use, usize::MAX);
    assert_slots_never_overlap(&p);
}

const SEGMENTS: &str = r#"Graph(name: "segments", passes: [
    Pass(id: "clear", kind: "clear"),
    Repeat(
        id: "segments",
        count: Fixed(4),
        carry: {
            "accum": (init: "clear.color", next: "seg.color"),
            "depth": (init: "clear.depth", next: "seg.depth"),
        },
        body: [
            Pass(id: "seg", kind: "segment", params: {"steps": 16},
                 inputs: {"accum": "segments.accum", "depth": "segments.depth"}),
        ],
    ),
], outputs: {"image": "segments.accum"})"#;

#[test]
fn repeat_group_unrolls_with_ping_pong() {
    let p = plan(SEGMENTS);
    assert_eq!(labels(&p), ["clear", "segments[0]/seg", "segments[1]/seg", "segments[2]/seg", "segments[3]/seg"]);
    assert_eq!(p.steps[2].iteration, Some((1, 4)));
    assert_eq!(p.steps[2].pass_id, "seg");
    assert_eq!(resource_of(&p, "segments[0]/seg", "accum"), "clear.color");
    for i in 1..4 {
        assert_eq!(resource_of(&p, &format!("segments[{i}]/seg"), "accum"), format!("segments[{}]/seg.color", i - 1));
    }
    // After the group, the carried value is the last iteration's.
    assert_eq!(p.resources[p.outputs["image"]].name, "segments[3]/seg.color");
    let color_slots: Vec<usize> =
        p.slots.iter().enumerate().filter(|(_, s)| s.format() == Some(RGBA32)).map(|(i, _)| i).collect();
    assert_eq!(color_slots.len(), 2, "accumulation ping-pongs between two targets:\n{}", p.to_text());
    assert_slots_never_overlap(&p);
}

#[test]
fn modify_port_keeps_one_slot_through_the_iterations() {
    let p = plan(SEGMENTS);
    let depth_slots: Vec<usize> =
        p.slots.iter().enumerate().filter(|(_, s)| s.format() == Some(DEPTH)).map(|(i, _)| i).collect();
    assert_eq!(depth_slots.len(), 1, "{}", p.to_text());
    let holds: Vec<&str> = p.slots[depth_slots[0]].holds.iter().map(|&r| p.resources[r].name.as_str()).collect();
    assert_eq!(
        holds,
        [
            "clear.depth",
            "segments[0]/seg.depth",
            "segments[1]/seg.depth",
            "segments[2]/seg.depth",
            "segments[3]/seg.depth"
        ]
    );
    // Iteration 1 modifies the version iteration 0 wrote.
    match binding(&p, "segments[1]/seg", "depth") {
        Binding::Resource { id, written: Some(w) } => {
            assert_eq!(p.resources[*id].name, "segments[0]/seg.depth");
            assert_eq!(p.resources[*w].name, "segments[1]/seg.depth");
            assert_eq!(p.resources[*w].modifies, Some(*id));
        }
        other => panic!("depth bound to {other:?}"),
    }
    assert_eq!(p.steps[1].params.uint("steps"), 16, "the test plugin's parameter reaches the step");
}

#[test]
fn readers_of_the_old_version_run_before_the_modifier() {
    // The modifier comes first in the document; the reader of the unmodified depth must still
    // run before it, or it would see the modified texture.
    let p = plan(
        r#"Graph(name: "modify", passes: [
            Pass(id: "clear", kind: "clear"),
            Pass(id: "term", kind: "terminate", inputs: {"color": "clear.color", "depth": "clear.depth"}),
            Pass(id: "peek", kind: "depth_peek", inputs: {"depth": "clear.depth"}),
            Pass(id: "after", kind: "depth_peek", inputs: {"depth": "term.depth"}),
            Pass(id: "mix", kind: "blend", inputs: {"a": "peek.out", "b": "after.out"}),
        ], outputs: {"image": "mix.out"})"#,
    );
    let order = labels(&p);
    let pos = |l: &str| order.iter().position(|x| *x == l).unwrap_or_else(|| panic!("{l} not scheduled"));
    assert!(pos("peek") < pos("term"), "{order:?}");
    assert!(pos("term") < pos("after"), "{order:?}");
    assert_eq!(resource_of(&p, "peek", "depth"), "clear.depth");
    assert_eq!(resource_of(&p, "after", "depth"), "term.depth");
    assert_eq!(slot_of(&p, "clear.depth"), slot_of(&p, "term.depth"));
}

#[test]
fn history_source_is_persistent_and_never_pooled() {
    let p = plan(
        r#"Graph(name: "history",
            history: {"prev": (of: "march.out", initial: Clear(0.0, 0.0, 0.0, 1.0))},
            passes: [
                Pass(id: "splat", kind: "filter", inputs: {"src": "history.prev"}),
                Pass(id: "march", kind: "filter", inputs: {"src": "splat.out"}),
                Pass(id: "post", kind: "filter", inputs: {"src": "march.out"}),
                Pass(id: "post2", kind: "filter", inputs: {"src": "post.out"}),
                Pass(id: "post3", kind: "filter", inputs: {"src": "post2.out"}),
            ],
            outputs: {"image": "post3.out"})"#,
    );
    assert_eq!(binding(&p, "splat", "src"), &Binding::History("prev".to_string()));
    let s = slot_of(&p, "march.out");
    assert!(p.slots[s].persistent);
    assert_eq!(p.slots[s].holds.len(), 1, "the history source shares its texture with nobody:\n{}", p.to_text());
    assert_eq!(p.resources[p.history["prev"].source].name, "march.out");
    let m = p.memory();
    assert_eq!(m.history_bytes, 2 * 64 * 32 * 16, "current and previous frame");
    assert!(p.to_text().contains("history prev: previous frame of march.out\n"));
    assert_slots_never_overlap(&p);
}

const GATED: &str = r#"Graph(name: "gated", passes: [
    Pass(id: "march", kind: "source"),
    Pass(id: "aa", kind: "antialias", inputs: {"src": "march.out"}, otherwise: {"out": "march.out"}),
    Pass(id: "shade", kind: "filter", when: ["shading"], inputs: {"src": "aa.out"}, otherwise: {"out": "aa.out"}),
    Pass(id: "present", kind: "filter", inputs: {"src": "shade.out"}),
], outputs: {"image": "present.out"})"#;

#[test]
fn gated_passes_run_only_with_all_their_features() {
    let off = plan(GATED);
    assert_eq!(labels(&off), ["march", "present"]);
    assert_eq!(
        off.gated,
        [("aa".to_string(), vec!["antialias".to_string()]), ("shade".to_string(), vec!["shading".to_string()])]
    );
    // Both stand-ins chain: present reads march's output directly.
    assert_eq!(resource_of(&off, "present", "src"), "march.out");
    assert!(off.to_text().contains("off by features: aa (needs antialias), shade (needs shading)\n"));

    let aa_only = plan_with(GATED, &CompileOptions::new(64, 32).with_features(["antialias"]));
    assert_eq!(labels(&aa_only), ["march", "aa", "present"]);
    assert_eq!(resource_of(&aa_only, "present", "src"), "aa.out");

    let all = plan_with(GATED, &CompileOptions::new(64, 32).with_features(["antialias", "shading"]));
    assert_eq!(labels(&all), ["march", "aa", "shade", "present"]);
    assert!(all.gated.is_empty());
    assert_eq!(resource_of(&all, "present", "src"), "shade.out");
}

#[test]
fn when_and_plugin_features_combine() {
    let src = r#"Graph(name: "both", passes: [
        Pass(id: "march", kind: "source"),
        Pass(id: "aa", kind: "antialias", when: ["hq"], inputs: {"src": "march.out"}, otherwise: {"out": "march.out"}),
    ], outputs: {"image": "aa.out"})"#;
    let hq_only = plan_with(src, &CompileOptions::new(64, 32).with_features(["hq"]));
    assert_eq!(labels(&hq_only), ["march"]);
    assert_eq!(hq_only.gated, [("aa".to_string(), vec!["antialias".to_string()])]);
    let both = plan_with(src, &CompileOptions::new(64, 32).with_features(["hq", "antialias"]));
    assert_eq!(labels(&both), ["march", "aa"]);
}

const SCENE_COUNT: &str = r#"Graph(name: "scene",
    inputs: {"longest_ray": Scalar(20.0)},
    passes: [
        Pass(id: "clear", kind: "clear"),
        Repeat(
            id: "segments",
            count: Scene(name: "longest_ray", divide_by: 8.0, max: 64),
            carry: {
                "accum": (init: "clear.color", next: "seg.color"),
                "depth": (init: "clear.depth", next: "seg.depth"),
            },
            body: [Pass(id: "seg", kind: "segment", inputs: {"accum": "segments.accum", "depth": "segments.depth"})],
        ),
    ],
    outputs: {"image": "segments.accum"})"#;

#[test]
fn scene_derived_repeat_count() {
    let iterations = |p: &Plan| p.steps.iter().filter(|s| s.pass_id == "seg").count();
    // The Scalar input's default: ceil(20 / 8) = 3.
    assert_eq!(iterations(&plan(SCENE_COUNT)), 3);
    // A scene value overrides it: ceil(100 / 8) = 13.
    let scene = CompileOptions::new(64, 32).with_scalar("longest_ray", 100.0);
    let p = plan_with(SCENE_COUNT, &scene);
    assert_eq!(iterations(&p), 13);
    assert_eq!(p.steps.last().map(|s| s.label.as_str()), Some("segments[12]/seg"));
    // Clamped to max, and to at least one iteration.
    assert_eq!(iterations(&plan_with(SCENE_COUNT, &CompileOptions::new(64, 32).with_scalar("longest_ray", 1e6))), 64);
    assert_eq!(iterations(&plan_with(SCENE_COUNT, &CompileOptions::new(64, 32).with_scalar("longest_ray", 0.0))), 1);
}

/// Regression: a repeat body written `Pass(...)` was rejected ("Expected struct `PassDoc` but
/// found `Pass`") because the body's struct kept its Rust name.
#[test]
fn repeat_body_accepts_pass_named_and_unnamed() {
    let named = plan(SEGMENTS);
    let unnamed = plan(&SEGMENTS.replace("Pass(id: \"seg\"", "(id: \"seg\""));
    assert_eq!(labels(&named), labels(&unnamed));
}

#[test]
fn modify_port_access_is_reported_in_the_plan() {
    let p = plan(SEGMENTS);
    let step = &p.steps[1];
    let depth = step.ports.iter().find(|b| b.port == "depth").expect("segment declares depth");
    assert_eq!(depth.access, Access::Modify);
    assert!(p.to_text().contains("modify depth      clear.depth @slot"), "{}", p.to_text());
}

/// Every iteration modifying the same (uncarried) value is an error whose help shows the carry.
#[test]
fn modifying_an_uncarried_value_in_every_iteration_explains_the_carry() {
    let src = SEGMENTS.replace(r#""depth": "segments.depth""#, r#""depth": "clear.depth""#);
    let err =
        compile("test.ron", &src, &registry(), &CompileOptions::new(64, 32)).expect_err("two modifiers of one value");
    assert_eq!(
        err.to_string(),
        "test.ron: pass \"seg\", field inputs: passes \"segments[0]/seg\" and \"segments[1]/seg\" both modify \"clear.depth\"\n  \
         help: every iteration of repeat group \"segments\" modifies it; carry it instead: carry: {\"depth\": (init: \"clear.depth\", \
         next: \"seg.depth\")} and read \"segments.depth\""
    );
}
