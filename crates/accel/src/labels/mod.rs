//! Label maps and their tables (issue "several volumes", items 3 and 6): what a segmentation's
//! integer values mean — a name, a colour, an opacity, whether it is shown — read from the
//! tables the tools users segment with write, and the census of a label map (voxels and
//! physical volume per label).
//!
//! - [`itksnap`]: ITK-SNAP's label description file (`IDX R G B A VIS MSH "LABEL"`).
//! - [`slicer`]: 3D Slicer's colour table (`.ctbl`, `.txt`: `value name R G B A`).
//! - [`slicer_seg`]: the segment names and colours a 3D Slicer segmentation (`.seg.nrrd`) keeps in
//!   its header.
//! - [`census`]: the labels a volume holds, counted.
//! - [`sample`]: a label map sampled without mixing label numbers (nearest, smooth indicators).
//! - [`cubes`]: where a label map holds one label, per block (a march reads nothing there).
//! - [`LabelTable::default_for`]: a palette with the map's own values where there is no table.
//!
//! A table names labels by value; a value without an entry takes [`default_label`] (and the
//! caller says so once). Value 0 is the background: transparent unless a table says otherwise.

pub mod census;
pub mod cubes;
pub mod itksnap;
pub mod sample;
pub mod slicer;
pub mod slicer_seg;

use std::collections::BTreeMap;
use std::path::Path;

/// One label: what value `value` of a label map stands for.
#[derive(Clone, Debug, PartialEq)]
pub struct Label {
    /// The name a table gives it (or `Label N`).
    pub name: String,
    /// Colour, the sRGB bytes the table writes.
    pub rgb: [u8; 3],
    /// Opacity 0..1.
    pub opacity: f32,
    /// Whether it is shown.
    pub visible: bool,
}

/// The labels of a map by value.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LabelTable {
    /// Entries by label value.
    pub labels: BTreeMap<u32, Label>,
    /// Where the table came from (a file, or "default palette").
    pub source: String,
}

/// A table file that cannot be read: the file, the line (1-based) and what is wrong there.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum LabelTableError {
    /// A line that is not an entry of the format.
    #[error("{file}:{line}: {message}")]
    Line {
        /// The table file.
        file: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong and how to fix it.
        message: String,
    },
    /// The file cannot be read, or is no table of a known format.
    #[error("{file}: {message}")]
    File {
        /// The table file.
        file: String,
        /// What is wrong and how to fix it.
        message: String,
    },
}

/// One entry line of a table file, split into fields, whose errors name the file and the line.
pub(crate) struct Entry<'a> {
    file: &'a str,
    line: usize,
    /// The whitespace-separated fields.
    pub fields: Vec<&'a str>,
}

impl<'a> Entry<'a> {
    /// The entry lines of `text`: blank lines and `#` comments skipped, fields split on white space.
    pub fn lines(file: &'a str, text: &'a str) -> impl Iterator<Item = (Entry<'a>, &'a str)> {
        text.lines().enumerate().filter_map(move |(i, line)| {
            let line = line.trim();
            (!line.is_empty() && !line.starts_with('#'))
                .then(|| (Entry { file, line: i + 1, fields: line.split_whitespace().collect() }, line))
        })
    }

    /// An error at this line.
    pub fn error(&self, message: String) -> LabelTableError {
        LabelTableError::Line { file: self.file.to_string(), line: self.line, message }
    }

    /// Field `k` as a label value.
    pub fn value(&self, k: usize) -> Result<u32, LabelTableError> {
        self.fields[k]
            .parse()
            .map_err(|_| self.error(format!("label value \"{}\" is not a whole number 0..4294967295", self.fields[k])))
    }

    /// Field `k` as a colour byte, named `what` in the error.
    pub fn byte(&self, k: usize, what: &str) -> Result<u8, LabelTableError> {
        self.fields[k]
            .parse()
            .map_err(|_| self.error(format!("{what} \"{}\" is not a whole number 0..255", self.fields[k])))
    }
}

/// The colour of label `value` where no table names it: value 0 (background) is black and
/// hidden; others walk the hue circle by the golden angle, so neighbouring values differ.
pub fn default_label(value: u32) -> Label {
    if value == 0 {
        return Label { name: "background".to_string(), rgb: [0, 0, 0], opacity: 0.0, visible: false };
    }
    let hue = (value as f64 * 137.507_764_050_037_9).rem_euclid(360.0);
    Label { name: format!("Label {value}"), rgb: hsv_bytes(hue, 0.65, 0.95), opacity: 1.0, visible: true }
}

/// HSV (hue in degrees, s and v in 0..1) as RGB bytes.
fn hsv_bytes(hue: f64, s: f64, v: f64) -> [u8; 3] {
    let c = v * s;
    let h = hue / 60.0;
    let x = c * (1.0 - (h.rem_euclid(2.0) - 1.0).abs());
    let (r, g, b) = match h as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    [r, g, b].map(|t| ((t + m) * 255.0).round().clamp(0.0, 255.0) as u8)
}

