//! The OME-NGFF `multiscales` metadata (<https://ngff.openmicroscopy.org/0.5/#multiscale-md>):
//! its axes (`t`, `c`, then the space axes `z`, `y`, `x`), units and the scale and translation
//! of each resolution level — read from a group's attributes as NGFF 0.4 (`.zattrs`, Zarr v2)
//! or 0.5 (`zarr.json`'s `ome` key, Zarr v3) write them, and checked.

use std::path::Path;

use serde_json::{Map, Value};

use crate::ZarrError;

/// The NGFF versions read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NgffVersion {
    /// 0.4: Zarr v2, `multiscales` at the top of `.zattrs`.
    V04,
    /// 0.5: Zarr v3, under the `ome` key of the group's attributes.
    V05,
}

impl NgffVersion {
    /// "0.4" or "0.5".
    pub fn as_str(self) -> &'static str {
        match self {
            NgffVersion::V04 => "0.4",
            NgffVersion::V05 => "0.5",
        }
    }
}

/// What an axis stands for.
#[derive(Clone, Debug, PartialEq)]
pub enum AxisKind {
    /// A space axis (`z`, `y`, `x`).
    Space,
    /// Time (`t`): a volume per time point (`--frame`).
    Time,
    /// Channels (`c`): a volume per channel.
    Channel,
    /// Another type the file names.
    Other(String),
}

/// One axis of the arrays, in array order.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// Its name (`z`, `y`, `x`, `t`, `c`).
    pub name: String,
    /// Its type.
    pub kind: AxisKind,
    /// Its unit as written (`micrometer`), if any.
    pub unit: Option<String>,
}

/// One resolution level: the path of its array and its transform into physical units.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelMeta {
    /// The array's path in the store (`"0"`, `"s1"`).
    pub path: String,
    /// Size of one voxel per axis (array order), in the axes' units.
    pub scale: Vec<f64>,
    /// Position of voxel 0's centre per axis (array order); zeros where none is given.
    pub translation: Vec<f64>,
}

/// An image's multiscales metadata, checked: axes in array order and the levels finest first.
#[derive(Clone, Debug, PartialEq)]
pub struct Multiscale {
    /// The version the metadata says.
    pub version: NgffVersion,
    /// The image's name, if given.
    pub name: Option<String>,
    /// The axes.
    pub axes: Vec<Axis>,
    /// The levels, finest (the full resolution) first.
    pub levels: Vec<LevelMeta>,
}

/// Millimetres per unit, for the NGFF (UDUNITS) length units; `None` for another.
pub fn millimetres_per(unit: &str) -> Option<f64> {
    Some(match unit {
        "angstrom" => 1e-7,
        "nanometer" => 1e-6,
        "micrometer" => 1e-3,
        "millimeter" => 1.0,
        "centimeter" => 10.0,
        "meter" => 1e3,
        "kilometer" => 1e6,
        "inch" => 25.4,
        "foot" => 304.8,
        _ => return None,
    })
}

impl Multiscale {
    /// The multiscales metadata of a group's `attributes`, checked; `store` names it in errors.
    pub fn from_attributes(store: &Path, attributes: &Map<String, Value>) -> Result<Self, ZarrError> {
        let bad = |field: &str, problem: String| ZarrError::Metadata {
            path: store.to_path_buf(),
            field: field.to_string(),
            problem,
        };
        let (version, list) = match (attributes.get("ome"), attributes.get("multiscales")) {
            (Some(ome), _) => {
                let version = ome.get("version").and_then(Value::as_str).unwrap_or("(none)");
                if version != "0.5" {
                    return Err(ZarrError::Version { path: store.to_path_buf(), version: version.to_string() });
                }
                (NgffVersion::V05, ome.get("multiscales"))
            }
            (None, Some(list)) => {
                let version = list.get(0).and_then(|m| m.get("version")).and_then(Value::as_str).unwrap_or("(none)");
                if version != "0.4" {
                    return Err(ZarrError::Version { path: store.to_path_buf(), version: version.to_string() });
                }
                (NgffVersion::V04, Some(list))
            }
            (None, None) => return Err(ZarrError::NotOme { path: store.to_path_buf() }),
        };
        let first = list
            .and_then(Value::as_array)
            .and_then(|l| l.first())
            .ok_or_else(|| bad("multiscales", "an empty list; an image has one multiscale entry".to_string()))?;
        let axes = parse_axes(first, &bad)?;
        let (global_scale, global_translation) = transforms(first.get("coordinateTransformations"), axes.len())
            .map_err(|p| bad("multiscales[0].coordinateTransformations", p))?;
        let datasets =
            first.get("datasets").and_then(Value::as_array).filter(|d| !d.is_empty()).ok_or_else(|| {
                bad("multiscales[0].datasets", "missing or empty: one entry per resolution level".into())
            })?;
        let mut levels = Vec::with_capacity(datasets.len());
        for (i, d) in datasets.iter().enumerate() {
            let field = format!("multiscales[0].datasets[{i}]");
            let path = d
                .get("path")
                .and_then(Value::as_str)
                .filter(|p| !p.is_empty() && !p.starts_with('/') && !p.split('/').any(|s| s == ".."))
                .ok_or_else(|| bad(&format!("{field}.path"), "a relative path of the level's array".into()))?;
            let (scale, translation) = transforms(d.get("coordinateTransformations"), axes.len())
                .map_err(|p| bad(&format!("{field}.coordinateTransformations"), p))?;
            let scale: Vec<f64> = scale.iter().zip(&global_scale).map(|(a, b)| a * b).collect();
            let translation: Vec<f64> =
                translation.iter().zip(&global_scale).zip(&global_translation).map(|((t, g), gt)| t * g + gt).collect();
            levels.push(LevelMeta { path: path.to_string(), scale, translation });
        }
        // Levels go from fine to coarse: every space axis's voxel grows or stays.
        for (i, pair) in levels.windows(2).enumerate() {
            for (a, axis) in axes.iter().enumerate().filter(|(_, axis)| axis.kind == AxisKind::Space) {
                if pair[1].scale[a] < pair[0].scale[a] {
                    return Err(bad(
                        &format!("multiscales[0].datasets[{}].coordinateTransformations", i + 1),
                        format!(
                            "axis \"{}\": voxels of {} after {} at level {i}; levels run from the finest to the coarsest",
                            axis.name, pair[1].scale[a], pair[0].scale[a]
                        ),
                    ));
                }
            }
        }
        let name = first.get("name").and_then(Value::as_str).map(str::to_string);
        Ok(Multiscale { version, name, axes, levels })
    }

