//! Writing values back into a graph file's text: `volgraph set` and, through it, any tool that
//! changes a parameter or a graph input and wants the file to learn of it. Only the value's text
//! changes — comments, order and layout stay — because the edit replaces the value's span in the
//! source ([`super::spans`]). A parameter the file does not write yet is added to the pass's
//! `params` map (the map is created after `kind` when the pass has none), with the file's own
//! line ending. A key the file writes twice is edited where it takes effect: its last copy,
//! the one the compiler reads.

use super::ast::{GraphDoc, InputKind, NodeDoc};
use super::parse_graph;
use super::spans::{Node, Span, SpannedValue, parse_spanned};
use crate::suggest::{comma_list, guess_then};

/// What one assignment sets.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SetTarget {
    /// `PASS.PARAM`: a parameter of a pass (in a repeat group's body too).
    Param {
        /// The pass id.
        pass: String,
        /// The parameter.
        param: String,
    },
    /// `input.NAME`: the value of a graph `Scalar` input.
    Input(String),
}

impl SetTarget {
    /// Parses `PASS.PARAM` or `input.NAME`.
    pub fn parse(text: &str) -> Result<Self, String> {
        match text.split_once('.') {
            Some(("input", name)) if !name.is_empty() => Ok(Self::Input(name.to_string())),
            Some((pass, param)) if !pass.is_empty() && !param.is_empty() && !param.contains('.') => {
                Ok(Self::Param { pass: pass.to_string(), param: param.to_string() })
            }
            _ => Err(format!("\"{text}\": expected PASS.PARAM or input.NAME")),
        }
    }
}

impl std::fmt::Display for SetTarget {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Param { pass, param } => write!(f, "{pass}.{param}"),
            Self::Input(name) => write!(f, "input.{name}"),
        }
    }
}

/// One text replacement: `span` of the source becomes `text`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TextEdit {
    /// What is replaced (empty for an insertion).
    pub span: Span,
    /// The new text.
    pub text: String,
}

/// The edits that set `target` to `value` (RON text, checked to be exactly one value on one
/// line, with no comment) in `source`. Names the graph does not have are errors with a "did you
/// mean". A byte-order mark and RON attributes (`#![enable(...)]`) before the graph stay.
pub fn edit_for(source: &str, target: &SetTarget, value: &str) -> Result<Vec<TextEdit>, String> {
    let value = value.trim();
    check_value(target, value)?;
    // A UTF-8 byte-order mark is not part of the graph (as `compile` reads it); spans are
    // counted in `source`, the mark included.
    let bom = if source.starts_with('\u{feff}') { '\u{feff}'.len_utf8() } else { 0 };
    let mut edits = edits_in(&source[bom..], target, value)?;
    for e in &mut edits {
        e.span.start += bom;
        e.span.end += bom;
    }
    Ok(edits)
}

/// Spans of the copies of `target`'s key that `source` writes before the one that takes effect
/// (a map key written twice: the compiler reads the last); empty when it is written once.
pub fn shadowed_copies(source: &str, target: &SetTarget) -> Vec<Span> {
    let bom = if source.starts_with('\u{feff}') { '\u{feff}'.len_utf8() } else { 0 };
    let Some(tree) = parse_spanned(&source[bom..]) else { return Vec::new() };
    let root = tree.unwrap_variant();
    let (map, key) = match target {
        SetTarget::Input(name) => (root.field("inputs"), name.as_str()),
        SetTarget::Param { pass, param } => {
            let doc: Option<GraphDoc> = parse_graph(&source[bom..]).ok();
            let node = doc.and_then(|doc| pass_node(&doc, root, pass));
            (node.and_then(|n| n.field("params")), param.as_str())
        }
    };
    let Some(map) = map else { return Vec::new() };
    let mut copies: Vec<Span> = map.entries(key).map(|(k, _)| k.span).collect();
    copies.pop();
    copies.iter().map(|s| Span { start: s.start + bom, end: s.end + bom }).collect()
}

