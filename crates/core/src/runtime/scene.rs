//! What a [`Runtime`] renders: the graph inputs the application binds (volume, transfer-function
//! LUT, its own textures; held in [`super::inputs::InputStore`]) and the scene settings that
//! shape every frame (opacity reference, sort-last volume window, crop box and clip planes), with
//! the scene values and the volume description the frame contract sees.

use std::collections::BTreeMap;
use std::sync::Arc;

use volgraph_accel::cuts::Cuts;

use super::{CameraData, OpacityReference, Runtime, RuntimeError, VolumeDesc, VolumeFormat, VolumeWindow, frame};
use crate::graph::ast::InputKind;

impl Runtime {
    /// The bound volume's description and texture format.
    pub fn volume(&self) -> Option<(VolumeDesc, VolumeFormat)> {
        self.inputs.volume()
    }

    /// Binds a volume to graph input `name` (uploads only new content).
    pub fn bind_volume(&mut self, name: &str, volume: &volgraph_accel::volume::Volume) -> Result<bool, RuntimeError> {
        Ok(self.inputs.bind_volume(&self.gpu, name, volume)?)
    }

    /// Binds a volume read brick by brick to graph input `name`: only a pass that streams it
    /// (`raycast_stream`) can draw it; the frame's volume box is its finest level's.
    pub fn bind_pyramid(&mut self, name: &str, source: Arc<dyn volgraph_accel::pyramid::PyramidSource>) {
        self.inputs.bind_pyramid(&self.gpu, name, source);
    }

    /// Binds a transfer-function LUT to graph input `name` (uploads only new content).
    pub fn bind_lut(&mut self, name: &str, lut: &[[f32; 4]]) -> Result<bool, RuntimeError> {
        Ok(self.inputs.bind_lut(&self.gpu, name, lut)?)
    }

    /// Binds a label table (RGBA by label value: `volgraph_accel::labels::LabelTable::lut`) to
    /// graph input `name`, a `LabelTable` (uploads only new content).
    pub fn bind_label_table(&mut self, name: &str, table: &[[f32; 4]]) -> Result<bool, RuntimeError> {
        Ok(self.inputs.bind_label_table(&self.gpu, name, table)?)
    }

    /// Binds an application-made texture to graph input `name` (a transfer function's is 1D,
    /// one RGBA texel per LUT entry, as `bind_lut` uploads it; a volume's is 3D).
    pub fn bind_texture(&mut self, name: &str, texture: wgpu::Texture) {
        self.inputs.bind_texture(name, texture);
    }

    /// Uploads done since start (a plan change re-uploads nothing).
    pub fn uploads(&self) -> u64 {
        self.inputs.uploads()
    }

    /// Binds `volume` and `lut` to every graph input of kind Volume and TransferFunction in
    /// `inputs` (a plan's inputs).
    pub fn bind_scene(
        &mut self,
        inputs: &BTreeMap<String, InputKind>,
        volume: &volgraph_accel::volume::Volume,
        lut: &[[f32; 4]],
    ) -> Result<(), RuntimeError> {
        let mut uploaded = false;
        for (name, kind) in inputs {
            match kind {
                InputKind::Volume => uploaded |= self.bind_volume(name, volume)?,
                InputKind::TransferFunction => uploaded |= self.bind_lut(name, lut)?,
                // The volume's own labels in the default palette (a label map bound as the scene's
                // volume; anything else leaves a table the caller binds).
                InputKind::LabelTable => {
                    if let Ok(census) = volgraph_accel::labels::census::census(volume) {
                        let values = census.values();
                        let len = values.last().map_or(1, |v| *v as usize + 1);
                        let table = volgraph_accel::labels::LabelTable::default_for(values).lut(len);
                        uploaded |= self.bind_label_table(name, &table)?;
                    }
                }
                InputKind::Scalar(_) | InputKind::Data(_) => {}
            }
        }
        // What history keeps was computed from the old inputs (Klein et al. 2005 §4.1: a new
        // transfer function restarts from the box).
        if uploaded {
            self.invalidate_history();
        }
        Ok(())
    }

