//! The graph file as written: what serde reads from RON, before any validation.
//! The format is documented with a complete annotated example in `docs/graph_format.md`.

use std::collections::BTreeMap;

use serde::Deserialize;

use crate::format::{TargetFormat, TargetSize};

/// A whole graph file: `Graph( ... )`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "Graph")]
pub struct GraphDoc {
    /// A short name, shown in plans and benchmarks.
    pub name: String,
    /// What the graph does, for people.
    #[serde(default)]
    pub description: String,
    /// Values the application binds: `{"volume": Volume, "tf": TransferFunction, "segments": Scalar(8.0)}`.
    #[serde(default)]
    pub inputs: BTreeMap<String, InputKind>,
    /// Previous-frame values: `{"prev_hit": (of: "march.hit", initial: Clear(0.0, 0.0, 0.0, 0.0))}`.
    #[serde(default)]
    pub history: BTreeMap<String, HistoryDoc>,
    /// Passes and repeat groups, in any order (the scheduler orders them).
    pub passes: Vec<NodeDoc>,
    /// Named results: `{"image": "march.color"}`.
    pub outputs: BTreeMap<String, String>,
    /// Pass kinds this graph declares itself, each implemented by a WGSL file alone:
    /// `{"edge_enhance": WgslKind(shader: "edge_enhance.wgsl", ...)}` (see [`WgslKindDoc`]).
    #[serde(default)]
    pub kinds: BTreeMap<String, WgslKindDoc>,
    /// Passes left out while a measurement of the last frames says they do not pay:
    /// `{"reprojection": (passes: ["splat", "holes"], measure: "march.leapable", below: 24.0)}`
    /// (see [`BypassDoc`]).
    #[serde(default)]
    pub bypass: BTreeMap<String, BypassDoc>,
}

/// A bypass: `passes` are not run while the per-pixel mean of the buffer `measure` (u32 words a
/// pass on the other side adds into, read back from the last finished frame) stays below
/// `below`. Their outputs read by the passes that still run are cleared to zero, which such a
/// reader's port must declare means "none" (`PortSpec::zero_means_none`): for Klein et al.
/// 2005, a cleared `start` begins every ray at the box.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BypassDoc {
    /// The passes left out together.
    pub passes: Vec<String>,
    /// `"<pass>.<buffer output>"`: the per-pixel measure, summed over its u32 words.
    pub measure: String,
    /// The threshold per viewport pixel: a number, or `"input.NAME"` (a Scalar input).
    pub below: Threshold,
}

/// A number written in the file or the value of a Scalar graph input.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum Threshold {
    /// The value itself.
    Value(f64),
    /// `"input.NAME"`.
    Input(String),
}

/// A pass kind implemented by one WGSL compute shader, declared in the graph file: its ports and
/// parameters are declared here, the parameter block is laid out from them (one `f32` per
/// parameter, in the order given: `struct Params { a: f32, b: f32, ... }` bound as `params`),
/// and it is validated, planned, culled, pooled, timed and hot-reloaded like a built-in.
/// Bindings are by global name, as for every pass: an input port `color` is the shader's
/// `color`, an output `out` its storage texture `out`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, rename = "WgslKind")]
pub struct WgslKindDoc {
    /// The shader file, found like every shader (the graph's `shaders/` folders, then the
    /// built-in ones).
    pub shader: String,
    /// One line saying what the pass does.
    #[serde(default)]
    pub summary: String,
    /// A compute shader (the default) or a fullscreen fragment shader.
    #[serde(default)]
    pub form: WgslForm,
    /// The entry point: the compute entry, or the fragment entry (whose output struct's members
    /// are named after the outputs; the vertex stage is `vs_fullscreen` of
    /// `common/fullscreen.wgsl`, which the shader imports). Default `cs_main` / `fs_main`.
    #[serde(default)]
    pub entry: Option<String>,
    /// The shader's `@workgroup_size(x, y)`: the dispatch covers the first output with it.
    #[serde(default = "default_wgsl_workgroup")]
    pub workgroup: (u32, u32),
    /// Input ports: name → what they read.
    #[serde(default)]
    pub inputs: BTreeMap<String, WgslInput>,
    /// Output ports: name → the storage texture format the shader writes.
    pub outputs: BTreeMap<String, TargetFormat>,
    /// Parameters, in the order of the shader's `Params` struct.
    #[serde(default)]
    pub params: Vec<WgslParamDoc>,
}

/// How a WGSL-only pass runs.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
pub enum WgslForm {
    /// One invocation per pixel of the first output (storage textures).
    #[default]
    Compute,
    /// One fullscreen triangle; the fragment shader returns the outputs.
    Fragment,
}

