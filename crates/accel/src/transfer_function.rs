//! Transfer functions: piecewise-linear RGBA over data values, read from RON files
//! (`graphs/tf/*.ron`) or imported from ParaView colour-map JSON, and baked into the LUT that the
//! GPU and the CPU reference both sample (`docs/rendering_model.md`, "Classification").
//!
//! File format (colours linear RGB in 0..1, `alpha` = opacity per unit step, `value` in data
//! units, points sorted by value and inside `domain`):
//!
//! ```ron
//! TransferFunction(
//!     domain: (0.0, 255.0),
//!     points: [
//!         (value: 0.0, color: (0.0, 0.0, 0.0), alpha: 0.0),
//!         (value: 255.0, color: (1.0, 1.0, 1.0), alpha: 0.5),
//!     ],
//! )
//! ```
//!
//! Mapping to the LUT: texel `i` of an `n`-texel LUT holds the function at normalized
//! `s = (i + 0.5)/n`. [`TransferFunction::to_lut`] maps `s ∈ [0, 1]` onto the TF's own domain;
//! [`TransferFunction::to_lut_for`] maps it onto the volume's `value_range`, which is what the
//! volume's normalized values mean (`uint8` → 0..255). The two agree when the domain equals the
//! volume's range, as for [`TransferFunction::default_for`] and `uint8` data with domain
//! (0, 255); [`TransferFunction::normalized_domain_for`] says where the domain falls in `s`.

mod paraview;
mod scanner_presets;

pub use paraview::ParaviewColorMap;
pub use scanner_presets::ScannerPreset;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::volume::Volume;

/// LUT resolution used by [`TransferFunction::lookup`] and by default on the GPU.
pub const DEFAULT_LUT_SIZE: usize = 256;

/// One control point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControlPoint {
    /// Data value (in the units of the volume's voxels, e.g. 0..255 for `uint8`).
    pub value: f64,
    /// Linear RGB, each in [0, 1] (straight, not premultiplied).
    pub color: [f64; 3],
    /// Opacity per unit step (`unit_world`), in [0, 1].
    pub alpha: f64,
}

/// A piecewise-linear transfer function over `domain` (data units). Outside the first and last
/// points it holds their values.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransferFunction {
    /// `(min, max)` data values the LUT covers.
    pub domain: (f64, f64),
    /// Control points, sorted by `value`, inside `domain`. Two points may share a value to make
    /// a step.
    pub points: Vec<ControlPoint>,
}

/// Why a transfer function could not be read or is invalid. Messages name the file, the point
/// and field, and say how to fix it.
#[derive(Debug, thiserror::Error)]
pub enum TfError {
    /// The file cannot be read (missing, not a regular file, too large, not text).
    #[error(transparent)]
    Read(#[from] crate::input_file::InputFileError),
    /// The RON text does not parse into a `TransferFunction`.
    #[error("{}:{line}:{col}: {message}; see graphs/tf/default.ron for the format", .path.display())]
    Ron {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        col: usize,
        /// ron's message.
        message: String,
    },
    /// The JSON text does not parse.
    #[error("{}:{line}:{col}: invalid JSON: {message}", .path.display())]
    Json {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        col: usize,
        /// serde_json's message.
        message: String,
    },
    /// The domain is empty or not finite.
    #[error(
        "{}: domain ({lo}, {hi}) is not a range; write `domain: (min, max)` with finite min < max in data units",
        .path.display()
    )]
    BadDomain {
        /// The file.
        path: PathBuf,
        /// Domain start.
        lo: f64,
        /// Domain end.
        hi: f64,
    },
    /// No control point.
    #[error(
        "{}: `points` is empty; add at least one point such as `(value: 0.0, color: (1.0, 1.0, 1.0), alpha: 0.0)`",
        .path.display()
    )]
    NoPoints {
        /// The file.
        path: PathBuf,
    },
    /// A point outside the domain.
    #[error(
        "{}: points[{index}].value = {value} is outside the domain ({lo}, {hi}); move the point into the domain or widen the domain",
        .path.display()
    )]
    OutsideDomain {
        /// The file.
        path: PathBuf,
        /// Index of the point.
        index: usize,
        /// Its value.
        value: f64,
        /// Domain start.
        lo: f64,
        /// Domain end.
        hi: f64,
    },
    /// Points out of order.
    #[error(
        "{}: points[{index}].value = {value} is smaller than points[{previous_index}].value = {previous}; list the points in increasing value",
        .path.display()
    )]
    Unsorted {
        /// The file.
        path: PathBuf,
        /// Index of the point.
        index: usize,
        /// Its value.
        value: f64,
        /// `index - 1`.
        previous_index: usize,
        /// The previous point's value.
        previous: f64,
    },
    /// A colour channel or alpha outside [0, 1].
    #[error(
        "{}: points[{index}].{field} = {value} is outside [0, 1]; colours are linear RGB in 0..1 and alpha is opacity per unit step in 0..1",
        .path.display()
    )]
    OutOfUnitRange {
        /// The file.
        path: PathBuf,
        /// Index of the point.
        index: usize,
        /// `color.r`, `color.g`, `color.b` or `alpha`.
        field: &'static str,
        /// The value found.
        value: f64,
    },
    /// A ParaView colour map with the wrong shape.
    #[error("{}: {message}", .path.display())]
    Paraview {
        /// The file.
        path: PathBuf,
        /// What is wrong and how to fix it.
        message: String,
    },
}