    /// Scene values of what is bound, for compiling: the bound volume's
    /// [`LONGEST_RAY_VOXELS`](super::LONGEST_RAY_VOXELS) and [`BLOCK_SIZE`](super::BLOCK_SIZE). Computed in this one place.
    pub fn scene_values(&self) -> BTreeMap<String, f64> {
        self.volume_desc().map(|v| frame::scene_values_of(&v)).unwrap_or_default()
    }

    /// Sets what the transfer function's opacity is per (per voxel by default; per world unit
    /// keeps the look when the resolution changes). Takes effect with the next frame.
    pub fn set_opacity_reference(&mut self, reference: OpacityReference) {
        self.opacity_reference = reference;
    }

    /// What the transfer function's opacity is per.
    pub fn opacity_reference(&self) -> OpacityReference {
        self.opacity_reference
    }

    /// Declares the bound volume a window of a larger one (sort-last rendering,
    /// `docs/scaling.md`): rays meet the whole volume's box, samples are taken in the window's
    /// own box only, and cameras given in the whole volume's world are moved to the window's.
    /// `None`: the bound volume is the whole volume.
    pub fn set_volume_window(&mut self, window: Option<VolumeWindow>) {
        if self.window != window {
            self.window = window;
            self.invalidate_history();
        }
    }

    /// Sets the scene's crop box and clip planes (volume fractions of the whole volume,
    /// `volgraph_accel::cuts`). Moving a box or plane takes effect with the next frame; turning
    /// a kind of cut on needs a plan applied after this call (the cut's code is compiled in only
    /// then: `volgraph_compiler::cut_effects`), else the next frame is refused.
    pub fn set_cuts(&mut self, cuts: Cuts) {
        if self.cuts != cuts {
            self.cuts = cuts;
            self.invalidate_history();
        }
    }

    /// The scene's cuts.
    pub fn cuts(&self) -> Cuts {
        self.cuts
    }

    /// Sets the scene's one light (`volgraph_accel::light`): [`Self::set_lights`] of it.
    pub fn set_light(&mut self, light: volgraph_accel::light::Light) {
        self.set_lights(light.into());
    }

    /// Sets the scene's lights: the next frame is shaded by them, and accumulated history
    /// restarts when one moved.
    pub fn set_lights(&mut self, lights: volgraph_accel::light::Lights) {
        if self.lights != lights {
            self.lights = lights;
            self.invalidate_history();
        }
    }

    /// Sets the scene's environment map (what a path tracer's paths see when they leave the
    /// volume; `None`: the pass's own generated sky): uploaded once, bound by name
    /// (`environment_map`) to every pass that declares it. Accumulated history restarts.
    pub fn set_environment(&mut self, map: Option<Arc<volgraph_accel::environment::EnvironmentMap>>) {
        if self.environment != map {
            self.system.environment_map = super::record::environment_view(
                &self.gpu,
                map.as_deref().unwrap_or(&volgraph_accel::environment::EnvironmentMap::uniform([0.0; 3])),
            );
            self.environment = map;
            self.invalidate_history();
        }
    }

    /// The scene's environment map, if any.
    pub fn environment(&self) -> Option<&Arc<volgraph_accel::environment::EnvironmentMap>> {
        self.environment.as_ref()
    }

    /// The scene's lights.
    pub fn lights(&self) -> volgraph_accel::light::Lights {
        self.lights
    }

    /// The bound volume as the frame contract describes it (windowed when a window is set).
    pub(super) fn volume_desc(&self) -> Option<VolumeDesc> {
        let (desc, _) = self.inputs.volume()?;
        let desc = match &self.window {
            Some(window) => VolumeDesc::of_window(desc.dims, window),
            None => desc,
        };
        Some(desc.with_opacity_reference(self.opacity_reference))
    }

    /// `camera` (in the whole volume's world) in the bound box's world.
    pub(super) fn local_camera(&self, camera: CameraData) -> CameraData {
        match self.volume_desc().and_then(|v| v.window) {
            Some(w) => camera.translated(-w.centre_world),
            None => camera,
        }
    }
}
