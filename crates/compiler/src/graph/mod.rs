//! Graph files: the RON syntax ([`ast`]), parsing with located errors, and source spans
//! ([`spans`]).

pub mod ast;
pub mod edit;
pub mod locate;
pub mod spans;

use crate::diagnostic::{Diagnostic, Location};
use crate::graph::spans::Span;

/// Parses graph text. RON's own syntax and shape errors come back located.
pub fn parse_graph(source: &str) -> Result<ast::GraphDoc, Diagnostic> {
    let options = ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES)
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
    options.from_str::<ast::GraphDoc>(source).map_err(|e| {
        let offset = offset_of(source, e.span.start.line, e.span.start.col);
        let end = offset_of(source, e.span.end.line, e.span.end.col).max(offset);
        let (message, help) = explain_ron_error(&e.code);
        let mut d = Diagnostic::new(Location::Span(Span { start: offset, end }), message);
        if let Some(h) = help {
            d = d.with_help(h);
        }
        d
    })
}

/// Byte offset of a 1-based (line, column-in-chars) position.
fn offset_of(source: &str, line: usize, col: usize) -> usize {
    let mut offset = 0;
    for (i, l) in source.split_inclusive('\n').enumerate() {
        if i + 1 == line {
            let chars: usize = l.chars().take(col.saturating_sub(1)).map(char::len_utf8).sum();
            return offset + chars;
        }
        offset += l.len();
    }
    source.len()
}

fn explain_ron_error(code: &ron::Error) -> (String, Option<String>) {
    use ron::Error as E;
    match code {
        E::NoSuchStructField { expected, found, outer } => {
            let outer = outer.as_deref().unwrap_or("this struct");
            let list = expected.iter().map(|s| format!("`{s}`")).collect::<Vec<_>>().join(", ");
            let mut help = format!("{outer} accepts: {list}");
            if let Some(best) = crate::suggest::closest(found, expected.iter().copied()) {
                help = format!("did you mean `{best}`? {help}");
            }
            (format!("unknown field `{found}` in {outer}"), Some(help))
        }
        E::MissingStructField { field, outer } => {
            let outer = outer.as_deref().unwrap_or("this struct");
            (format!("{outer} is missing the field `{field}`"), Some(format!("add `{field}: ...` to {outer}")))
        }
        E::DuplicateStructField { field, outer } => {
            let outer = outer.as_deref().unwrap_or("this struct");
            (format!("field `{field}` appears twice in {outer}"), Some("keep one of them".to_string()))
        }
        E::NoSuchEnumVariant { expected, found, outer } => {
            let outer = outer.as_deref().unwrap_or("this enum");
            let list = expected.iter().map(|s| format!("`{s}`")).collect::<Vec<_>>().join(", ");
            let mut help = format!("{outer} is one of: {list}");
            if let Some(best) = crate::suggest::closest(found, expected.iter().copied()) {
                help = format!("did you mean `{best}`? {help}");
            }
            (format!("unknown {outer} `{found}`"), Some(help))
        }
        E::Eof => (
            "the file ends in the middle of a value".to_string(),
            Some("close every `(`, `[` and `{` and end strings with `\"`".to_string()),
        ),
        E::ExpectedComma => {
            ("expected `,` here".to_string(), Some("separate fields, list items and map entries with `,`".to_string()))
        }
        E::ExpectedMapColon => {
            ("expected `:` after the map key".to_string(), Some("write map entries as \"key\": value".to_string()))
        }
        E::ExpectedArrayEnd => (
            "expected `]` or `,` here".to_string(),
            Some("close the list with `]`, or put `,` between its items".to_string()),
        ),
        E::ExpectedMapEnd => (
            "expected `}` or `,` here".to_string(),
            Some("close the map with `}`, or put `,` between its entries".to_string()),
        ),
        E::ExpectedStructLikeEnd | E::ExpectedOptionEnd => (
            "expected `)` or `,` here".to_string(),
            Some("close the parenthesis with `)`, or put `,` between its fields".to_string()),
        ),
        E::ExceededRecursionLimit => (
            "brackets nest more than 128 levels deep here".to_string(),
            Some(
                "a graph file needs only a few levels of `(`, `[` and `{`; look for brackets opened here and never \
                 closed, or a generated value nested too deeply"
                    .to_string(),
            ),
        ),
        E::ExpectedStringEnd => ("this string is never closed".to_string(), Some("end it with `\"`".to_string())),
        E::UnclosedBlockComment => ("this comment is never closed".to_string(), Some("end it with `*/`".to_string())),
        E::TrailingCharacters => (
            "unexpected text after the end of the graph".to_string(),
            Some("a graph file holds one Graph(...); remove what follows its closing `)`".to_string()),
        ),
        E::ExpectedDifferentStructName { expected, found } => (
            format!("expected `{expected}(...)` here, found `{found}(...)`"),
            Some(format!("write `{expected}(...)`, or leave the name out: `(...)`")),
        ),
        other => {
            // ron's own wording starts with a capital ("Expected string"); keep it mid-sentence.
            let text = other.to_string();
            let mut chars = text.chars();
            let text = match chars.next() {
                Some(c) => c.to_lowercase().chain(chars).collect(),
                None => text,
            };
            (
                format!("syntax error: {text}"),
                Some("see docs/graph_format.md for the syntax and the type of every field".to_string()),
            )
        }
    }
}
