//! Loading what a scene (or the command line in its place) names: the volume `render` and
//! `view` show, read with the flags over the scene's `volume_options`, and the transfer function.

use std::path::{Path, PathBuf};

use super::{NamedPreset, PRESETS, Scene, TfSource, VolumeSource, is_tf_name, tf_preset};

/// The volume `render` and `view` show, loaded, and where it came from.
pub struct ShownVolume {
    /// The voxels.
    pub volume: volgraph_accel::volume::Volume,
    /// Where it came from, as a saved view writes it; `Err`: why a saved view cannot name it
    /// (DICOM slices given one by one that are not all of their folder's).
    pub source: Result<VolumeSource, String>,
    /// How it was read (the flags, over the scene's `volume_options` for the scene's volume).
    pub options: volgraph_accel::load::LoadOptions<'static>,
    /// Its default transfer function is Marschner–Lobb's ([`marschner_lobb_tf`]).
    pub marschner_lobb_tf: bool,
    /// Notes for stderr (what the loader repaired or chose).
    pub notes: Vec<String>,
}

/// Loads the volume `render` and `view` show: `--volume` (files, a DICOM folder or slices, or a
/// volume's name) read with the command line's flags; else the scene's volume, read with its
/// `volume_options` under the flags; else the generated Marschner–Lobb 64³. One function for
/// both commands, so a view saved as a scene renders with the same volume and default TF.
pub fn load_shown_volume(
    paths: &[PathBuf],
    scene: Option<&Scene>,
    flags: &volgraph_accel::load::LoadOptions<'static>,
) -> anyhow::Result<ShownVolume> {
    use crate::inputs::VolumeName;
    let source = match (paths, scene) {
        ([one], _) => match crate::inputs::volume_name(one) {
            Some(VolumeName::Generated(name)) => Ok(VolumeSource::Generated(name)),
            Some(VolumeName::Dataset(name)) => Ok(VolumeSource::Dataset(name)),
            None => Ok(VolumeSource::File(one.display().to_string())),
        },
        // DICOM slices given one by one: their folder, if they are all of it.
        ([_, ..], _) => slices_folder(paths),
        ([], Some(scene)) => Ok(scene.volume.clone()),
        ([], None) => Ok(VolumeSource::Generated("ml64".to_string())),
    };
    let marschner_lobb_tf = source.as_ref().is_ok_and(marschner_lobb_tf);
    let (volume, options, notes) = match (paths, scene) {
        ([], Some(scene)) => {
            let options = merged_options(
                flags,
                &scene
                    .volume_options
                    .load_options()
                    .map_err(|e| anyhow::anyhow!("{}: volume_options: {e:#}", scene.path.display()))?,
            );
            let (volume, notes) = load_volume(scene, &options)?;
            (volume, options, notes)
        }
        // The default volume is `Generated("ml64")` (what a saved view writes): `--spacing`
        // applies to it as to a named volume, and the flags of a file's layout are refused.
        ([], None) => {
            if has_layout(flags) {
                return Err(anyhow::anyhow!(
                    "no --volume was given, and the default volume (the generated ml64) is no file: --series, \
                     --frame, --dims, --dtype and --big-endian describe a file's layout; give --volume FILE or \
                     remove them (--spacing may stay)"
                ));
            }
            let (mut volume, notes) = crate::inputs::volume(paths, flags)?;
            if let Some(spacing) = flags.raw.spacing {
                volume.spacing = spacing;
            }
            (volume, flags.clone(), notes)
        }
        _ => {
            let (volume, notes) = crate::inputs::volume(paths, flags)?;
            (volume, flags.clone(), notes)
        }
    };
    Ok(ShownVolume { volume, source, options, marschner_lobb_tf, notes })
}

