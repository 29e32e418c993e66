//! `volgraph info FILE|DIR`: what a user checks first about a volume — dimensions, voxel type,
//! spacing and physical extent, orientation (patient frame), modality and units, the value
//! range, the histogram's percentiles and its background (the low peak of air or scanner noise
//! that the fitted default transfer function starts above), where that transfer function
//! starts, the automatic iso value, and for a DICOM folder the series it holds.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::anyhow;
use volgraph_accel::histogram::Histogram;
use volgraph_accel::load::LoadOptions;
use volgraph_accel::load::dicom;
use volgraph_accel::transfer_function::TransferFunction;
use volgraph_accel::volume::Volume;

/// `--labels` / `--label-table TABLE`: report the volume as a label map, named by TABLE.
#[derive(Clone, Debug, Default)]
pub struct Labels {
    /// The label table, or none for the default palette.
    pub table: Option<PathBuf>,
}

/// The report for `paths`: the series list of a DICOM folder holding several (and the first
/// series, or the one `--series` picks), else the one volume; with `labels`, its labels.
pub fn run(paths: &[PathBuf], options: &LoadOptions<'static>, labels: Option<&Labels>) -> anyhow::Result<String> {
    let named = crate::named_inputs::named_volumes(paths)?;
    if !named.is_empty() {
        return several(&named, options, labels);
    }
    if let [one] = paths
        && volgraph_zarr::is_zarr(one)
    {
        return crate::zarr_input::describe(one);
    }
    let mut out = String::new();
    if dicom::is_dicom_input(paths) {
        let series = dicom::list_series(paths).map_err(|e| anyhow!("{e}"))?;
        let _ = writeln!(out, "DICOM series ({}):\n{}", series.len(), dicom::series_list(&series));
        if series.len() > 1 && options.series.is_none() {
            let _ = writeln!(out, "describing series 1; choose another with --series N");
        }
    }
    let mut chosen = options.clone();
    if dicom::is_dicom_input(paths) && chosen.series.is_none() {
        chosen.series = Some("1".to_string());
    }
    let (volume, notes) = crate::inputs::volume(paths, &chosen)?;
    for note in notes {
        crate::stdout::eprintln_escaped!("note: {note}");
    }
    let name = paths.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(" ");
    out.push_str(&describe(Path::new(&name), &volume));
    if let Some(labels) = labels {
        // A 3D Slicer or DICOM segmentation names its own segments.
        let own = match (&labels.table, paths) {
            (None, [one]) if volgraph_accel::labels::names_its_labels(one) => Labels { table: Some(one.clone()) },
            _ => labels.clone(),
        };
        out.push_str(&label_report(&volume, &own)?);
    }
    Ok(out)
}

/// `volgraph info ct=CT pet=PET …`: each volume's report, then whether they lie in one frame and
/// where their boxes overlap (issue 43, item 6) — what binding them to one graph needs.
fn several(
    named: &[(String, PathBuf)],
    options: &LoadOptions<'static>,
    labels: Option<&Labels>,
) -> anyhow::Result<String> {
    let mut out = String::new();
    let mut volumes = Vec::new();
    for (name, path) in named {
        let (volume, notes) = crate::inputs::volume(std::slice::from_ref(path), options)
            .map_err(|e| anyhow!("{name}={}: {e:#}", path.display()))?;
        for note in notes {
            crate::stdout::eprintln_escaped!("note: {note}");
        }
        let _ = write!(out, "{name}: ");
        out.push_str(&describe(path, &volume));
        volumes.push((name.as_str(), volume));
    }
    if let Some(labels) = labels {
        // --labels describes the last volume (the segmentation listed after its scan).
        if let Some((_, last)) = volumes.last() {
            out.push_str(&label_report(last, labels)?);
        }
    }
    let _ = writeln!(out, "together");
    for (i, (a, va)) in volumes.iter().enumerate() {
        for (b, vb) in &volumes[i + 1..] {
            let _ = writeln!(out, "  {a} and {b}: {}", relation(va, vb));
        }
    }
    Ok(out)
}

