//! Located, actionable errors about graph files.
//!
//! Every problem found while compiling a graph becomes one [`Diagnostic`]: what is wrong, where
//! (a byte span in the file, or the pass and field when no span can be found) and how to fix it.
//! Compilation collects all of them before failing ([`Diagnostics`]). `Display` prints the
//! compiler-style one-liner tests compare word for word,
//! `graphs/kw03.ron:14:9: pass "march" reads "dirs.dir2", but ...`, followed by an indented
//! `help:` line; the `miette::Diagnostic` impl lets the app draw the source excerpt.

use std::fmt;
use std::sync::Arc;

use crate::graph::spans::{Span, line_col};

/// Where a diagnostic points.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Location {
    /// A byte span in the graph file.
    Span(Span),
    /// No span could be found: the pass (or group) id and the field.
    Field {
        /// The pass or repeat id.
        pass: String,
        /// The field within it (`inputs.dir`, `params.step_voxels`).
        field: String,
    },
    /// The file as a whole.
    File,
}

/// One problem in a graph file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Diagnostic {
    /// What is wrong.
    pub message: String,
    /// How to fix it, if we can say.
    pub help: Option<String>,
    /// Where.
    pub location: Location,
}

/// The longest message or help kept whole; longer ones (a 100 KB string pasted into a graph
/// file and quoted back) keep their start and end around an ellipsis.
const MAX_MESSAGE_CHARS: usize = 600;

fn clip_message(text: String) -> String {
    let text = crate::terminal::escape_controls(&text).into_owned();
    let count = text.chars().count();
    if count <= MAX_MESSAGE_CHARS {
        return text;
    }
    let head: String = text.chars().take(MAX_MESSAGE_CHARS - 120).collect();
    let tail: String = text.chars().skip(count - 100).collect();
    format!("{head} … ({} characters left out) … {tail}", count - (MAX_MESSAGE_CHARS - 20))
}

impl Diagnostic {
    /// A diagnostic at `location`.
    pub fn new(location: Location, message: impl Into<String>) -> Self {
        Self { message: clip_message(message.into()), help: None, location }
    }

    /// Adds the fix.
    pub fn with_help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(clip_message(help.into()));
        self
    }
}

/// All problems of one graph file, with the file's name and text for rendering.
#[derive(Clone, Debug, Default, thiserror::Error)]
pub struct Diagnostics {
    /// The file name as given (used as the prefix of every line).
    pub file: String,
    /// The file text.
    pub text: Arc<str>,
    /// The problems, in the order found.
    pub items: Vec<Diagnostic>,
}

impl Diagnostics {
    /// The `file:line:col` (or `file: pass "x", field y`) prefix of one item.
    pub fn position(&self, d: &Diagnostic) -> String {
        let file = crate::terminal::escape_controls(&self.file);
        match &d.location {
            Location::Span(s) => {
                let (line, col) = line_col(&self.text, s.start);
                format!("{file}:{line}:{col}")
            }
            Location::Field { pass, field } => {
                let (pass, field) = (crate::terminal::escape_controls(pass), crate::terminal::escape_controls(field));
                format!("{file}: pass \"{pass}\", field {field}")
            }
            Location::File => file.into_owned(),
        }
    }
}

impl fmt::Display for Diagnostics {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, d) in self.items.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "{}: {}", self.position(d), d.message)?;
            if let Some(help) = &d.help {
                write!(f, "\n  help: {help}")?;
            }
        }
        Ok(())
    }
}

/// Lines longer than this get no source excerpt.
const MAX_EXCERPT_LINE: usize = 240;

/// The length in bytes of the line holding byte `offset` and of its neighbours (miette shows
/// one line of context on each side).
fn longest_line_around(text: &str, offset: usize) -> usize {
    let offset = offset.min(text.len());
    let start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let before = text[..start.saturating_sub(1)].rfind('\n').map_or(0, |i| i + 1);
    text[before..].split('\n').take(3).map(str::len).max().unwrap_or(0)
}

/// One item rendered for miette, with its label in the source.
#[derive(Debug)]
struct MietteItem {
    message: String,
    help: Option<String>,
    span: Option<Span>,
    source: miette::NamedSource<String>,
}

impl fmt::Display for MietteItem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for MietteItem {}

impl miette::Diagnostic for MietteItem {
    fn help<'a>(&'a self) -> Option<Box<dyn fmt::Display + 'a>> {
        self.help.as_ref().map(|h| Box::new(h) as Box<dyn fmt::Display>)
    }

    fn source_code(&self) -> Option<&dyn miette::SourceCode> {
        Some(&self.source)
    }

    fn labels(&self) -> Option<Box<dyn Iterator<Item = miette::LabeledSpan> + '_>> {
        let span = self.span?;
        Some(Box::new(std::iter::once(miette::LabeledSpan::at(span.start..span.end, "here"))))
    }
}

impl Diagnostics {
    /// Each item as a `miette::Report` with the source excerpt (for the CLI).
    pub fn to_miette_reports(&self) -> Vec<miette::Report> {
        self.items
            .iter()
            .map(|d| {
                let (span, message) = match &d.location {
                    // An excerpt of a very long line (minified or generated files) would print the
                    // whole line; the one-line form already gives line and column.
                    Location::Span(s) if longest_line_around(&self.text, s.start) > MAX_EXCERPT_LINE => {
                        let (line, col) = line_col(&self.text, s.start);
                        (None, format!("line {line}, column {col}: {}", d.message))
                    }
                    Location::Span(s) => (Some(*s), d.message.clone()),
                    Location::Field { pass, field } => (
                        None,
                        format!(
                            "pass \"{}\", field {}: {}",
                            crate::terminal::escape_controls(pass),
                            crate::terminal::escape_controls(field),
                            d.message
                        ),
                    ),
                    Location::File => (None, d.message.clone()),
                };
                miette::Report::new(MietteItem {
                    message,
                    help: d.help.clone(),
                    span,
                    // The excerpt shows the file with its control characters masked (same byte
                    // length, so the span still fits): a name holding ESC cannot drive the terminal.
                    source: miette::NamedSource::new(
                        crate::terminal::escape_controls(&self.file),
                        crate::terminal::mask_controls(&self.text).into_owned(),
                    ),
                })
            })
            .collect()
    }
}
