//! Where a series' slices lie: sorted along the slice normal by ImagePositionPatient (never by
//! file name or InstanceNumber), spacing from the positions, and the three direction vectors
//! that [`crate::load::AxisOrientation`] turns into flips and axis swaps (DICOM PS3.3
//! C.7.6.2.1.1: ImageOrientationPatient holds the row direction — the way the column index
//! grows — then the column direction; PixelSpacing is the row spacing, then the column
//! spacing).

use std::path::PathBuf;

use glam::DVec3;

use super::super::LoadError;

/// Positions closer than this (mm) along the normal are the same position.
const SAME_POSITION_MM: f64 = 1e-3;
/// Spacing differences below this share of the median are rounding in the header.
const SPACING_TOLERANCE: f64 = 0.01;
/// A step this many times the median spacing or more is a gap: slices are missing.
const GAP_FACTOR: f64 = 1.5;
/// Direction cosines that differ by less than this are the same orientation.
const ORIENTATION_TOLERANCE: f64 = 1e-4;
/// ImageOrientationPatient's vectors are unit length and perpendicular within this (headers
/// round the cosines to a few digits).
const UNIT_TOLERANCE: f64 = 1e-2;

/// What geometry needs of one slice's header.
#[derive(Clone, Debug, PartialEq)]
pub struct SliceGeometry {
    /// The file.
    pub path: PathBuf,
    /// ImagePositionPatient: the centre of the first pixel, mm.
    pub position: Option<DVec3>,
    /// ImageOrientationPatient: row direction then column direction.
    pub orientation: Option<[f64; 6]>,
    /// PixelSpacing: between rows, then between columns (mm).
    pub pixel_spacing: Option<[f64; 2]>,
    /// Rows, Columns.
    pub rows: u32,
    /// Columns.
    pub columns: u32,
}

/// The sorted stack: slice order, and the world step of one voxel along each file axis
/// (column index, row index, slice).
#[derive(Clone, Debug, PartialEq)]
pub struct Stack {
    /// Indices into the input, in increasing position along the normal.
    pub order: Vec<usize>,
    /// World step per file axis: along a row, down a column, to the next slice.
    pub directions: [DVec3; 3],
    /// The centre of the first pixel of the first slice (mm).
    pub origin: DVec3,
    /// Warnings (unequal spacing), one sentence each.
    pub notes: Vec<String>,
}

fn geometry_error(series: &str, message: String) -> LoadError {
    LoadError::DicomGeometry { series: series.to_string(), message }
}

fn name(s: &SliceGeometry) -> String {
    s.path.display().to_string()
}

