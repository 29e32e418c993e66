//! The transfer function being edited: the one on screen, the one its source gives (a file, a
//! preset, the fit to the data), where "save TF" writes and what it writes, and which file
//! changes are edits to reload. The histogram and presets the editor shows are computed once per
//! volume. The session uploads the LUT; nothing here needs a device.

use std::path::{Path, PathBuf};

use volgraph_accel::transfer_function::TransferFunction;
use volgraph_accel::volume::Volume;

use super::same_file;
use crate::inputs;
use crate::scene::TfSource;

/// Bins of the TF editor's histogram.
pub const HISTOGRAM_BINS: usize = 256;

/// Where "save TF" writes a TF that came from no file (fitted to the data).
pub const SAVED_TF: &str = "view.tf.ron";

/// The transfer function of a session and where it comes from.
pub struct TfEdits {
    /// The transfer function on screen (the TF editor's).
    tf: TransferFunction,
    /// The TF as its source gives it (the file's, the preset's, the fitted one): the TF on
    /// screen differs from it after an edit that is not saved.
    pristine: TransferFunction,
    /// The TF's file (watched), if it came from one.
    path: Option<PathBuf>,
    /// A ParaView colour map's name (`--tf-map`).
    map: Option<String>,
    /// Where the TF came from, for "save view" (`None`: fitted to the data).
    source: Option<TfSource>,
    /// Whether the volume is a generated Marschner–Lobb one (its own default TF).
    generated: bool,
    /// The text this viewer last wrote to the TF file: the watcher's event for it is not a
    /// reload.
    written: Option<String>,
    /// Save the TF file after every edit (the panel's toggle).
    pub save_on_change: bool,
    /// Where "save TF" writes a TF that came from no file: [`SAVED_TF`], or a named input's own
    /// (`view.pet_tf.tf.ron`).
    fitted_file: String,
    /// Voxels per bin of the volume's normalized values (the TF editor's histogram).
    histogram: Vec<u64>,
    /// The data values the histogram's ends stand for.
    value_range: (f64, f64),
    /// The TF editor's presets for this volume (computed once: MR's reads percentiles).
    presets: Vec<(&'static str, TransferFunction)>,
}

impl TfEdits {
    /// `tf` over `volume`, read from `path` (`None`: no file to watch) with colour map `map`,
    /// named `source` for "save view".
    pub fn new(
        tf: TransferFunction,
        path: Option<PathBuf>,
        map: Option<String>,
        source: Option<TfSource>,
        volume: &Volume,
        generated: bool,
    ) -> Self {
        Self {
            pristine: tf.clone(),
            tf,
            path,
            map,
            source,
            generated,
            written: None,
            save_on_change: false,
            fitted_file: SAVED_TF.to_string(),
            histogram: volgraph_accel::histogram::Histogram::of(volume, HISTOGRAM_BINS).counts,
            value_range: volume.value_range,
            presets: presets_for(volume),
        }
    }

    /// This TF saved, where it came from no file, as `view.INPUT.tf.ron` (a named input's, so two
    /// editors never write one file).
    pub fn for_input(mut self, input: &str) -> Self {
        self.fitted_file = format!("view.{input}.tf.ron");
        self
    }

    /// The transfer function on screen.
    pub fn transfer_function(&self) -> &TransferFunction {
        &self.tf
    }

    /// The TF's file, if it came from one (or was saved to one).
    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }

    /// Where the TF came from, for "save view" (`None`: fitted to the data).
    pub fn source(&self) -> Option<&TfSource> {
        self.source.as_ref()
    }