/// A value `set` writes: one RON value, on one line, with no comment — a `//` would comment
/// out what follows the value on its line, a line break would mix line endings.
fn check_value(target: &SetTarget, value: &str) -> Result<(), String> {
    let shown = crate::terminal::escape_controls(value);
    if ron::from_str::<ron::Value>(value).is_err() {
        return Err(format!(
            "{target}={shown}: \"{shown}\" is not a RON value; write numbers as 0.5, booleans as true, strings in quotes (\"feature.shading\")"
        ));
    }
    if value.chars().any(char::is_control) {
        return Err(format!(
            "{target}={shown}: the value holds a line break or another control character; write it on one line (inside a string, as an escape: \\n)"
        ));
    }
    // The lenient reading skips comments: a value it reads whole has none before or after it.
    let whole = parse_spanned(value).is_some_and(|v| v.span.start == 0 && v.span.end == value.len());
    if !whole {
        return Err(format!(
            "{target}={shown}: write one plain RON value (a number, true/false, a \"string\", a list), with no comment before or after it"
        ));
    }
    Ok(())
}

/// The spanned node of pass `pass` (the last pass of that id, at the top level or in a repeat
/// group's body).
fn pass_node<'a>(doc: &GraphDoc, root: &'a SpannedValue, pass: &str) -> Option<&'a SpannedValue> {
    let (top, body) = pass_path(doc, pass)?;
    let node = root.field("passes").and_then(|l| l.index(top)).map(SpannedValue::unwrap_variant);
    match body {
        None => node,
        Some(i) => node.and_then(|n| n.field("body")).and_then(|l| l.index(i)).map(SpannedValue::unwrap_variant),
    }
}

/// Where pass `pass` sits: (index in `passes`, index in its repeat group's body).
fn pass_path(doc: &GraphDoc, pass: &str) -> Option<(usize, Option<usize>)> {
    let mut path = None;
    for (top, node) in doc.passes.iter().enumerate() {
        match node {
            NodeDoc::Pass(p) if p.id == pass => path = Some((top, None)),
            NodeDoc::Pass(_) => {}
            NodeDoc::Repeat(r) => {
                for (i, p) in r.body.iter().enumerate() {
                    if p.id == pass {
                        path = Some((top, Some(i)));
                    }
                }
            }
        }
    }
    path
}

fn edits_in(source: &str, target: &SetTarget, value: &str) -> Result<Vec<TextEdit>, String> {
    let doc: GraphDoc = parse_graph(source).map_err(|d| format!("the graph does not parse: {}", d.message))?;
    let tree = parse_spanned(source).ok_or_else(|| "the graph's text could not be read for positions".to_string())?;
    let root = tree.unwrap_variant();
    match target {
        SetTarget::Input(name) => {
            let Some(kind) = doc.inputs.get(name) else {
                let names: Vec<&str> = doc.inputs.keys().map(String::as_str).collect();
                return Err(format!(
                    "{target}: the graph has no input \"{name}\"; {}",
                    guess_then(
                        name,
                        names.iter().copied(),
                        "input.",
                        format!("its inputs are: {}", comma_list(&names))
                    )
                ));
            };
            if !matches!(kind, InputKind::Scalar(_)) {
                return Err(format!("{target}: input \"{name}\" is a {kind:?}, not a Scalar: it has no value to set"));
            }
            let entry = root.field("inputs").and_then(|m| m.entry(name)).map(|(_, v)| v);
            let inner = match entry.map(|v| &v.node) {
                Some(Node::Struct { items, .. }) if items.len() == 1 => &items[0],
                _ => return Err(format!("{target}: cannot find the value of input \"{name}\" in the text")),
            };
            Ok(vec![TextEdit { span: inner.span, text: value.to_string() }])
        }
        SetTarget::Param { pass, param } => {
            if pass_path(&doc, pass).is_none() {
                let ids: Vec<&str> = doc
                    .passes
                    .iter()
                    .flat_map(|n| match n {
                        NodeDoc::Pass(p) => vec![p.id.as_str()],
                        NodeDoc::Repeat(r) => r.body.iter().map(|p| p.id.as_str()).collect(),
                    })
                    .collect();
                return Err(format!(
                    "{target}: the graph has no pass \"{pass}\"; {}",
                    guess_then(pass, ids.iter().copied(), "", format!("its passes are: {}", comma_list(&ids)))
                ));
            }
            let node = pass_node(&doc, root, pass)
                .ok_or_else(|| format!("{target}: cannot find pass \"{pass}\" in the text"))?;
            insert_or_replace(source, node, param, value)
                .ok_or_else(|| format!("{target}: cannot find where to write it"))
        }
    }
}

