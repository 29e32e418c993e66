//! `volgraph view --script`: the lines read from stdin, parsed whole. A line is one command;
//! anything after it is an error, never silently dropped (`quit now` is not `quit`).

use std::path::PathBuf;

use volgraph_accel::cuts::{ClipPlane, CropBox};
use volgraph_accel::transfer_function::ControlPoint;

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
    /// `crop X0,Y0,Z0,X1,Y1,Z1` or `crop off`: the panel's crop box.
    Crop(Option<CropBox>),
    /// `clip NX,NY,NZ,D` (one plane, replacing any) or `clip off`.
    Clip(Option<ClipPlane>),
    /// `save-scene PATH`: the panel's "save view" (camera, crop, clip, TF, effects) to a scene file.
    SaveScene(PathBuf),
    /// `tf-point VALUE R,G,B,A`: the TF editor's point at data value VALUE (linear colour,
    /// opacity), replacing one at the same value.
    TfPoint(ControlPoint),
    /// `tf-save`: the TF editor's "save TF".
    TfSave,
    /// `tf-edit INPUT`: the TF editor edits the transfer-function input INPUT (`pet_tf`: one
    /// editor per scalar volume).
    TfEdit(String),
    /// `light AZ,EL` or `light headlight`: the panel's light.
    Light(volgraph_accel::light::Light),
    /// `slices on|off`: open or close the slice panes.
    Slices(bool),
    /// `window CENTER,WIDTH`: the slice panes' window in data units.
    SliceWindow(volgraph_accel::volume_meta::Window),
    /// `click X Y`: a left click at window pixel (X, Y).
    Click(f64, f64),
    /// `wheel X Y LINES`: the wheel turned LINES notches at window pixel (X, Y).
    Wheel(f64, f64, f64),
    /// `label VALUE show|hide|only` or `label all`: the label list's visibility switches.
    Label(super::label_list::LabelEdit),
}

/// What the script accepts, for messages.
pub const USAGE: &str = "quit, screenshot PATH, param PASS.NAME VALUE, write, crop X0,Y0,Z0,X1,Y1,Z1|off, clip NX,NY,NZ,D|off, save-scene PATH, tf-point VALUE R,G,B,A, tf-save, tf-edit INPUT, light AZ,EL|headlight, slices on|off, window CENTER,WIDTH, click X Y, wheel X Y LINES, label VALUE show|hide|only, label all";

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
        "tf-save" if rest.is_empty() => Ok(Some(ScriptCommand::TfSave)),
        "tf-save" => Err(format!("\"{line}\": tf-save takes nothing after it (found \"{rest}\")")),
        "tf-edit" if rest.is_empty() || rest.contains(char::is_whitespace) => {
            Err(format!("\"{line}\": write tf-edit INPUT (a transfer-function input of the graph, e.g. pet_tf)"))
        }
        "tf-edit" => Ok(Some(ScriptCommand::TfEdit(rest.to_string()))),
        "light" => volgraph_accel::light::Light::parse(rest)
            .map(|l| Some(ScriptCommand::Light(l)))
            .map_err(|e| format!("\"{line}\": {e}")),
        "tf-point" => {
            let bad =
                || format!("\"{line}\": write tf-point VALUE R,G,B,A (data value; linear colour and opacity in 0..1)");
            let (value, rgba) = rest.split_once(char::is_whitespace).ok_or_else(bad)?;
            let value: f64 = value.parse().ok().filter(|v: &f64| v.is_finite()).ok_or_else(bad)?;
            let parts: Vec<f64> =
                rgba.trim().split(',').map(|p| p.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|_| bad())?;
            match parts.as_slice() {
                [r, g, b, a] if [*r, *g, *b, *a].iter().all(|c| (0.0..=1.0).contains(c)) => {
                    Ok(Some(ScriptCommand::TfPoint(ControlPoint { value, color: [*r, *g, *b], alpha: *a })))
                }
                _ => Err(bad()),
            }
        }
        "slices" => match rest {
            "on" => Ok(Some(ScriptCommand::Slices(true))),
            "off" => Ok(Some(ScriptCommand::Slices(false))),
            _ => Err(format!("\"{line}\": write slices on or slices off")),
        },
        "window" => {
            let bad = || format!("\"{line}\": write window CENTER,WIDTH (data units, width > 0), e.g. window 40,400");
            let parts = finite_numbers(rest, ',').ok_or_else(bad)?;
            match parts.as_slice() {
                [center, width] if *width > 0.0 => {
                    Ok(Some(ScriptCommand::SliceWindow(volgraph_accel::volume_meta::Window {
                        center: *center,
                        width: *width,
                    })))
                }
                _ => Err(bad()),
            }
        }
        "click" => match finite_numbers(rest, ' ').as_deref() {
            Some([x, y]) => Ok(Some(ScriptCommand::Click(*x, *y))),
            _ => Err(format!("\"{line}\": write click X Y (window pixels)")),
        },
        "wheel" => match finite_numbers(rest, ' ').as_deref() {
            Some([x, y, lines]) => Ok(Some(ScriptCommand::Wheel(*x, *y, *lines))),
            _ => Err(format!("\"{line}\": write wheel X Y LINES (window pixels, notches: + up)")),
        },
        "save-scene" if rest.is_empty() => Err(format!("\"{line}\": write save-scene PATH")),
        "save-scene" => Ok(Some(ScriptCommand::SaveScene(PathBuf::from(rest)))),
        "crop" if rest == "off" => Ok(Some(ScriptCommand::Crop(None))),
        "crop" => {
            CropBox::parse(rest).map(|c| Some(ScriptCommand::Crop(Some(c)))).map_err(|e| format!("\"{line}\": {e}"))
        }
        "clip" if rest == "off" => Ok(Some(ScriptCommand::Clip(None))),
        "clip" => {
            ClipPlane::parse(rest).map(|p| Some(ScriptCommand::Clip(Some(p)))).map_err(|e| format!("\"{line}\": {e}"))
        }
        "label" => {
            use super::label_list::LabelEdit;
            let words: Vec<&str> = rest.split_whitespace().collect();
            match words.as_slice() {
                ["all"] => Ok(Some(ScriptCommand::Label(LabelEdit::ShowAll))),
                [value, what] => {
                    let value: u32 = value.parse().map_err(|_| {
                        format!("\"{line}\": the label value must be a whole number 0 to 4294967295, not \"{value}\"")
                    })?;
                    match *what {
                        "show" => Ok(Some(ScriptCommand::Label(LabelEdit::Visible(value, true)))),
                        "hide" => Ok(Some(ScriptCommand::Label(LabelEdit::Visible(value, false)))),
                        "only" => Ok(Some(ScriptCommand::Label(LabelEdit::ShowOnly(value)))),
                        _ => Err(format!("\"{line}\": write label VALUE show|hide|only, or label all")),
                    }
                }
                _ => Err(format!("\"{line}\": write label VALUE show|hide|only, or label all")),
            }
        }
        other => Err(format!("\"{line}\": unknown command \"{other}\"; known: {USAGE}")),
    }
}