    /// The array positions of the three space axes (z, y, x order as stored).
    pub fn space_axes(&self) -> [usize; 3] {
        let space: Vec<usize> =
            self.axes.iter().enumerate().filter(|(_, a)| a.kind == AxisKind::Space).map(|(i, _)| i).collect();
        [space[0], space[1], space[2]]
    }

    /// The array position of the axis of `kind`, if the image has one.
    pub fn axis_of(&self, kind: &AxisKind) -> Option<usize> {
        self.axes.iter().position(|a| &a.kind == kind)
    }
}

fn parse_axes(first: &Value, bad: &dyn Fn(&str, String) -> ZarrError) -> Result<Vec<Axis>, ZarrError> {
    let list = first
        .get("axes")
        .and_then(Value::as_array)
        .ok_or_else(|| bad("multiscales[0].axes", "missing: a list of {name, type, unit} per array axis".into()))?;
    let mut axes = Vec::with_capacity(list.len());
    for (i, a) in list.iter().enumerate() {
        let field = format!("multiscales[0].axes[{i}]");
        let name = a
            .get("name")
            .and_then(Value::as_str)
            .ok_or_else(|| bad(&format!("{field}.name"), "missing: each axis has a name".into()))?;
        let kind = match a.get("type").and_then(Value::as_str) {
            Some("space") => AxisKind::Space,
            Some("time") => AxisKind::Time,
            Some("channel") => AxisKind::Channel,
            Some(other) => AxisKind::Other(other.to_string()),
            None => match name {
                "x" | "y" | "z" => AxisKind::Space,
                "t" => AxisKind::Time,
                "c" => AxisKind::Channel,
                _ => AxisKind::Other(String::new()),
            },
        };
        let unit = a.get("unit").and_then(Value::as_str).map(str::to_string);
        axes.push(Axis { name: name.to_string(), kind, unit });
    }
    let space = axes.iter().filter(|a| a.kind == AxisKind::Space).count();
    if space != 3 {
        let names: Vec<&str> = axes.iter().map(|a| a.name.as_str()).collect();
        return Err(bad(
            "multiscales[0].axes",
            format!("{space} space axes ({}): volgraph renders volumes, with three (z, y, x)", names.join(", ")),
        ));
    }
    if let Some(other) = axes.iter().find(|a| matches!(a.kind, AxisKind::Other(_))) {
        return Err(bad(
            "multiscales[0].axes",
            format!("axis \"{}\" is neither space, time nor channel: volgraph reads t, c, z, y, x", other.name),
        ));
    }
    Ok(axes)
}