impl WgslKindDoc {
    /// The entry point, defaulted by form.
    pub fn entry_point(&self) -> &str {
        self.entry.as_deref().unwrap_or(match self.form {
            WgslForm::Compute => "cs_main",
            WgslForm::Fragment => "fs_main",
        })
    }
}

fn default_wgsl_workgroup() -> (u32, u32) {
    (8, 8)
}

/// What an input port of a WGSL-only pass reads.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
pub enum WgslInput {
    /// A viewport-sized float target (sampled with `textureLoad`).
    Target,
    /// The volume as a 3D texture.
    Volume,
    /// The transfer-function LUT.
    TransferFunction,
}

/// A parameter of a WGSL-only pass: an `f32` in `[min, max]`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct WgslParamDoc {
    /// Name in the graph and in the shader's `Params` struct.
    pub name: String,
    /// Value when the graph does not set it.
    pub default: f64,
    /// Smallest valid value.
    pub min: f64,
    /// Largest valid value.
    pub max: f64,
    /// What it does.
    #[serde(default)]
    pub doc: String,
}

/// The kind of a graph input.
#[derive(Clone, Debug, Deserialize, PartialEq)]
pub enum InputKind {
    /// The scalar volume, bound as a 3D texture.
    Volume,
    /// The transfer function, bound as a 1D LUT texture (`texture_1d<f32>`, N RGBA texels).
    TransferFunction,
    /// A label map's table: colour and opacity per label value (0 where hidden), bound as a 2D
    /// texture of 256 texels per row, label `v` at `(v % 256, v / 256)` (`texture_2d<f32>`), so
    /// every u16 value has its entry. Filled from an ITK-SNAP or 3D Slicer table, a
    /// `.seg.nrrd`'s segments or the default palette.
    LabelTable,
    /// A scene scalar with its default value (repeat counts, thresholds).
    Scalar(f64),
    /// A value in the data's units (HU for CT), or `Auto`: what the data suggests — for an
    /// isovalue, the surface between the background and the object. Bound to parameters as a
    /// normalized scalar once a volume is known (the scene values [`DATA_LOW`], [`DATA_HIGH`],
    /// [`DATA_AUTO_ISO`]); without a volume, data units are taken as normalized and `Auto` is
    /// 0.5. Written `Data(Auto)` or `Data(Value(300.0))`; a user value set for it (`--set`) is
    /// in data units too.
    Data(DataValue),
}

impl InputKind {
    /// How `volgraph plan` names the kind: `Volume`, `TransferFunction`, `Scalar = 4`,
    /// `Data(Auto)`, `Data(300)`.
    pub fn describe(&self) -> String {
        match self {
            InputKind::Volume => "Volume".to_string(),
            InputKind::TransferFunction => "TransferFunction".to_string(),
            InputKind::LabelTable => "LabelTable".to_string(),
            InputKind::Scalar(v) => format!("Scalar = {v}"),
            InputKind::Data(DataValue::Auto) => "Data(Auto)".to_string(),
            InputKind::Data(DataValue::Value(v)) => format!("Data({v})"),
        }
    }
}

/// The default of a [`InputKind::Data`] input.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
pub enum DataValue {
    /// What the data suggests.
    Auto,
    /// A value in the data's units.
    Value(f64),
}

/// Scene value: the data value that normalizes to 0.
pub const DATA_LOW: &str = "data_low";
/// Scene value: the data value that normalizes to 1.
pub const DATA_HIGH: &str = "data_high";
/// Scene value: the normalized value `Data(Auto)` takes.
pub const DATA_AUTO_ISO: &str = "data_auto_iso";

/// A history entry: the previous frame's value of a target.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HistoryDoc {
    /// The target whose previous-frame value is read, as `"<pass>.<output>"`.
    pub of: String,
    /// The value on the first frame and after invalidation.
    #[serde(default)]
    pub initial: HistoryInitial,
    /// Passes whose parameter edits make the kept value stale (an isovalue change: Klein et al.
    /// 2005 §4.1); the history restarts from `initial` when one of them is rebuilt or updated.
    #[serde(default)]
    pub reset_on_params_of: Vec<String>,
    /// The camera may turn at most this many degrees between two frames before the kept value
    /// is thrown away (a camera jump: Klein et al. 2005 §4.1). Unbounded when absent.
    #[serde(default)]
    pub max_camera_degrees: Option<f64>,
    /// The kept value is thrown away whenever the camera moves at all — turns, zooms or pans:
    /// progressive accumulation (a path tracer's running mean), which holds only for one view.
    #[serde(default)]
    pub while_camera_still: bool,
}