    /// The presets the TF editor offers for this volume: the general ones over its values, and
    /// the scanner presets of its modality (the CT ones in HU, MR's percentile ramp).
    pub fn presets(&self) -> &[(&'static str, TransferFunction)] {
        &self.presets
    }

    /// The volume's histogram (voxels per bin of normalized value) and the data values its
    /// ends stand for: the TF editor's backdrop, in the data's units.
    pub fn histogram(&self) -> (&[u64], (f64, f64)) {
        (&self.histogram, self.value_range)
    }

    /// Whether a TF point at data value `value` is one the editor could place: within the
    /// data's range, or one range-width beyond either end (a ramp may start outside the data).
    pub fn check_value(&self, value: f64) -> Result<(), String> {
        let (lo, hi) = self.value_range;
        let width = if hi > lo { hi - lo } else { 1.0 };
        if value.is_finite() && value >= lo - width && value <= hi + width {
            return Ok(());
        }
        Err(format!(
            "{value}: a TF point must lie within the data's values {lo}..{hi} or one range beyond ({}..{})",
            lo - width,
            hi + width
        ))
    }

    /// Whether the TF on screen is not what its source gives (an edit not saved, a preset picked
    /// in the editor), or is a colour map a scene cannot name (`--tf-map`).
    pub fn edited(&self) -> bool {
        self.tf != self.pristine || self.map.is_some()
    }

    /// Checks an edit `tf` as a file at the save path would be checked.
    pub fn validate(&self, tf: &TransferFunction) -> Result<(), String> {
        tf.validate(&self.save_path()).map_err(|e| e.to_string())
    }

    /// The edit `tf` is on screen now.
    pub fn set(&mut self, tf: TransferFunction) {
        self.tf = tf;
    }

    /// Reads the TF from its source again (the file changed), fitted to `volume` as at start.
    pub fn read(&self, volume: &Volume) -> anyhow::Result<TransferFunction> {
        inputs::transfer_function(self.path.as_ref(), self.map.as_deref(), volume, self.generated).map(|(tf, _)| tf)
    }

    /// `tf`, read from the source again, is on screen now and is what the source gives.
    pub fn reloaded(&mut self, tf: TransferFunction) {
        self.pristine = tf.clone();
        self.tf = tf;
    }

    /// Whether files `changed` on disk hold an edit of the TF's file to reload (the viewer's own
    /// save is none).
    pub fn needs_reload(&self, changed: &[PathBuf]) -> bool {
        let Some(tf) = &self.path else { return false };
        changed.iter().any(|c| same_file(c, tf))
            && (self.written.is_none()
                || volgraph_accel::input_file::read_text(tf, "transfer function").ok() != self.written)
    }

    /// Where "save TF" writes: the TF's file; for a scanner preset (`--tf ct-bone`)
    /// `NAME.tf.ron` in the current folder (a name `--tf NAME` never reads in the preset's place);
    /// for a fitted TF `view.tf.ron` (a named input's `view.INPUT.tf.ron`) there. The TF's own file is returned as `--tf` gave it
    /// (relative to the current folder where it was given so, the path the viewer watches); the
    /// preset's and the fitted TF's new files are made absolute, so the "saved" line says where
    /// they went.
    pub fn save_path(&self) -> PathBuf {
        let path = match (&self.path, &self.source) {
            (Some(path), _) => return path.clone(),
            // A preset, or a built-in TF's name (`graphs/tf/vessels.ron` where no such file is).
            (None, Some(TfSource::Preset(name) | TfSource::File(name) | TfSource::BuiltIn(name))) => {
                let stem = Path::new(name).file_name().map_or(String::new(), |n| n.to_string_lossy().into_owned());
                PathBuf::from(format!("{}.tf.ron", stem.strip_suffix(".ron").unwrap_or(&stem)))
            }
            (None, _) => PathBuf::from(&self.fitted_file),
        };
        std::env::current_dir().map_or(path.clone(), |dir| dir.join(path))
    }

    /// The text "save TF" writes to `path`: RON, or ParaView JSON where the file is one (with
    /// the file's other maps kept).
    pub fn save_text(&self, path: &Path) -> String {
        if !path.extension().is_some_and(|e| e.eq_ignore_ascii_case("json")) {
            return self.tf.to_ron_string();
        }
        let original = volgraph_accel::input_file::read_text(path, "transfer function").ok();
        let index = match (&original, self.map.as_deref()) {
            (Some(text), Some(name)) => serde_json::from_str::<serde_json::Value>(text)
                .ok()
                .and_then(|v| v.as_array().and_then(|maps| maps.iter().position(|m| m["Name"] == name)))
                .unwrap_or(0),
            _ => 0,
        };
        self.tf.to_paraview_json(original.as_deref(), index)
    }

    /// Saves the TF to its file as it came, or where [`Self::save_path`] says for a preset or a
    /// fitted TF (which is then the TF's file, watched); atomic. `volume` is what a ParaView
    /// map's file is read back over.
    pub fn save(&mut self, volume: &Volume) -> anyhow::Result<PathBuf> {
        let path = self.save_path();
        let text = self.save_text(&path);
        crate::atomic_write::write_atomically(&path, &text)?;
        self.written = Some(text);
        self.path = Some(path.clone());
        self.source = Some(TfSource::File(path.display().to_string()));
        // What the file gives back (a ParaView map's colours pass through sRGB): a view saved
        // now refers to the file only if it draws the TF on screen.
        self.pristine = self.read(volume).unwrap_or_else(|_| self.pristine.clone());
        Ok(path)
    }
}

/// The general presets over `volume`'s values and the scanner presets of its modality.
fn presets_for(volume: &Volume) -> Vec<(&'static str, TransferFunction)> {
    use volgraph_accel::transfer_function::{Preset, ScannerPreset};
    let mut out: Vec<(&'static str, TransferFunction)> =
        Preset::ALL.iter().map(|p| (p.name(), TransferFunction::preset(*p, volume.value_range))).collect();
    let modality = volume.meta.modality.as_deref().unwrap_or("");
    for preset in ScannerPreset::ALL {
        let fits =
            if preset.is_ct() { modality.eq_ignore_ascii_case("CT") } else { modality.eq_ignore_ascii_case("MR") };
        if fits {
            out.push((preset.name(), preset.for_volume(volume)));
        }
    }
    out
}
