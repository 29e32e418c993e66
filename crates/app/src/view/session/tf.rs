//! The session's transfer function on the runtime — the TF editor's edits uploaded, "save TF",
//! reloads of its file (the model of it is [`TfEdits`](crate::view::workbench::TfEdits)) — and
//! "save view", which must save the TF on screen.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::anyhow;
use volgraph_accel::transfer_function::TransferFunction;
use volgraph_core::cut_effects;

use super::{Event, LiveSession};
use crate::inputs;

impl LiveSession {
    /// The transfer-function file changed: read it and upload the new LUT (history restarts:
    /// Klein et al. 2005 §4).
    pub fn reload_transfer_function(&mut self) -> Vec<Event> {
        let start = Instant::now();
        let result = self
            .bench
            .tf
            .read(&self.volume)
            .map_err(|e| format!("{e:#}"))
            .and_then(|tf| {
                self.set_transfer_function(&tf).map_err(|e| format!("{e:#}"))?;
                self.bench.tf.reloaded(tf);
                Ok(())
            })
            .map(|_| "LUT uploaded, history restarted".to_string());
        self.outcome("transfer function".to_string(), start, result)
    }

    /// The transfer function the editor edits (on screen).
    pub fn transfer_function(&self) -> &TransferFunction {
        self.bench.edited_tf().transfer_function()
    }

    /// The TF editor's edit of the TF it edits ([`Self::select_transfer_function`]): checked,
    /// uploaded at once (only what reads the TF reruns: the classification, distance map and
    /// pre-integration table, by input version), and saved when "save on change" is on.
    pub fn edit_transfer_function(&mut self, tf: TransferFunction) -> Vec<Event> {
        let start = Instant::now();
        let target = self.bench.tf_target.clone();
        let result = self.bench.edited_tf().validate(&tf).and_then(|()| {
            match &target {
                None => self.set_transfer_function(&tf),
                Some(input) => self.set_named_transfer_function(input, tf.clone()),
            }
            .map_err(|e| format!("{e:#}"))
        });
        let result = result.map(|()| {
            self.bench.edited_tf_mut().set(tf);
            "LUT uploaded".to_string()
        });
        let what = match &target {
            None => "transfer function edit".to_string(),
            Some(input) => format!("transfer function edit ({input})"),
        };
        let mut events = self.outcome(what, start, result);
        if self.bench.edited_tf().save_on_change && self.error.is_none() {
            events.extend(self.save_transfer_function_events());
        }
        events
    }

    /// Which transfer function the editor edits, by the graph input it feeds: a TF input bound
    /// by name or of another volume (`pet_tf`), or any other TF input (the frame volume's).
    pub fn select_transfer_function(&mut self, input: &str) -> Result<(), String> {
        if self.bench.named_tfs.iter().any(|(n, _)| n == input) {
            self.bench.tf_target = Some(input.to_string());
            return Ok(());
        }
        let inputs = self.plan().map(|p| p.inputs.clone()).unwrap_or_default();
        let tf_inputs: Vec<&String> = inputs
            .iter()
            .filter(|(_, k)| matches!(k, volgraph_core::graph::ast::InputKind::TransferFunction))
            .map(|(n, _)| n)
            .collect();
        if tf_inputs.iter().any(|n| n.as_str() == input) {
            self.bench.tf_target = None;
            return Ok(());
        }
        Err(format!(
            "\"{input}\" is no transfer-function input of this graph; its inputs are: {}",
            tf_inputs.iter().map(|n| n.as_str()).collect::<Vec<_>>().join(", ")
        ))
    }

    /// The editors the panel offers: `(input, label)`, the frame volume's first (`None` where
    /// every TF input is bound by name), then each named one with the volume it classifies.
    pub fn transfer_function_targets(&self) -> Vec<(Option<String>, String)> {
        let Some(b) = &self.bindings else { return Vec::new() };
        let mut out = Vec::new();
        let inputs = self.plan().map(|p| p.inputs.clone()).unwrap_or_default();
        let frame_inputs: Vec<&String> = inputs
            .iter()
            .filter(|(n, k)| {
                matches!(k, volgraph_core::graph::ast::InputKind::TransferFunction)
                    && !b.tfs.iter().any(|t| &t.input == *n)
            })
            .map(|(n, _)| n)
            .collect();
        if !frame_inputs.is_empty() {
            let names: Vec<&str> = frame_inputs.iter().map(|n| n.as_str()).collect();
            out.push((None, format!("{} ({})", names.join(", "), self.volume.name)));
        }
        for t in &b.tfs {
            out.push((Some(t.input.clone()), format!("{} ({})", t.input, b.base_of(t, &self.volume).name)));
        }
        out
    }

    /// Sets the named transfer-function input `input` to `tf` and uploads its LUT.
    fn set_named_transfer_function(&mut self, input: &str, tf: TransferFunction) -> anyhow::Result<()> {
        let bindings = self.bindings.as_mut().ok_or_else(|| anyhow!("no transfer function is bound by name"))?;
        let lut = bindings
            .set_tf(input, tf, &self.volume)
            .ok_or_else(|| anyhow!("\"{input}\" is not bound by name"))?
            .to_vec();
        self.runtime.bind_lut(input, &lut).map_err(|e| anyhow!(e))?;
        self.runtime.invalidate_history();
        Ok(())
    }

