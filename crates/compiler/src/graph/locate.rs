//! Finding the span of a graph element named by its position in the document.

use crate::diagnostic::Location;
use crate::graph::spans::{Node, Span, SpannedValue, parse_spanned};

/// Where a pass sits in the document: `passes[top]`, or `passes[top].body[index]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PassPath {
    /// Index in the top-level `passes` list.
    pub top: usize,
    /// Index in the repeat group's `body`, if inside one.
    pub body: Option<usize>,
}

/// Answers "where is X" for diagnostics; falls back to [`Location::Field`].
pub struct Locator {
    tree: Option<SpannedValue>,
}

impl Locator {
    /// Reads `source` for spans.
    pub fn new(source: &str) -> Self {
        Self { tree: parse_spanned(source) }
    }

    fn node(&self, path: PassPath) -> Option<&SpannedValue> {
        let top = self.tree.as_ref()?.unwrap_variant().field("passes")?.index(path.top)?.unwrap_variant();
        match path.body {
            None => Some(top),
            Some(i) => Some(top.field("body")?.index(i)?.unwrap_variant()),
        }
    }

    fn or_field(span: Option<Span>, id: &str, field: &str) -> Location {
        match span {
            Some(s) => Location::Span(s),
            None => Location::Field { pass: id.to_string(), field: field.to_string() },
        }
    }

    /// The value of a top-level field (`outputs`, `history`, ...).
    pub fn top_field(&self, field: &str) -> Option<&SpannedValue> {
        self.tree.as_ref()?.unwrap_variant().field(field)
    }

    /// The value of field `field` of the pass at `path` (e.g. its `kind` string).
    pub fn pass_field(&self, path: PassPath, id: &str, field: &str) -> Location {
        Self::or_field(self.node(path).and_then(|n| n.field(field)).map(|v| v.span), id, field)
    }

    /// The key (`key = true`) or value of entry `key` in map field `map` of the pass.
    pub fn pass_entry(&self, path: PassPath, id: &str, map: &str, key: &str, want_key: bool) -> Location {
        let span = self
            .node(path)
            .and_then(|n| n.field(map))
            .and_then(|m| m.entry(key))
            .map(|(k, v)| if want_key { k.span } else { v.span });
        Self::or_field(span, id, &format!("{map}.{key}"))
    }

    /// A field of an entry in a map field (`carry."accum".next`).
    pub fn pass_entry_field(&self, path: PassPath, id: &str, map: &str, key: &str, field: &str) -> Location {
        let span = self
            .node(path)
            .and_then(|n| n.field(map))
            .and_then(|m| m.entry(key))
            .and_then(|(_, v)| v.unwrap_variant().field(field))
            .map(|v| v.span);
        Self::or_field(span, id, &format!("{map}.{key}.{field}"))
    }

    /// The `i`-th item of list field `list` of the pass (`when[0]`).
    pub fn pass_list_item(&self, path: PassPath, id: &str, list: &str, i: usize) -> Location {
        let span = self.node(path).and_then(|n| n.field(list)).and_then(|l| l.index(i)).map(|v| v.span);
        Self::or_field(span, id, &format!("{list}[{i}]"))
    }

    /// The value of a top-level map entry (`outputs."image"`), or its key.
    pub fn top_entry(&self, map: &str, key: &str, want_key: bool) -> Location {
        let span = self.top_field(map).and_then(|m| m.entry(key)).map(|(k, v)| if want_key { k.span } else { v.span });
        match span {
            Some(s) => Location::Span(s),
            None => Location::Field { pass: "(graph)".to_string(), field: format!("{map}.{key}") },
        }
    }

    /// A field inside a top-level map entry's struct value (`history."prev".of`).
    pub fn top_entry_field(&self, map: &str, key: &str, field: &str) -> Location {
        let span = self
            .top_field(map)
            .and_then(|m| m.entry(key))
            .and_then(|(_, v)| v.unwrap_variant().field(field))
            .map(|v| v.span);
        match span {
            Some(s) => Location::Span(s),
            None => Location::Field { pass: "(graph)".to_string(), field: format!("{map}.{key}.{field}") },
        }
    }

    /// Whether the lenient reader understood the file (for tests).
    pub fn understood(&self) -> bool {
        matches!(self.tree.as_ref().map(|t| &t.node), Some(Node::Struct { .. }))
    }
}
