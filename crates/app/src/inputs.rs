//! Reading the user's inputs: graph files, volumes (or a generated default), transfer
//! functions, sizes and cameras from the command line.

use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail};
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::histogram::ValueSummary;
use volgraph_accel::load::{LoadOptions, RawOptions};
use volgraph_accel::transfer_function::{ScannerPreset, TransferFunction};
use volgraph_accel::volume::Volume;

/// The LUT resolution uploaded for every transfer function.
pub const LUT_SIZE: usize = 256;

/// Reads a graph file's text; a path that is no file but names a built-in graph
/// (`kruger_westermann_2003/rc_b`, [`crate::builtin_graphs`]) gives that graph's text.
pub fn read_graph(path: &Path) -> anyhow::Result<String> {
    // `symlink_metadata`: a dangling link or an unreadable file is the user's file, not a name.
    if path.symlink_metadata().is_err()
        && let Some((_, text)) = crate::builtin_graphs::find(path)
    {
        return Ok(text.to_string());
    }
    match volgraph_accel::input_file::read_text(path, "graph file") {
        Err(volgraph_accel::input_file::InputFileError::Io { reason, .. })
            if reason.kind() == std::io::ErrorKind::NotFound =>
        {
            let names: Vec<&str> = crate::builtin_graphs::EMBEDDED_GRAPHS.iter().map(|(n, _)| *n).collect();
            let guess =
                volgraph_core::suggest::closest(&crate::builtin_graphs::normalized(path), names.iter().copied())
                    .map_or(String::new(), |g| format!("did you mean the built-in graph \"{g}\"? "));
            bail!(
                "{}: cannot read the graph file: no such file, nor a built-in graph of that name; {guess}`volgraph \
                 graphs` lists the built-in ones",
                path.display()
            )
        }
        other => Ok(other?),
    }
}

/// The largest ratio of voxel sides `--spacing` accepts (as for a header's spacing).
const MAX_SPACING_RATIO: f64 = volgraph_accel::load::MAX_SPACING_RATIO;

/// How to read the volume: `--dims`, `--dtype`, `--spacing`, `--big-endian` for raw files,
/// `--series`, `--frame` for scanner data.
pub fn raw_options(raw: &crate::cli::RawArgs) -> anyhow::Result<LoadOptions<'static>> {
    Ok(LoadOptions { raw: raw_layout(raw)?, series: raw.series.clone(), frame: raw.frame, progress: None })
}

/// Raw-file options from `--dims`, `--dtype`, `--spacing`, `--big-endian`.
fn raw_layout(raw: &crate::cli::RawArgs) -> anyhow::Result<RawOptions> {
    let mut o = RawOptions::default();
    if let Some(d) = &raw.dims {
        let parts: Vec<&str> = d.split(['x', 'X']).collect();
        let fail = || anyhow!("--dims \"{d}\": expected XxYxZ with positive integers, e.g. 128x128x64");
        if parts.len() != 3 {
            return Err(fail());
        }
        let v: Vec<u32> =
            parts.iter().map(|p| p.trim().parse::<u32>().map_err(|_| fail())).collect::<Result<_, _>>()?;
        if v.contains(&0) {
            return Err(fail());
        }
        o.dims = Some(glam::UVec3::new(v[0], v[1], v[2]));
    }
    if let Some(t) = &raw.dtype {
        o.dtype = Some(
            volgraph_accel::volume::VoxelType::from_name(t)
                .ok_or_else(|| anyhow!("--dtype \"{t}\": expected uint8, uint16, int16 or float32"))?,
        );
    }
    if let Some(s) = &raw.spacing {
        let fail = || anyhow!("--spacing \"{s}\": expected three positive numbers X,Y,Z, e.g. 1,1,1.4");
        let v: Vec<f64> =
            s.split(',').map(|p| p.trim().parse::<f64>().map_err(|_| fail())).collect::<Result<_, _>>()?;
        if v.len() != 3 || v.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
            return Err(fail());
        }
        // The box is scaled to its longest side in f32: beyond this ratio the shortest side is
        // below f32's resolution and the volume renders as nothing.
        let (lo, hi) = (v.iter().copied().fold(f64::INFINITY, f64::min), v.iter().copied().fold(0.0, f64::max));
        if hi / lo > MAX_SPACING_RATIO {
            bail!(
                "--spacing \"{s}\": the longest voxel side is {:.1e} times the shortest; at most {MAX_SPACING_RATIO:.0e} \
                 (give the spacing in one unit, e.g. mm for every axis)",
                hi / lo
            );
        }
        o.spacing = Some(glam::DVec3::new(v[0], v[1], v[2]));
    }
    if raw.big_endian {
        o.endianness = volgraph_accel::load::Endianness::Big;
    }
    Ok(o)
}

