//! Property test: compiling mutated graph files never panics, and every failure is located.
//!
//! Seeds are the repository's valid graphs (`graphs/basic/*.ron`) and a Krüger–Westermann
//! multipass graph with a repeat group, history and gating. Mutations: truncation at a random
//! byte offset, random byte flips and insertions (including multibyte UTF-8 and bytes that make
//! the text invalid UTF-8, read lossily as an editor would show it), swapped, duplicated and
//! deleted tokens, and renamed ids. Each failure's position must be `file:line:col` inside the
//! file, or name the pass and field. The case counts keep the run to about a second in CI;
//! `VOLGRAPH_FUZZ_CASES=100000` hunts longer.

mod support;

use std::path::Path;

use proptest::prelude::*;
use volgraph_compiler::{CompileOptions, Location, compile};

const FILE: &str = "fuzz.ron";

const MULTIPASS: &str = r#"// Krüger–Westermann multipass with history and an optional pass.
Graph(
    name: "kw_multipass",
    inputs: {"volume": Volume, "tf": TransferFunction, "longest_ray": Scalar(200.0)},
    history: {"prev": (of: "present.display", initial: Clear(0.0, 0.0, 0.0, 1.0))},
    passes: [
        Pass(id: "entry", kind: "entry_points"),
        Pass(id: "dirs", kind: "ray_directions", inputs: {"entry": "entry.entry"}),
        Pass(id: "clear", kind: "clear_targets"),
        Repeat(
            id: "segments",
            count: Scene(name: "longest_ray", divide_by: 8.0, max: 64),
            carry: {
                "accum": (init: "clear.color", next: "seg.color"),
                "depth": (init: "clear.depth", next: "term.depth"),
            },
            body: [
                Pass(id: "seg", kind: "raycast_segment", params: {"steps": 8},
                     inputs: {"entry": "entry.entry", "dir": "dirs.dir", "volume": "input.volume",
                              "tf": "input.tf", "accum": "segments.accum", "depth": "segments.depth"}),
                Pass(id: "term", kind: "termination_test", params: {"alpha": 0.95},
                     inputs: {"color": "seg.color", "depth": "seg.depth"}),
            ],
        ),
        Pass(id: "present", kind: "present", inputs: {"color": "segments.accum"}),
    ],
    outputs: {"image": "segments.accum", "display": "present.display"},
)
"#;

fn seeds() -> Vec<String> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../graphs/basic");
    let mut seeds: Vec<String> = std::fs::read_dir(&dir)
        .expect("graphs/basic exists")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .filter_map(|p| std::fs::read_to_string(p).ok())
        .collect();
    seeds.sort();
    seeds.push(MULTIPASS.to_string());
    seeds
}

/// Compiles `text` and checks the contract; `Err` describes a violation.
fn check(text: &str) -> Result<(), String> {
    let registry = support::registry();
    let options = CompileOptions::new(320, 200).with_scalar("longest_ray", 40.0);
    let Err(d) = compile(FILE, text, &registry, &options) else {
        return Ok(());
    };
    if d.items.is_empty() {
        return Err("compile failed with no diagnostics".to_string());
    }
    let lines = text.split('\n').count();
    for item in &d.items {
        let position = d.position(item);
        match &item.location {
            Location::Span(span) => {
                if span.start > text.len() || span.end < span.start {
                    return Err(format!("span {span:?} outside a {}-byte file: {}", text.len(), item.message));
                }
                let rest = position.strip_prefix("fuzz.ron:").unwrap_or_default();
                let nums: Vec<usize> = rest.split(':').filter_map(|n| n.parse().ok()).collect();
                if nums.len() != 2 || nums[0] == 0 || nums[0] > lines || nums[1] == 0 {
                    return Err(format!("bad position {position:?} for {:?}", item.message));
                }
            }
            Location::Field { pass, field } => {
                if pass.is_empty() || field.is_empty() {
                    return Err(format!("empty pass or field in {position:?}: {}", item.message));
                }
            }
            Location::File => return Err(format!("unlocated diagnostic: {}", item.message)),
        }
        if item.message.is_empty() {
            return Err(format!("empty message at {position}"));
        }
    }
    let shown = d.to_string();
    let first = d.position(&d.items[0]);
    if !shown.starts_with(&format!("{first}: ")) {
        return Err(format!("Display does not start with the position: {shown}"));
    }
    Ok(())
}

/// Rough RON tokens: strings, punctuation, runs of other non-space characters, whitespace.
fn tokens(text: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(c) = rest.chars().next() {
        let len = if c == '"' {
            rest[1..].find('"').map_or(rest.len(), |i| i + 2)
        } else if "()[]{},:".contains(c) {
            1
        } else if c.is_whitespace() {
            rest.find(|x: char| !x.is_whitespace()).unwrap_or(rest.len())
        } else {
            rest.find(|x: char| x.is_whitespace() || "()[]{},:\"".contains(x)).unwrap_or(rest.len())
        };
        out.push(&rest[..len]);
        rest = &rest[len..];
    }
    out
}