/// Named transfer functions for benchmarks, defined over fractions of any domain.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Preset {
    /// A general-purpose ramp: low values transparent, rising colour and opacity.
    Default,
    /// Almost everything above the lowest 5% of the domain is fully opaque, so rays end after a
    /// few samples: early ray termination pays.
    Opaque,
    /// Everything below 60% of the domain is fully transparent: empty-space skipping pays.
    Sparse,
}

impl Preset {
    /// All presets.
    pub const ALL: [Preset; 3] = [Preset::Default, Preset::Opaque, Preset::Sparse];

    /// The preset's name, also its file name in `graphs/tf/<name>.ron`.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Default => "default",
            Preset::Opaque => "opaque",
            Preset::Sparse => "sparse",
        }
    }

    /// The preset named `name`, if any.
    pub fn from_name(name: &str) -> Option<Preset> {
        Preset::ALL.into_iter().find(|p| p.name() == name)
    }

    /// Control points as `(fraction of the domain, rgb, alpha)`.
    fn shape(self) -> &'static [(f64, [f64; 3], f64)] {
        match self {
            Preset::Default => &[
                (0.0, [0.0, 0.0, 0.0], 0.0),
                (0.1, [0.05, 0.05, 0.3], 0.0),
                (0.3, [0.2, 0.4, 0.9], 0.05),
                (0.6, [0.9, 0.6, 0.2], 0.25),
                (1.0, [1.0, 1.0, 1.0], 0.6),
            ],
            Preset::Opaque => &[(0.0, [0.0, 0.0, 0.0], 0.0), (0.05, [0.8, 0.7, 0.6], 1.0), (1.0, [1.0, 1.0, 1.0], 1.0)],
            Preset::Sparse => &[
                (0.0, [0.0, 0.0, 0.0], 0.0),
                (0.6, [0.2, 0.5, 1.0], 0.0),
                (0.8, [1.0, 0.6, 0.2], 0.3),
                (1.0, [1.0, 1.0, 1.0], 0.8),
            ],
        }
    }
}

impl TransferFunction {
    /// The preset `preset` stretched over `domain`.
    pub fn preset(preset: Preset, domain: (f64, f64)) -> TransferFunction {
        let (lo, hi) = domain;
        let points = preset
            .shape()
            .iter()
            .map(|&(t, color, alpha)| ControlPoint { value: lo + t * (hi - lo), color, alpha })
            .collect();
        TransferFunction { domain, points }
    }