/// How two volumes lie to each other: the same grid, boxes overlapping (by what share of each),
/// or apart — in the patient frame when both are in it, else in their index boxes.
fn relation(a: &Volume, b: &Volume) -> String {
    use volgraph_accel::volume_meta::WorldFrame;
    let patient = a.meta.frame == WorldFrame::Lps && b.meta.frame == WorldFrame::Lps;
    if a.meta.frame != b.meta.frame {
        return format!(
            "different frames ({} / {}): where one lies in the other is unknown",
            a.meta.frame.describe(),
            b.meta.frame.describe()
        );
    }
    if let Err(e) = volgraph_accel::fusion::same_frame_of_reference(a, b) {
        return format!("warning: {e}");
    }
    let same_grid = a.dims == b.dims
        && (a.spacing - b.spacing).abs().max_element() <= 1e-6 * a.spacing.max_element()
        && a.meta.origin == b.meta.origin;
    // The box each covers (voxel centres ± half a voxel), in mm from the origin of the patient
    // frame (or from voxel 0 where a file gives no origin).
    let span = |v: &Volume| {
        let lo = v.meta.origin.unwrap_or_default() - v.spacing * 0.5;
        (lo, lo + v.spacing * v.dims.as_dvec3())
    };
    let ((alo, ahi), (blo, bhi)) = (span(a), span(b));
    let (lo, hi) = (alo.max(blo), ahi.min(bhi));
    let size = |lo: glam::DVec3, hi: glam::DVec3| (hi - lo).max(glam::DVec3::ZERO).element_product();
    let common = size(lo, hi);
    let frame = if patient { "in the patient frame" } else { "in index space (no patient frame)" };
    let unit = if patient { " mm" } else { " (spacing units)" };
    let fmt = |lo: glam::DVec3, hi: glam::DVec3| {
        format!("({:.1}, {:.1}, {:.1})–({:.1}, {:.1}, {:.1}){unit}", lo.x, lo.y, lo.z, hi.x, hi.y, hi.z)
    };
    if same_grid {
        format!("the same grid {frame} (one march can sample both voxel for voxel)")
    } else if common <= 0.0 {
        format!("warning: their boxes do not overlap {frame}: {} and {}", fmt(alo, ahi), fmt(blo, bhi))
    } else {
        format!(
            "boxes overlap {frame} over {:.1} % of the first and {:.1} % of the second ({}); grids differ",
            100.0 * common / size(alo, ahi),
            100.0 * common / size(blo, bhi),
            fmt(lo, hi)
        )
    }
}

/// The labels of `volume` as a label map: one line a value present, named by the table.
pub fn label_report(volume: &Volume, labels: &Labels) -> anyhow::Result<String> {
    use volgraph_accel::labels::{LabelTable, census::census};
    let census = census(volume).map_err(|e| anyhow!("{e}"))?;
    let values = census.values();
    let (table, table_notes) = match &labels.table {
        Some(path) => LabelTable::read(path).map_err(|e| anyhow!("{e}"))?,
        None => (LabelTable::default_for(values.iter().copied()), Vec::new()),
    };
    // Millilitres where the spacing is in millimetres: a file in the patient frame (DICOM, NIfTI,
    // an anatomical NRRD space); a raw volume's spacing has no unit.
    let physical = volume.meta.frame == volgraph_accel::volume_meta::WorldFrame::Lps;
    let mut out = String::new();
    let labelled = values.iter().filter(|v| **v != 0).count();
    let _ = writeln!(
        out,
        "  labels       {labelled} label{} and {}, names from {}",
        if labelled == 1 { "" } else { "s" },
        if values.first() == Some(&0) { "the background (0)" } else { "no background (no 0)" },
        dicom::one_line(&table.source)
    );
    let width = values.iter().map(|v| dicom::one_line(&table.label(*v).name).chars().count()).max().unwrap_or(4).max(4);
    let size = if physical { "volume" } else { "volume (spacing units³)" };
    let _ = writeln!(out, "    {:>6}  {:<width$}  {:>12}  {size}", "value", "name", "voxels");
    for count in &census.counts {
        let label = table.label(count.value);
        let amount = census.millilitres(count.voxels);
        let volume_text = if physical {
            format!("{amount:.3} mL")
        } else {
            format!("{:.4}", count.voxels as f64 * census.voxel_volume)
        };
        let shown = if label.visible { "" } else { "  (hidden)" };
        let _ = writeln!(
            out,
            "    {:>6}  {:<width$}  {:>12}  {volume_text}{shown}",
            count.value,
            dicom::one_line(&label.name),
            count.voxels
        );
    }
    for note in table_notes {
        let _ = writeln!(out, "  note: {}", dicom::one_line(&note));
    }
    if labels.table.is_some() {
        let unnamed: Vec<u32> = values.iter().copied().filter(|v| *v != 0 && !table.labels.contains_key(v)).collect();
        if !unnamed.is_empty() {
            let _ = writeln!(
                out,
                "  note: {} value{} of the map {} no entry in the table ({}): shown with the default palette",
                unnamed.len(),
                if unnamed.len() == 1 { "" } else { "s" },
                if unnamed.len() == 1 { "has" } else { "have" },
                list(&unnamed)
            );
        }
        let missing = table.missing_from(&values);
        if !missing.is_empty() {
            let _ = writeln!(
                out,
                "  note: the table names {} label{} the map lacks ({})",
                missing.len(),
                if missing.len() == 1 { "" } else { "s" },
                list(&missing)
            );
        }
    }
    Ok(out)
}

