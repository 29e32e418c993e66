//! What the panel reads off the running view: the data value under the cursor, and the live
//! accuracy's comparison job (the last frame's image with everything the converged reference
//! needs).

use volgraph_accel::camera::OrbitCamera;

use super::{LiveSession, Resting};

impl LiveSession {
    /// After a frame of a path tracer whose mean starts over on any change: its image at each
    /// power of two of samples, for the estimate of the view's error
    /// (`volgraph_accel::progressive_error`; one read-back per doubling).
    ///
    /// A graph whose pixels keep their own counts (a `samples` output: a reprojecting path
    /// tracer) is estimated over the frames since the camera last moved, each pixel weighted by
    /// its counts (`estimated_rmse_counted`).
    pub(super) fn track_noise(&mut self, camera: &OrbitCamera) {
        let history = self.runtime.history_stats();
        if crate::render::estimates_noise(self.runtime.plan()) {
            let spp = history.run + 1;
            if self.noise.wants(spp)
                && let Ok(image) = self.runtime.read_output("image")
            {
                self.noise.offer(history.restarts, spp, image.to_rgba_f64());
            }
            return;
        }
        if !self.runtime.plan().is_some_and(|p| p.outputs.contains_key(crate::render::SAMPLES_OUTPUT)) {
            return;
        }
        if self.resting.camera != Some(*camera) {
            self.resting = Resting { camera: Some(*camera), frames: 0, moves: self.resting.moves + 1 };
        }
        self.resting.frames += 1;
        let frames = self.resting.frames;
        if self.noise.wants(frames)
            && let (Ok(image), Ok(counts)) =
                (self.runtime.read_output("image"), self.runtime.read_output(crate::render::SAMPLES_OUTPUT))
        {
            let counts = counts.to_rgba_f64().iter().map(|p| p[0]).collect();
            self.noise.offer_counted(self.resting_key(), frames, image.to_rgba_f64(), Some(counts));
        }
    }

    /// The frame volume.
    pub fn volume(&self) -> &volgraph_accel::volume::Volume {
        &self.volume
    }

    /// Whether the volume's axes lie in the patient (LPS): the patient views name its sides.
    pub fn in_patient_frame(&self) -> bool {
        self.volume.meta.frame == volgraph_accel::volume_meta::WorldFrame::Lps
    }

    /// The volume's patient box (LPS corner and extent, mm) when it lies in the patient frame:
    /// the crop sliders say where they cut in mm.
    pub fn patient_box(&self) -> Option<(glam::DVec3, glam::DVec3)> {
        self.volume.meta.patient_box(self.volume.dims.as_dvec3(), self.volume.spacing)
    }

    /// What names one accumulation of a graph with per-pixel counts: the history's restarts
    /// and the camera's moves.
    fn resting_key(&self) -> u64 {
        (self.runtime.history_stats().restarts << 32) ^ self.resting.moves
    }

    /// The view's estimated error at the samples it holds now (from the last doubling), for
    /// the panel: `None` before the second sample or for a graph it is not made for.
    pub fn noise_line(&self) -> Option<String> {
        let history = self.runtime.history_stats();
        if crate::render::estimates_noise(self.runtime.plan()) {
            return self.noise.last(history.restarts).map(|e| e.line(history.run + 1));
        }
        self.noise.last(self.resting_key()).map(|e| e.line_resting())
    }

    /// What lies under window pixel `cursor` (physical pixels) seen by `camera`: the first
    /// visible point along its ray (the TF, the crop and clip planes as drawn) and the data value
    /// there, as a line for the panel in the data's units; `None` off the volume.
    pub fn probe_line(&self, camera: &OrbitCamera, cursor: (f64, f64)) -> Option<String> {
        let (w, h) = self.options().viewport;
        if !(cursor.0 >= 0.0 && cursor.1 >= 0.0) {
            return None;
        }
        let pixel = (cursor.0 as u32, cursor.1 as u32);
        let cuts = self.runtime.cuts();
        // A label map is seen through its label table: the probe's LUT over its normalized values.
        let lut = match self.labels() {
            Some(list) => label_probe_lut(&self.volume, &list.lut()),
            None => self.lut.clone(),
        };
        let p = volgraph_accel::probe::first_visible(&self.volume, &lut, camera, (w, h), pixel, 0.5, &cuts)?;
        let units = self.volume.meta.units.as_deref().map_or(String::new(), |u| format!(" {u}"));
        // The label there: the volume's own value where it is the label map, else the map's
        // voxel at that patient point (a segmentation over its scan).
        let label = match (self.labels(), self.labels_are_the_volume) {
            (Some(list), true) => {
                let value = p.value.round().max(0.0) as u32;
                list.name_of(value).map_or(String::new(), |name| format!(", label {value} \"{name}\""))
            }
            _ => self.label_line(p.voxel / self.volume.dims.as_dvec3()),
        };
        // In the patient frame, where that is in mm, as the clinical tools say it.
        let patient = self
            .volume
            .meta
            .patient_point(p.voxel, self.volume.spacing)
            .map_or(String::new(), |mm| format!(", {}", volgraph_accel::volume_meta::patient_label(mm)));
        Some(format!(
            "under the cursor: {:.4}{units}{label} at voxel ({:.1}, {:.1}, {:.1}){patient}, α {:.2}",
            p.value, p.voxel.x, p.voxel.y, p.voxel.z, p.alpha
        ))
    }

