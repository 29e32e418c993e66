//! The session's transfer function — the TF editor's edits, "save TF", reloads of its file —
//! and "save view", which must save the TF on screen.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::anyhow;
use volgraph_accel::transfer_function::TransferFunction;
use volgraph_accel::volume::Volume;
use volgraph_core::cut_effects;

use super::{Event, LiveSession};
use crate::inputs;

impl LiveSession {
    /// The transfer-function file changed: read it and upload the new LUT (history restarts:
    /// Klein et al. 2005 §4).
    pub fn reload_transfer_function(&mut self) -> Vec<Event> {
        let start = Instant::now();
        let result =
            inputs::transfer_function(self.tf_path.as_ref(), self.tf_map.as_deref(), &self.volume, self.generated)
                .map_err(|e| format!("{e:#}"))
                .and_then(|(tf, _)| {
                    self.set_transfer_function(&tf).map_err(|e| format!("{e:#}"))?;
                    self.tf_pristine = tf.clone();
                    self.tf = tf;
                    Ok(())
                })
                .map(|_| "LUT uploaded, history restarted".to_string());
        self.outcome("transfer function".to_string(), start, result)
    }

    /// The presets the TF editor offers for this volume: the general ones over its values, and
    /// the scanner presets of its modality (the CT ones in HU, MR's percentile ramp).
    pub fn tf_presets(&self) -> &[(&'static str, TransferFunction)] {
        &self.tf_presets
    }

    /// Whether a TF point at data value `value` is one the editor could place: within the
    /// data's range, or one range-width beyond either end (a ramp may start outside the data).
    pub fn check_tf_value(&self, value: f64) -> Result<(), String> {
        let (lo, hi) = self.volume.value_range;
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

    /// The transfer function on screen.
    pub fn transfer_function(&self) -> &TransferFunction {
        &self.tf
    }

    /// The volume's histogram (voxels per bin of normalized value) and the data values its
    /// ends stand for: the TF editor's backdrop, in the data's units.
    pub fn histogram(&self) -> (&[u64], (f64, f64)) {
        (&self.histogram, self.volume.value_range)
    }

    /// The TF editor's edit: checked, uploaded at once (only what reads the TF reruns: the
    /// classification, distance map and pre-integration table, by input version), and saved
    /// when "save on change" is on.
    pub fn edit_transfer_function(&mut self, tf: TransferFunction) -> Vec<Event> {
        let start = Instant::now();
        let path = self.tf_save_path();
        let result = tf
            .validate(&path)
            .map_err(|e| e.to_string())
            .and_then(|()| self.set_transfer_function(&tf).map_err(|e| format!("{e:#}")))
            .map(|()| {
                self.tf = tf;
                "LUT uploaded".to_string()
            });
        let mut events = self.outcome("transfer function edit".to_string(), start, result);
        if self.save_tf_on_change && self.error.is_none() {
            events.extend(self.save_transfer_function_events());
        }
        events
    }

    /// Where "save TF" writes: the TF's file; for a scanner preset (`--tf ct-bone`)
    /// `NAME.tf.ron` in the current folder (a name `--tf NAME` never reads in the preset's place);
    /// for a fitted TF `view.tf.ron` there. The TF's own file is returned as `--tf` gave it (relative
    /// to the current folder where it was given so, the path the viewer watches); the preset's and
    /// the fitted TF's new files are made absolute, so the "saved" line says where they went.
    fn tf_save_path(&self) -> PathBuf {
        let path = match (&self.tf_path, &self.tf_source) {
            (Some(path), _) => return path.clone(),
            // A preset, or a built-in TF's name (`graphs/tf/vessels.ron` where no such file is).
            (
                None,
                Some(
                    crate::scene::TfSource::Preset(name)
                    | crate::scene::TfSource::File(name)
                    | crate::scene::TfSource::BuiltIn(name),
                ),
            ) => {
                let stem = Path::new(name).file_name().map_or(String::new(), |n| n.to_string_lossy().into_owned());
                PathBuf::from(format!("{}.tf.ron", stem.strip_suffix(".ron").unwrap_or(&stem)))
            }
            (None, _) => PathBuf::from(SAVED_TF),
        };
        std::env::current_dir().map_or(path.clone(), |dir| dir.join(path))
    }

    /// Saves the TF to its file as it came (RON, or ParaView JSON with the file's other maps
    /// kept), or where [`Self::tf_save_path`] says for a preset or a fitted TF (which the
    /// viewer then watches); atomic.
    pub fn save_transfer_function(&mut self) -> anyhow::Result<PathBuf> {
        let path = self.tf_save_path();
        let is_json = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("json"));
        let text = if is_json {
            let original = volgraph_accel::input_file::read_text(&path, "transfer function").ok();
            let index = match (&original, self.tf_map.as_deref()) {
                (Some(text), Some(name)) => serde_json::from_str::<serde_json::Value>(text)
                    .ok()
                    .and_then(|v| v.as_array().and_then(|maps| maps.iter().position(|m| m["Name"] == name)))
                    .unwrap_or(0),
                _ => 0,
            };
            self.tf.to_paraview_json(original.as_deref(), index)
        } else {
            self.tf.to_ron_string()
        };
        crate::atomic_write::write_atomically(&path, &text)?;
        self.tf_written = Some(text);
        self.tf_path = Some(path.clone());
        self.tf_source = Some(crate::scene::TfSource::File(path.display().to_string()));
        // What the file gives back (a ParaView map's colours pass through sRGB): a view saved
        // now refers to the file only if it draws the TF on screen.
        self.tf_pristine = inputs::transfer_function(Some(&path), self.tf_map.as_deref(), &self.volume, self.generated)
            .map_or_else(|_| self.tf_pristine.clone(), |(tf, _)| tf);
        Ok(path)
    }

    /// [`Self::save_transfer_function`] as events.
    pub fn save_transfer_function_events(&mut self) -> Vec<Event> {
        match self.save_transfer_function() {
            Ok(path) => vec![Event::Saved { what: "transfer function".to_string(), path }],
            Err(e) => vec![Event::NotSaved { what: "transfer function".to_string(), message: format!("{e:#}") }],
        }
    }

    /// Uploads `tf` as the LUT of every transfer-function input.
    pub fn set_transfer_function(&mut self, tf: &TransferFunction) -> anyhow::Result<()> {
        self.lut = tf.to_lut_for(&self.volume, inputs::LUT_SIZE);
        // Only the TF inputs: re-binding the volume would hash all its voxels to find it unchanged
        // (~4 ms of every edit on a 256³ volume).
        let inputs = self.plan().map(|p| p.inputs.clone()).unwrap_or_default();
        for (name, kind) in &inputs {
            if matches!(kind, volgraph_core::graph::ast::InputKind::TransferFunction) {
                self.runtime.bind_lut(name, &self.lut).map_err(|e| anyhow!(e))?;
            }
        }
        self.runtime.invalidate_history();
        Ok(())
    }

    /// What "save view" writes: this graph, volume, TF, effects and cuts seen by `camera` in a
    /// window of `viewport` pixels (the window's, not the level of detail's coarse image while
    /// something moves). An error where a scene cannot name the volume (DICOM slices given one
    /// by one that are not all of their folder's), saying what to give instead.
    pub fn saved_view(
        &self,
        camera: &volgraph_accel::camera::OrbitCamera,
        viewport: (u32, u32),
    ) -> anyhow::Result<crate::scene::SavedView> {
        Ok(crate::scene::SavedView {
            graph: self.graph.clone(),
            volume: self.volume_source.clone().map_err(|why| anyhow!("{why}"))?,
            volume_options: crate::scene::VolumeOptions::of(&self.volume_options),
            transfer_function: self.tf_source.clone(),
            camera: *camera,
            viewport,
            effects: self.options.features.iter().filter(|f| !cut_effects::is_cut_feature(f)).cloned().collect(),
            precision: self.options.precision,
            opacity_reference: self.opacity_reference,
            cuts: self.runtime.cuts(),
        })
    }

    /// Whether the TF on screen is not what its source gives (an edit not saved, a preset picked
    /// in the editor), or is a colour map a scene cannot name (`--tf-map`).
    pub fn tf_edited(&self) -> bool {
        self.tf != self.tf_pristine || self.tf_map.is_some()
    }

    /// "Save view": the scene [`Self::saved_view`] describes, written to `path`. A TF on screen
    /// that its source does not give ([`Self::tf_edited`]) is written beside the scene
    /// ([`crate::scene::tf_file_beside`]) and the scene refers to that file, so the scene draws
    /// what is on screen. Both targets are checked (not a folder, FIFO or device; not read-only;
    /// a folder that takes a new file) before anything is written, so a refused scene leaves no
    /// TF file behind. Returns the TF file written, if any, and whether it replaced an earlier
    /// one (the same scene name's own companion, from an earlier save).
    pub fn save_view(
        &self,
        camera: &volgraph_accel::camera::OrbitCamera,
        viewport: (u32, u32),
        path: &Path,
    ) -> anyhow::Result<Option<SavedTf>> {
        let mut view = self.saved_view(camera, viewport)?;
        check_write_target(path, "the scene")?;
        let mut tf_file = None;
        if self.tf_edited() {
            let beside = crate::scene::tf_file_beside(path);
            let same = |a: &Path, b: &Path| matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y);
            if self.tf_path.as_deref().is_some_and(|own| own == beside || same(own, &beside)) {
                return Err(anyhow!(
                    "{}: is the transfer function's own file, where the edited one on screen would go beside the \
                     scene; save the TF (\"save TF\") first, or save the view under another name",
                    beside.display()
                ));
            }
            check_write_target(&beside, "the edited transfer function the saved view needs")?;
            let text = self.tf.to_ron_string();
            let back = TransferFunction::from_ron_str(&text, &beside).map_err(|e| anyhow!("{e}"))?;
            if back != self.tf {
                return Err(anyhow!(
                    "{}: the edited transfer function does not read back the same from RON; save it with \"save TF\" \
                     and save the view again",
                    beside.display()
                ));
            }
            let replaced = beside.symlink_metadata().is_ok();
            crate::atomic_write::write_atomically(&beside, &text)
                .map_err(|e| anyhow!("{e:#} (the edited transfer function the saved view needs)"))?;
            view.transfer_function = Some(crate::scene::TfSource::File(beside.display().to_string()));
            tf_file = Some(SavedTf { path: beside, replaced });
        }
        if let Err(e) = view.save(path) {
            // The scene was refused after all (changed since the check): a TF file this save
            // made new is no one's companion.
            if let Some(tf) = tf_file.as_ref().filter(|tf| !tf.replaced) {
                let _ = std::fs::remove_file(&tf.path);
            }
            return Err(e);
        }
        Ok(tf_file)
    }
}

