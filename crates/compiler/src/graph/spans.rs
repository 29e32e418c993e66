//! Source locations for graph files.
//!
//! serde reads the RON into [`super::ast`] types, which carry no positions. To point an error at
//! the exact token, this module reads the same text a second time into a lenient tree of spanned
//! values and answers path queries such as `passes[2].inputs["dir"]`. It never fails: on text it
//! does not understand it simply finds nothing, and the error falls back to naming the pass and
//! field.

/// A byte range in the source text.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Span {
    /// Byte offset of the first character.
    pub start: usize,
    /// Byte offset one past the last character.
    pub end: usize,
}

/// 1-based line and column (in characters) of a byte offset.
pub fn line_col(source: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(source.len());
    let before = &source[..floor_char_boundary(source, offset)];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

fn floor_char_boundary(s: &str, mut i: usize) -> usize {
    while i > 0 && !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// A spanned RON value (lenient: enough structure to find things).
#[derive(Clone, Debug)]
pub struct SpannedValue {
    /// Where the whole value is.
    pub span: Span,
    /// What it is.
    pub node: Node,
}

/// The shapes of [`SpannedValue`].
#[derive(Clone, Debug)]
pub enum Node {
    /// A string literal (unescaped content).
    Str(String),
    /// Any other atom: number, identifier, char.
    Atom(String),
    /// `Name(field: v, ...)`, `(a, b)`, `Name(v)`: named fields and positional items.
    Struct {
        /// The identifier before the parenthesis, if any.
        name: Option<String>,
        /// `field: value` entries with the field's span.
        fields: Vec<(String, Span, SpannedValue)>,
        /// Positional entries.
        items: Vec<SpannedValue>,
    },
    /// `[a, b]`.
    List(Vec<SpannedValue>),
    /// `{k: v}`.
    Map(Vec<(SpannedValue, SpannedValue)>),
}

impl SpannedValue {
    /// The value of field `name` of a struct.
    pub fn field(&self, name: &str) -> Option<&SpannedValue> {
        match &self.node {
            Node::Struct { fields, .. } => fields.iter().find(|(k, _, _)| k == name).map(|(_, _, v)| v),
            _ => None,
        }
    }

    /// The span of the field name `name` of a struct.
    pub fn field_name_span(&self, name: &str) -> Option<Span> {
        match &self.node {
            Node::Struct { fields, .. } => fields.iter().find(|(k, _, _)| k == name).map(|(_, s, _)| *s),
            _ => None,
        }
    }

    /// The `i`-th element of a list, or the single positional item of an enum variant such as
    /// `Pass(...)` when `i` indexes into a list of variants (see [`Self::unwrap_variant`]).
    pub fn index(&self, i: usize) -> Option<&SpannedValue> {
        match &self.node {
            Node::List(v) => v.get(i),
            _ => None,
        }
    }

    /// For a map with string keys: the entry whose key is `key` → (key, value). A key written
    /// twice gives its last entry, the one the graph uses (serde keeps the last of a map's
    /// duplicate keys).
    pub fn entry(&self, key: &str) -> Option<(&SpannedValue, &SpannedValue)> {
        match &self.node {
            Node::Map(entries) => {
                entries.iter().rev().find(|(k, _)| matches!(&k.node, Node::Str(s) if s == key)).map(|(k, v)| (k, v))
            }
            _ => None,
        }
    }

    /// For a map with string keys: every entry whose key is `key`, in the text's order.
    pub fn entries<'a>(&'a self, key: &'a str) -> impl Iterator<Item = (&'a SpannedValue, &'a SpannedValue)> + 'a {
        let entries = match &self.node {
            Node::Map(entries) => entries.as_slice(),
            _ => &[],
        };
        entries.iter().filter(move |(k, _)| matches!(&k.node, Node::Str(s) if s == key)).map(|(k, v)| (k, v))
    }

    /// `Pass(id: ..)` is a struct named `Pass` with fields; RON also allows `Pass((id: ..))`.
    /// Either way this returns the node holding the fields.
    pub fn unwrap_variant(&self) -> &SpannedValue {
        match &self.node {
            Node::Struct { fields, items, .. } if fields.is_empty() && items.len() == 1 => &items[0],
            _ => self,
        }
    }
}

/// Parses `source` leniently; `None` when even the lenient reading fails. A UTF-8 byte-order
/// mark counts as whitespace and RON's inner attributes (`#![enable(implicit_some)]`) before
/// the value are skipped, as RON reads them.
pub fn parse_spanned(source: &str) -> Option<SpannedValue> {
    let tokens = tokenize(source);
    let mut p = Parser { tokens: &tokens, pos: 0 };
    p.skip_attributes();
    p.value()
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Str(String),
    Atom(String),
    Punct(char),
}

fn tokenize(src: &str) -> Vec<(Tok, Span)> {
    let bytes = src.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        if c.is_ascii_whitespace() {
            i += 1;
        } else if src[i..].starts_with('\u{feff}') {
            i += '\u{feff}'.len_utf8();
        } else if c == b'/' && bytes.get(i + 1) == Some(&b'/') {
            while i < bytes.len() && bytes[i] != b'\n' {
                i += 1;
            }
        } else if c == b'/' && bytes.get(i + 1) == Some(&b'*') {
            i += 2;
            while i + 1 < bytes.len() && !(bytes[i] == b'*' && bytes[i + 1] == b'/') {
                i += 1;
            }
            i = (i + 2).min(bytes.len());
        } else if c == b'"' {
            let start = i;
            i += 1;
            let mut s = String::new();
            while i < bytes.len() && bytes[i] != b'"' {
                if bytes[i] == b'\\' && i + 1 < bytes.len() {
                    i += 1;
                }
                let ch_start = i;
                i += 1;
                while i < bytes.len() && !src.is_char_boundary(i) {
                    i += 1;
                }
                s.push_str(&src[ch_start..i]);
            }
            i = (i + 1).min(bytes.len());
            out.push((Tok::Str(s), Span { start, end: i }));
        } else if matches!(c, b'(' | b')' | b'[' | b']' | b'{' | b'}' | b',' | b':') {
            out.push((Tok::Punct(c as char), Span { start: i, end: i + 1 }));
            i += 1;
        } else {
            let start = i;
            while i < bytes.len() {
                let b = bytes[i];
                if b.is_ascii_whitespace() || matches!(b, b'(' | b')' | b'[' | b']' | b'{' | b'}' | b',' | b':' | b'"')
                {
                    break;
                }
                i += 1;
            }
            while i < bytes.len() && !src.is_char_boundary(i) {
                i += 1;
            }
            if i == start {
                i += 1;
            }
            out.push((Tok::Atom(src[start..i].to_string()), Span { start, end: i }));
        }
    }
    out
}

struct Parser<'a> {
    tokens: &'a [(Tok, Span)],
    pos: usize,
}