/// Up to eight values, then how many more.
fn list(values: &[u32]) -> String {
    let shown: Vec<String> = values.iter().take(8).map(u32::to_string).collect();
    match values.len() {
        n if n > 8 => format!("{}, … {} more", shown.join(", "), n - 8),
        _ => shown.join(", "),
    }
}

/// The report on `volume`, read from `path`.
pub fn describe(path: &Path, volume: &Volume) -> String {
    let (lo, hi) = volume.value_range;
    let data = |normalized: f64| lo + normalized * (hi - lo);
    let d = volume.dims;
    let e = volume.extent();
    let meta = &volume.meta;
    // Header text (a DICOM SeriesDescription, a NIfTI `descrip`) shown on one line: a newline
    // in it would forge a line of this report (`error: …`).
    let shown = |text: &str| dicom::one_line(text);
    let units = meta.units.as_deref().map_or(String::new(), |u| format!(" {}", shown(u)));
    let mut out = String::new();
    let _ = writeln!(out, "{}", path.display());
    if let Some(description) = &meta.description {
        let _ = writeln!(out, "  description  {}", shown(description));
    }
    let _ = writeln!(
        out,
        "  modality     {}, values in {}",
        meta.modality.as_deref().map_or("unknown".into(), shown),
        meta.units.as_deref().map_or("file units (no physical unit given)".into(), shown)
    );
    let _ = writeln!(out, "  dimensions   {} × {} × {} voxels, {}", d.x, d.y, d.z, volume.data.type_name());
    let _ = writeln!(
        out,
        "  spacing      {} × {} × {} (extent {:.4} × {:.4} × {:.4})",
        volume.spacing.x, volume.spacing.y, volume.spacing.z, e.x, e.y, e.z
    );
    let _ = writeln!(out, "  orientation  {}", meta.frame.describe());
    if let Some(o) = meta.origin {
        let _ = writeln!(out, "  origin       ({:.3}, {:.3}, {:.3}) mm, the centre of voxel (0, 0, 0)", o.x, o.y, o.z);
    }
    let _ = writeln!(out, "  value range  {lo} … {hi}{units} (normalized to 0 … 1 on the GPU)");
    if let Some(w) = meta.window {
        let _ = writeln!(out, "  window       centre {} width {}{units} (from the file)", w.center, w.width);
    }
    let h = Histogram::of(volume, 256);
    let _ = writeln!(
        out,
        "  percentiles  1 %: {:.4}   50 %: {:.4}   99 %: {:.4}   (data values)",
        data(h.percentile(0.01)),
        data(h.percentile(0.5)),
        data(h.percentile(0.99))
    );
    let values = volgraph_accel::histogram::ValueSummary::of(volume);
    if let Some(p) = values.padding() {
        let _ = writeln!(
            out,
            "  padding      {:.1} % of the voxels at {:.4}{units}, below the Hounsfield scale's floor and apart from every \
             other value (outside the scanner's field of view): hidden, and left out of the background",
            100.0 * p.fraction,
            data(p.value)
        );
    }
    match volgraph_accel::histogram::background_in(&values) {
        Some(b) => {
            let _ = writeln!(
                out,
                "  background   the histogram's low mode at {:.4}{units}: {:.1} % of the voxels lie in it, from {:.4} to \
                 {:.4}{units} (air or the scanner's noise floor)",
                data(b.mode),
                100.0 * b.fraction,
                data(b.floor),
                data(b.ceiling)
            );
        }
        None => {
            let _ = writeln!(
                out,
                "  background   none (no mode at or below the median holding a tenth of the voxels{})",
                if values.hounsfield() { ", below -500 HU" } else { "" }
            );
        }
    }
    // Where the fitted default (`TransferFunction::default_for`) stops being transparent: the
    // last transparent point before the first visible one.
    let tf = TransferFunction::default_for(volume);
    let first_visible = tf.points.iter().position(|p| p.alpha > 0.0).unwrap_or(0);
    let clear_to = first_visible.checked_sub(1).map_or(lo, |i| tf.points[i].value);
    let _ = writeln!(
        out,
        "  default TF   the default ramp over {lo} … {hi}, transparent up to {clear_to:.4} (see the background)"
    );
    let _ = writeln!(
        out,
        "  auto iso     {:.4}{units} (iso_value: Auto; normalized {:.4})",
        data(volgraph_accel::histogram::auto_iso(volume)),
        volgraph_accel::histogram::auto_iso(volume)
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_report_names_every_figure() {
        let volume = volgraph_accel::generate::marschner_lobb(16);
        let text = describe(Path::new("ml16"), &volume);
        for expected in
            ["16 × 16 × 16 voxels, uint8", "spacing", "value range  0 … 255", "percentiles", "background", "default TF"]
        {
            assert!(text.contains(expected), "missing {expected:?} in\n{text}");
        }
    }
}