    /// The transfer function fitted to `volume`: the [`Preset::Default`] ramp over its
    /// `value_range` (for `uint8`, 0..255), made transparent up to the top of its background —
    /// the histogram's low peak of air or scanner noise
    /// ([`crate::histogram::Histogram::background`]) — so the object shows instead of a box of
    /// noise. Where the ramp is transparent there anyway (a background below a tenth of the
    /// range), it is the plain ramp. Its domain is the volume's range, so [`Self::to_lut`] and
    /// [`Self::to_lut_for`] agree for it. A volume whose range is empty (a constant float
    /// volume) gets the domain (lo, lo + 1).
    pub fn default_for(volume: &Volume) -> TransferFunction {
        Self::default_fitted(&crate::histogram::ValueSummary::of(volume))
    }

    /// [`Self::default_for`] from what it reads of a volume (a sort-last render's ranks fit it to
    /// the whole file's summary, so each gets what one process would).
    pub fn default_fitted(values: &crate::histogram::ValueSummary) -> TransferFunction {
        let (lo, hi) = values.value_range;
        let hi = if hi > lo { hi } else { lo + 1.0 };
        let ramp = TransferFunction::preset(Preset::Default, (lo, hi));
        let Some(background) = crate::histogram::background_in(values) else { return ramp };
        ramp.hidden_below(lo + background.ceiling * (hi - lo))
    }

    /// This transfer function with every value below `cut` transparent: a step at `cut` from
    /// nothing to what it was there, unchanged above.
    pub fn hidden_below(&self, cut: f64) -> TransferFunction {
        let at = self.eval(cut);
        if !(cut > self.domain.0 && cut < self.domain.1) || at[3] == 0.0 {
            let mut all = self.clone();
            all.points.iter_mut().filter(|p| p.value < cut).for_each(|p| p.alpha = 0.0);
            return all;
        }
        let color = [at[0], at[1], at[2]];
        let mut points: Vec<ControlPoint> =
            self.points.iter().filter(|p| p.value < cut).map(|p| ControlPoint { alpha: 0.0, ..p.clone() }).collect();
        points.push(ControlPoint { value: cut, color, alpha: 0.0 });
        points.push(ControlPoint { value: cut, color, alpha: at[3] });
        points.extend(self.points.iter().filter(|p| p.value > cut).cloned());
        TransferFunction { domain: self.domain, points }
    }

