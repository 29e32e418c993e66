//! The fuzzer's inputs: hostile tokens and names, the mutations of a graph file's text, and
//! the assignment `set` is given (a declared parameter or input, a new one, a name the graph
//! lacks; values valid, out of range and hostile).

use std::sync::OnceLock;

use proptest::prelude::*;
use volgraph_core::graph::ast::{InputKind, NodeDoc};
use volgraph_core::graph::parse_graph;

use crate::fuzz_runner::token_at;

/// Tokens and values chosen to break the file or the value written.
pub(super) const HOSTILE: &[&str] = &[
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
    "0.25",
    "1e39",
    "NaN",
    "inf",
    "true",
    "4294967296",
    "\"feature.shading\"",
    "\"input.threshold\"",
    "\"dvr\"",
    "\"iso\"",
    "Scalar(0.5)",
    "// c",
    "/* c */",
    "/*",
    "\u{1b}]0;x\u{7}",
    "\u{feff}",
    "\r",
    "\n",
    "\r\n",
    "é",
    "Some(1)",
    "r#\"x\"#",
    "'a'",
    "[1, 2]",
    "{\"a\": 1}",
    "0.5 // c",
    "#![enable(implicit_some)]",
];

/// Names a graph may or may not use.
pub(super) const NAMES: &[&str] = &[
    "step_voxels",
    "max_steps",
    "threshold",
    "background",
    "iso_value",
    "mode",
    "shading",
    "jitter",
    "nope",
    "",
    "volume",
    "tf",
    "a.b",
    "\u{1b}[2J",
    "é",
];

/// One edit of a seed text.
#[derive(Clone, Debug)]
pub(super) enum Mutation {
    /// Insert a hostile token at a fraction of the length.
    Insert(f64, usize),
    /// Replace the token (identifier run or quoted string) at a fraction of the length.
    Replace(f64, usize),
    /// Copy the line at a fraction (a `"key": value,` line, say) after itself, its value
    /// replaced by a hostile token when `Some`.
    DuplicateLine(f64, Option<usize>),
    /// Every LF becomes CRLF.
    Crlf,
    /// A UTF-8 byte-order mark first.
    Bom,
    /// `#![enable(implicit_some)]` first.
    EnableHeader,
    /// A comment at the start of the line at a fraction.
    Comment(f64, bool),
    /// Cut the text at a fraction.
    Truncate(f64),
}

pub(super) fn mutation() -> impl Strategy<Value = Mutation> {
    let at = 0.0..1.0f64;
    let token = 0..HOSTILE.len();
    prop_oneof![
        1 => (at.clone(), token.clone()).prop_map(|(a, t)| Mutation::Insert(a, t)),
        2 => (at.clone(), token.clone()).prop_map(|(a, t)| Mutation::Replace(a, t)),
        4 => (at.clone(), proptest::option::weighted(0.3, token)).prop_map(|(a, t)| Mutation::DuplicateLine(a, t)),
        3 => Just(Mutation::Crlf),
        3 => Just(Mutation::Bom),
        3 => Just(Mutation::EnableHeader),
        3 => (at.clone(), any::<bool>()).prop_map(|(a, b)| Mutation::Comment(a, b)),
        1 => at.prop_map(Mutation::Truncate),
    ]
}

pub(super) fn mutate(text: &str, mutations: &[Mutation]) -> Vec<u8> {
    let mut bytes = text.as_bytes().to_vec();
    let pos = |f: f64, len: usize| ((f * len as f64) as usize).min(len);
    let line_start = |bytes: &[u8], at: usize| bytes[..at].iter().rposition(|b| *b == b'\n').map_or(0, |i| i + 1);
    for m in mutations {
        let len = bytes.len();
        match m {
            Mutation::Insert(f, t) => {
                let at = pos(*f, len);
                bytes.splice(at..at, HOSTILE[*t].bytes());
            }
            Mutation::Replace(f, t) => {
                let (s, e) = token_at(&bytes, pos(*f, len));
                bytes.splice(s..e, HOSTILE[*t].bytes());
            }
            Mutation::DuplicateLine(f, t) => {
                let start = line_start(&bytes, pos(*f, len));
                let end = bytes[start..].iter().position(|b| *b == b'\n').map_or(len, |i| start + i + 1);
                let mut line = bytes[start..end].to_vec();
                if let Some(t) = t
                    && let Some(colon) = line.iter().position(|b| *b == b':')
                {
                    let (s, e) = token_at(&line, colon + 2);
                    if s > colon {
                        line.splice(s..e, HOSTILE[*t].bytes());
                    }
                }
                bytes.splice(end..end, line);
            }
            Mutation::Crlf => {
                bytes = String::from_utf8_lossy(&bytes).replace("\r\n", "\n").replace('\n', "\r\n").into_bytes();
            }
            Mutation::Bom => bytes.splice(0..0, "\u{feff}".bytes()).for_each(drop),
            Mutation::EnableHeader => bytes.splice(0..0, "#![enable(implicit_some)]\n".bytes()).for_each(drop),
            Mutation::Comment(f, block) => {
                let at = line_start(&bytes, pos(*f, len));
                let c: &[u8] = if *block { b"/* set */ " } else { b"// set\n" };
                bytes.splice(at..at, c.iter().copied());
            }
            Mutation::Truncate(f) => bytes.truncate(pos(*f, len)),
        }
    }
    bytes
}

