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

/// One colour map chosen from a ParaView file, with what the user should know about the choice.
#[derive(Clone, Debug, PartialEq)]
pub struct ParaviewColorMap {
    /// The transfer function.
    pub tf: TransferFunction,
    /// The map's `"Name"`, when it has one.
    pub name: Option<String>,
    /// Its index in the file's array (0 for a single object).
    pub index: usize,
    /// Every map's name (or `#i` for unnamed ones), in file order.
    pub all: Vec<String>,
    /// What was approximated (midpoint/sharpness other than linear), one sentence each.
    pub notes: Vec<String>,
}

fn map_label(map: &Value, i: usize) -> String {
    map.get("Name").and_then(Value::as_str).map_or_else(|| format!("#{i}"), str::to_string)
}

/// Parses ParaView colour-map JSON and picks map `wanted` (its `"Name"`, or `#i`), the first
/// when `None`.
pub(super) fn parse_map(text: &str, path: &Path, wanted: Option<&str>) -> Result<ParaviewColorMap, TfError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let root: Value = serde_json::from_str(text).map_err(|e| {
        // serde_json appends " at line L column C"; the location is shown in front instead.
        let full = e.to_string();
        let message = full.split(" at line ").next().unwrap_or(&full).to_string();
        TfError::Json { path: path.to_path_buf(), line: e.line(), col: e.column(), message }
    })?;
    let fail = |message: String| TfError::Paraview { path: path.to_path_buf(), message };
    let maps: Vec<&Value> = match &root {
        Value::Array(items) => items.iter().collect(),
        other => vec![other],
    };
    if maps.is_empty() {
        return Err(fail("the JSON array is empty; it needs one colour map object with \"RGBPoints\"".into()));
    }
    let all: Vec<String> = maps.iter().enumerate().map(|(i, m)| map_label(m, i)).collect();
    let index = match wanted {
        None => 0,
        Some(w) => all.iter().position(|n| n == w).ok_or_else(|| {
            let list = all.iter().map(|n| format!("\"{n}\"")).collect::<Vec<_>>().join(", ");
            let guess = all
                .iter()
                .map(|n| (strsim::normalized_levenshtein(w, n), n))
                .filter(|(score, _)| *score >= 0.6)
                .max_by(|a, b| a.0.total_cmp(&b.0))
                .map_or(String::new(), |(_, g)| format!("did you mean \"{g}\"? "));
            fail(format!("holds no colour map named \"{w}\"; {guess}it holds: {list}"))
        })?,
    };
    let map = maps[index];
    let Some(object) = map.as_object() else {
        return Err(fail("expected a colour map object (or an array of them) with \"RGBPoints\"".into()));
    };
    let rgb = quads(object, "RGBPoints", "x, r, g, b").map_err(&fail)?;
    let opacity = match object.get("Points") {
        Some(_) => Some(quads(object, "Points", "x, alpha, midpoint, sharpness").map_err(&fail)?),
        None => None,
    };
    // Same rule as the RON format: colours and opacities are in [0, 1], never clamped silently.
    for (i, q) in rgb.iter().enumerate() {
        for (k, channel) in ["r", "g", "b"].iter().enumerate() {
            let v = q[k + 1];
            if !(0.0..=1.0).contains(&v) {
                return Err(fail(format!(
                    "RGBPoints point {i} ({channel}, RGBPoints[{}]) = {v} is outside [0, 1]; ParaView colours are sRGB in 0..1",
                    4 * i + k + 1
                )));
            }
        }
    }
    let mut notes = Vec::new();
    for (i, q) in opacity.iter().flatten().enumerate() {
        if !(0.0..=1.0).contains(&q[1]) {
            return Err(fail(format!(
                "Points point {i} (alpha, Points[{}]) = {} is outside [0, 1]; opacity is in 0..1",
                4 * i + 1,
                q[1]
            )));
        }
        if (q[2] - 0.5).abs() > 1e-9 || q[3].abs() > 1e-9 {
            notes.push(format!(
                "Points point {i} has midpoint {} and sharpness {}; volgraph interpolates opacity linearly \
                 (midpoint 0.5, sharpness 0)",
                q[2], q[3]
            ));
        }
    }

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
        Some(points) => points.iter().map(|q| (q[0], [q[1]])).collect(),
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
    let name = map.get("Name").and_then(Value::as_str).map(str::to_string);
    Ok(ParaviewColorMap { tf, name, index, all, notes })
}