impl Parser<'_> {
    fn peek(&self) -> Option<&(Tok, Span)> {
        self.tokens.get(self.pos)
    }

    /// Skips `#![...]` attributes: a `#`, a `!` (one token with it or not) and a bracketed list.
    fn skip_attributes(&mut self) {
        loop {
            let start = self.pos;
            match self.peek() {
                Some((Tok::Atom(a), _)) if a == "#!" => self.pos += 1,
                Some((Tok::Atom(a), _)) if a == "#" => {
                    self.pos += 1;
                    if !matches!(self.peek(), Some((Tok::Atom(b), _)) if b == "!") {
                        self.pos = start;
                        return;
                    }
                    self.pos += 1;
                }
                _ => return,
            }
            if !self.eat('[') {
                self.pos = start;
                return;
            }
            let mut depth = 1;
            while depth > 0 {
                match self.peek() {
                    None => return,
                    Some((Tok::Punct('['), _)) => depth += 1,
                    Some((Tok::Punct(']'), _)) => depth -= 1,
                    _ => {}
                }
                self.pos += 1;
            }
        }
    }

    fn eat(&mut self, c: char) -> bool {
        if matches!(self.peek(), Some((Tok::Punct(p), _)) if *p == c) {
            self.pos += 1;
            true
        } else {
            false
        }
    }

    fn value(&mut self) -> Option<SpannedValue> {
        let (tok, span) = self.peek()?.clone();
        self.pos += 1;
        match tok {
            Tok::Str(s) => Some(SpannedValue { span, node: Node::Str(s) }),
            Tok::Punct('(') => self.paren(None, span.start),
            Tok::Punct('[') => {
                let mut items = Vec::new();
                while !self.eat(']') {
                    items.push(self.value()?);
                    if !self.eat(',') && !matches!(self.peek(), Some((Tok::Punct(']'), _))) {
                        return None;
                    }
                }
                Some(SpannedValue { span: self.close(span.start), node: Node::List(items) })
            }
            Tok::Punct('{') => {
                let mut entries = Vec::new();
                while !self.eat('}') {
                    let k = self.value()?;
                    if !self.eat(':') {
                        return None;
                    }
                    let v = self.value()?;
                    entries.push((k, v));
                    if !self.eat(',') && !matches!(self.peek(), Some((Tok::Punct('}'), _))) {
                        return None;
                    }
                }
                Some(SpannedValue { span: self.close(span.start), node: Node::Map(entries) })
            }
            Tok::Atom(a) => {
                if matches!(self.peek(), Some((Tok::Punct('('), _))) {
                    self.pos += 1;
                    self.paren(Some(a), span.start)
                } else {
                    Some(SpannedValue { span, node: Node::Atom(a) })
                }
            }
            Tok::Punct(_) => None,
        }
    }

    fn close(&self, start: usize) -> Span {
        let end = self.tokens.get(self.pos.wrapping_sub(1)).map_or(start, |(_, s)| s.end);
        Span { start, end }
    }

    fn paren(&mut self, name: Option<String>, start: usize) -> Option<SpannedValue> {
        let mut fields = Vec::new();
        let mut items = Vec::new();
        while !self.eat(')') {
            let is_field = matches!(
                (self.tokens.get(self.pos), self.tokens.get(self.pos + 1)),
                (Some((Tok::Atom(_), _)), Some((Tok::Punct(':'), _)))
            );
            if is_field {
                let (Tok::Atom(k), kspan) = self.tokens[self.pos].clone() else { return None };
                self.pos += 2;
                let v = self.value()?;
                fields.push((k, kspan, v));
            } else {
                items.push(self.value()?);
            }
            if !self.eat(',') && !matches!(self.peek(), Some((Tok::Punct(')'), _))) {
                return None;
            }
        }
        Some(SpannedValue { span: self.close(start), node: Node::Struct { name, fields, items } })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_nested_string_spans() {
        let src = "Graph(name: \"g\", passes: [Pass(id: \"a\", inputs: {\"x\": \"b.y\"})])";
        let tree = parse_spanned(src).expect("lenient parse");
        let pass = tree.field("passes").and_then(|p| p.index(0)).map(|p| p.unwrap_variant());
        let (_, v) = pass.and_then(|p| p.field("inputs")).and_then(|m| m.entry("x")).expect("entry");
        assert_eq!(&src[v.span.start..v.span.end], "\"b.y\"");
        assert_eq!(line_col(src, v.span.start), (1, 55));
    }

    #[test]
    fn attributes_and_a_byte_order_mark_are_skipped() {
        let src = "\u{feff}#![enable(implicit_some)]\n# ! [enable(unwrap_newtypes)]\nGraph(name: \"g\")";
        let tree = parse_spanned(src).expect("lenient parse");
        let name = tree.field("name").expect("name");
        assert_eq!(&src[name.span.start..name.span.end], "\"g\"");
    }

    #[test]
    fn a_duplicated_key_gives_its_last_entry() {
        let src = "{\"a\": 1, \"b\": 2, \"a\": 3}";
        let tree = parse_spanned(src).expect("lenient parse");
        let (_, v) = tree.entry("a").expect("entry");
        assert_eq!(&src[v.span.start..v.span.end], "3");
        assert_eq!(tree.entries("a").count(), 2);
    }

    #[test]
    fn line_col_counts_lines_and_chars() {
        assert_eq!(line_col("ab\ncdé\nx", 8), (3, 1));
        assert_eq!(line_col("ab\ncdé\nx", 4), (2, 2));
    }
}