    /// Checks the rules of the file format; `path` names the source in messages.
    pub fn validate(&self, path: &Path) -> Result<(), TfError> {
        let path_buf = || path.to_path_buf();
        let (lo, hi) = self.domain;
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(TfError::BadDomain { path: path_buf(), lo, hi });
        }
        if self.points.is_empty() {
            return Err(TfError::NoPoints { path: path_buf() });
        }
        for (index, p) in self.points.iter().enumerate() {
            if !(lo..=hi).contains(&p.value) {
                return Err(TfError::OutsideDomain { path: path_buf(), index, value: p.value, lo, hi });
            }
            if index > 0 && p.value < self.points[index - 1].value {
                return Err(TfError::Unsorted {
                    path: path_buf(),
                    index,
                    value: p.value,
                    previous_index: index - 1,
                    previous: self.points[index - 1].value,
                });
            }
            let channels = [("color.r", p.color[0]), ("color.g", p.color[1]), ("color.b", p.color[2])];
            for (field, value) in channels.into_iter().chain([("alpha", p.alpha)]) {
                if !(0.0..=1.0).contains(&value) {
                    return Err(TfError::OutOfUnitRange { path: path_buf(), index, field, value });
                }
            }
        }
        Ok(())
    }

    /// Parses and validates RON text; `path` names the source in messages.
    pub fn from_ron_str(text: &str, path: &Path) -> Result<TransferFunction, TfError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let tf: TransferFunction = ron::from_str(text).map_err(|e| TfError::Ron {
            path: path.to_path_buf(),
            line: e.span.start.line,
            col: e.span.start.col,
            message: e.code.to_string(),
        })?;
        tf.validate(path)?;
        Ok(tf)
    }

    /// Reads and validates a RON transfer function file.
    pub fn load(path: &Path) -> Result<TransferFunction, TfError> {
        let text = crate::input_file::read_text(path, "transfer function")?;
        TransferFunction::from_ron_str(&text, path)
    }

    /// The RON text of this transfer function (what [`Self::from_ron_str`] reads back).
    pub fn to_ron_string(&self) -> String {
        let config = ron::ser::PrettyConfig::new().struct_names(true);
        // Serializing plain numbers, arrays and structs into a String cannot fail.
        ron::ser::to_string_pretty(self, config).unwrap_or_default()
    }

    /// This transfer function as ParaView colour-map JSON written into `original` (the file's
    /// text, when it had one: map `index` is replaced, every other map and key kept), else as a
    /// fresh one-map file; [`Self::from_paraview_json`] reads it back to the same function.
    pub fn to_paraview_json(&self, original: Option<&str>, index: usize) -> String {
        paraview::write_map(self, original, index)
    }

    /// Imports a ParaView colour-map JSON text (see [`Self::load_paraview`]).
    pub fn from_paraview_json(text: &str, path: &Path) -> Result<TransferFunction, TfError> {
        paraview::parse_map(text, path, None).map(|m| m.tf)
    }

    /// Imports a ParaView colour-map JSON file: an array whose first object has `RGBPoints`
    /// (`[x, r, g, b, …]`) and optionally `Points` (`[x, alpha, midpoint, sharpness, …]`).
    /// ParaView colours are sRGB and are converted to linear RGB; a `"ColorSpace": "HSV"` map gets
    /// points along its HSV path (other colour spaces than RGB and HSV are interpolated in RGB,
    /// with a note); midpoint and sharpness are ignored (with a note); without
    /// `Points` the opacity ramps from 0 to 1 over the domain. The domain is the range of all x.
    pub fn load_paraview(path: &Path) -> Result<TransferFunction, TfError> {
        Self::load_paraview_map(path, None).map(|m| m.tf)
    }

    /// Like [`Self::load_paraview`], choosing the colour map named `name` (its `"Name"`, or `#i`
    /// for the i-th) from a file that holds several, and saying which was used.
    pub fn load_paraview_map(path: &Path, name: Option<&str>) -> Result<ParaviewColorMap, TfError> {
        let text = crate::input_file::read_text(path, "transfer function")?;
        paraview::parse_map(&text, path, name)
    }

    /// Map `name` (the first when `None`) of ParaView JSON `text`; `path` names it in messages.
    pub fn load_paraview_map_from_str(
        text: &str,
        path: &Path,
        name: Option<&str>,
    ) -> Result<TransferFunction, TfError> {
        paraview::parse_map(text, path, name).map(|m| m.tf)
    }

    /// RGBA at data value `v`: linear between the control points around it, the end points'
    /// values beyond them. `[0; 4]` with no points; NaN is treated as the domain start.
    pub fn eval(&self, v: f64) -> [f64; 4] {
        let rgba = |p: &ControlPoint| [p.color[0], p.color[1], p.color[2], p.alpha];
        let v = if v.is_nan() { self.domain.0 } else { v };
        let Some(first) = self.points.first() else {
            return [0.0; 4];
        };
        let upper = self.points.partition_point(|p| p.value <= v);
        if upper == 0 {
            return rgba(first);
        }
        if upper == self.points.len() {
            return rgba(&self.points[upper - 1]);
        }
        let (a, b) = (&self.points[upper - 1], &self.points[upper]);
        // a.value <= v < b.value, so the width is positive.
        let t = (v - a.value) / (b.value - a.value);
        let (ca, cb) = (rgba(a), rgba(b));
        std::array::from_fn(|k| ca[k] + t * (cb[k] - ca[k]))
    }

    /// Texel `i` of an `n`-texel LUT over data values `lo..hi`.
    fn texel(&self, i: usize, n: usize, (lo, hi): (f64, f64)) -> [f32; 4] {
        let s = (i as f64 + 0.5) / n as f64;
        self.eval(lo + s * (hi - lo)).map(|c| c as f32)
    }

    /// An `n`-texel RGBA LUT over `s ∈ [0, 1]` mapped onto the TF's domain; texel `i` holds
    /// the function at `s = (i + 0.5)/n`.
    pub fn to_lut(&self, n: usize) -> Vec<[f32; 4]> {
        (0..n).map(|i| self.texel(i, n, self.domain)).collect()
    }

    /// An `n`-texel LUT over `s ∈ [0, 1]` mapped onto `volume.value_range`: texel `i` holds the
    /// function at the data value whose normalized value is `(i + 0.5)/n`. Use this one when the
    /// TF's domain may differ from the volume's range.
    pub fn to_lut_for(&self, volume: &Volume, n: usize) -> Vec<[f32; 4]> {
        (0..n).map(|i| self.texel(i, n, volume.value_range)).collect()
    }

    /// Where the TF's domain lies in the volume's normalized values `s`: `(0, 1)` when the
    /// domain equals `volume.value_range`. An empty volume range gives `(0, 1)`.
    pub fn normalized_domain_for(&self, volume: &Volume) -> (f64, f64) {
        let (lo, hi) = volume.value_range;
        if hi > lo { ((self.domain.0 - lo) / (hi - lo), (self.domain.1 - lo) / (hi - lo)) } else { (0.0, 1.0) }
    }

    /// What a linear 1D sampler returns at `s` on `self.to_lut(DEFAULT_LUT_SIZE)`, computed
    /// without building the LUT (bit-identical to [`lut_sample`] on it).
    pub fn lookup(&self, s: f64) -> [f64; 4] {
        sample_with(DEFAULT_LUT_SIZE, s, |i| self.texel(i, DEFAULT_LUT_SIZE, self.domain))
    }
}

