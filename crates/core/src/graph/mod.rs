//! Graph files: the RON syntax ([`ast`]), parsing with located errors, and source spans
//! ([`spans`]).

pub mod ast;
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
        other => (format!("syntax error: {other}"), None),
    }
}
