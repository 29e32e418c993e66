//! The input fuzzer of issue 19: mutated graph files — the shipped graphs and one declaring a
//! WGSL-only kind, whose shader is checked at plan time — and mutated scene files, each read
//! exactly as `volgraph plan` and `volgraph render --scene` read them. The property: no panic,
//! no hang (each case well under `HANG_SECONDS`), and the right outcome — a plan, or an error
//! with a non-empty message that names the file (graph diagnostics with a line and column or
//! the pass and field).
//!
//! `VOLGRAPH_FUZZ_CASES` sets the number of cases (default 512 in CI; the issue's long run was
//! 1,000,000); the summary line gives the counts a long run is recorded with.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use proptest::prelude::*;
use volgraph_core::shader_source::ShaderSources;

use crate::fuzz_runner::token_at;
use volgraph_core::{CompileOptions, Registry, check_plan_bindings, compile};

const HANG_SECONDS: f64 = 5.0;

fn cases() -> u32 {
    std::env::var("VOLGRAPH_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(512)
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A graph of WGSL-only kinds (params blocks, workgroups, inputs and outputs) and `present`:
/// small shaders, so checking every accepted case's bindings with naga stays cheap.
const WGSL_GRAPH: &str = r#"Graph(
    name: "tint",
    inputs: {"volume": Volume, "gain": Scalar(1.0)},
    kinds: {
        "slice": WgslKind(
            shader: "slice.wgsl",
            summary: "the volume's middle slice",
            inputs: {"volume": Volume},
            outputs: {"color": Rgba16Float},
            params: [(name: "z", default: 0.5, min: 0.0, max: 1.0)],
        ),
        "tint": WgslKind(
            shader: "tint.wgsl",
            summary: "scales the colour",
            inputs: {"color": Target},
            outputs: {"out": Rgba16Float},
            workgroup: (8, 8),
            params: [(name: "gain", default: 1.0, min: 0.0, max: 4.0), (name: "bias", default: 0.0, min: -1.0, max: 1.0)],
        ),
    },
    passes: [
        Pass(id: "s", kind: "slice", inputs: {"volume": "input.volume"}),
        Pass(id: "t", kind: "tint", params: {"gain": "input.gain"}, inputs: {"color": "s.color"}),
        Pass(id: "present", kind: "present", inputs: {"color": "t.out"}),
    ],
    outputs: {"image": "t.out", "display": "present.display"},
)
"#;

const TINT_WGSL: &str = "struct Params { gain: f32, bias: f32 }\n\
@group(0) @binding(auto) var<uniform> params: Params;\n\
@group(0) @binding(auto) var color: texture_2d<f32>;\n\
@group(0) @binding(auto) var out: texture_storage_2d<rgba16float, write>;\n\
@compute @workgroup_size(8, 8)\n\
fn cs_main(@builtin(global_invocation_id) id: vec3<u32>) {\n\
    let c = textureLoad(color, vec2<i32>(id.xy), 0);\n\
    textureStore(out, vec2<i32>(id.xy), c * params.gain + vec4<f32>(params.bias));\n\
}\n";

const SLICE_WGSL: &str = "struct Params { z: f32 }\n\
@group(0) @binding(auto) var<uniform> params: Params;\n\
@group(0) @binding(auto) var volume: texture_3d<f32>;\n\
@group(0) @binding(auto) var color: texture_storage_2d<rgba16float, write>;\n\
@compute @workgroup_size(8, 8)\n\
fn cs_main(@builtin(global_invocation_id) id: vec3<u32>) {\n\
    let n = textureDimensions(volume);\n\
    let p = vec3<u32>(min(id.xy, n.xy - 1u), u32(params.z * f32(n.z - 1u)));\n\
    textureStore(color, vec2<i32>(id.xy), vec4<f32>(textureLoad(volume, p, 0).r));\n\
}\n";

/// What a case reads: a graph or a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Graph,
    Scene,
}

struct Seeds {
    texts: Vec<(Kind, String)>,
    /// The folder holding the scene and graph seeds' neighbours (a `shaders/` with `tint.wgsl`).
    dir: PathBuf,
    registry: Registry,
    sources: ShaderSources,
}

fn seeds() -> &'static Seeds {
    static SEEDS: OnceLock<Seeds> = OnceLock::new();
    SEEDS.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("volgraph-input-fuzz-{}", std::process::id()));
        let _ = std::fs::create_dir_all(dir.join("shaders"));
        let _ = std::fs::write(dir.join("shaders/tint.wgsl"), TINT_WGSL);
        let _ = std::fs::write(dir.join("shaders/slice.wgsl"), SLICE_WGSL);
        let mut texts = vec![(Kind::Graph, WGSL_GRAPH.to_string())];
        for sub in ["graphs/basic", "graphs/klein_2005", "graphs/kruger_westermann_2003", "scenes"] {
            let Ok(entries) = std::fs::read_dir(root().join(sub)) else { continue };
            let mut files: Vec<PathBuf> = entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == "ron"))
                .collect();
            files.sort();
            let kind = if sub == "scenes" { Kind::Scene } else { Kind::Graph };
            texts.extend(files.iter().filter_map(|p| std::fs::read_to_string(p).ok()).map(|t| (kind, t)));
        }
        let sources = volgraph_passes::builtin_shaders().prepend_disk(dir.join("shaders"));
        Seeds { texts, dir, registry: volgraph_passes::builtin_registry(), sources }
    })
}

