//! The scene effects a DVR raycaster specializes for (issue "effects a scene asks for"):
//! `shading` (Blinn–Phong of every sample with the gradient), `preintegration` (Engel et al.
//! 2001's segment table), `tricubic` (B-spline reconstruction from 8 trilinear fetches),
//! `shadows` and `ambient_occlusion` (the light reaching each sample and its ambient share, from
//! an illumination volume: `shadows.rs`). Each is
//! a boolean parameter a graph wires to a scene feature — `"shading": "feature.shading"` — and
//! an `#if NAME` in the shaders, so a scene that leaves an effect off compiles none of its code
//! (`tests/effects_not_compiled.rs`) and builds none of its tables. Jitter is the existing
//! `jitter` parameter, wired the same way. The f64 reference computes the same effects
//! (`volgraph_accel::reference::Effects`).

use volgraph_compiler::Params;
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{CreateContext, PassError, RecordContext};

use crate::defines;
#[cfg(feature = "gpu")]
use crate::preintegration::PreintegrationTable;
use crate::raycast_params::Sampling;

/// The scene effects the built-in raycasters compile in, each a boolean parameter a graph wires
/// to `"feature.NAME"`: every kind that marches with the shared core declares them
/// (`PassDecl::scene_effects`), and a scene may ask for what some registered kind declares.
pub const SCENE_EFFECTS: [&str; 6] =
    ["shading", "preintegration", "tricubic", "jitter", "shadows", "ambient_occlusion"];

volgraph_compiler::pass_params! {
    /// The effect switches, declared once (all off by default); each is an `#if` of the same
    /// name in capitals in the shaders ([`EffectFlags::defines`]).
    pub struct EffectFlags {
        shading: bool = false, "Blinn–Phong headlight shading of every sample with the gradient (central differences)";
        preintegration: bool = false,
            "pre-integrated classification of the segment between samples (Engel et al. 2001), table rebuilt when the TF changes";
        tricubic: bool = false, "tricubic B-spline reconstruction from 8 trilinear fetches instead of trilinear";
        shadows: bool = false,
            "shadows: the light reaching each sample through the volume (a light volume, rebuilt when the volume, TF or light changes) scales its lit terms";
        ambient_occlusion: bool = false,
            "ambient occlusion: the unoccluded share of each sample's neighbourhood (14 rays of 8 voxels, in the light volume) scales its ambient light";
    }
}

impl EffectFlags {
    /// Every effect off (a kind that declares none).
    pub const OFF: Self =
        Self { shading: false, preintegration: false, tricubic: false, shadows: false, ambient_occlusion: false };

    /// The effects of `params` (all off for a kind that does not declare them).
    pub fn of(params: &Params) -> Self {
        Self::try_from_params(params).unwrap_or(Self::OFF)
    }

    /// The `#if` names of the effects turned on.
    pub fn defines(&self) -> Vec<&'static str> {
        [
            (self.shading, defines::SHADING),
            (self.preintegration, defines::PREINTEGRATION),
            (self.tricubic, defines::TRICUBIC),
            (self.shadows, defines::SHADOWS),
            (self.ambient_occlusion, defines::AMBIENT_OCCLUSION),
        ]
        .into_iter()
        .filter_map(|(on, define)| on.then_some(define))
        .collect()
    }
}

/// The effect switches as a block: each turns its `#if` on; a change rebuilds the node (its
/// pre-integration table is made with it).
pub fn effect_block() -> volgraph_compiler::block::ParamBlock {
    EffectFlags::block(volgraph_compiler::block::OnChange::Rebuild).with_defines(|p| EffectFlags::of(p).defines())
}

/// The shader uses the effects add to a raycaster's own: the pre-integration table's compute
/// pipelines when `preintegration` is on (one of the two is built, by what the device filters),
/// the light volume's when `shadows` is on and the pass's volume is a texture
/// (`volume_texture`; the brick raycaster computes it on the CPU).
pub fn effect_shader_uses(params: &Params, volume_texture: bool) -> Vec<volgraph_compiler::ShaderUse> {
    let flags = EffectFlags::of(params);
    let mut uses = Vec::new();
    if flags.preintegration {
        uses.extend(crate::preintegration::table_shader_uses());
    }
    if (flags.shadows || flags.ambient_occlusion) && volume_texture {
        uses.push(crate::shadows::light_shader_use(params));
    }
    uses
}

/// `JITTER` when the `jitter` parameter is on: the `#if`s of the sampling block
/// (`raycast_params::sampling_block`), so every kind that takes it compiles the jitter in.
pub fn jitter_defines(params: &Params) -> Vec<&'static str> {
    let sampling = Sampling::try_from_params(params);
    match sampling.map(|s| (s.jitter, s.jitter_per_frame)) {
        None | Some((false, _)) => Vec::new(),
        Some((true, false)) => vec![defines::JITTER],
        Some((true, true)) => vec![defines::JITTER, defines::JITTER_PER_FRAME],
    }
}