/// Sorts `slices` of series `series` and derives the stack's geometry; `slice_thickness` is the
/// fallback spacing of a one-slice series.
pub fn stack(series: &str, slices: &[SliceGeometry], slice_thickness: Option<f64>) -> Result<Stack, LoadError> {
    let first = slices.first().ok_or_else(|| geometry_error(series, "the series has no slices".into()))?;
    for s in slices {
        if (s.rows, s.columns) != (first.rows, first.columns) {
            return Err(geometry_error(
                series,
                format!(
                    "slices of different sizes: {} is {}x{} pixels but {} is {}x{}; a volume needs equal slices \
                     (pick one series with --series, or remove the odd files)",
                    name(first),
                    first.columns,
                    first.rows,
                    name(s),
                    s.columns,
                    s.rows
                ),
            ));
        }
    }
    let orientation = first.orientation.unwrap_or([1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    for s in slices {
        let o = s.orientation.unwrap_or(orientation);
        if o.iter().zip(&orientation).any(|(a, b)| (a - b).abs() > ORIENTATION_TOLERANCE) {
            return Err(geometry_error(
                series,
                format!(
                    "{} has ImageOrientationPatient {} but {} has {}; the slices of one volume share one \
                     orientation (pick one series with --series)",
                    name(s),
                    numbers_text(&o),
                    name(first),
                    numbers_text(&orientation)
                ),
            ));
        }
    }
    let row = DVec3::new(orientation[0], orientation[1], orientation[2]);
    let column = DVec3::new(orientation[3], orientation[4], orientation[5]);
    let normal = row.cross(column);
    let unit = |v: DVec3| (v.length() - 1.0).abs() <= UNIT_TOLERANCE;
    if !(unit(row) && unit(column) && row.dot(column).abs() <= UNIT_TOLERANCE) {
        return Err(geometry_error(
            series,
            format!(
                "{}: ImageOrientationPatient (0020,0037) {} is not two perpendicular unit vectors (lengths {} and {}, \
                 dot product {}); fix the header (e.g. with dcmodify) or remove the file",
                name(first),
                numbers_text(&orientation),
                num(row.length()),
                num(column.length()),
                num(row.dot(column))
            ),
        ));
    }
    let (row, column, normal) = (row.normalize(), column.normalize(), normal.normalize());
    let mut notes = Vec::new();
    if first.pixel_spacing.is_none() {
        notes.push(format!(
            "{} has no PixelSpacing (0028,0030): 1 × 1 mm pixels assumed; give --spacing if the images have a known size",
            name(first)
        ));
    }
    let [row_spacing, column_spacing] = first.pixel_spacing.unwrap_or([1.0, 1.0]);
    if !(row_spacing > 0.0 && column_spacing > 0.0 && row_spacing.is_finite() && column_spacing.is_finite()) {
        return Err(geometry_error(
            series,
            format!(
                "{}: PixelSpacing (0028,0030) {}\\{} must be two positive numbers (mm)",
                name(first),
                num(row_spacing),
                num(column_spacing)
            ),
        ));
    }

    let mut positions = Vec::with_capacity(slices.len());
    for s in slices {
        match s.position {
            Some(p) if p.is_finite() => positions.push(p),
            _ => {
                return Err(geometry_error(
                    series,
                    format!(
                        "{} has no ImagePositionPatient (0020,0032); volgraph orders slices by their position, \
                         never by file name or InstanceNumber; the file is not a cross-sectional image or lost its \
                         geometry",
                        name(s)
                    ),
                ));
            }
        }
    }
    let along: Vec<f64> = positions.iter().map(|p| p.dot(normal)).collect();
    let mut order: Vec<usize> = (0..slices.len()).collect();
    order.sort_by(|&a, &b| along[a].total_cmp(&along[b]));

    let spacing = if order.len() < 2 {
        slice_thickness.filter(|t| *t > 0.0 && t.is_finite()).unwrap_or(row_spacing.min(column_spacing))
    } else {
        let steps: Vec<f64> = order.windows(2).map(|w| along[w[1]] - along[w[0]]).collect();
        if let Some(k) = steps.iter().position(|s| !s.is_finite()) {
            return Err(geometry_error(
                series,
                format!(
                    "{} at {} and {} at {} are too far apart to measure (ImagePositionPatient (0020,0032) values \
                     near 1e308); fix the header (e.g. with dcmodify) or remove the odd file",
                    name(&slices[order[k]]),
                    position_text(positions[order[k]]),
                    name(&slices[order[k + 1]]),
                    position_text(positions[order[k + 1]])
                ),
            ));
        }
        for (k, &step) in steps.iter().enumerate() {
            if step < SAME_POSITION_MM {
                let (a, b) = (&slices[order[k]], &slices[order[k + 1]]);
                return Err(geometry_error(
                    series,
                    format!(
                        "{} and {} lie at the same position {} along the slice normal ({:.3} mm); a series holds one \
                         slice per position: remove the duplicate (or pick one series with --series)",
                        name(a),
                        name(b),
                        position_text(positions[order[k]]),
                        along[order[k]]
                    ),
                ));
            }
        }
        let mut sorted = steps.clone();
        sorted.sort_by(f64::total_cmp);
        let median = sorted[sorted.len() / 2];
        if let Some(k) = steps.iter().position(|&s| s >= GAP_FACTOR * median) {
            let missing = ((steps[k] / median).round() as usize).saturating_sub(1);
            return Err(geometry_error(
                series,
                format!(
                    "a gap: {} slices of {median:.3} mm step, but {:.3} mm between {} at {:.3} mm and {} at {:.3} mm — \
                     about {missing} slice(s) missing; the series is incomplete (copy the missing files)",
                    steps.len() + 1,
                    steps[k],
                    name(&slices[order[k]]),
                    along[order[k]],
                    name(&slices[order[k + 1]]),
                    along[order[k + 1]]
                ),
            ));
        }
        let (lo, hi) = (sorted[0], sorted[sorted.len() - 1]);
        let mean = (along[order[order.len() - 1]] - along[order[0]]) / steps.len() as f64;
        if hi - lo > SPACING_TOLERANCE * median {
            let k = steps.iter().position(|&s| s == hi).unwrap_or(0);
            notes.push(format!(
                "warning: unequal slice spacing, {lo:.3} to {hi:.3} mm (the widest between {} and {}); rendered with \
                 the mean {mean:.3} mm",
                name(&slices[order[k]]),
                name(&slices[order[k + 1]])
            ));
        }
        // In-plane drift between slices (gantry tilt) would need a sheared grid.
        let first_pos = positions[order[0]];
        for &i in &order {
            let offset = positions[i] - first_pos;
            let lateral = offset - normal * offset.dot(normal);
            if lateral.length() > 0.01 * row_spacing.min(column_spacing).max(mean) {
                return Err(geometry_error(
                    series,
                    format!(
                        "{} at {} is shifted {:.3} mm sideways from the first slice: the slices are not stacked along \
                         their normal (gantry tilt or a sheared acquisition); volgraph renders axis-aligned grids: \
                         resample the series (e.g. 3D Slicer's \"Resample Scalar Volume\") first",
                        name(&slices[i]),
                        position_text(positions[i]),
                        lateral.length()
                    ),
                ));
            }
        }
        mean
    };
    if !(spacing.is_finite() && spacing > 0.0) {
        return Err(geometry_error(
            series,
            format!(
                "the slices' ImagePositionPatient (0020,0032) values, from {} to {}, give a slice spacing of {} mm, not \
                 a finite positive distance; fix the header (e.g. with dcmodify) or remove the odd files",
                position_text(positions[order[0]]),
                position_text(positions[order[order.len() - 1]]),
                num(spacing)
            ),
        ));
    }
    Ok(Stack {
        origin: positions[order[0]],
        order,
        directions: [row * column_spacing, column * row_spacing, normal * spacing],
        notes,
    })
}

fn position_text(p: DVec3) -> String {
    format!("({}, {}, {})", num(p.x), num(p.y), num(p.z))
}

/// `v` for a message: up to three decimals, or in scientific notation where that would print
/// hundreds of digits (1e300) or only zeros.
fn num(v: f64) -> String {
    if v == 0.0 || (1e-3..1e9).contains(&v.abs()) {
        let text = format!("{v:.3}");
        let text = text.trim_end_matches('0').trim_end_matches('.');
        if text == "-0" { "0".to_string() } else { text.to_string() }
    } else {
        format!("{v:.3e}")
    }
}

/// Numbers as a DICOM multi-value: `1\\0\\0\\0\\1\\0`.
fn numbers_text(values: &[f64]) -> String {
    values.iter().map(|&v| num(v)).collect::<Vec<_>>().join("\\")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn slice(i: usize, z: f64) -> SliceGeometry {
        SliceGeometry {
            path: PathBuf::from(format!("s{i}.dcm")),
            position: Some(DVec3::new(-10.0, -20.0, z)),
            orientation: Some([1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
            pixel_spacing: Some([0.5, 0.7]),
            rows: 4,
            columns: 3,
        }
    }

    #[test]
    fn slices_sort_by_position_not_by_input_order() {
        let slices: Vec<_> = [4.0, 0.0, 2.0, 6.0].iter().enumerate().map(|(i, &z)| slice(i, z)).collect();
        let s = stack("s", &slices, None).expect("a stack");
        assert_eq!(s.order, vec![1, 2, 0, 3]);
        assert_eq!(s.directions, [DVec3::new(0.7, 0.0, 0.0), DVec3::new(0.0, 0.5, 0.0), DVec3::new(0.0, 0.0, 2.0)]);
        assert!(s.notes.is_empty());
    }

    #[test]
    fn a_gap_names_the_slices_around_it() {
        let slices: Vec<_> = [0.0, 2.0, 4.0, 8.0, 10.0].iter().enumerate().map(|(i, &z)| slice(i, z)).collect();
        let e = stack("s", &slices, None).expect_err("a gap").to_string();
        assert!(
            e.contains("between s2.dcm at 4.000 mm and s3.dcm at 8.000 mm") && e.contains("1 slice(s) missing"),
            "{e}"
        );
    }

    #[test]
    fn positions_too_far_apart_are_an_error_not_a_panic() {
        let slices: Vec<_> = [-1.7e308, 1.7e308].iter().enumerate().map(|(i, &z)| slice(i, z)).collect();
        let e = stack("s", &slices, None).expect_err("too far").to_string();
        assert!(
            e.contains("s0.dcm at (-10, -20, -1.700e308) and s1.dcm at (-10, -20, 1.700e308) are too far apart"),
            "{e}"
        );
    }

    #[test]
    fn a_duplicate_position_is_an_error() {
        let slices: Vec<_> = [0.0, 2.0, 2.0].iter().enumerate().map(|(i, &z)| slice(i, z)).collect();
        let e = stack("s", &slices, None).expect_err("a duplicate").to_string();
        assert!(e.contains("s1.dcm and s2.dcm lie at the same position"), "{e}");
    }
}
