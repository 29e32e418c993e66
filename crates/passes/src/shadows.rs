//! The `shadows` scene effect (issue "light that scatters", item 1; Behrens & Ratering 1998's
//! shadow volume): a light volume — at each voxel of a grid of up to 64³, the transmittance
//! toward each of the scene's lights (one channel each) through the classified volume (`volgraph_accel::light::LightGrid`,
//! the very function the f64 reference calls) — that the march reads at every sample
//! (`shaders/common/shadows.wgsl`) to scale the light reaching it. Not a pass: each raycaster
//! that shades with it owns one, like the pre-integration table, and rebuilds it only when the
//! volume's or TF's content (their input versions), the lights, the opacity unit or the
//! reconstruction change. With the headlight the light comes from the eye along the camera's
//! forward axis, so the volume follows the camera.
//!
//! The grid is computed on the GPU (`shaders/light_volume.wgsl`, one compute dispatch, written
//! as `Rgba16Float`: T ∈ \[0, 1\] in f16 is within 2⁻¹¹) where the pass's volume is a texture;
//! the brick raycaster's GPU volume is an atlas of resident bricks, not the volume, so there it
//! is computed on the CPU (rayon) from the voxels and LUT the runtime keeps for every bound
//! volume and TF — by `LightGrid::compute`, the reference's own function — and uploaded as
//! `Rgba16Float` as well.

use volgraph_compiler::ShaderUse;

/// The light volume's compute entry point, declared by the raycasters whose volume is a texture;
/// with several volumes (`params` set fusion) it reads their combined opacity, through the
/// raycaster's `fusion` uniform and label quads.
pub fn light_shader_use(params: &volgraph_compiler::Params) -> ShaderUse {
    crate::fusion::with_fusion_uniform(
        ShaderUse::new("light_volume.wgsl", "cs_light_volume").binds(&["light_out", "label_quads"]),
        params,
    )
}

// The light volume's four channels: one per light, then ambient occlusion.
const _: () = assert!(volgraph_accel::light::MAX_LIGHTS == 3);

/// The ports whose versions rebuild the light volume of several volumes besides the volume and
/// TF: the others' voxels and TFs, and the label table (a label hidden casts no shadow).
const FUSION_INPUTS: [&str; 8] =
    ["second", "second_tf", "third", "third_tf", "fourth", "fourth_tf", "overlay", "label_table"];

#[cfg(feature = "gpu")]
use volgraph_core::runtime::{ComputePassPipeline, ComputePipelineSpec, CreateContext, PassError, RecordContext};

/// What a light volume was built for: the volume's and TF's versions, each light's direction or
/// a point light's position (with `true`), the opacity unit's bits and the cuts.
#[cfg(feature = "gpu")]
type BuildKey = (
    Option<u64>,
    Option<u64>,
    [([u64; 3], bool); volgraph_accel::light::MAX_LIGHTS],
    u64,
    volgraph_accel::cuts::Cuts,
    [Option<u64>; FUSION_INPUTS.len()],
);

#[cfg(feature = "gpu")]
/// A raycaster's light volume and what it was built for.
pub struct LightVolume {
    view: Option<wgpu::TextureView>,
    /// Where the pass's volume is a texture: the compute pipeline that writes the grid.
    gpu: Option<ComputePassPipeline>,
    /// (volume version, TF version, light direction or point light position (shadows only),
    /// opacity unit, cuts) of the last build.
    built_for: Option<BuildKey>,
    /// The field is the tricubic B-spline (the `tricubic` effect), as the march reconstructs it.
    tricubic: bool,
    /// Which channels: transmittance toward the light (`shadows`), ambient occlusion.
    shadows: bool,
    occlusion: bool,
    /// Builds so far (tests, the viewer).
    pub builds: u64,
}

#[cfg(feature = "gpu")]
impl LightVolume {
    /// Not built yet; `tricubic`: reconstruct the field as the march does. On the GPU where the
    /// pass's `volume` port is the volume's texture (`volume_texture`), else on the CPU.
    pub fn new(
        ctx: &CreateContext<'_>,
        flags: &crate::effects::EffectFlags,
        volume_texture: bool,
    ) -> Result<Self, PassError> {
        let gpu = if volume_texture {
            let declared = light_shader_use(ctx.params);
            let mut defines: Vec<&str> = [
                (flags.tricubic, crate::defines::TRICUBIC),
                (flags.shadows, crate::defines::SHADOWS),
                (flags.ambient_occlusion, crate::defines::AMBIENT_OCCLUSION),
            ]
            .into_iter()
            .filter_map(|(on, d)| on.then_some(d))
            .collect();
            defines.extend(crate::fusion::FusionSettings::of(ctx.params).defines());
            Some(
                ctx.compute_pipeline(&ComputePipelineSpec { defines: &defines, ..ComputePipelineSpec::of(&declared) })?,
            )
        } else {
            None
        };
        Ok(Self {
            view: None,
            gpu,
            built_for: None,
            tricubic: flags.tricubic,
            shadows: flags.shadows,
            occlusion: flags.ambient_occlusion,
            builds: 0,
        })
    }

    /// The light volume, once built.
    pub fn view(&self) -> Option<&wgpu::TextureView> {
        self.view.as_ref()
    }

