//! Loading what a scene (or the command line in its place) names: the volume `render` and
//! `view` show, read with the flags over the scene's `volume_options`, and the transfer function.

use std::path::{Path, PathBuf};

use super::{NamedPreset, PRESETS, Scene, TfSource, VolumeSource, is_tf_name, tf_preset};

/// The volume `render` and `view` show, loaded, and where it came from.
pub struct ShownVolume {
    /// The voxels.
    pub volume: volgraph_accel::volume::Volume,
    /// Where it came from, as a saved view writes it.
    pub source: VolumeSource,
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
            Some(VolumeName::Generated(name)) => VolumeSource::Generated(name),
            Some(VolumeName::Dataset(name)) => VolumeSource::Dataset(name),
            None => VolumeSource::File(one.display().to_string()),
        },
        // DICOM slices given one by one: their folder.
        ([first, ..], _) => VolumeSource::File(first.parent().unwrap_or(Path::new(".")).display().to_string()),
        ([], Some(scene)) => scene.volume.clone(),
        ([], None) => VolumeSource::Generated("ml64".to_string()),
    };
    let marschner_lobb_tf = marschner_lobb_tf(&source);
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
                TfSource::File(p) | TfSource::Preset(p) => PathBuf::from(p),
            };
            let (tf, notes) = crate::inputs::transfer_function(Some(&path), tf_map, volume, marschner_lobb_tf)
                .map_err(|e| anyhow::anyhow!("{}: transfer_function: {e:#}", scene.path.display()))?;
            // A preset's name is no file to watch or save to.
            let file = (!is_tf_name(&path) || path.symlink_metadata().is_ok()).then_some(path);
            Ok((tf, file, notes))
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
