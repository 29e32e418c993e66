//! The scene effects a DVR raycaster specializes for (issue "effects a scene asks for"):
//! `shading` (Blinn–Phong of every sample with the gradient), `preintegration` (Engel et al.
//! 2001's segment table), `tricubic` (B-spline reconstruction from 8 trilinear fetches). Each is
//! a boolean parameter a graph wires to a scene feature — `"shading": "feature.shading"` — and
//! an `#if NAME` in the shaders, so a scene that leaves an effect off compiles none of its code
//! (`tests/effects_not_compiled.rs`) and builds none of its tables. Jitter is the existing
//! `jitter` parameter, wired the same way. The f64 reference computes the same effects
//! (`volgraph_accel::reference::Effects`).

use volgraph_core::runtime::{CreateContext, PassError, RecordContext};
use volgraph_core::{ParamSpec, Params};

use crate::preintegration::PreintegrationTable;

/// (parameter and feature name, shader define, what it does).
pub const EFFECTS: [(&str, &str, &str); 3] = [
    ("shading", "SHADING", "Blinn–Phong headlight shading of every sample with the gradient (central differences)"),
    (
        "preintegration",
        "PREINTEGRATION",
        "pre-integrated classification of the segment between samples (Engel et al. 2001), table rebuilt when the TF changes",
    ),
    ("tricubic", "TRICUBIC", "tricubic B-spline reconstruction from 8 trilinear fetches instead of trilinear"),
];

/// The effect parameters (all off by default).
pub fn effect_param_specs() -> Vec<ParamSpec> {
    EFFECTS.iter().map(|&(name, _, doc)| ParamSpec::boolean(name, false, doc)).collect()
}

/// The shading coefficients DVR shading reads (the isosurface's too).
pub const SHADING_PARAMS: [&str; 4] = ["ambient", "diffuse", "specular", "shininess"];

/// The shader uses the effects add to a raycaster's own: the pre-integration table's compute
/// pipelines when `preintegration` is on (one of the two is built, by what the device filters).
pub fn effect_shader_uses(params: &Params) -> Vec<volgraph_core::plugin::ShaderUse> {
    if params.boolean("preintegration") { crate::preintegration::TABLE_SHADERS.to_vec() } else { Vec::new() }
}

/// The `#if` names of the effects `params` turn on (`jitter`, a raycast parameter, is JITTER).
pub fn effect_defines(params: &Params) -> Vec<&'static str> {
    let mut defines: Vec<&'static str> =
        EFFECTS.iter().filter(|(name, ..)| params.boolean_or(name, false)).map(|&(_, define, _)| define).collect();
    defines.extend(jitter_defines(params));
    defines
}

/// `JITTER` when the `jitter` parameter is on: for passes that march the raycast samples
/// without the other effects (the segment loop, its termination test, the fetch probe).
pub fn jitter_defines(params: &Params) -> Vec<&'static str> {
    match (params.boolean_or("jitter", false), params.boolean_or("jitter_per_frame", false)) {
        (false, _) => Vec::new(),
        (true, false) => vec!["JITTER"],
        (true, true) => vec!["JITTER", "JITTER_PER_FRAME"],
    }
}

/// Whether two parameter sets compile the same effects (else the node is rebuilt).
pub fn same_effects(old: &Params, new: &Params) -> bool {
    EFFECTS
        .iter()
        .map(|(name, ..)| *name)
        .chain(["jitter", "jitter_per_frame"])
        .all(|name| old.boolean_or(name, false) == new.boolean_or(name, false))
}

/// What a raycaster node keeps for its effects: the pre-integration table when that effect is on.
pub struct EffectState {
    table: Option<PreintegrationTable>,
}

impl EffectState {
    /// Builds what the effects in `ctx.params` need.
    pub fn new(ctx: &CreateContext<'_>) -> Result<Self, PassError> {
        let table = ctx.params.boolean("preintegration").then(|| PreintegrationTable::new(ctx)).transpose()?;
        Ok(Self { table })
    }

    /// Brings derived data up to date before the raycaster records (the table after a TF or step
    /// change); `params` is the raycaster's uniform buffer.
    pub fn update(
        &mut self,
        ctx: &mut RecordContext<'_>,
        params: &wgpu::Buffer,
        step_voxels: f64,
    ) -> Result<(), PassError> {
        match &mut self.table {
            Some(t) => t.update(ctx, params, step_voxels),
            None => Ok(()),
        }
    }

    /// The bindings the effects add (`preintegrated`).
    pub fn bindings(&self) -> Vec<(&'static str, wgpu::BindingResource<'_>)> {
        self.table.iter().map(|t| ("preintegrated", wgpu::BindingResource::TextureView(&t.view))).collect()
    }

    /// Table builds so far (0 without pre-integration).
    pub fn table_builds(&self) -> u64 {
        self.table.as_ref().map_or(0, |t| t.builds)
    }

    /// Forgets derived data after new parameters (the step may have changed).
    pub fn invalidate(&mut self) {
        if let Some(t) = &mut self.table {
            t.invalidate();
        }
    }
}

/// The extra binding names of a raycaster with effects, after its own.
pub fn with_effect_bindings(own: &[&'static str]) -> Vec<&'static str> {
    let mut names = own.to_vec();
    names.push("preintegrated");
    names
}