/// Loads `--volume` (a file, a DICOM folder or slice files, or a volume's name: [`volume_name`]),
/// or generates the default (Marschner–Lobb 64³) when none is given. What the loader repaired or
/// reordered comes back as notes for stderr. A DICOM series shows a progress bar on a terminal
/// while it loads.
pub fn volume(paths: &[PathBuf], options: &LoadOptions<'_>) -> anyhow::Result<(Volume, Vec<String>)> {
    match paths {
        [] => Ok((default_volume().clone(), Vec::new())),
        [one] => match volume_name(one) {
            Some(name) => named_volume(&name, options),
            None => volume_files(paths, options),
        },
        paths => volume_files(paths, options),
    }
}

/// Loads a volume file, a DICOM folder or DICOM slice files (never a name: a scene's `File`
/// is a path relative to the scene).
pub fn volume_files(paths: &[PathBuf], options: &LoadOptions<'_>) -> anyhow::Result<(Volume, Vec<String>)> {
    let Some(p) = paths.first() else { bail!("no volume file given") };
    if let [one] = paths
        && volgraph_zarr::is_zarr(one)
    {
        return crate::zarr_input::read(one, options);
    }
    let loaded = crate::load_progress::load_with_progress(paths, options).map_err(|e| anyhow!("{e}"))?;
    Ok((loaded.volume, load_notes(&p.display().to_string(), &loaded.report)))
}

/// What the loader of `what` repaired or ignored, for stderr.
fn load_notes(what: &str, report: &volgraph_accel::load::LoadReport) -> Vec<String> {
    let mut notes: Vec<String> = report.notes.iter().map(|n| format!("{what}: {n}")).collect();
    if report.non_finite_replaced() > 0 {
        notes.push(format!("{what}: replaced {} NaN/Inf voxels", report.non_finite_replaced()));
    }
    notes
}

/// A volume given by name where a path could stand (`--volume lobster`, `--volume ml64`), as
/// `volgraph bench graphs --datasets` takes them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum VolumeName {
    /// A generated volume (`ml64`, `vessels128`: `volgraph_accel::generate::by_name`).
    Generated(String),
    /// A dataset of the data folder (`lobster`: `$VOLGRAPH_DATA/volumes`, with its MANIFEST
    /// row's voxel spacing).
    Dataset(String),
}

/// `path` as a volume's name: there is no such file or folder, and it has no folder part and no
/// extension. A generator's name (or one with a generator's prefix and a bad edge, whose error
/// then says the range) is generated; any other is a data-folder dataset.
pub fn volume_name(path: &Path) -> Option<VolumeName> {
    use volgraph_accel::generate::{NamedVolumeError, by_name};
    let missing = path.symlink_metadata().is_err_and(|e| e.kind() == std::io::ErrorKind::NotFound);
    if !missing || path.components().count() != 1 || path.extension().is_some() {
        return None;
    }
    let name = path.to_str()?.to_string();
    Some(match by_name(&name) {
        Err(NamedVolumeError::Unknown { .. }) => VolumeName::Dataset(name),
        _ => VolumeName::Generated(name),
    })
}