/// What a raycaster that fuses several volumes binds itself beside its march (`ShaderUse::binds`):
/// the compute raycaster's pre-corrected table, the pre-integration tables and the light volume
/// ([`EffectState::bindings`]) and what is made from a label map (`FusionState::bindings`).
pub const MARCH_BINDINGS: &[&str] = &[
    "corrected",
    "preintegrated",
    "second_preintegrated",
    "third_preintegrated",
    "fourth_preintegrated",
    "light_volume",
    "label_quads",
    "label_cubes",
];

#[cfg(feature = "gpu")]
/// What a raycaster node keeps for its effects: the pre-integration table and the light volume
/// when those effects are on.
pub struct EffectState {
    /// The frame volume's, then each scalar partner's (`preintegration::TABLES`).
    tables: Vec<PreintegrationTable>,
    light: Option<crate::shadows::LightVolume>,
}

#[cfg(feature = "gpu")]
impl EffectState {
    /// Builds what the effects in `ctx.params` need; `volume_texture`: the pass's `volume` port
    /// is the volume's texture (not voxels on the CPU, as the brick raycaster's).
    pub fn new(ctx: &CreateContext<'_>, volume_texture: bool) -> Result<Self, PassError> {
        let flags = EffectFlags::of(ctx.params);
        // One table per transfer function: the frame volume's, and several scalar volumes'.
        let partners = crate::fusion::FusionSettings::of(ctx.params).scalar_partners().len();
        let tables = match flags.preintegration {
            true => crate::preintegration::TABLES[..1 + partners]
                .iter()
                .map(|&table| PreintegrationTable::new(ctx, table))
                .collect::<Result<Vec<_>, _>>()?,
            false => Vec::new(),
        };
        let light = (flags.shadows || flags.ambient_occlusion)
            .then(|| crate::shadows::LightVolume::new(ctx, &flags, volume_texture))
            .transpose()?;
        Ok(Self { tables, light })
    }

    /// Brings derived data up to date before the raycaster records (the table after a TF or step
    /// change); `params` is the raycaster's uniform buffer, `fusion` its fusion bindings
    /// (`FusionState::bindings`, brought up to date first; empty for one volume).
    pub fn update(
        &mut self,
        ctx: &mut RecordContext<'_>,
        params: &wgpu::Buffer,
        step_voxels: f64,
        fusion: &[(&'static str, wgpu::BindingResource<'_>)],
    ) -> Result<(), PassError> {
        if let Some(light) = &mut self.light {
            light.update(ctx, fusion)?;
        }
        for table in &mut self.tables {
            table.update(ctx, params, step_voxels)?;
        }
        Ok(())
    }

    /// The bindings the effects add (`preintegrated` and the partners' tables, `light_volume`).
    pub fn bindings(&self) -> Vec<(&'static str, wgpu::BindingResource<'_>)> {
        let table = self.tables.iter().map(|t| (t.binding, wgpu::BindingResource::TextureView(&t.table.view)));
        let light =
            self.light.iter().filter_map(|l| l.view()).map(|v| ("light_volume", wgpu::BindingResource::TextureView(v)));
        table.chain(light).collect()
    }

    /// Light-volume builds so far (0 without shadows).
    pub fn light_builds(&self) -> u64 {
        self.light.as_ref().map_or(0, |l| l.builds)
    }

    /// Table builds so far (0 without pre-integration).
    pub fn table_builds(&self) -> u64 {
        self.tables.iter().map(|t| t.builds).sum()
    }

    /// Forgets derived data after new parameters (the step may have changed).
    pub fn invalidate(&mut self) {
        for t in &mut self.tables {
            t.invalidate();
        }
    }
}

#[cfg(test)]
mod tests {
    use volgraph_compiler::KindLookup;

    use super::SCENE_EFFECTS;

    /// What a scene may ask for is what the kinds declare: every kind that declares the scene
    /// effects takes each as a parameter (a graph wires it to `"feature.NAME"`), the marching
    /// families all declare them, and the registry's list is theirs.
    #[test]
    fn the_scene_effects_are_what_the_raycasters_declare() {
        let registry = crate::builtin_registry();
        let mut expected = SCENE_EFFECTS.to_vec();
        expected.sort_unstable();
        assert_eq!(registry.scene_effects(), expected);
        let declaring: Vec<&str> = registry
            .kind_names()
            .into_iter()
            .filter(|k| !registry.decl(k).expect("kind").scene_effects().is_empty())
            .collect();
        for family in ["raycast", "raycast_compute", "raycast_segment", "raycast_bricks", "antialias"] {
            assert!(declaring.contains(&family), "{family} declares the scene effects: {declaring:?}");
        }
        for kind in declaring {
            let decl = registry.decl(kind).expect("kind");
            let params: Vec<&str> = decl.params().iter().map(|p| p.name).collect();
            for effect in decl.scene_effects() {
                assert!(params.contains(effect), "{kind} declares {effect} but has no such parameter: {params:?}");
            }
            // Shading reads the headlight's coefficients: without the block they are zeros
            // and a shaded image is black (raycast_bricks was, on both the GPU and its
            // reference, which read the same parameters).
            for coefficient in ["ambient", "diffuse", "specular", "shininess"] {
                assert!(params.contains(&coefficient), "{kind} takes shading but not {coefficient}: {params:?}");
            }
        }
    }
}