/// Replaces the value of `params[param]` of pass `node`, or adds the entry: on a line of its
/// own after the last entry's line (comments stay where they were) when the map spans lines,
/// else inline; a pass without `params` gets the map after `kind`, the same way.
fn insert_or_replace(source: &str, node: &SpannedValue, param: &str, value: &str) -> Option<Vec<TextEdit>> {
    let entry = format!("\"{param}\": {value}");
    let (anchor_key, anchor_value, new_text) = match node.field("params") {
        Some(map) => {
            if let Some((_, v)) = map.entry(param) {
                return Some(vec![TextEdit { span: v.span, text: value.to_string() }]);
            }
            let Node::Map(entries) = &map.node else { return None };
            let Some((k, v)) = entries.last() else {
                let at = map.span.start + 1;
                return Some(vec![TextEdit { span: Span { start: at, end: at }, text: entry }]);
            };
            (k.span, v.span, entry)
        }
        None => {
            let kind = node.field("kind")?;
            let key = node.field_name_span("kind")?;
            (key, kind.span, format!("params: {{{entry}}}"))
        }
    };
    let mut edits = Vec::new();
    let rest = &source[anchor_value.end..];
    let has_comma = rest.trim_start().starts_with(',');
    let line_start = source[..anchor_key.start].rfind('\n').map_or(0, |i| i + 1);
    let indent = &source[line_start..anchor_key.start];
    let own_line = indent.trim().is_empty() && rest.find('\n').is_some();
    if own_line {
        if !has_comma {
            edits.push(TextEdit {
                span: Span { start: anchor_value.end, end: anchor_value.end },
                text: ",".to_string(),
            });
        }
        let at = anchor_value.end + rest.find('\n')? + 1;
        // The anchor line's own ending: a CRLF file stays CRLF.
        let newline = if source[..at].ends_with("\r\n") { "\r\n" } else { "\n" };
        edits.push(TextEdit { span: Span { start: at, end: at }, text: format!("{indent}{new_text},{newline}") });
    } else {
        let at = if has_comma { anchor_value.end + rest.find(',')? + 1 } else { anchor_value.end };
        let text = if has_comma { format!(" {new_text},") } else { format!(", {new_text}") };
        edits.push(TextEdit { span: Span { start: at, end: at }, text });
    }
    Some(edits)
}