/// The transfer-function file "save view" wrote beside the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct SavedTf {
    /// `NAME.tf.ron` beside `NAME.ron`.
    pub path: PathBuf,
    /// It replaced a file of that name: the companion an earlier save of this scene name wrote.
    pub replaced: bool,
}

/// Refuses a path "save view" cannot write `what` to, before anything is written: a folder,
/// FIFO or device (a FIFO would block the window), a file its owner may not write (by the
/// permission bits, as [`crate::atomic_write::write_atomically`] decides), a folder that is
/// missing or takes no new file.
fn check_write_target(path: &Path, what: &str) -> anyhow::Result<()> {
    let shown = path.display();
    if let Ok(Some(kind)) = volgraph_accel::input_file::special_kind(path) {
        return Err(anyhow!("{shown}: is {kind}, not a file to write {what} to; give the path of a file"));
    }
    if let Ok(meta) = std::fs::metadata(path) {
        #[cfg(unix)]
        let read_only = {
            use std::os::unix::fs::PermissionsExt as _;
            meta.permissions().mode() & 0o200 == 0
        };
        #[cfg(not(unix))]
        let read_only = meta.permissions().readonly();
        if read_only {
            return Err(anyhow!(
                "{shown} is read-only; make it writable (chmod u+w) or save the view elsewhere (nothing was written)"
            ));
        }
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    tempfile::Builder::new().prefix(".volgraph-save-check.").tempfile_in(&dir).map(drop).map_err(|e| {
        let reason =
            e.raw_os_error().map_or_else(|| e.kind().to_string(), |c| std::io::Error::from_raw_os_error(c).to_string());
        anyhow!(
            "{shown}: cannot write {what}: the folder {} refused a new file: {reason} (nothing was written)",
            dir.display()
        )
    })
}

/// The scanner preset `--tf PATH` reads (no such file, a preset's name), as
/// `inputs::transfer_function` decides it.
pub(super) fn scanner_preset_named(path: &Path) -> Option<&'static str> {
    if path.exists() {
        return None;
    }
    path.to_str().and_then(volgraph_accel::transfer_function::ScannerPreset::from_name).map(|p| p.name())
}

/// Bins of the TF editor's histogram.
pub(super) const HISTOGRAM_BINS: usize = 256;

/// Where "save TF" writes a TF that came from no file (fitted to the data).
pub const SAVED_TF: &str = "view.tf.ron";

/// The general presets over `volume`'s values and the scanner presets of its modality.
pub(super) fn tf_presets_for(volume: &Volume) -> Vec<(&'static str, TransferFunction)> {
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