/// `text` split at `separator` (runs of spaces count once) as finite numbers; `None` if any is
/// not one.
fn finite_numbers(text: &str, separator: char) -> Option<Vec<f64>> {
    text.split(separator)
        .map(str::trim)
        .filter(|p| !(separator == ' ' && p.is_empty()))
        .map(|p| p.parse::<f64>().ok().filter(|v| v.is_finite()))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_parse_whole() {
        assert_eq!(parse_line("  quit "), Ok(Some(ScriptCommand::Quit)));
        assert_eq!(parse_line(""), Ok(None));
        assert_eq!(parse_line("write"), Ok(Some(ScriptCommand::Write)));
        assert_eq!(parse_line("crop off"), Ok(Some(ScriptCommand::Crop(None))));
        assert!(matches!(parse_line("clip 1,0,0,0.5"), Ok(Some(ScriptCommand::Clip(Some(_))))));
        assert!(parse_line("write now").is_err());
        assert_eq!(parse_line("slices on"), Ok(Some(ScriptCommand::Slices(true))));
        use crate::view::label_list::LabelEdit;
        assert_eq!(parse_line("label 3 hide"), Ok(Some(ScriptCommand::Label(LabelEdit::Visible(3, false)))));
        assert_eq!(parse_line("label  7 only"), Ok(Some(ScriptCommand::Label(LabelEdit::ShowOnly(7)))));
        assert_eq!(parse_line("label all"), Ok(Some(ScriptCommand::Label(LabelEdit::ShowAll))));
        assert!(parse_line("label -1 hide").is_err() && parse_line("label 3 hidden").is_err());
        assert!(parse_line("label 3 hide now").is_err() && parse_line("label").is_err());
        assert_eq!(parse_line("click 410  20.5"), Ok(Some(ScriptCommand::Click(410.0, 20.5))));
        assert_eq!(parse_line("wheel 410 20 -3"), Ok(Some(ScriptCommand::Wheel(410.0, 20.0, -3.0))));
        let bone = volgraph_accel::volume_meta::Window { center: 400.0, width: 1800.0 };
        assert_eq!(parse_line("window 400, 1800"), Ok(Some(ScriptCommand::SliceWindow(bone))));
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
            ("slices maybe", "write slices on or slices off"),
            ("window 40", "write window CENTER,WIDTH"),
            ("window 40,-1", "write window CENTER,WIDTH"),
            ("window NaN,400", "write window CENTER,WIDTH"),
            ("click 10", "write click X Y"),
            ("wheel 1 2 inf", "write wheel X Y LINES"),
            ("crop 0,0,0,1,1", "got 5"),
            ("tf-point 40 1,0,0", "write tf-point VALUE R,G,B,A"),
            ("tf-point 40 1,0,0,2", "write tf-point VALUE R,G,B,A"),
            ("clip 0,0,0,1", "no direction"),
        ] {
            let err = parse_line(line).expect_err(line);
            assert!(err.contains(expected), "{line}: {err}");
        }
    }
}