/// The scale (required where transforms are listed) and translation of a transform list;
/// ones and zeros where there is none.
fn transforms(list: Option<&Value>, n: usize) -> Result<(Vec<f64>, Vec<f64>), String> {
    let (mut scale, mut translation) = (vec![1.0; n], vec![0.0; n]);
    let Some(list) = list else { return Ok((scale, translation)) };
    let list = list.as_array().ok_or("a list of {type: scale|translation, …}")?;
    for t in list {
        let kind = t.get("type").and_then(Value::as_str).unwrap_or("");
        let values = |key: &str| -> Result<Vec<f64>, String> {
            let v = t.get(key).and_then(Value::as_array).ok_or(format!("a \"{kind}\" transform without \"{key}\""))?;
            let numbers: Option<Vec<f64>> = v.iter().map(Value::as_f64).collect();
            let numbers =
                numbers.filter(|n| n.iter().all(|x| x.is_finite())).ok_or(format!("\"{key}\": finite numbers"))?;
            if numbers.len() != n {
                return Err(format!("\"{key}\" has {} values for {n} axes", numbers.len()));
            }
            Ok(numbers)
        };
        match kind {
            "scale" => {
                scale = values("scale")?;
                if let Some(bad) = scale.iter().find(|s| **s <= 0.0) {
                    return Err(format!("a scale of {bad}: voxel sizes are > 0"));
                }
            }
            "translation" => translation = values("translation")?,
            "identity" => {}
            other => return Err(format!("transform type \"{other}\": NGFF levels use scale and translation")),
        }
    }
    Ok((scale, translation))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn attrs(v: Value) -> Map<String, Value> {
        v.as_object().cloned().unwrap_or_default()
    }

    fn axes_tczyx() -> Value {
        json!([
            {"name": "t", "type": "time", "unit": "second"},
            {"name": "c", "type": "channel"},
            {"name": "z", "type": "space", "unit": "micrometer"},
            {"name": "y", "type": "space", "unit": "micrometer"},
            {"name": "x", "type": "space", "unit": "micrometer"}
        ])
    }

    #[test]
    fn version_0_5_reads_axes_scales_and_translations() {
        let a = attrs(json!({"ome": {"version": "0.5", "multiscales": [{
            "name": "cells",
            "axes": axes_tczyx(),
            "datasets": [
                {"path": "0", "coordinateTransformations": [{"type": "scale", "scale": [1, 1, 2, 0.5, 0.5]},
                                                             {"type": "translation", "translation": [0, 0, 10, 0, 0]}]},
                {"path": "1", "coordinateTransformations": [{"type": "scale", "scale": [1, 1, 4, 1, 1]}]}
            ],
            "coordinateTransformations": [{"type": "scale", "scale": [2, 1, 1, 1, 1]}]
        }]}}));
        let m = Multiscale::from_attributes(Path::new("s.zarr"), &a).expect("valid metadata");
        assert_eq!(m.version, NgffVersion::V05);
        assert_eq!(m.space_axes(), [2, 3, 4]);
        assert_eq!(m.axis_of(&AxisKind::Channel), Some(1));
        assert_eq!(m.levels[0].scale, vec![2.0, 1.0, 2.0, 0.5, 0.5]);
        assert_eq!(m.levels[0].translation, vec![0.0, 0.0, 10.0, 0.0, 0.0]);
        assert_eq!(m.levels[1].scale[2], 4.0);
        assert_eq!(millimetres_per("micrometer"), Some(1e-3));
    }

    #[test]
    fn version_0_4_and_bad_metadata_are_named() {
        let ok = attrs(json!({"multiscales": [{"version": "0.4", "axes": [
            {"name": "z", "type": "space"}, {"name": "y", "type": "space"}, {"name": "x", "type": "space"}],
            "datasets": [{"path": "0", "coordinateTransformations": [{"type": "scale", "scale": [1, 1, 1]}]}]}]}));
        assert_eq!(Multiscale::from_attributes(Path::new("s"), &ok).expect("valid 0.4").version, NgffVersion::V04);
        let cases = [
            (json!({"multiscales": [{"version": "0.3", "axes": ["z", "y", "x"], "datasets": []}]}), "\"0.3\""),
            (json!({"ome": {"version": "0.6"}}), "\"0.6\""),
            (json!({"foo": 1}), "multiscales"),
            (
                json!({"ome": {"version": "0.5", "multiscales": [{"axes": [{"name": "y", "type": "space"},
                {"name": "x", "type": "space"}], "datasets": [{"path": "0"}]}]}}),
                "2 space axes",
            ),
            (
                json!({"ome": {"version": "0.5", "multiscales": [{"axes": axes_tczyx(), "datasets": [
                {"path": "0", "coordinateTransformations": [{"type": "scale", "scale": [1, 1, 0, 1, 1]}]}]}]}}),
                "a scale of 0",
            ),
            (
                json!({"ome": {"version": "0.5", "multiscales": [{"axes": axes_tczyx(), "datasets": [
                {"path": "0", "coordinateTransformations": [{"type": "scale", "scale": [1, 1, 2, 2, 2]}]},
                {"path": "1", "coordinateTransformations": [{"type": "scale", "scale": [1, 1, 1, 1, 1]}]}]}]}}),
                "from the finest to the coarsest",
            ),
            (
                json!({"ome": {"version": "0.5", "multiscales": [{"axes": axes_tczyx(), "datasets": [
                {"path": "../x"}]}]}}),
                "datasets[0].path",
            ),
        ];
        for (value, want) in cases {
            let e = Multiscale::from_attributes(Path::new("s.zarr"), &attrs(value)).expect_err("refused").to_string();
            assert!(e.contains(want), "{e} lacks {want}");
        }
    }
}
