//! `volgraph info FILE`: what a user checks first about a volume — dimensions, voxel type,
//! spacing and physical extent, the value range, the histogram's percentiles and its background
//! (the low peak of air or scanner noise that the fitted default transfer function starts
//! above), and where that transfer function starts.

use std::fmt::Write as _;
use std::path::Path;

use volgraph_accel::histogram::Histogram;
use volgraph_accel::transfer_function::TransferFunction;
use volgraph_accel::volume::Volume;

/// The report on `volume`, read from `path`.
pub fn describe(path: &Path, volume: &Volume) -> String {
    let (lo, hi) = volume.value_range;
    let data = |normalized: f64| lo + normalized * (hi - lo);
    let d = volume.dims;
    let e = volume.extent();
    let mut out = String::new();
    let _ = writeln!(out, "{}", path.display());
    let _ = writeln!(out, "  dimensions   {} × {} × {} voxels, {}", d.x, d.y, d.z, volume.data.type_name());
    let _ = writeln!(
        out,
        "  spacing      {} × {} × {} (extent {:.4} × {:.4} × {:.4})",
        volume.spacing.x, volume.spacing.y, volume.spacing.z, e.x, e.y, e.z
    );
    let _ = writeln!(out, "  value range  {lo} … {hi} (normalized to 0 … 1 on the GPU)");
    let h = Histogram::of(volume, 256);
    let _ = writeln!(
        out,
        "  percentiles  1 %: {:.4}   50 %: {:.4}   99 %: {:.4}   (data values)",
        data(h.percentile(0.01)),
        data(h.percentile(0.5)),
        data(h.percentile(0.99))
    );
    match h.background() {
        Some(b) => {
            let _ = writeln!(
                out,
                "  background   a peak at {:.4} holding {:.1} % of the voxels, up to {:.4} (air or the scanner's noise \
                 floor)",
                data(b.mode),
                100.0 * b.fraction,
                data(b.ceiling)
            );
        }
        None => {
            let _ = writeln!(out, "  background   none (no low peak holding a tenth of the voxels)");
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