/// Which assignment a case makes.
#[derive(Clone, Debug)]
pub(super) enum Pick {
    /// The `i`-th (modulo) value the graph writes: a pass parameter or a Scalar input.
    Existing(usize),
    /// Parameter `NAMES[n]` of the `i`-th (modulo) pass.
    OfPass(usize, usize),
    /// Input `NAMES[n]`.
    Input(usize),
    /// Raw `PASS.PARAM` text made of two names.
    Raw(usize, usize),
    /// The `j`-th (modulo) parameter the `i`-th pass's kind declares, set to its default, its
    /// minimum or its maximum (`j % 3`): mostly parameters the file does not write yet.
    Declared(usize, usize),
}

/// Values to set: the first `VALID` are values most parameters take.
pub(super) const VALUES: &[&str] = &[
    "0.25",
    "0.5",
    "0.75",
    "1",
    "0.01",
    "16",
    "true",
    "false",
    "\"iso\"",
    "0",
    "-1",
    "1e39",
    "NaN",
    "inf",
    "true",
    "false",
    "4096",
    "1048577",
    "0.01",
    "16",
    "\"dvr\"",
    "\"iso\"",
    "\"feature.shading\"",
    "\"input.threshold\"",
    "\"x\"",
    "\"a // b\"",
    "\"a\\nb\"",
    " 0.75 ",
    "0.25 // c",
    "/* c */ 1",
    "[1, 2]",
    "(",
    "",
    "\u{1b}",
    "1\n",
    "\r\n0.5",
    "0.5,",
    "0.5}",
    "Some(1)",
    "0.5 0.25",
    "'a'",
    "r#\"x\"#",
    "1_000",
    "0x10",
    "Scalar(1)",
];

pub(super) const VALID: usize = 9;

pub(super) fn pick() -> impl Strategy<Value = Pick> {
    prop_oneof![
        6 => any::<usize>().prop_map(Pick::Existing),
        3 => (any::<usize>(), 0..NAMES.len()).prop_map(|(i, n)| Pick::OfPass(i, n)),
        1 => (0..NAMES.len()).prop_map(Pick::Input),
        1 => (0..NAMES.len(), 0..NAMES.len()).prop_map(|(a, b)| Pick::Raw(a, b)),
        3 => (any::<usize>(), any::<usize>()).prop_map(|(i, j)| Pick::Declared(i, j)),
    ]
}

/// The `j`-th parameter kind `kind` declares and a value text for it (`j % 3`: default,
/// minimum, maximum).
pub(super) fn declared(kind: &str, j: usize) -> Option<(String, String)> {
    use volgraph_core::KindLookup as _;
    use volgraph_core::params::ParamKind;
    static REGISTRY: OnceLock<volgraph_core::Registry> = OnceLock::new();
    let params = REGISTRY.get_or_init(volgraph_passes::builtin_registry).decl(kind)?.params();
    let spec = params.get(j % params.len().max(1))?;
    let value = match (&spec.kind, j % 3) {
        (ParamKind::Float { default, .. }, 0) | (ParamKind::Float { min: default, .. }, 1) => format!("{default:?}"),
        (ParamKind::Float { max, .. }, _) => format!("{max:?}"),
        (ParamKind::UInt { default, .. }, 0) | (ParamKind::UInt { min: default, .. }, 1) => default.to_string(),
        (ParamKind::UInt { max, .. }, _) => max.to_string(),
        (ParamKind::Bool { default }, _) => default.to_string(),
        (ParamKind::Choice { options, .. }, _) => format!("\"{}\"", options.get(j % options.len().max(1))?),
    };
    Some((spec.name.to_string(), value))
}

/// The case's target text, from the graph as far as it parses, and the value a
/// [`Pick::Declared`] sets.
pub(super) fn target_text(text: &str, pick: &Pick) -> (String, Option<String>) {
    let doc = parse_graph(text.strip_prefix('\u{feff}').unwrap_or(text)).ok();
    let passes: Vec<(String, String, Vec<String>)> = doc
        .iter()
        .flat_map(|d| d.passes.iter())
        .flat_map(|n| match n {
            NodeDoc::Pass(p) => vec![p],
            NodeDoc::Repeat(r) => r.body.iter().collect(),
        })
        .map(|p| (p.id.clone(), p.kind.clone(), p.params.keys().cloned().collect()))
        .collect();
    let pass_of = |i: usize| passes.get(i % passes.len().max(1)).map_or("march".to_string(), |p| p.0.clone());
    if let Pick::Declared(i, j) = pick
        && let Some((id, kind, _)) = passes.get(i % passes.len().max(1))
        && let Some((param, value)) = declared(kind, *j)
    {
        return (format!("{id}.{param}"), Some(value));
    }
    let target = match pick {
        Pick::Existing(i) => {
            let mut all: Vec<String> =
                passes.iter().flat_map(|(id, _, params)| params.iter().map(move |p| format!("{id}.{p}"))).collect();
            if let Some(d) = &doc {
                all.extend(
                    d.inputs
                        .iter()
                        .filter(|(_, k)| matches!(k, InputKind::Scalar(_)))
                        .map(|(n, _)| format!("input.{n}")),
                );
            }
            all.get(i % all.len().max(1)).cloned().unwrap_or_else(|| "march.step_voxels".to_string())
        }
        Pick::OfPass(i, n) => format!("{}.{}", pass_of(*i), NAMES[*n]),
        Pick::Input(n) => format!("input.{}", NAMES[*n]),
        Pick::Raw(a, b) | Pick::Declared(a, b) => format!("{}.{}", NAMES[*a % NAMES.len()], NAMES[*b % NAMES.len()]),
    };
    (target, None)
}
