//! ITK-SNAP's label description file, as its "Label Editor → Export" writes it: `#` comment lines
//! (a header naming the fields), then one label a line,
//!
//! ```text
//!     1   255    0    0        1  1  1    "Liver"
//! ```
//!
//! — value, red, green, blue (0..255), opacity (0..1), visibility (0/1), mesh visibility (0/1)
//! and the description in double quotes (which may hold spaces).

use super::{Entry, Label, LabelTable, LabelTableError};

/// Whether `text` is ITK-SNAP's format: its header comment, or an entry ending in a quoted label.
pub fn looks_like(text: &str) -> bool {
    text.lines().any(|l| {
        let l = l.trim();
        l.contains("ITK-SnAP Label Description") || (!l.starts_with('#') && l.ends_with('"') && l.contains(" \""))
    })
}

/// Parses the file's `text` (named `file` in messages).
pub fn parse(file: &str, text: &str) -> Result<LabelTable, LabelTableError> {
    let mut table = LabelTable { labels: Default::default(), source: file.to_string() };
    for (entry, line) in Entry::lines(file, text) {
        let (fields, name) = match line.find('"') {
            Some(q) => {
                let rest = &line[q + 1..];
                let end = rest
                    .rfind('"')
                    .ok_or_else(|| entry.error("the label's description has no closing \"".to_string()))?;
                (&line[..q], rest[..end].to_string())
            }
            None => {
                return Err(entry.error("no quoted description; an entry is IDX R G B A VIS MSH \"LABEL\"".to_string()));
            }
        };
        // The numbers before the quoted description.
        let entry = Entry { fields: fields.split_whitespace().collect(), ..entry };
        if entry.fields.len() != 7 {
            return Err(entry.error(format!(
                "{} fields before the description, ITK-SNAP writes 7: IDX R G B A VIS MSH \"LABEL\"",
                entry.fields.len()
            )));
        }
        let numbers = &entry.fields;
        let at = |message: String| entry.error(message);
        let value = entry.value(0)?;
        let rgb = [entry.byte(1, "red")?, entry.byte(2, "green")?, entry.byte(3, "blue")?];
        let opacity: f32 = numbers[4]
            .parse()
            .ok()
            .filter(|a: &f32| (0.0..=1.0).contains(a))
            .ok_or_else(|| at(format!("opacity \"{}\" is not a number 0..1", numbers[4])))?;
        let flag = |k: usize, what: &str| match numbers[k] {
            "0" => Ok(false),
            "1" => Ok(true),
            other => Err(at(format!("{what} \"{other}\" is not 0 or 1"))),
        };
        let visible = flag(5, "visibility")?;
        flag(6, "mesh visibility")?;
        if table.labels.insert(value, Label { name, rgb, opacity, visible }).is_some() {
            return Err(at(format!("label {value} is described twice; keep one line for it")));
        }
    }
    if table.labels.is_empty() {
        return Err(LabelTableError::File {
            file: file.to_string(),
            message: "no label entries (IDX R G B A VIS MSH \"LABEL\" lines)".to_string(),
        });
    }
    Ok(table)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The header and first entries of the file ITK-SNAP 4 exports, written out here.
    const EXPORTED: &str = "################################################
# ITK-SnAP Label Description File
# File format: 
# IDX   -R-  -G-  -B-  -A--  VIS MSH  LABEL
# Fields: 
#    IDX:   Zero-based index 
#    -R-:   Red color component (0..255)
#    -G-:   Green color component (0..255)
#    -B-:   Blue color component (0..255)
#    -A-:   Label transparency (0.00 .. 1.00)
#    VIS:   Label visibility (0 or 1)
#    MSH:   Label mesh visibility (0 or 1)
#  LABEL:   Label description 
################################################
    0     0    0    0        0  0  0    \"Clear Label\"
    1   255    0    0        1  1  1    \"Label 1\"
    2     0  255    0      0.5  1  1    \"left kidney\"
   17    10   20   30        1  0  1    \"portal vein\"
";

    #[test]
    fn an_exported_file_gives_every_label() {
        let table = parse("labels.txt", EXPORTED).expect("parses");
        assert_eq!(table.labels.len(), 4);
        assert_eq!(
            table.labels[&0],
            Label { name: "Clear Label".into(), rgb: [0, 0, 0], opacity: 0.0, visible: false }
        );
        assert_eq!(table.labels[&2].name, "left kidney");
        assert_eq!(table.labels[&2].opacity, 0.5);
        assert_eq!(table.labels[&17].rgb, [10, 20, 30]);
        assert!(!table.labels[&17].visible);
        assert!(looks_like(EXPORTED));
    }

    #[test]
    fn a_bad_line_is_named_with_its_number_and_the_fix() {
        let cases = [
            ("    1   256    0    0        1  1  1    \"x\"", "labels.txt:1: red \"256\" is not a whole number 0..255"),
            ("    1   255    0    0        1.5  1  1    \"x\"", "labels.txt:1: opacity \"1.5\" is not a number 0..1"),
            ("    1   255    0    0        1  2  1    \"x\"", "labels.txt:1: visibility \"2\" is not 0 or 1"),
            ("    1   255    0    0        1  1    \"x\"", "labels.txt:1: 6 fields before the description"),
            ("    1   255    0    0        1  1  1    Liver", "labels.txt:1: no quoted description"),
            ("   -1   255    0    0        1  1  1    \"x\"", "labels.txt:1: label value \"-1\""),
        ];
        for (line, want) in cases {
            let err = parse("labels.txt", line).expect_err(line).to_string();
            assert!(err.starts_with(want), "{line}: {err}");
        }
        let twice = "1 1 2 3 1 1 1 \"a\"\n# comment\n1 4 5 6 1 1 1 \"b\"\n";
        assert_eq!(
            parse("t.txt", twice).expect_err("twice").to_string(),
            "t.txt:3: label 1 is described twice; keep one line for it"
        );
        assert!(parse("t.txt", "# only a header\n").is_err());
    }
}