/// What a history target holds when there is no previous frame.
#[derive(Clone, Debug, Deserialize, PartialEq)]
pub enum HistoryInitial {
    /// Cleared to this RGBA value, written `Clear(r, g, b, a)` (graph files are read with
    /// RON's `unwrap_variant_newtypes`, so the tuple's own parentheses are left out).
    Clear((f64, f64, f64, f64)),
}

impl Default for HistoryInitial {
    fn default() -> Self {
        HistoryInitial::Clear((0.0, 0.0, 0.0, 0.0))
    }
}

/// One entry of `passes`: a pass or a repeat group.
#[derive(Clone, Debug, Deserialize)]
pub enum NodeDoc {
    /// A single pass.
    Pass(PassDoc),
    /// A body of passes run several times with feedback.
    Repeat(RepeatDoc),
}

/// A pass: one node of the graph. Written `Pass(id: .., kind: ..)` both in `passes` (where
/// `Pass` is the [`NodeDoc`] variant) and in a repeat group's `body` (where it is this struct's
/// name; the name may also be left out).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "Pass")]
pub struct PassDoc {
    /// Unique id, used in references (`"<id>.<output>"`), labels and messages.
    pub id: String,
    /// The plugin name (`"raycast"`, `"entry_points"`, ...).
    pub kind: String,
    /// Typed parameters, checked against the plugin's declaration.
    #[serde(default)]
    pub params: BTreeMap<String, ron::Value>,
    /// Input port → `"<pass>.<output>"`, `"input.<name>"`, `"history.<name>"` or, inside a
    /// repeat body, `"<repeat id>.<carried name>"`.
    #[serde(default)]
    pub inputs: BTreeMap<String, String>,
    /// Output port → target declaration overriding the plugin's defaults.
    #[serde(default)]
    pub outputs: BTreeMap<String, TargetDoc>,
    /// Scene features that must all be on for this pass to be scheduled.
    #[serde(default)]
    pub when: Vec<String>,
    /// When the pass is gated off: output port → the reference that stands in for it.
    #[serde(default)]
    pub otherwise: BTreeMap<String, String>,
}

/// An output target declaration; every field defaults to the plugin's choice.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TargetDoc {
    /// Pixel format.
    #[serde(default)]
    pub format: Option<TargetFormat>,
    /// Size relative to the viewport or absolute.
    #[serde(default)]
    pub size: Option<TargetSize>,
}

/// A repeat group: `body` runs `count` times; `carry` feeds values from one iteration to the next.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RepeatDoc {
    /// Unique id; `"<id>.<carried>"` names a carried value (inside: the previous iteration's,
    /// after the group: the last iteration's).
    pub id: String,
    /// How many iterations.
    pub count: RepeatCount,
    /// Carried values: name → where the first iteration's value comes from and which body
    /// output becomes the next iteration's.
    pub carry: BTreeMap<String, CarryDoc>,
    /// The passes of one iteration.
    pub body: Vec<PassDoc>,
}

/// The iteration count of a repeat group.
#[derive(Clone, Debug, Deserialize, PartialEq)]
pub enum RepeatCount {
    /// A fixed count.
    Fixed(u32),
    /// `ceil(scene scalar / divide_by)`, clamped to `1..=max`.
    Scene {
        /// The graph input (a `Scalar`) or derived scene quantity to read.
        name: String,
        /// Divisor (e.g. Krüger–Westermann's M steps per segment).
        #[serde(default = "one")]
        divide_by: f64,
        /// A Scalar graph input to divide by instead of `divide_by`, so the count and the
        /// passes that read the same scalar (`params: {"segment_steps": "input.segment_steps"}`)
        /// can never disagree.
        #[serde(default)]
        divide_by_input: Option<String>,
        /// Scalar graph inputs whose product divides instead (with `divide_by`): Krüger &
        /// Westermann's loop counts `longest_ray_voxels / (step_voxels · segment_steps)`.
        #[serde(default)]
        divide_by_inputs: Vec<String>,
        /// Upper bound on the count.
        #[serde(default = "default_max_iterations")]
        max: u32,
    },
}

fn one() -> f64 {
    1.0
}

fn default_max_iterations() -> u32 {
    256
}

/// One carried value of a repeat group.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CarryDoc {
    /// The value before the first iteration: a reference from outside the group.
    pub init: String,
    /// The body output that becomes the next iteration's value: `"<body pass>.<output>"`.
    pub next: String,
}
