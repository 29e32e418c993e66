//! The names and colours of a 3D Slicer segmentation file (`.seg.nrrd`): Slicer writes each
//! segment into the NRRD header as `key:=value` pairs,
//!
//! ```text
//! Segment0_Name:=liver
//! Segment0_Color:=0.866667 0.509804 0.396078
//! Segment0_LabelValue:=1
//! Segment0_Layer:=0
//! ```
//!
//! (colour components 0..1; `LabelValue` the voxel value of the segment in its layer). Segments of
//! layer 0 are read; a segmentation with overlapping segments keeps more layers, which a label map
//! of one value a voxel cannot hold — they are left out with a note.

use std::collections::BTreeMap;

use super::{Label, LabelTable, LabelTableError};

/// The segments of a `.seg.nrrd` header's `pairs` (`(line, key, value)`, from
/// `load::nrrd_key_values`), as a table, and notes (segments of other layers left out). `file`
/// names the file in messages.
pub fn table_from_pairs(
    file: &str,
    pairs: &[(usize, String, String)],
) -> Result<(LabelTable, Vec<String>), LabelTableError> {
    // Segment index → its fields (value and the line it is on).
    let mut segments: BTreeMap<u32, BTreeMap<&str, (&str, usize)>> = BTreeMap::new();
    for (line, key, value) in pairs {
        let Some(rest) = key.strip_prefix("Segment") else { continue };
        let Some((index, field)) = rest.split_once('_') else { continue };
        let Ok(index) = index.parse::<u32>() else { continue };
        segments.entry(index).or_default().insert(field, (value.as_str(), *line));
    }
    let mut table = LabelTable { labels: BTreeMap::new(), source: file.to_string() };
    let mut other_layers = 0;
    for (index, fields) in &segments {
        let at = |line: usize, message: String| LabelTableError::Line { file: file.to_string(), line, message };
        let first_line = fields.values().map(|(_, l)| *l).min().unwrap_or(0);
        let layer = match fields.get("Layer") {
            Some((v, line)) => v
                .trim()
                .parse::<u32>()
                .map_err(|_| at(*line, format!("Segment{index}_Layer \"{v}\" is not a whole number")))?,
            None => 0,
        };
        if layer != 0 {
            other_layers += 1;
            continue;
        }
        let (value, line) = fields.get("LabelValue").copied().ok_or_else(|| {
            at(first_line, format!("Segment{index} has no Segment{index}_LabelValue; it is no segment of a label map"))
        })?;
        let value: u32 = value
            .trim()
            .parse()
            .map_err(|_| at(line, format!("Segment{index}_LabelValue \"{value}\" is not a whole number")))?;
        let name = fields.get("Name").map_or_else(|| format!("Segment {index}"), |(v, _)| v.trim().to_string());
        let rgb = match fields.get("Color") {
            Some((v, line)) => {
                let parts: Vec<f64> = v.split_whitespace().filter_map(|c| c.parse().ok()).collect();
                if parts.len() != 3 || parts.iter().any(|c| !(0.0..=1.0).contains(c)) {
                    return Err(at(*line, format!("Segment{index}_Color \"{v}\" is not three numbers 0..1")));
                }
                [0, 1, 2].map(|k| (parts[k] * 255.0).round() as u8)
            }
            None => super::default_label(value).rgb,
        };
        if table.labels.insert(value, Label { name, rgb, opacity: 1.0, visible: true }).is_some() {
            return Err(at(line, format!("label value {value} is given to two segments of layer 0")));
        }
    }
    if segments.is_empty() {
        return Err(LabelTableError::File {
            file: file.to_string(),
            message: "no Segment*_ keys in its header: not a 3D Slicer segmentation (.seg.nrrd)".to_string(),
        });
    }
    let mut notes = Vec::new();
    if other_layers > 0 {
        notes.push(format!(
            "{file}: {other_layers} segment{} of other layers (overlapping segments) left out; only layer 0 is a label map",
            if other_layers == 1 { "" } else { "s" }
        ));
    }
    Ok((table, notes))
}

/// Whether `path` names a Slicer segmentation (`.seg.nrrd`).
pub fn is_seg_nrrd(path: &std::path::Path) -> bool {
    path.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.to_ascii_lowercase().ends_with(".seg.nrrd"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pairs(text: &str) -> Vec<(usize, String, String)> {
        text.lines()
            .enumerate()
            .filter_map(|(i, l)| l.split_once(":=").map(|(k, v)| (i + 1, k.to_string(), v.to_string())))
            .collect()
    }

    #[test]
    fn a_segmentation_header_gives_names_colours_and_values() {
        let header = "Segment0_Color:=0.866667 0.509804 0.396078\nSegment0_ID:=Segment_1\nSegment0_LabelValue:=1\n\
                      Segment0_Layer:=0\nSegment0_Name:=liver\nSegment1_Color:=0.2 0.4 1\nSegment1_LabelValue:=7\n\
                      Segment1_Name:=portal vein\nSegment2_LabelValue:=1\nSegment2_Layer:=1\nSegment2_Name:=tumour\n\
                      Segmentation_MasterRepresentation:=Binary labelmap\n";
        let (table, notes) = table_from_pairs("s.seg.nrrd", &pairs(header)).expect("reads");
        assert_eq!(table.labels.len(), 2);
        assert_eq!(table.labels[&1], Label { name: "liver".into(), rgb: [221, 130, 101], opacity: 1.0, visible: true });
        assert_eq!(table.labels[&7].name, "portal vein");
        assert_eq!(table.labels[&7].rgb, [51, 102, 255]);
        assert_eq!(
            notes,
            ["s.seg.nrrd: 1 segment of other layers (overlapping segments) left out; only layer 0 is a label map"]
        );
    }

    #[test]
    fn a_bad_segment_key_names_its_line() {
        let err = table_from_pairs("s.seg.nrrd", &pairs("Segment0_Name:=a\nSegment0_LabelValue:=x\n")).expect_err("x");
        assert_eq!(err.to_string(), "s.seg.nrrd:2: Segment0_LabelValue \"x\" is not a whole number");
        let err =
            table_from_pairs("s.seg.nrrd", &pairs("Segment0_LabelValue:=1\nSegment0_Color:=1 2 3\n")).expect_err("2");
        assert!(err.to_string().starts_with("s.seg.nrrd:2: Segment0_Color \"1 2 3\""), "{err}");
        let err = table_from_pairs("s.seg.nrrd", &pairs("Segment0_Name:=a\n")).expect_err("no value");
        assert!(err.to_string().contains("has no Segment0_LabelValue"), "{err}");
        assert!(table_from_pairs("plain.nrrd", &pairs("foo:=bar\n")).is_err());
    }
}