/// Loads a named volume. `--spacing` overrides the volume's; the flags that describe a file's
/// layout (`--dims`, `--dtype`, `--big-endian`, `--series`, `--frame`) are refused.
fn named_volume(name: &VolumeName, options: &LoadOptions<'_>) -> anyhow::Result<(Volume, Vec<String>)> {
    use volgraph_accel::generate::{NAMED_GENERATORS, by_name};
    let (VolumeName::Generated(n) | VolumeName::Dataset(n)) = name;
    let raw = &options.raw;
    let big_endian = matches!(raw.endianness, volgraph_accel::load::Endianness::Big);
    if raw.dims.is_some() || raw.dtype.is_some() || big_endian || options.series.is_some() || options.frame.is_some() {
        bail!(
            "{n} names a volume, not a file: --dims, --dtype, --big-endian, --series and --frame describe a file's \
             layout; remove them (--spacing may stay)"
        );
    }
    let (mut volume, notes) = match name {
        VolumeName::Generated(_) => (by_name(n).map_err(|e| anyhow!("{e}"))?, Vec::new()),
        VolumeName::Dataset(_) => {
            let loaded = volgraph_accel::data_dir::load_dataset(n).map_err(|e| {
                anyhow!("{n}: no such file or folder, and not a volume's name: {e}; a generated volume is named {NAMED_GENERATORS}")
            })?;
            let notes = load_notes(n, &loaded.report);
            (loaded.volume, notes)
        }
    };
    if let Some(spacing) = raw.spacing {
        volume.spacing = spacing;
    }
    Ok((volume, notes))
}

/// The generated default volume, made once per process.
pub fn default_volume() -> &'static Volume {
    static DEFAULT: std::sync::OnceLock<Volume> = std::sync::OnceLock::new();
    DEFAULT.get_or_init(|| volgraph_accel::generate::marschner_lobb(64))
}

/// The transfer function for the generated default volume: an opaque band around ρ = 0.5 that
/// shows Marschner–Lobb's rings (`graphs/tf/marschner_lobb.ron`, compiled in so a fresh clone
/// renders it from any directory).
const MARSCHNER_LOBB_TF: &str = include_str!("../../../graphs/tf/marschner_lobb.ron");

/// Loads `--tf` (RON, or ParaView JSON by extension; `map` picks a colour map from a ParaView
/// file holding several), or the default for the volume (for the generated default volume,
/// `graphs/tf/marschner_lobb.ron`), with notes about the choice for stderr.
pub fn transfer_function(
    path: Option<&PathBuf>,
    map: Option<&str>,
    volume: &Volume,
    generated: bool,
) -> anyhow::Result<(TransferFunction, Vec<String>)> {
    transfer_function_fitted(path, map, volume, &ValueSummary::of(volume), generated)
}

/// [`transfer_function`] with the fitted defaults (the default TF, the MR preset) taken from
/// `values`, the summary of the whole volume, where `volume` may be only a part or a preview of
/// it (a sort-last render: every rank fits to the whole file's histogram, as one process does).
pub fn transfer_function_fitted(
    path: Option<&PathBuf>,
    map: Option<&str>,
    volume: &Volume,
    values: &ValueSummary,
    generated: bool,
) -> anyhow::Result<(TransferFunction, Vec<String>)> {
    let is_json = path.is_some_and(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("json")));
    if let Some(name) = map
        && !is_json
    {
        bail!(
            "--tf-map \"{name}\" picks a colour map from a ParaView .json file, but {} is not one; remove --tf-map",
            path.map_or_else(|| "no --tf was given".to_string(), |p| format!("--tf {}", p.display()))
        );
    }
    let mut notes = Vec::new();
    let tf = match path {
        None if generated => {
            TransferFunction::from_ron_str(MARSCHNER_LOBB_TF, Path::new("graphs/tf/marschner_lobb.ron"))
                .map_err(|e| anyhow!("{e}"))?
        }
        None => TransferFunction::default_fitted(values),
        Some(p) if is_json => {
            let chosen = TransferFunction::load_paraview_map(p, map).map_err(|e| anyhow!("{e}"))?;
            if chosen.all.len() > 1 && map.is_none() {
                let names: Vec<String> = chosen.all.iter().map(|n| format!("\"{n}\"")).collect();
                notes.push(format!(
                    "{} holds {} colour maps ({}); using the first, \"{}\"; choose another with --tf-map NAME",
                    p.display(),
                    chosen.all.len(),
                    names.join(", "),
                    chosen.all[chosen.index]
                ));
            }
            notes.extend(chosen.notes.iter().map(|n| format!("{}: {n}", p.display())));
            chosen.tf
        }
        // `--tf ct-bone`: a built-in scanner preset (a file of that name wins).
        Some(p)
            if !p.exists()
                && let Some(preset) = p.to_str().and_then(ScannerPreset::from_name) =>
        {
            if preset.is_ct() && !values.ct_hu {
                notes.push(format!(
                    "warning: --tf {} is written in Hounsfield units, but the volume's values are {}; the preset \
                     fits CT data (DICOM CT, or NIfTI/NRRD holding HU)",
                    preset.name(),
                    volume.meta.units.as_deref().map_or("in no known unit".to_string(), |u| format!("in {u}"))
                ));
            }
            preset.fitted(values)
        }
        // `graphs/tf/NAME.ron` where no such file exists: the copy compiled into the program;
        // a plain name (`engine_opaque`) of the data folder's tf/ (a scene's `Data("…")`).
        Some(p) => match (crate::builtin_graphs::find_tf(p), data_folder_tf(p)) {
            (Some((_, text)), _) => TransferFunction::from_ron_str(text, p).map_err(|e| anyhow!("{e}"))?,
            (None, Some(file)) => TransferFunction::load(&file).map_err(|e| anyhow!("{e}"))?,
            (None, None) => TransferFunction::load(p).map_err(|e| tf_read_error(p, e))?,
        },
    };
    if let Some(p) = path
        && let Some(note) = domain_note(&tf, volume)
    {
        notes.push(format!("{}: {note}", p.display()));
    }
    Ok((tf, notes))
}

