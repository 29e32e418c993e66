//! ParaView colour-map JSON import (the format of ParaView's "Export colour map" and its
//! `ColorMaps.json`). See [`super::TransferFunction::load_paraview`] for the rules.

use std::path::Path;

use serde_json::Value;

use super::{ControlPoint, TfError, TransferFunction};
use crate::srgb;

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
/// Points between each pair of `[x, r, g, b]` points (sRGB) along the HSV path between them.
fn hsv_resampled(rgb: &[[f64; 4]]) -> Vec<[f64; 4]> {
    const STEPS: usize = 32;
    let mut out = Vec::with_capacity(rgb.len() * STEPS);
    for pair in rgb.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let (ha, hb) = (rgb_to_hsv([a[1], a[2], a[3]]), rgb_to_hsv([b[1], b[2], b[3]]));
        // The hue of a grey point is undefined: take the other end's.
        let (ha, hb) = match (ha[1] == 0.0, hb[1] == 0.0) {
            (true, false) => ([hb[0], ha[1], ha[2]], hb),
            (false, true) => (ha, [ha[0], hb[1], hb[2]]),
            _ => (ha, hb),
        };
        let mut dh = hb[0] - ha[0];
        if dh > 0.5 {
            dh -= 1.0;
        } else if dh < -0.5 {
            dh += 1.0;
        }
        for k in 0..STEPS {
            let t = k as f64 / STEPS as f64;
            let h = (ha[0] + t * dh).rem_euclid(1.0);
            let c = hsv_to_rgb([h, ha[1] + t * (hb[1] - ha[1]), ha[2] + t * (hb[2] - ha[2])]);
            out.push([a[0] + t * (b[0] - a[0]), c[0], c[1], c[2]]);
        }
    }
    if let Some(last) = rgb.last() {
        out.push(*last);
    }
    out
}

/// `[h, s, v]` in 0..1 of an RGB colour in 0..1.
fn rgb_to_hsv([r, g, b]: [f64; 3]) -> [f64; 3] {
    let max = r.max(g).max(b);
    let min = r.min(g).min(b);
    let d = max - min;
    let h = if d == 0.0 {
        0.0
    } else if max == r {
        ((g - b) / d).rem_euclid(6.0) / 6.0
    } else if max == g {
        ((b - r) / d + 2.0) / 6.0
    } else {
        ((r - g) / d + 4.0) / 6.0
    };
    [h, if max == 0.0 { 0.0 } else { d / max }, max]
}

/// The RGB colour of `[h, s, v]` in 0..1.
fn hsv_to_rgb([h, s, v]: [f64; 3]) -> [f64; 3] {
    let h6 = h.rem_euclid(1.0) * 6.0;
    let i = h6.floor();
    let f = h6 - i;
    let (p, q, t) = (v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f)));
    match i as u32 % 6 {
        0 => [v, t, p],
        1 => [q, v, p],
        2 => [p, v, t],
        3 => [p, q, v],
        4 => [t, p, v],
        _ => [v, p, q],
    }
}

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

    // ParaView interpolates colours in its `ColorSpace`: RGB (the default) is what the LUT's
    // linear interpolation between points does; for HSV, points are added along each segment
    // (hue the short way round, as ParaView's default HSVWrap does), so the piecewise-linear
    // LUT follows the HSV path within 1/255.
    let space = object.get("ColorSpace").and_then(Value::as_str).unwrap_or("RGB");
    let rgb = match space.to_ascii_uppercase().as_str() {
        "RGB" => rgb,
        "HSV" => hsv_resampled(&rgb),
        other => {
            notes.push(format!(
                "ColorSpace \"{space}\" is not supported ({other}); its colours are interpolated in RGB instead \
                 (RGB and HSV are)"
            ));
            rgb
        }
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

    let colors: Vec<(f64, [f64; 3])> = rgb.iter().map(|q| (q[0], [q[1], q[2], q[3]].map(srgb::decode))).collect();
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

/// `tf` as ParaView colour-map JSON, written into `original` (the file it came from) when that
/// parses: map `index` of it takes the new `RGBPoints` (sRGB), `Points` (linear opacity,
/// midpoint 0.5, sharpness 0) and `ColorSpace` "RGB", and every other map and key is kept; a
/// fresh single map otherwise. The domain's ends are written as points, so reading it back
/// gives the same function.
pub(super) fn write_map(tf: &TransferFunction, original: Option<&str>, index: usize) -> String {
    let mut points = tf.points.clone();
    for (end, at_start) in [(tf.domain.0, true), (tf.domain.1, false)] {
        let present = points.iter().any(|p| p.value == end);
        if !present {
            let [r, g, b, a] = tf.eval(end);
            let point = ControlPoint { value: end, color: [r, g, b], alpha: a };
            if at_start { points.insert(0, point) } else { points.push(point) }
        }
    }
    let rgb: Vec<Value> = points
        .iter()
        .flat_map(|p| [p.value, srgb::encode(p.color[0]), srgb::encode(p.color[1]), srgb::encode(p.color[2])])
        .map(Value::from)
        .collect();
    let alpha: Vec<Value> = points.iter().flat_map(|p| [p.value, p.alpha, 0.5, 0.0]).map(Value::from).collect();
    let mut root: Value = original
        .and_then(|t| serde_json::from_str(t.strip_prefix('\u{feff}').unwrap_or(t)).ok())
        .unwrap_or_else(|| serde_json::json!([{ "Name": "volgraph" }]));
    let map = match &mut root {
        Value::Array(items) if index < items.len() => &mut items[index],
        Value::Array(_) => return write_map(tf, None, 0),
        single => single,
    };
    if let Value::Object(object) = map {
        object.insert("ColorSpace".into(), Value::from("RGB"));
        object.insert("RGBPoints".into(), Value::Array(rgb));
        object.insert("Points".into(), Value::Array(alpha));
    }
    serde_json::to_string_pretty(&root).unwrap_or_default()
}