/// Inserted text: multibyte characters, RON punctuation and words the format uses.
const SNIPPETS: [&str; 12] = ["é", "→", "🦀", "\u{0}", "\"", "(", "]", "}", ":", ",", "Repeat(", "..."];

#[derive(Clone, Debug)]
enum Mutation {
    Truncate(usize),
    FlipByte(usize, u8),
    Insert(usize, usize),
    SwapTokens(usize, usize),
    DuplicateToken(usize),
    DeleteToken(usize),
    RenameId(usize, String),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        any::<usize>().prop_map(Mutation::Truncate),
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Mutation::FlipByte(i, b)),
        (any::<usize>(), 0..SNIPPETS.len()).prop_map(|(i, s)| Mutation::Insert(i, s)),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Mutation::SwapTokens(a, b)),
        any::<usize>().prop_map(Mutation::DuplicateToken),
        any::<usize>().prop_map(Mutation::DeleteToken),
        (any::<usize>(), "[a-z_é.]{0,6}").prop_map(|(i, s)| Mutation::RenameId(i, s)),
    ]
}

fn apply(text: &str, m: &Mutation) -> String {
    let bytes = text.as_bytes();
    let at = |i: usize| {
        if bytes.is_empty() { 0 } else { i % (bytes.len() + 1) }
    };
    match m {
        Mutation::Truncate(i) => String::from_utf8_lossy(&bytes[..at(*i)]).into_owned(),
        Mutation::FlipByte(i, b) => {
            let mut v = bytes.to_vec();
            if !v.is_empty() {
                let i = i % v.len();
                v[i] = *b;
            }
            String::from_utf8_lossy(&v).into_owned()
        }
        Mutation::Insert(i, s) => {
            let mut v = bytes.to_vec();
            let i = at(*i);
            v.splice(i..i, SNIPPETS[*s].bytes());
            String::from_utf8_lossy(&v).into_owned()
        }
        Mutation::SwapTokens(a, b) => {
            let mut t = tokens(text);
            if !t.is_empty() {
                let n = t.len();
                t.swap(a % n, b % n);
            }
            t.concat()
        }
        Mutation::DuplicateToken(i) => {
            let mut t = tokens(text);
            if !t.is_empty() {
                let i = i % t.len();
                t.insert(i, t[i]);
            }
            t.concat()
        }
        Mutation::DeleteToken(i) => {
            let mut t = tokens(text);
            if !t.is_empty() {
                let i = i % t.len();
                t.remove(i);
            }
            t.concat()
        }
        Mutation::RenameId(i, new) => {
            // Replace one quoted string (an id, a reference, a port name) by another word.
            let t = tokens(text);
            let strings: Vec<usize> = (0..t.len()).filter(|&k| t[k].starts_with('"')).collect();
            if strings.is_empty() {
                return text.to_string();
            }
            let k = strings[i % strings.len()];
            let quoted = format!("\"{new}\"");
            let mut out: Vec<&str> = t.clone();
            out[k] = &quoted;
            out.concat()
        }
    }
}

fn fuzz_cases() -> u32 {
    std::env::var("VOLGRAPH_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(1024)
}

#[test]
fn seeds_compile() {
    for seed in seeds() {
        let registry = support::registry();
        let options = CompileOptions::new(320, 200);
        if let Err(d) = compile(FILE, &seed, &registry, &options) {
            panic!("seed does not compile:\n{d}\n{seed}");
        }
    }
}

#[test]
fn tokens_round_trip() {
    for seed in seeds() {
        assert_eq!(tokens(&seed).concat(), seed);
    }
}

proptest! {
    // 1,024 cases each run in well under a second; VOLGRAPH_FUZZ_CASES raises it for a long hunt.
    #![proptest_config(ProptestConfig { cases: fuzz_cases(), failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn one_mutation_never_panics_and_is_located(seed in 0usize..16, m in mutation()) {
        let seeds = seeds();
        let text = apply(&seeds[seed % seeds.len()], &m);
        prop_assert_eq!(check(&text), Ok(()), "mutation {:?} gave:\n{}", m, text);
    }

    #[test]
    fn several_mutations_never_panic_and_are_located(seed in 0usize..16, ms in prop::collection::vec(mutation(), 2..6)) {
        let seeds = seeds();
        let mut text = seeds[seed % seeds.len()].clone();
        for m in &ms {
            text = apply(&text, m);
        }
        prop_assert_eq!(check(&text), Ok(()), "mutations {:?} gave:\n{}", ms, text);
    }
}

/// The property is not vacuous: a mutation that breaks the file fails with a located error.
#[test]
fn broken_files_fail_with_a_location() {
    for m in [Mutation::Truncate(MULTIPASS.len() / 2), Mutation::Insert(MULTIPASS.find("passes").unwrap_or(0), 2)] {
        let text = apply(MULTIPASS, &m);
        let err = compile(FILE, &text, &support::registry(), &CompileOptions::new(320, 200)).expect_err("broken file");
        assert!(err.to_string().starts_with("fuzz.ron:"), "{err}");
        assert_eq!(check(&text), Ok(()));
    }
}