/// The folder of DICOM slices given one by one, as a saved view names them: only when the files
/// are exactly the DICOM files that loading their one folder reads (compared canonicalized), so
/// the saved scene loads the same slices; else why not, and what to give instead. (A part of a
/// folder saved as the folder would load other slices, or another series; a bare file name's
/// `parent()` is `""`, the scene's own folder.)
fn slices_folder(paths: &[PathBuf]) -> Result<VolumeSource, String> {
    use std::collections::BTreeSet;
    let refuse = |why: String| {
        format!(
            "cannot save this view: {why}; a scene names a DICOM volume by its folder, which would load other \
             slices. Give the folder instead (volgraph view GRAPH --volume DIR, with --series N where it holds \
             several series), then save the view"
        )
    };
    let mut given = BTreeSet::new();
    let mut folder: Option<PathBuf> = None;
    for p in paths {
        let real = p.canonicalize().map_err(|e| refuse(format!("{}: {e}", p.display())))?;
        if real.is_dir() {
            return Err(refuse(format!("{} is a folder, given with other paths", p.display())));
        }
        let parent = real.parent().map(Path::to_path_buf).unwrap_or_default();
        match &folder {
            Some(f) if *f != parent => {
                return Err(refuse(format!(
                    "the slices given lie in more than one folder ({} and {})",
                    f.display(),
                    parent.display()
                )));
            }
            _ => folder = Some(parent),
        }
        given.insert(real);
    }
    let folder = folder.unwrap_or_default();
    let mut in_folder = BTreeSet::new();
    let mut seen = BTreeSet::new();
    let mut stack = vec![folder.clone()];
    while let Some(dir) = stack.pop() {
        if !seen.insert(dir.canonicalize().unwrap_or_else(|_| dir.clone())) {
            continue;
        }
        let Ok(entries) = std::fs::read_dir(&dir) else { continue };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
            } else if path.is_file() && volgraph_accel::load::dicom::is_dicom_input(std::slice::from_ref(&path)) {
                in_folder.insert(path.canonicalize().unwrap_or(path));
            }
        }
    }
    if let Some(other) = in_folder.difference(&given).next() {
        return Err(refuse(format!(
            "the {} slices given are not all the DICOM files of their folder {} ({} more there, e.g. {})",
            given.len(),
            folder.display(),
            in_folder.difference(&given).count(),
            other.display()
        )));
    }
    if let Some(odd) = given.difference(&in_folder).next() {
        return Err(refuse(format!(
            "{} is not a DICOM file loading the folder {} reads",
            odd.display(),
            folder.display()
        )));
    }
    Ok(VolumeSource::File(folder.display().to_string()))
}

/// Whether a volume's default transfer function (none given) is `graphs/tf/marschner_lobb.ron`,
/// which shows Marschner–Lobb's rings: for the generated 8-bit Marschner–Lobb volumes (`ml64`,
/// the default, any edge), whose values the file's 0..255 points are written in; every other
/// volume (the float `mlf64` too, valued 0..1) gets one fitted to its data. The one rule for
/// `render`, `view` and scenes.
pub fn marschner_lobb_tf(source: &VolumeSource) -> bool {
    matches!(source, VolumeSource::Generated(name) if name.starts_with("ml") && !name.starts_with("mlf"))
}

/// `flags`, each over the scene's `scene` value.
fn merged_options(
    flags: &volgraph_accel::load::LoadOptions<'static>,
    scene: &volgraph_accel::load::LoadOptions<'static>,
) -> volgraph_accel::load::LoadOptions<'static> {
    use volgraph_accel::load::{Endianness, LoadOptions, RawOptions};
    let big = |o: &LoadOptions<'_>| matches!(o.raw.endianness, Endianness::Big);
    LoadOptions {
        raw: RawOptions {
            dims: flags.raw.dims.or(scene.raw.dims),
            dtype: flags.raw.dtype.or(scene.raw.dtype),
            endianness: if big(flags) || big(scene) { Endianness::Big } else { Endianness::default() },
            spacing: flags.raw.spacing.or(scene.raw.spacing),
        },
        series: flags.series.clone().or_else(|| scene.series.clone()),
        frame: flags.frame.or(scene.frame),
        progress: None,
    }
}