    /// The named TF files that changed on disk (`changed`): each read again over its volume and
    /// uploaded.
    pub(super) fn reload_named_transfer_functions(&mut self, changed: &[PathBuf]) -> Vec<Event> {
        let stale: Vec<String> =
            self.bench.named_tfs.iter().filter(|(_, e)| e.needs_reload(changed)).map(|(n, _)| n.clone()).collect();
        let mut events = Vec::new();
        for input in stale {
            let start = Instant::now();
            let volume = self.named_tf_volume(&input).clone();
            let Some(at) = self.bench.named_tfs.iter().position(|(n, _)| *n == input) else { continue };
            let result = self.bench.named_tfs[at].1.read(&volume).map_err(|e| format!("{e:#}")).and_then(|tf| {
                self.set_named_transfer_function(&input, tf.clone()).map_err(|e| format!("{e:#}"))?;
                self.bench.named_tfs[at].1.reloaded(tf);
                Ok("LUT uploaded, history restarted".to_string())
            });
            events.extend(self.outcome(format!("transfer function ({input})"), start, result));
        }
        events
    }

    /// The volume the named TF `input` classifies (the frame volume where it has no other).
    fn named_tf_volume(&self, input: &str) -> &volgraph_accel::volume::Volume {
        let named = self.bindings.as_ref().and_then(|b| b.tfs.iter().find(|t| t.input == input).map(|t| (b, t)));
        named.map_or(&self.volume, |(b, t)| b.base_of(t, &self.volume))
    }

    /// Saves the edited TF ([`Self::select_transfer_function`]) to its file as it came (RON, or
    /// ParaView JSON with the file's other maps kept), or where
    /// [`TfEdits::save_path`](crate::view::workbench::TfEdits::save_path) says for a preset or a
    /// fitted TF (which the viewer then watches); atomic.
    pub fn save_transfer_function(&mut self) -> anyhow::Result<PathBuf> {
        let volume = match self.bench.tf_target.clone() {
            Some(input) => self.named_tf_volume(&input).clone(),
            None => return self.bench.tf.save(&self.volume),
        };
        self.bench.edited_tf_mut().save(&volume)
    }

    /// [`Self::save_transfer_function`] as events.
    pub fn save_transfer_function_events(&mut self) -> Vec<Event> {
        let what = match &self.bench.tf_target {
            None => "transfer function".to_string(),
            Some(input) => format!("transfer function ({input})"),
        };
        match self.save_transfer_function() {
            Ok(path) => vec![Event::Saved { what, path }],
            Err(e) => vec![Event::NotSaved { what, message: format!("{e:#}") }],
        }
    }

    /// Uploads `tf` as the LUT of every transfer-function input not bound by name (the frame
    /// volume's).
    pub fn set_transfer_function(&mut self, tf: &TransferFunction) -> anyhow::Result<()> {
        self.lut = tf.to_lut_for(&self.volume, inputs::LUT_SIZE);
        // Only the TF inputs: re-binding the volume would hash all its voxels to find it unchanged
        // (~4 ms of every edit on a 256³ volume).
        let inputs = self.plan().map(|p| p.inputs.clone()).unwrap_or_default();
        // Inputs bound by name keep their own (their editors are the named ones).
        let named = |name: &str| self.bindings.as_ref().is_some_and(|b| b.tfs.iter().any(|t| t.input == name));
        for (name, kind) in &inputs {
            if matches!(kind, volgraph_core::graph::ast::InputKind::TransferFunction) && !named(name) {
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
        if let Some(b) = self.bindings.as_ref().filter(|b| !b.others.is_empty()) {
            let names: Vec<&str> = b.others.iter().map(|(n, _)| n.as_str()).collect();
            return Err(anyhow!(
                "save view keeps one volume, and this view binds others by name ({}); give them to `volgraph render \
                 --scene` with a `volumes:` map, or view one volume",
                names.join(", ")
            ));
        }
        Ok(crate::scene::SavedView {
            graph: self.bench.graph.path().to_path_buf(),
            volume: self.volume_source.clone().map_err(|why| anyhow!("{why}"))?,
            volume_options: crate::scene::VolumeOptions::of(&self.volume_options),
            transfer_function: self.bench.tf.source().cloned(),
            camera: *camera,
            viewport,
            effects: self.options().features.iter().filter(|f| !cut_effects::is_cut_feature(f)).cloned().collect(),
            precision: self.options().precision,
            opacity_reference: self.opacity_reference,
            cuts: self.runtime.cuts(),
            lights: self.runtime.lights(),
            environment: self.environment.clone(),
        })
    }

    /// Whether the TF on screen is not what its source gives (an edit not saved, a preset picked
    /// in the editor), or is a colour map a scene cannot name (`--tf-map`).
    pub fn tf_edited(&self) -> bool {
        self.bench.tf.edited()
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
            if self.bench.tf.path().is_some_and(|own| own == beside || same(own, &beside)) {
                return Err(anyhow!(
                    "{}: is the transfer function's own file, where the edited one on screen would go beside the \
                     scene; save the TF (\"save TF\") first, or save the view under another name",
                    beside.display()
                ));
            }
            check_write_target(&beside, "the edited transfer function the saved view needs")?;
            let tf = self.bench.tf.transfer_function();
            let text = tf.to_ron_string();
            let back = TransferFunction::from_ron_str(&text, &beside).map_err(|e| anyhow!("{e}"))?;
            if back != *tf {
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
