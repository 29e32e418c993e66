//! WGSL parsed and validated with naga, its errors located in the file a developer edits
//! (through the `#import` map of [`crate::shader_source`]): what `volgraph plan` checks shaders
//! with, and what the runtime's shader library reports before wgpu sees a module.

use crate::shader_source::ShaderSource;

/// `path:line:col: message` for a naga error at `location` of the assembled text, pointing at
/// the original file through the import map and showing that file's line; naga's own report
/// (whose frame shows the assembled text) only where no location is known.
fn located(
    source: &ShaderSource,
    file: &str,
    location: Option<naga::SourceLocation>,
    message: &str,
    report: String,
) -> String {
    match location.and_then(|l| source.origin_of_line(l.line_number as usize).map(|o| (o, l))) {
        // naga's own frame shows the assembled text (imports inlined) under the root file's
        // name, so its line numbers match no file on disk: show the line where it came from.
        Some(((path, line), l)) => {
            // naga's column is in bytes; the caret line copies tabs so it lines up.
            let col = l.line_position;
            let text = source.text.lines().nth((l.line_number as usize).saturating_sub(1)).unwrap_or("");
            let before = text.get(..(col as usize).saturating_sub(1)).unwrap_or("");
            let caret: String = before.chars().map(|c| if c == '\t' { '\t' } else { ' ' }).collect();
            let rest = text.get(before.len()..).unwrap_or("");
            let width = rest.get(..(l.length as usize).min(rest.len())).map_or(1, |s| s.chars().count().max(1));
            format!(
                "{}:{line}:{col}: {message}\n  --> {}:{line}:{col}\n   |\n   | {text}\n   | {caret}{}",
                path.display(),
                path.display(),
                "^".repeat(width)
            )
        }
        None => format!("{file}: {message}\n{report}"),
    }
}

/// Parses and validates WGSL with naga; the error names the original file and line (through
/// `#import`) and carries naga's full report.
pub fn parse_and_validate_source(
    file: &str,
    source: &ShaderSource,
) -> Result<(naga::Module, naga::valid::ModuleInfo), String> {
    let text = &source.text;
    let module = naga::front::wgsl::parse_str(text)
        .map_err(|e| located(source, file, e.location(text), e.message(), e.emit_to_string_with_path(text, file)))?;
    let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
        .validate(&module)
        .map_err(|e| {
            // The whole chain: the top level alone ("Function 'fs_main' is invalid") hides the cause.
            let mut message = e.as_inner().to_string();
            let mut cause = std::error::Error::source(e.as_inner());
            while let Some(c) = cause {
                message.push_str(&format!(": {c}"));
                cause = c.source();
            }
            located(source, file, e.location(text), &message, e.emit_to_string_with_path(text, file))
        })?;
    Ok((module, info))
}

/// Parses and validates WGSL text with naga (no import map); the error is naga's full report.
pub fn parse_and_validate(file: &str, text: &str) -> Result<(naga::Module, naga::valid::ModuleInfo), String> {
    let module = naga::front::wgsl::parse_str(text).map_err(|e| e.emit_to_string_with_path(text, file))?;
    let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
        .validate(&module)
        .map_err(|e| e.emit_to_string_with_path(text, file))?;
    Ok((module, info))
}