/// Whether `options` say how to read a file (`--series`, `--frame`, `--dims`, `--dtype`,
/// `--big-endian`), which a named or the default volume is not.
fn has_layout(options: &volgraph_accel::load::LoadOptions<'_>) -> bool {
    let raw = &options.raw;
    raw.dims.is_some()
        || raw.dtype.is_some()
        || matches!(raw.endianness, volgraph_accel::load::Endianness::Big)
        || options.series.is_some()
        || options.frame.is_some()
}

/// A scene's volume read with `options` (the flags over its `volume_options`), with notes for
/// stderr. The error names the scene file and field.
fn load_volume(
    scene: &Scene,
    options: &volgraph_accel::load::LoadOptions<'static>,
) -> anyhow::Result<(volgraph_accel::volume::Volume, Vec<String>)> {
    let at = |e: anyhow::Error| anyhow::anyhow!("{}: volume: {e:#}", scene.path.display());
    let name = match &scene.volume {
        VolumeSource::File(p) => return crate::inputs::volume_files(&[PathBuf::from(p)], options).map_err(at),
        VolumeSource::Dataset(name) | VolumeSource::Generated(name) => name,
    };
    if has_layout(options) {
        return Err(anyhow::anyhow!(
            "{}: volume_options: \"{name}\" names a volume, not a file: series, frame, dims, dtype and big_endian (or \
             --series, --frame, --dims, --dtype, --big-endian) describe a file's layout; remove them (spacing may stay)",
            scene.path.display()
        ));
    }
    let mut volume = match &scene.volume {
        VolumeSource::Dataset(name) => {
            volgraph_accel::data_dir::load_dataset(name).map_err(|e| at(anyhow::anyhow!("{e}")))?.volume
        }
        _ => volgraph_accel::generate::by_name(name).map_err(|e| {
            at(match e {
                volgraph_accel::generate::NamedVolumeError::Unknown { .. } => anyhow::anyhow!(
                    "Generated(\"{name}\") names no generated volume; use {}",
                    volgraph_accel::generate::NAMED_GENERATORS
                ),
                other => anyhow::anyhow!("Generated(\"{name}\"): {other}"),
            })
        })?,
    };
    if let Some(spacing) = options.raw.spacing {
        volume.spacing = spacing;
    }
    Ok((volume, Vec::new()))
}

/// A scene's transfer function for `volume`: a file (also returned, so a viewer can watch it),
/// a preset, or the default fitted to the data; with notes for stderr. `marschner_lobb_tf`:
/// [`ShownVolume::marschner_lobb_tf`].
pub fn load_transfer_function(
    scene: &Scene,
    tf_map: Option<&str>,
    volume: &volgraph_accel::volume::Volume,
    marschner_lobb_tf: bool,
) -> anyhow::Result<(volgraph_accel::transfer_function::TransferFunction, Option<PathBuf>, Vec<String>)> {
    use volgraph_accel::transfer_function::TransferFunction;
    match &scene.transfer_function {
        Some(source @ (TfSource::File(_) | TfSource::Data(_))) => {
            let path = match source {
                TfSource::Data(name) => volgraph_accel::data_dir::data_dir().join("tf").join(format!("{name}.ron")),
                TfSource::File(p) | TfSource::Preset(p) | TfSource::BuiltIn(p) => PathBuf::from(p),
            };
            let (tf, notes) = crate::inputs::transfer_function(Some(&path), tf_map, volume, marschner_lobb_tf)
                .map_err(|e| anyhow::anyhow!("{}: transfer_function: {e:#}", scene.path.display()))?;
            // A preset's name is no file to watch or save to.
            let file = (!is_tf_name(&path) || path.symlink_metadata().is_ok()).then_some(path);
            Ok((tf, file, notes))
        }
        // The program's own copy, whatever file of that name the current folder holds.
        Some(TfSource::BuiltIn(name)) => {
            let at = |e: String| anyhow::anyhow!("{}: transfer_function: {e}", scene.path.display());
            let shown = PathBuf::from(format!("graphs/tf/{name}.ron"));
            if tf_map.is_some() {
                return Err(at(format!(
                    "--tf-map picks a colour map from a ParaView .json file, but {} is a built-in RON TF; remove \
                     --tf-map",
                    shown.display()
                )));
            }
            let (_, text) =
                crate::builtin_graphs::builtin_tf(&shown).ok_or_else(|| at(format!("no built-in TF \"{name}\"")))?;
            let tf = TransferFunction::from_ron_str(text, &shown).map_err(|e| at(e.to_string()))?;
            let notes = crate::inputs::domain_note(&tf, volume).into_iter().collect();
            Ok((tf, None, notes))
        }
        Some(TfSource::Preset(name)) => {
            let tf = match tf_preset(name) {
                Some(NamedPreset::General(preset)) => {
                    let (lo, hi) = volume.value_range;
                    TransferFunction::preset(preset, (lo, if hi > lo { hi } else { lo + 1.0 }))
                }
                Some(NamedPreset::Scanner(preset)) => preset.for_volume(volume),
                None => {
                    return Err(anyhow::anyhow!(
                        "{}: transfer_function: Preset(\"{name}\") is not a preset; {PRESETS}",
                        scene.path.display()
                    ));
                }
            };
            Ok((tf, None, Vec::new()))
        }
        None => {
            let (tf, notes) = crate::inputs::transfer_function(None, tf_map, volume, marschner_lobb_tf)?;
            Ok((tf, None, notes))
        }
    }
}