/// What a WebGPU linear sampler with clamp-to-edge returns at `s` from `lut`: linear between
/// texel centres `(i + 0.5)/n`, clamped to the end texels (`docs/rendering_model.md`). NaN `s`
/// reads as 0; an empty LUT gives zeros. GPUs interpolate with limited fractional precision (8
/// bits on many), so GPU results match this only within that tolerance.
pub fn lut_sample(lut: &[[f32; 4]], s: f64) -> [f64; 4] {
    sample_with(lut.len(), s, |i| lut[i])
}

fn sample_with(n: usize, s: f64, texel: impl Fn(usize) -> [f32; 4]) -> [f64; 4] {
    if n == 0 {
        return [0.0; 4];
    }
    let s = if s.is_nan() { 0.0 } else { s.clamp(-1.0, 2.0) };
    let x = s * n as f64 - 0.5;
    let base = x.floor();
    let f = x - base;
    let clamp = |i: f64| i.clamp(0.0, (n - 1) as f64) as usize;
    let (a, b) = (texel(clamp(base)), texel(clamp(base + 1.0)));
    std::array::from_fn(|k| a[k] as f64 * (1.0 - f) + b[k] as f64 * f)
}

/// Opacity of a step of `step_voxels` unit steps for opacity `alpha` per unit step:
/// `1 - (1 - alpha)^step_voxels` (`docs/rendering_model.md`, "Opacity correction"). `alpha`
/// is clamped to [0, 1].
pub fn opacity_correct(alpha: f64, step_voxels: f64) -> f64 {
    1.0 - (1.0 - alpha.clamp(0.0, 1.0)).powf(step_voxels)
}

/// The inverse of [`opacity_correct`]: the opacity per unit step that gives `alpha_step` over a
/// step of `step_voxels`, `1 - (1 - alpha_step)^(1/step_voxels)`. A non-positive step gives 0
/// for `alpha_step < 1` (no finite per-unit opacity reaches it in zero distance) and 1 for 1.
pub fn opacity_uncorrect(alpha_step: f64, step_voxels: f64) -> f64 {
    let a = alpha_step.clamp(0.0, 1.0);
    if step_voxels <= 0.0 {
        return if a >= 1.0 { 1.0 } else { 0.0 };
    }
    1.0 - (1.0 - a).powf(1.0 / step_voxels)
}
