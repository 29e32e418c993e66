//! `volgraph view --script`: the lines read from stdin, parsed whole. A line is one command;
//! anything after it is an error, never silently dropped (`quit now` is not `quit`).

use std::path::PathBuf;

/// One script command.
#[derive(Clone, Debug, PartialEq)]
pub enum ScriptCommand {
    /// `quit`: close the window after this frame.
    Quit,
    /// `screenshot PATH`: the rest of the line is the path (it may hold spaces).
    Screenshot(PathBuf),
    /// `param PASS.NAME VALUE`: the rest of the line is the RON value.
    Param {
        /// The pass id.
        pass: String,
        /// The parameter.
        name: String,
        /// The value.
        value: ron::Value,
    },
    /// `write`: the panel's "write to graph file" (the values changed here, into the graph).
    Write,
}

/// What the script accepts, for messages.
pub const USAGE: &str = "quit, screenshot PATH, param PASS.NAME VALUE, write";

/// Parses one line: `Ok(None)` for a blank line, `Err` naming what is wrong.
pub fn parse_line(line: &str) -> Result<Option<ScriptCommand>, String> {
    let line = line.trim();
    if line.is_empty() {
        return Ok(None);
    }
    let (command, rest) = line.split_once(char::is_whitespace).map_or((line, ""), |(c, r)| (c, r.trim()));
    match command {
        "quit" if rest.is_empty() => Ok(Some(ScriptCommand::Quit)),
        "quit" => Err(format!("\"{line}\": quit takes nothing after it (found \"{rest}\")")),
        "write" if rest.is_empty() => Ok(Some(ScriptCommand::Write)),
        "write" => Err(format!("\"{line}\": write takes nothing after it (found \"{rest}\")")),
        "screenshot" if rest.is_empty() => Err(format!("\"{line}\": write screenshot PATH")),
        "screenshot" => Ok(Some(ScriptCommand::Screenshot(PathBuf::from(rest)))),
        "param" => {
            let (key, value) = rest
                .split_once(char::is_whitespace)
                .ok_or_else(|| format!("\"{line}\": write param PASS.NAME VALUE"))?;
            let (pass, name) = key.split_once('.').ok_or_else(|| format!("\"{line}\": \"{key}\" is not PASS.NAME"))?;
            let value = ron::from_str::<ron::Value>(value.trim())
                .map_err(|e| format!("\"{line}\": the value \"{}\" is not one RON value ({})", value.trim(), e.code))?;
            Ok(Some(ScriptCommand::Param { pass: pass.to_string(), name: name.to_string(), value }))
        }
        other => Err(format!("\"{line}\": unknown command \"{other}\"; known: {USAGE}")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_parse_whole() {
        assert_eq!(parse_line("  quit "), Ok(Some(ScriptCommand::Quit)));
        assert_eq!(parse_line(""), Ok(None));
        assert_eq!(parse_line("write"), Ok(Some(ScriptCommand::Write)));
        assert!(parse_line("write now").is_err());
        assert_eq!(
            parse_line("screenshot my shots/a.png"),
            Ok(Some(ScriptCommand::Screenshot(PathBuf::from("my shots/a.png"))))
        );
        assert_eq!(
            parse_line("param march.step_voxels 0.75"),
            Ok(Some(ScriptCommand::Param {
                pass: "march".into(),
                name: "step_voxels".into(),
                value: ron::from_str("0.75").expect("a number")
            }))
        );
    }

    /// Issue 19: trailing text after a command was ignored.
    #[test]
    fn trailing_text_is_an_error() {
        for (line, expected) in [
            ("quit now", "quit takes nothing after it (found \"now\")"),
            ("param march.step_voxels 0.5 1.0", "is not one RON value"),
            ("param march 0.5", "\"march\" is not PASS.NAME"),
            ("screenshot", "write screenshot PATH"),
            ("qiut", "unknown command \"qiut\""),
        ] {
            let err = parse_line(line).expect_err(line);
            assert!(err.contains(expected), "{line}: {err}");
        }
    }
}