/// Where "save view" writes an edited transfer function that no file holds: beside the scene,
/// `NAME.tf.ron` for `NAME.ron` (`view.scene.ron` → `view.scene.tf.ron`, not the `view.tf.ron`
/// that "save TF" writes a fitted TF to).
pub fn tf_file_beside(scene: &Path) -> PathBuf {
    let name = scene.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let stem = name.strip_suffix(".ron").unwrap_or(&name);
    scene.with_file_name(format!("{stem}.tf.ron"))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Review of issue 47: DICOM slices given one by one were saved as `File(first.parent())`:
    /// some of a folder's slices saved as the whole folder (another volume on load), and a bare
    /// file name's parent `""` saved as `File("")` (the scene's own folder). The folder is saved
    /// only when the slices are exactly its DICOM files; else "save view" says why and what to
    /// give instead.
    #[test]
    fn dicom_slices_are_saved_as_their_folder_only_when_they_are_all_of_it() {
        let dir = std::env::temp_dir().join(format!("volgraph-slices-folder-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch");
        let slices: Vec<PathBuf> = ["a.dcm", "b.dcm", "c.dcm"].iter().map(|n| dir.join(n)).collect();
        for s in &slices {
            std::fs::write(s, b"").expect("slice");
        }
        std::fs::write(dir.join("notes.txt"), b"not DICOM").expect("other file");
        let real = dir.canonicalize().expect("real").display().to_string();
        assert_eq!(slices_folder(&slices), Ok(VolumeSource::File(real.clone())));
        // Given by a relative path (as bare names are): the folder is still the real one.
        let cwd = std::env::current_dir().expect("cwd");
        let up: PathBuf = cwd.components().skip(1).map(|_| "..").collect();
        let relative: Vec<PathBuf> = slices.iter().map(|s| up.join(s.strip_prefix("/").expect("absolute"))).collect();
        assert_eq!(slices_folder(&relative), Ok(VolumeSource::File(real)));
        // Two of the three: refused, saying what to give instead.
        let e = slices_folder(&slices[..2]).expect_err("a part of the folder");
        assert!(e.contains("cannot save this view") && e.contains("c.dcm") && e.contains("--volume DIR"), "{e}");
        // A slice in a subfolder, which loading the folder reads too.
        std::fs::create_dir_all(dir.join("sub")).expect("sub");
        std::fs::write(dir.join("sub").join("d.dcm"), b"").expect("slice");
        let e = slices_folder(&slices).expect_err("the folder holds more");
        assert!(e.contains("d.dcm") && e.contains("--series N"), "{e}");
        // Slices from two folders.
        let mut two = slices.clone();
        two.push(dir.join("sub").join("d.dcm"));
        let e = slices_folder(&two).expect_err("two folders");
        assert!(e.contains("more than one folder"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