/// Tokens chosen to break the format and the checks behind it.
const HOSTILE: &[&str] = &[
    "",
    "\"",
    "(",
    ")",
    "[",
    "]",
    "{",
    "}",
    ",",
    ":",
    "0",
    "-1",
    "1e39",
    "-1e309",
    "NaN",
    "inf",
    "4294967296",
    "18446744073709551615",
    "(65536, 65536)",
    "(0, 8)",
    "(7, 7)",
    "\"../../etc/passwd\"",
    "\"/etc/passwd\"",
    "\"a.txt\"",
    "\"tint.wgsl\"",
    "\"\u{1b}]0;x\u{7}\"",
    "\"\u{202e}\"",
    "\u{feff}",
    "when: [\"shadng\"]",
    "when: [\"shading\"]",
    "Fixed(1000000)",
    "Fixed(0)",
    "Scene(name: \"longest_ray_voxels\", divide_by: -1.0)",
    "Path(keyframes: [(frame: 4294967295, azimuth: 0, elevation: 0, distance: 3)])",
    "Orbit(azimuth: 0, elevation: 1e300, distance: 1e-300)",
    "Data(\"../x\")",
    "File(\"\")",
    "Generated(\"ml100000\")",
    "Generated(\"ml8\")",
    "\"feature.shading\"",
    "\"input.gain\"",
    "Fragment",
    "Compute",
    "Target",
    "Volume",
    "Rgba32Float",
    "Depth32Float",
    "Clear(0.0, 0.0, 0.0, 0.0)",
    "\u{0}",
    "é",
    "日本",
];

/// One edit of a seed text.
#[derive(Clone, Debug)]
enum Edit {
    /// Cut the text at a fraction of its length.
    Truncate(f64),
    /// Replace the byte at a fraction of the length with `b`.
    Flip(f64, u8),
    /// Insert a hostile token at a fraction of the length.
    Insert(f64, usize),
    /// Replace the token (a run of identifier characters or a quoted string) at a fraction of
    /// the length with a hostile token.
    Replace(f64, usize),
    /// Copy the token at one fraction over the token at another.
    Swap(f64, f64),
}

fn edit() -> impl Strategy<Value = Edit> {
    let at = 0.0..1.0f64;
    let token = 0..HOSTILE.len();
    prop_oneof![
        1 => at.clone().prop_map(Edit::Truncate),
        2 => (at.clone(), any::<u8>()).prop_map(|(a, b)| Edit::Flip(a, b)),
        3 => (at.clone(), token.clone()).prop_map(|(a, t)| Edit::Insert(a, t)),
        4 => (at.clone(), token).prop_map(|(a, t)| Edit::Replace(a, t)),
        2 => (at.clone(), at).prop_map(|(a, b)| Edit::Swap(a, b)),
    ]
}

fn apply(text: &str, edits: &[Edit]) -> String {
    let mut bytes = text.as_bytes().to_vec();
    let pos = |f: f64, len: usize| ((f * len as f64) as usize).min(len);
    for e in edits {
        let len = bytes.len();
        match e {
            Edit::Truncate(f) => bytes.truncate(pos(*f, len)),
            Edit::Flip(f, b) if len > 0 => bytes[pos(*f, len - 1)] = *b,
            Edit::Flip(..) => {}
            Edit::Insert(f, t) => {
                let at = pos(*f, len);
                bytes.splice(at..at, HOSTILE[*t].bytes());
            }
            Edit::Replace(f, t) => {
                let (s, e) = token_at(&bytes, pos(*f, len));
                bytes.splice(s..e, HOSTILE[*t].bytes());
            }
            Edit::Swap(a, b) => {
                let (s1, e1) = token_at(&bytes, pos(*a, len));
                let (s2, e2) = token_at(&bytes, pos(*b, len));
                let source = bytes[s2..e2].to_vec();
                bytes.splice(s1..e1, source);
            }
        }
    }
    // What an editor would show for bytes that are not UTF-8.
    String::from_utf8_lossy(&bytes).into_owned()
}

/// What one case gave.
#[derive(Debug, PartialEq, Eq, PartialOrd, Ord, Clone, Copy)]
enum Outcome {
    /// A graph that plans (bindings checked) or a scene that reads.
    Accepted,
    /// A located error.
    Rejected,
}

