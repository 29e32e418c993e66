//! Writing a benchmark's tables and JSON where its flags say (`--markdown`, `--json`).

use std::path::Path;

use anyhow::Context as _;

/// Writes `text` to `path` when the flag gave one; the error names the flag and the file.
pub fn write_file(path: Option<&Path>, text: &str, flag: &str) -> anyhow::Result<()> {
    match path {
        Some(p) => std::fs::write(p, text).with_context(|| format!("{flag} {}: cannot write the file", p.display())),
        None => Ok(()),
    }
}

/// A benchmark's Markdown table and JSON value, each written where its flag says.
pub fn write_markdown_and_json(
    markdown: (Option<&Path>, &str),
    json: (Option<&Path>, &serde_json::Value),
) -> anyhow::Result<()> {
    write_file(markdown.0, markdown.1, "--markdown")?;
    if json.0.is_some() {
        write_file(json.0, &(serde_json::to_string_pretty(json.1)? + "\n"), "--json")?;
    }
    Ok(())
}