/// The transfer function of the data folder's `tf/` a `--tf` argument names where no file of
/// that name exists: a plain name (no folder, no extension) with `tf/NAME.ron` there, as a
/// scene's `Data("NAME")` reads it (`--tf engine_opaque`, the peer benchmark's).
fn data_folder_tf(path: &Path) -> Option<PathBuf> {
    if path.symlink_metadata().is_ok() || path.components().count() != 1 || path.extension().is_some() {
        return None;
    }
    let name = path.to_str()?;
    if name.chars().any(volgraph_core::terminal::is_unsafe) || name == "." || name == ".." {
        return None;
    }
    // Anything of that name (a FIFO, a folder) is handed on, and the loader refuses it by kind.
    let file = volgraph_accel::data_dir::data_dir().join("tf").join(format!("{name}.ron"));
    file.symlink_metadata().is_ok().then_some(file)
}

/// A `--tf` file that cannot be read; where no such file exists, the preset it may have meant
/// (`CT-BONE`, `ct_bone`, `ct-bones` → `ct-bone`), or the presets when it looks like a name.
fn tf_read_error(path: &Path, error: volgraph_accel::transfer_function::TfError) -> anyhow::Error {
    let missing = path.symlink_metadata().is_err_and(|e| e.kind() == std::io::ErrorKind::NotFound);
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or_default();
    if !missing {
        return anyhow!("{error}");
    }
    match ScannerPreset::closest(name) {
        Some(preset) => anyhow!(
            "{error}; did you mean the built-in preset \"{}\" (--tf {})? The presets are {}",
            preset.name(),
            preset.name(),
            ScannerPreset::names()
        ),
        None if path.components().count() == 1 && path.extension().is_none() => {
            anyhow!(
                "{error}; nor is it a built-in preset (they are {}) or a transfer function of the data folder ({})",
                ScannerPreset::names(),
                volgraph_accel::data_dir::data_dir().join("tf").display()
            )
        }
        None => anyhow!("{error}"),
    }
}

/// A warning when the TF's domain and the volume's values do not overlap: every voxel then
/// takes the colour of one end of the TF (clamp to edge), and the volume renders as a uniform
/// box or not at all.
pub fn domain_note(tf: &TransferFunction, volume: &Volume) -> Option<String> {
    // The values the volume holds, not its type's range: a CT in int16 spans −1024…3071, not
    // −32768…32767.
    let (lo, hi) = volume.data_min_max();
    let (d0, d1) = tf.domain;
    if d1 < lo || d0 > hi {
        let side = if d1 < lo { "below" } else { "above" };
        Some(format!(
            "warning: the transfer function's domain [{d0}, {d1}] lies wholly {side} the volume's values [{lo}, {hi}]; \
             every voxel takes the TF's {} colour (a uniform box or nothing); write the control points in the \
             volume's values",
            if d1 < lo { "last" } else { "first" }
        ))
    } else {
        None
    }
}