fn run_case(kind: Kind, text: &str) -> Result<Outcome, String> {
    let seeds = seeds();
    match kind {
        Kind::Graph => {
            let name = seeds.dir.join("fuzz.ron").display().to_string();
            let options = CompileOptions::new(64, 64).with_features(["shading"]);
            match compile(&name, text, &seeds.registry, &options) {
                // The built-in kinds' shaders do not change with the graph text and are checked
                // by the golden and declared-pipeline tests; a graph of the graph's own kinds
                // has its (small) shaders checked here, as `volgraph plan` does.
                Ok(plan) if !plan.kinds.is_empty() => {
                    let problems = check_plan_bindings(&plan, &seeds.registry, &seeds.sources);
                    if problems.iter().any(|d| d.message.trim().is_empty()) {
                        return Err("a binding problem with an empty message".into());
                    }
                    Ok(if problems.is_empty() { Outcome::Accepted } else { Outcome::Rejected })
                }
                Ok(_) => Ok(Outcome::Accepted),
                Err(d) if !d.items.is_empty() && d.to_string().starts_with(&d.file) => {
                    if d.items.iter().any(|i| i.message.trim().is_empty()) {
                        return Err(format!("a diagnostic with an empty message: {d}"));
                    }
                    Ok(Outcome::Rejected)
                }
                Err(d) => Err(format!("graph diagnostics without a location: {d}")),
            }
        }
        Kind::Scene => {
            let path = seeds.dir.join("fuzz_scene.ron");
            match crate::scene::Scene::from_str(text, &path) {
                Ok(scene) => {
                    // What render does next with a scene: its frame count and cameras.
                    let frames = scene.frame_count();
                    if !(1..=crate::scene::MAX_FRAMES).contains(&frames) {
                        return Err(format!("a scene of {frames} frames was accepted"));
                    }
                    if let Some(camera) = &scene.camera {
                        for f in [0, frames / 2, frames - 1] {
                            let c = camera.at(f);
                            let ok = c.azimuth_deg.is_finite()
                                && c.elevation_deg.abs() <= 90.0
                                && c.distance.is_finite()
                                && c.distance > 0.0;
                            if !ok {
                                return Err(format!("frame {f} has camera {c:?}"));
                            }
                        }
                    }
                    Ok(Outcome::Accepted)
                }
                Err(e) if e.to_string().starts_with(&path.display().to_string()) => Ok(Outcome::Rejected),
                Err(e) => Err(format!("a scene error that does not name the file: {e}")),
            }
        }
    }
}

#[test]
fn mutated_graphs_with_wgsl_kinds_and_scenes_never_panic_hang_or_fail_unlocated() {
    let count = seeds().texts.len();
    assert!(count >= 8, "the seeds: the WGSL-kind graph, shipped graphs and scenes ({count})");
    let strategy = (0..count, proptest::collection::vec(edit(), 0..4));
    let mutated = |(seed, edits): &(usize, Vec<Edit>)| {
        let (kind, text) = &seeds().texts[*seed];
        (*kind, apply(text, edits))
    };
    let run = crate::fuzz_runner::fuzz(
        &strategy,
        cases(),
        HANG_SECONDS,
        |v| {
            let (kind, text) = mutated(v);
            format!("{kind:?}:\n{text}")
        },
        |v| {
            let (kind, text) = mutated(v);
            run_case(kind, &text).map(|o| (format!("{kind:?}"), o))
        },
    );
    if let Some(failure) = run.failure {
        panic!("{failure}");
    }
    let (total, counts) = (run.total(), &run.counts);
    eprintln!(
        "input fuzz: {total} graph and scene files, 0 panics, 0 hangs (slowest {:.1} ms), 0 unlocated or wrong \
         outcomes; outcomes {counts:?}",
        run.slowest.as_secs_f64() * 1e3
    );
    // Not vacuous: graphs and scenes are both accepted and rejected.
    if total >= 256 {
        for kind in ["Graph", "Scene"] {
            for outcome in [Outcome::Accepted, Outcome::Rejected] {
                assert!(counts.contains_key(&(kind.to_string(), outcome)), "no {kind} {outcome:?}: {counts:?}");
            }
        }
    }
}

#[test]
fn the_wgsl_seed_plans_and_its_tokens_edit_as_intended() {
    assert_eq!(run_case(Kind::Graph, WGSL_GRAPH), Ok(Outcome::Accepted));
    let text = "a \"quoted\" word_1.x";
    assert_eq!(token_at(text.as_bytes(), 2), (2, 10));
    assert_eq!(token_at(text.as_bytes(), 4), (3, 9));
    assert_eq!(token_at(text.as_bytes(), 13), (11, 19));
    assert_eq!(apply("abc def", &[Edit::Replace(0.9, 1)]), "abc \"");
}
