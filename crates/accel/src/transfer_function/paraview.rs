//! ParaView colour-map JSON import (the format of ParaView's "Export colour map" and its
//! `ColorMaps.json`). See [`super::TransferFunction::load_paraview`] for the rules.

use std::path::Path;

use serde_json::Value;

use super::{ControlPoint, TfError, TransferFunction};

/// sRGB-encoded channel → linear (IEC 61966-2-1).
fn srgb_to_linear(c: f64) -> f64 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

/// Groups a flat number array `[x, a, b, c, x, …]` into `[x, a, b, c]` quadruples, checking the
/// shape and that x never decreases.
fn quads(object: &serde_json::Map<String, Value>, key: &str, layout: &str) -> Result<Vec<[f64; 4]>, String> {
    let Some(value) = object.get(key) else {
        return Err(format!("the colour map has no \"{key}\" array; it needs [{layout}, …]"));
    };
    let Some(items) = value.as_array() else {
        return Err(format!("\"{key}\" is not an array; it needs [{layout}, …]"));
    };
    let mut numbers = Vec::with_capacity(items.len());
    for (i, item) in items.iter().enumerate() {
        match item.as_f64() {
            Some(n) => numbers.push(n),
            None => return Err(format!("{key}[{i}] is {item}, not a number")),
        }
    }
    if numbers.is_empty() || numbers.len() % 4 != 0 {
        return Err(format!("\"{key}\" has {} numbers; it needs groups of four ({layout})", numbers.len()));
    }
    let groups: Vec<[f64; 4]> = numbers.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
    for (i, pair) in groups.windows(2).enumerate() {
        if pair[1][0] < pair[0][0] {
            return Err(format!(
                "\"{key}\" x values must increase, but point {} has x = {} after x = {}",
                i + 1,
                pair[1][0],
                pair[0][0]
            ));
        }
    }
    Ok(groups)
}

/// Piecewise-linear interpolation of `(x, values)` rows at `x`, clamped at the ends.
fn interpolate<const N: usize>(rows: &[(f64, [f64; N])], x: f64) -> [f64; N] {
    let upper = rows.partition_point(|r| r.0 <= x);
    match upper {
        0 => rows.first().map(|r| r.1).unwrap_or([0.0; N]),
        u if u == rows.len() => rows[u - 1].1,
        u => {
            let (a, b) = (&rows[u - 1], &rows[u]);
            let t = (x - a.0) / (b.0 - a.0);
            std::array::from_fn(|k| a.1[k] + t * (b.1[k] - a.1[k]))
        }
    }
}

pub(super) fn parse(text: &str, path: &Path) -> Result<TransferFunction, TfError> {
    let root: Value = serde_json::from_str(text).map_err(|e| {
        // serde_json appends " at line L column C"; the location is shown in front instead.
        let full = e.to_string();
        let message = full.split(" at line ").next().unwrap_or(&full).to_string();
        TfError::Json { path: path.to_path_buf(), line: e.line(), col: e.column(), message }
    })?;
    let fail = |message: String| TfError::Paraview { path: path.to_path_buf(), message };
    let map = match &root {
        Value::Array(items) => items
            .first()
            .ok_or_else(|| fail("the JSON array is empty; it needs one colour map object with \"RGBPoints\"".into()))?,
        other => other,
    };
    let Some(object) = map.as_object() else {
        return Err(fail("expected a colour map object (or an array of them) with \"RGBPoints\"".into()));
    };
    let rgb = quads(object, "RGBPoints", "x, r, g, b").map_err(&fail)?;
    let opacity = match object.get("Points") {
        Some(_) => Some(quads(object, "Points", "x, alpha, midpoint, sharpness").map_err(&fail)?),
        None => None,
    };

    let xs_rgb = rgb.iter().map(|q| q[0]);
    let xs_alpha = opacity.iter().flatten().map(|q| q[0]);
    let mut xs: Vec<f64> = xs_rgb.chain(xs_alpha).filter(|x| x.is_finite()).collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    let (Some(&lo), Some(&hi)) = (xs.first(), xs.last()) else {
        return Err(fail("no finite x value in \"RGBPoints\"".into()));
    };
    if lo >= hi {
        return Err(fail(format!("every point has x = {lo}; a colour map needs two different x values")));
    }

    let colors: Vec<(f64, [f64; 3])> = rgb.iter().map(|q| (q[0], [q[1], q[2], q[3]].map(srgb_to_linear))).collect();
    let alphas: Vec<(f64, [f64; 1])> = match &opacity {
        Some(points) => points.iter().map(|q| (q[0], [q[1].clamp(0.0, 1.0)])).collect(),
        None => vec![(lo, [0.0]), (hi, [1.0])],
    };
    let points = xs
        .iter()
        .map(|&x| ControlPoint {
            value: x,
            color: interpolate(&colors, x).map(|c| c.clamp(0.0, 1.0)),
            alpha: interpolate(&alphas, x)[0],
        })
        .collect();
    let tf = TransferFunction { domain: (lo, hi), points };
    tf.validate(path)?;
    Ok(tf)
}