/// A note when nothing of `volume` can be seen under `lut`: every LUT entry its values reach
/// (with the neighbours linear filtering blends in) has opacity 0, so the image would show only
/// the background. `None` when something may be visible.
pub fn invisible_volume_note(volume: &Volume, lut: &[[f32; 4]]) -> Option<String> {
    let n = volume.voxel_count();
    if n == 0 || lut.is_empty() {
        return None;
    }
    let (lo, hi) = (0..n)
        .map(|i| volume.normalized(i))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    let size = lut.len() as f64;
    let first = ((lo * size - 0.5).floor().max(0.0) as usize).min(lut.len() - 1);
    let last = ((hi * size - 0.5).ceil().max(0.0) as usize).min(lut.len() - 1);
    if lut[first..=last].iter().any(|texel| texel[3] > 0.0) {
        return None;
    }
    let what = if lo == hi {
        format!("volume \"{}\" is constant (every voxel normalizes to {lo:.4})", volume.name)
    } else {
        format!("volume \"{}\" holds values {lo:.4}..={hi:.4} (normalized)", volume.name)
    };
    Some(format!(
        "{what}, and the transfer function gives all of them opacity 0, so the image shows only the background; \
         pass --tf with a transfer function that makes those values visible"
    ))
}

/// Parses `WxH`.
pub fn parse_size(text: &str) -> anyhow::Result<(u32, u32)> {
    let fail = || anyhow!("--size \"{text}\": expected WIDTHxHEIGHT, e.g. 512x512, each 1..=16384");
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(fail)?;
    let w: u32 = w.trim().parse().map_err(|_| fail())?;
    let h: u32 = h.trim().parse().map_err(|_| fail())?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(fail());
    }
    Ok((w, h))
}

/// Parses `azimuth,elevation,distance` (degrees, degrees, world units; the volume's longest
/// side is 1).
pub fn parse_camera(text: &str) -> anyhow::Result<OrbitCamera> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let fail = || {
        anyhow!(
            "--camera \"{text}\": expected AZIMUTH,ELEVATION,DISTANCE in degrees, degrees and world units, e.g. 30,20,3.2"
        )
    };
    if parts.len() != 3 {
        return Err(fail());
    }
    let v: Vec<f64> = parts.iter().map(|p| p.parse::<f64>().map_err(|_| fail())).collect::<Result<_, _>>()?;
    if !v.iter().all(|x| x.is_finite()) || v[2] <= 0.0 {
        bail!("--camera \"{text}\": values must be finite and the distance positive");
    }
    if v[1].abs() > 90.0 {
        bail!("--camera \"{text}\": elevation must be within -90..=90 degrees");
    }
    Ok(OrbitCamera { azimuth_deg: v[0], elevation_deg: v[1], distance: v[2], ..OrbitCamera::default() })
}

/// The scene values a graph's `Data(...)` inputs (`iso_value: Data(Auto)`, values in HU) are
/// resolved with: the volume's data range and automatic iso value.
pub fn data_scene_values(volume: &Volume) -> Vec<(String, f64)> {
    data_scene_values_of(&ValueSummary::of(volume))
}

/// [`data_scene_values`] from the summary of the whole volume.
pub fn data_scene_values_of(values: &ValueSummary) -> Vec<(String, f64)> {
    use volgraph_core::graph::ast::{DATA_AUTO_ISO, DATA_HIGH, DATA_LOW};
    let (lo, hi, auto) = volgraph_accel::histogram::data_scale_in(values);
    vec![(DATA_LOW.to_string(), lo), (DATA_HIGH.to_string(), hi), (DATA_AUTO_ISO.to_string(), auto)]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Only a missing path without a folder part or an extension is a volume's name; what a
    /// generator would make is generated (a bad edge too, so its error names the range).
    #[test]
    fn volume_names_are_missing_plain_names() {
        assert_eq!(volume_name(Path::new("ml64")), Some(VolumeName::Generated("ml64".into())));
        assert_eq!(volume_name(Path::new("ml1")), Some(VolumeName::Generated("ml1".into())));
        assert_eq!(volume_name(Path::new("lobster")), Some(VolumeName::Dataset("lobster".into())));
        for path in ["lobster.raw", "dir/lobster", "./lobster", "..", ".", ""] {
            assert_eq!(volume_name(Path::new(path)), None, "{path}");
        }
    }
}