    /// Rebuilds from the pass's `volume` and `tf` ports when they, the light or the opacity unit
    /// changed since the last build.
    /// Rebuilds the volume when what it depends on changed; `fusion`: the raycaster's fusion
    /// bindings (`FusionState::bindings`, written before), empty for one volume.
    pub fn update(
        &mut self,
        ctx: &mut RecordContext<'_>,
        fusion: &[(&'static str, wgpu::BindingResource<'_>)],
    ) -> Result<(), PassError> {
        let frame = ctx.frame;
        // Only shadows depend on the light (ambient occlusion does not follow the camera). A
        // point light in the bound box's own world (a sort-last window centres it on its origin).
        let window_centre = frame.volume.and_then(|v| v.window).map_or(glam::DVec3::ZERO, |w| w.centre_world);
        let towards: Vec<volgraph_accel::light::Toward> = if self.shadows {
            frame
                .lights
                .toward_with(-frame.camera.forward)
                .into_iter()
                .map(|toward| match toward {
                    volgraph_accel::light::Toward::Point(at) => {
                        volgraph_accel::light::Toward::Point(at - window_centre)
                    }
                    direction => direction,
                })
                .collect()
        } else {
            Vec::new()
        };
        let mut towards_key = [([0; 3], false); volgraph_accel::light::MAX_LIGHTS];
        for (slot, toward) in towards_key.iter_mut().zip(&towards) {
            *slot = match *toward {
                volgraph_accel::light::Toward::Direction(d) => (d.to_array().map(f64::to_bits), false),
                volgraph_accel::light::Toward::Point(at) => (at.to_array().map(f64::to_bits), true),
            };
        }
        let unit = frame.volume.map_or(1.0, |v| v.opacity_unit_voxels);
        let key = (
            ctx.input_version("volume"),
            ctx.input_version("tf"),
            towards_key,
            unit.to_bits(),
            // What the cuts keep (cut-away material casts no shadow).
            frame.cuts,
            FUSION_INPUTS.map(|port| ctx.input_version(port)),
        );
        if self.built_for == Some(key) && self.view.is_some() {
            return Ok(());
        }
        let dims = volgraph_accel::light::light_grid_dims(ctx.voxels("volume")?.dims);
        if let Some(pipeline) = &self.gpu {
            // The grid's texture, made anew when the volume's size changed.
            let size = wgpu::Extent3d { width: dims.x, height: dims.y, depth_or_array_layers: dims.z };
            let view = match &self.view {
                Some(v) if v.texture().size() == size && v.texture().format() == wgpu::TextureFormat::Rgba16Float => {
                    v.clone()
                }
                _ => ctx
                    .gpu
                    .device
                    .create_texture(&wgpu::TextureDescriptor {
                        label: Some(&format!("{} light volume", ctx.label)),
                        size,
                        mip_level_count: 1,
                        sample_count: 1,
                        dimension: wgpu::TextureDimension::D3,
                        format: wgpu::TextureFormat::Rgba16Float,
                        usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
                        view_formats: &[],
                    })
                    .create_view(&wgpu::TextureViewDescriptor::default()),
            };
            let mut extra = vec![("light_out", wgpu::BindingResource::TextureView(&view))];
            extra.extend(fusion.iter().cloned());
            let bg = ctx.bind_group(pipeline, &extra)?;
            let mut pass = ctx.begin_compute_pass();
            pass.set_pipeline(&pipeline.pipeline);
            pass.set_bind_group(0, &bg, &[]);
            pass.dispatch_workgroups(dims.x.div_ceil(4), dims.y.div_ceil(4), dims.z.div_ceil(4));
            drop(pass);
            self.view = Some(view);
            self.built_for = Some(key);
            self.builds += 1;
            return Ok(());
        }
        let volume = ctx.voxels("volume")?.clone();
        let lut = ctx.table("tf")?.clone();
        let tricubic = self.tricubic;
        let field = |u: glam::DVec3| if tricubic { volume.sample_tricubic(u) } else { volume.sample_trilinear(u) };
        let alpha = |u: glam::DVec3| volgraph_accel::reference::lut_sample(&lut, field(u))[3];
        let cuts = frame.cuts;
        let grid =
            volgraph_accel::light::LightGrid::compute(&volume, (&towards, self.occlusion), (unit, &cuts), &alpha);
        // The GPU's layout: each light's T in .rgb, AO in .a, 1 for a channel that is off.
        let channel = |values: Option<&Vec<f64>>, i: usize| values.and_then(|v| v.get(i)).map_or(1.0, |&v| v as f32);
        let texels: Vec<[f32; 4]> = (0..(grid.dims.x * grid.dims.y * grid.dims.z) as usize)
            .map(|i| {
                let t = |light: usize| channel(grid.transmittance.get(light), i);
                [t(0), t(1), t(2), channel(Some(&grid.occlusion), i)]
            })
            .collect();
        let texture =
            volgraph_core::runtime::upload::upload_rgba16f_3d(ctx.gpu, "light_volume", grid.dims.to_array(), &texels)
                .map_err(|e| PassError { pass: ctx.label.to_string(), message: e.to_string() })?;
        self.view = Some(texture.create_view(&wgpu::TextureViewDescriptor::default()));
        self.built_for = Some(key);
        self.builds += 1;
        Ok(())
    }
}