/// Applies edits (non-overlapping) to `source`.
pub fn apply(source: &str, edits: &[TextEdit]) -> String {
    let mut sorted: Vec<&TextEdit> = edits.iter().collect();
    sorted.sort_by_key(|e| std::cmp::Reverse(e.span.start));
    let mut out = source.to_string();
    for e in sorted {
        out.replace_range(e.span.start..e.span.end, &e.text);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const GRAPH: &str = r#"// A graph.
Graph(
    name: "g",
    inputs: {
        "volume": Volume,
        "threshold": Scalar(0.95), // the ERT threshold
    },
    passes: [
        Pass(id: "entry", kind: "entry_points"),
        Pass(
            id: "march",
            kind: "raycast",
            params: {
                "step_voxels": 0.5, // half a voxel
            },
        ),
        Pass(
            id: "present",
            kind: "present",
            inputs: {"color": "march.color"},
        ),
    ],
    outputs: {"display": "present.display"},
)
"#;

    fn set(target: &str, value: &str) -> Result<String, String> {
        let t = SetTarget::parse(target)?;
        Ok(apply(GRAPH, &edit_for(GRAPH, &t, value)?))
    }

    #[test]
    fn a_value_changes_only_its_text() {
        let out = set("march.step_voxels", "0.25").expect("set");
        assert_eq!(out, GRAPH.replace("\"step_voxels\": 0.5,", "\"step_voxels\": 0.25,"));
        let out = set("input.threshold", "0.99").expect("set");
        assert_eq!(out, GRAPH.replace("Scalar(0.95)", "Scalar(0.99)"));
    }

    #[test]
    fn a_new_parameter_joins_the_map_or_makes_one() {
        let out = set("march.threshold", "0.9").expect("set");
        assert!(out.contains("\"step_voxels\": 0.5, // half a voxel\n                \"threshold\": 0.9,\n"), "{out}");
        parse_graph(&out).expect("still a graph");
        let out = set("present.background", "0.2").expect("set");
        assert!(out.contains("kind: \"present\",\n            params: {\"background\": 0.2},\n"), "{out}");
        parse_graph(&out).expect("still a graph");
        let out = set("entry.x", "1").expect("set");
        assert!(out.contains("Pass(id: \"entry\", kind: \"entry_points\", params: {\"x\": 1}),"), "{out}");
        // A map that is one line gets the entry inline.
        let one_line = GRAPH.replace(
            "params: {\n                \"step_voxels\": 0.5, // half a voxel\n            },",
            "params: {\"step_voxels\": 0.5},",
        );
        let t = SetTarget::parse("march.threshold").expect("target");
        let out = apply(&one_line, &edit_for(&one_line, &t, "0.9").expect("set"));
        assert!(out.contains("params: {\"step_voxels\": 0.5, \"threshold\": 0.9},"), "{out}");
        parse_graph(&out).expect("still a graph");
    }

    #[test]
    fn unknown_names_are_refused_with_a_guess() {
        let e = set("mrach.step_voxels", "1").expect_err("no such pass");
        assert!(e.contains("did you mean \"march\"?"), "{e}");
        let e = set("input.treshold", "1").expect_err("no such input");
        assert!(e.contains("did you mean \"input.threshold\"?"), "{e}");
        let e = set("input.volume", "1").expect_err("not a scalar");
        assert!(e.contains("not a Scalar"), "{e}");
        let e = set("march.step_voxels", "0.5 0.25").expect_err("not one value");
        assert!(e.contains("is not a RON value"), "{e}");
        assert!(SetTarget::parse("march").is_err());
    }

    #[test]
    fn a_value_with_a_comment_or_a_line_break_is_refused() {
        // `// x` would comment out the rest of the value's line (a one-line map's other entries).
        for value in ["0.25 // x", "/* x */ 0.25", "[1,\n2]", "0.25 0.5"] {
            assert!(set("march.step_voxels", value).is_err(), "{value:?} was written");
        }
        assert!(set("march.step_voxels", "\"a // b\"").is_ok(), "a `//` inside a string is text");
    }

    #[test]
    fn crlf_files_and_a_byte_order_mark_keep_their_bytes() {
        let crlf = format!("\u{feff}{}", GRAPH.replace('\n', "\r\n"));
        let t = SetTarget::parse("march.threshold").expect("target");
        let out = apply(&crlf, &edit_for(&crlf, &t, "0.9").expect("set"));
        assert!(out.starts_with('\u{feff}'));
        assert_eq!(out.matches('\n').count(), out.matches("\r\n").count(), "{out:?}");
        assert!(out.contains("\"threshold\": 0.9,\r\n"), "{out:?}");
    }
}