/// Whether the volume file `path` names its own labels (a 3D Slicer `.seg.nrrd`, a DICOM SEG
/// file): its table is read from it where no other is given.
pub fn names_its_labels(path: &Path) -> bool {
    slicer_seg::is_seg_nrrd(path) || crate::load::dicom::seg::is_seg_file(path)
}

impl LabelTable {
    /// The default palette for the values `values` (a map's census), each [`default_label`].
    pub fn default_for(values: impl IntoIterator<Item = u32>) -> Self {
        Self {
            labels: values.into_iter().map(|v| (v, default_label(v))).collect(),
            source: "default palette".to_string(),
        }
    }

    /// The label of `value`: the table's entry, else [`default_label`].
    pub fn label(&self, value: u32) -> Label {
        self.labels.get(&value).cloned().unwrap_or_else(|| default_label(value))
    }

    /// Reads a table file, its format told by its text: ITK-SNAP's (entries with a quoted
    /// label, or its header comment) or 3D Slicer's colour table (`value name R G B A`); or the
    /// segments a segmentation names: a 3D Slicer `.seg.nrrd`'s header, a DICOM SEG's
    /// SegmentSequence ([`names_its_labels`]). Notes (segments
    /// left out) come back beside the table.
    pub fn read(path: &Path) -> Result<(Self, Vec<String>), LabelTableError> {
        let file = path.display().to_string();
        if crate::load::dicom::seg::is_seg_file(path) {
            let segments = crate::load::dicom::seg::segments(path)
                .map_err(|e| LabelTableError::File { file: file.clone(), message: e.to_string() })?;
            return Ok((crate::load::dicom::seg::table(path, &segments), Vec::new()));
        }
        if slicer_seg::is_seg_nrrd(path) {
            let pairs = crate::load::nrrd_key_values(path).map_err(|e| LabelTableError::File {
                file: file.clone(),
                message: format!("cannot read its header ({e})"),
            })?;
            return slicer_seg::table_from_pairs(&file, &pairs);
        }
        // The project's one bounded reader of a user's text file: refuses a FIFO, a device or a
        // folder, stops at its size limit, requires UTF-8.
        let text = crate::input_file::read_text(path, "label table").map_err(|e| LabelTableError::File {
            file: file.clone(),
            message: format!("cannot read the label table ({e})"),
        })?;
        Ok((Self::parse(&file, &text)?, Vec::new()))
    }

    /// [`Self::read`] of `text`, named `file` in messages.
    pub fn parse(file: &str, text: &str) -> Result<Self, LabelTableError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        if itksnap::looks_like(text) { itksnap::parse(file, text) } else { slicer::parse(file, text) }
    }

    /// The table as a LUT by label value for values `0..len`: straight colour (the bytes / 255)
    /// and opacity, 0 where a label is hidden; values without an entry take [`default_label`].
    /// What a graph's `LabelTable` input holds (the GPU reads texel `v`; opacity is per voxel
    /// unit of the frame volume, like a TF's).
    pub fn lut(&self, len: usize) -> Vec<[f32; 4]> {
        (0..len as u32)
            .map(|v| {
                let l = self.label(v);
                let a = if l.visible { l.opacity.clamp(0.0, 1.0) } else { 0.0 };
                [l.rgb[0] as f32 / 255.0, l.rgb[1] as f32 / 255.0, l.rgb[2] as f32 / 255.0, a]
            })
            .collect()
    }

    /// Values the table names that `present` (a map's census) lacks, for the one note a caller
    /// gives ("the table names labels the map lacks").
    pub fn missing_from(&self, present: &[u32]) -> Vec<u32> {
        self.labels.keys().copied().filter(|v| *v != 0 && present.binary_search(v).is_err()).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_palette_hides_the_background_and_tells_neighbours_apart() {
        let background = default_label(0);
        assert!(!background.visible && background.opacity == 0.0);
        let (a, b) = (default_label(1), default_label(2));
        assert!(a.visible && b.visible);
        let distance: i32 = a.rgb.iter().zip(b.rgb).map(|(x, y)| (*x as i32 - y as i32).abs()).sum();
        assert!(distance > 100, "labels 1 and 2 look alike: {:?} {:?}", a.rgb, b.rgb);
        assert_eq!(default_label(65_535).name, "Label 65535");
    }

    #[test]
    fn the_format_is_told_by_the_text() {
        let itk = LabelTable::parse("a.txt", "    1   255    0    0        1  1  1    \"Liver\"\n").expect("itk-snap");
        assert_eq!(itk.labels[&1].name, "Liver");
        let slicer =
            LabelTable::parse("b.ctbl", "# Color table file b.ctbl\n1 liver 221 130 101 255\n").expect("slicer");
        assert_eq!(slicer.labels[&1].name, "liver");
        assert_eq!(slicer.missing_from(&[0, 2]), [1]);
    }
}