    /// `, label V "NAME"` for the label map's voxel at the frame volume's texture point `u` (the
    /// same patient point on the map's own grid, its nearest voxel), or nothing where there is
    /// no label map, the point lies outside it or its label is unnamed.
    pub(super) fn label_line(&self, u: glam::DVec3) -> String {
        let Some(list) = self.labels() else { return String::new() };
        let map = match &self.label_map_input {
            None => Some(&self.volume),
            Some(input) => {
                self.bindings.as_ref().and_then(|b| b.others.iter().find(|(n, _)| n == input)).map(|(_, v)| v)
            }
        };
        let Some(map) = map else { return String::new() };
        let Ok(to_map) = volgraph_accel::fusion::TextureMap::between(&self.volume, map) else { return String::new() };
        let v = to_map.apply(u);
        if !volgraph_accel::fusion::in_box(v) {
            return String::new();
        }
        let (value, _) =
            volgraph_accel::labels::sample::sample_label(map, v, volgraph_accel::labels::sample::LabelFilter::Nearest);
        list.name_of(value).map_or(String::new(), |name| format!(", label {value} \"{name}\""))
    }

    /// A comparison of the view on screen (the last frame's `image`) with the converged
    /// reference, for a worker thread; `None` for a graph without a float `image` output or a
    /// raycaster (`march`) to take the settings from.
    pub fn accuracy_job(&mut self, camera: &OrbitCamera) -> Option<crate::view::accuracy::Job> {
        // A streamed volume (a store, a file over the memory budget): the session holds only its
        // coarsest level, and a reference over that would be compared with the full-resolution
        // image (it showed "max 253/255" for a correct image).
        if self.pyramid.is_some() {
            return None;
        }
        let plan = self.plan()?;
        let march = plan.steps.iter().find(|s| s.pass_id == "march" && s.params.declares("step_voxels"))?;
        // Several volumes: the viewer binds one, so only a label map coloured by its table (the
        // volume itself) has a reference to compare with.
        let fusion = volgraph_passes::fusion::FusionSettings::of(&march.params);
        let labels = match fusion.combine() {
            None => None,
            Some(volgraph_accel::fusion::Combine::Labels) => {
                let filter = match fusion.label_filter {
                    volgraph_passes::fusion::LabelFilterChoice::Smooth => {
                        volgraph_accel::labels::sample::LabelFilter::Smooth
                    }
                    volgraph_passes::fusion::LabelFilterChoice::Nearest => {
                        volgraph_accel::labels::sample::LabelFilter::Nearest
                    }
                };
                Some((self.labels()?.lut(), filter))
            }
            Some(_) => return None,
        };
        let mut settings = volgraph_passes::raycast_params::reference_settings(&march.params);
        settings.lights = self.runtime.lights();
        settings.opacity_unit_voxels = match self.opacity_reference {
            volgraph_core::runtime::OpacityReference::World => 1.0 / self.volume.unit_step_world(),
            volgraph_core::runtime::OpacityReference::Voxel => 1.0,
        };
        let size = plan.viewport;
        let image = self.runtime.read_output("image").ok()?;
        if (image.width, image.height) != size || image.channels != 4 {
            return None;
        }
        Some(crate::view::accuracy::Job {
            image: image.to_rgba_f64(),
            size,
            volume: self.volume.clone(),
            lut: self.lut.clone(),
            camera: *camera,
            settings,
            cuts: self.runtime.cuts(),
            labels,
        })
    }
}

/// A label table (RGBA by label value) as a LUT over the map's normalized values, for the probe:
/// entry i is the table's entry of the label nearest to the value it stands for.
fn label_probe_lut(map: &volgraph_accel::volume::Volume, table: &[[f32; 4]]) -> Vec<[f32; 4]> {
    const N: usize = 4096;
    (0..N)
        .map(|i| {
            let value = map.data_value((i as f64 + 0.5) / N as f64).round().max(0.0) as usize;
            table.get(value).copied().unwrap_or([0.0; 4])
        })
        .collect()
}
