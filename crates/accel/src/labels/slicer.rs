//! 3D Slicer's colour table (`.ctbl`, `.txt`: Colors module → export, and the tables it ships
//! such as `GenericAnatomyColors.txt`): `#` comment lines, then one entry a line,
//!
//! ```text
//! 1 liver 221 130 101 255
//! ```
//!
//! — value, name (one word: Slicer writes spaces as `_`), red, green, blue, alpha (0..255).
//! Columns after the sixth (terminology codes of newer tables) are not read.

use super::{Entry, Label, LabelTable, LabelTableError};

/// Parses the file's `text` (named `file` in messages).
pub fn parse(file: &str, text: &str) -> Result<LabelTable, LabelTableError> {
    let mut table = LabelTable { labels: Default::default(), source: file.to_string() };
    for (entry, _) in Entry::lines(file, text) {
        if entry.fields.len() < 6 {
            return Err(entry.error(format!(
                "{} fields; a colour table entry is `value name R G B A` (an ITK-SNAP label file quotes its names)",
                entry.fields.len()
            )));
        }
        let value = entry.value(0)?;
        let rgb = [entry.byte(2, "red")?, entry.byte(3, "green")?, entry.byte(4, "blue")?];
        let alpha = entry.byte(5, "alpha")?;
        let label = Label {
            name: entry.fields[1].replace('_', " "),
            rgb,
            opacity: f32::from(alpha) / 255.0,
            visible: alpha > 0,
        };
        if table.labels.insert(value, label).is_some() {
            return Err(entry.error(format!("label {value} is listed twice; keep one line for it")));
        }
    }
    if table.labels.is_empty() {
        return Err(LabelTableError::File {
            file: file.to_string(),
            message: "no colour table entries (`value name R G B A` lines); give an ITK-SNAP label description file \
                      or a 3D Slicer colour table"
                .to_string(),
        });
    }
    Ok(table)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_slicer_table_gives_names_colours_and_opacity() {
        let text = "# Color table file /tmp/organs.ctbl\n# 4 values\n0 background 0 0 0 0\n1 liver 221 130 101 255\n\
                    2 left_kidney 185 102 83 128\n5 spleen 157 108 162 255 SCT^78961009^Spleen extra\n";
        let table = parse("organs.ctbl", text).expect("parses");
        assert_eq!(table.labels.len(), 4);
        assert!(!table.labels[&0].visible);
        assert_eq!(table.labels[&1], Label { name: "liver".into(), rgb: [221, 130, 101], opacity: 1.0, visible: true });
        assert_eq!(table.labels[&2].name, "left kidney");
        assert!((table.labels[&2].opacity - 128.0 / 255.0).abs() < 1e-6);
        assert_eq!(table.labels[&5].name, "spleen");
    }

    #[test]
    fn a_bad_entry_is_named_with_its_line() {
        for (text, want) in [
            ("1 liver 221 130 101", "t.ctbl:1: 5 fields"),
            ("# c\n1 liver 300 130 101 255", "t.ctbl:2: red \"300\""),
            ("x liver 1 2 3 4", "t.ctbl:1: label value \"x\""),
            ("1 a 1 2 3 4\n1 b 1 2 3 4", "t.ctbl:2: label 1 is listed twice"),
        ] {
            let err = parse("t.ctbl", text).expect_err(text).to_string();
            assert!(err.starts_with(want), "{text}: {err}");
        }
        assert!(parse("t.ctbl", "# nothing\n").expect_err("empty").to_string().contains("no colour table entries"));
    }
}
