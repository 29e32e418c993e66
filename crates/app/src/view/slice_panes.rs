//! The clinical tools' slice panes beside the 3D view: axial, coronal and sagittal slices through
//! one point — the crosshair — each through a window in data units. They are a graph
//! (`graphs/clinical/slices.ron`, three `reslice` passes) on a runtime of their own on the
//! viewer's GPU: a crosshair move or a window edit compiles it with the new parameters, which
//! the runtime writes in place (nothing rebuilt), and renders it once; between changes its
//! outputs are only drawn again ([`Runtime::present`]). The geometry (which point a pane pixel
//! shows, where the crosshair lies in each pane) is `volgraph_accel::reslice`'s, the same the
//! pass and its f64 twin use.

use std::sync::Arc;
use std::time::Instant;

use glam::{DVec2, DVec3, UVec3};
use volgraph_accel::reslice::{PaneFit, SliceAxis, SlicePlane, default_window};
use volgraph_accel::volume::Volume;
use volgraph_accel::volume_meta::Window;
use volgraph_core::runtime::{CameraData, Gpu, Image, PresentTarget, Runtime, ShaderLibrary};
use volgraph_core::{CompileOptions, Registry};

/// The built-in graph the panes run.
pub const SLICES_GRAPH: &str = "clinical/slices";
/// … and with a label map over them.
pub const LABELLED_SLICES_GRAPH: &str = "clinical/slices_labels";

/// A label map to lay over the panes: the map and its table (`LabelTable::lut`).
pub struct PaneLabels<'a> {
    /// The label map, in the volume's patient frame.
    pub map: &'a Volume,
    /// Colour and opacity by label value, 0 where hidden.
    pub table: Vec<[f32; 4]>,
}

/// What the panes show: the crosshair (a texture point of the volume, `[0, 1]³`) and the
/// window, in data units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SliceView {
    /// The point the three planes pass through.
    pub crosshair: DVec3,
    /// Black at `center − width/2`, white at `center + width/2`.
    pub window: Window,
}

/// The three slice panes of a volume.
pub struct SlicePanes {
    runtime: Runtime,
    registry: Registry,
    /// The graph's name and text (with or without labels).
    graph: (&'static str, &'static str),
    dims: UVec3,
    spacing: DVec3,
    /// Half the volume box in world units (`Volume::half_extent_world`).
    half_extent: DVec3,
    /// The volume's own window (the file's, else its value range).
    file_window: Window,
    /// What the panes should show.
    pub view: SliceView,
    /// The three planes' outlines drawn in the 3D view.
    pub planes_in_3d: bool,
    /// What they show now, and at which pane size.
    rendered: Option<(SliceView, (u32, u32))>,
    /// Milliseconds of the last update: compile, apply, render and wait.
    pub last_update_ms: Option<f64>,
}

impl SlicePanes {
    /// The panes of `volume` on `gpu`, with `labels` over them when given: the crosshair at the
    /// central voxel, the file's window.
    pub fn new(gpu: Arc<Gpu>, volume: &Volume, labels: Option<PaneLabels<'_>>) -> Result<Self, String> {
        let name = if labels.is_some() { LABELLED_SLICES_GRAPH } else { SLICES_GRAPH };
        let graph = crate::builtin_graphs::find(std::path::Path::new(name))
            .ok_or_else(|| format!("the built-in graph {name} is missing from this build"))?;
        let mut runtime = Runtime::new(gpu, ShaderLibrary::new(volgraph_passes::builtin_shaders()));
        let bound = |e: volgraph_core::runtime::RuntimeError| format!("the slice panes: {e}");
        runtime.bind_volume("volume", volume).map_err(bound)?;
        if let Some(labels) = &labels {
            runtime.bind_volume("labels", labels.map).map_err(bound)?;
            runtime.bind_label_table("label_table", &labels.table).map_err(bound)?;
        }
        let file_window = default_window(volume);
        let centre = (volume.dims / 2).as_dvec3() + 0.5;
        Ok(Self {
            runtime,
            registry: volgraph_passes::builtin_registry(),
            graph,
            dims: volume.dims,
            spacing: volume.spacing,
            half_extent: volume.half_extent_world(),
            file_window,
            view: SliceView { crosshair: centre / volume.dims.as_dvec3(), window: file_window },
            planes_in_3d: true,
            rendered: None,
            last_update_ms: None,
        })
    }

    /// The volume's own window: the file's, else its value range.
    pub fn file_window(&self) -> Window {
        self.file_window
    }

    /// Where `axis`'s slice lies in a pane of `pane` pixels.
    pub fn fit(&self, axis: SliceAxis, pane: (u32, u32)) -> PaneFit {
        PaneFit::of(axis, self.dims, self.spacing, pane)
    }

    /// The plane `axis` shows: through the crosshair.
    pub fn plane(&self, axis: SliceAxis) -> SlicePlane {
        SlicePlane { axis, position: self.view.crosshair[axis.normal()] }
    }

    /// The crosshair in `axis`'s pane of `pane` pixels (pixels from its top left).
    pub fn crosshair_in(&self, axis: SliceAxis, pane: (u32, u32)) -> DVec2 {
        self.plane(axis).pane_point(&self.fit(axis, pane), self.view.crosshair)
    }

    /// A click (or drag) at pane point `p` of `axis`'s pane moves the crosshair there, within
    /// the plane; beside the slice it goes to the nearest point on it.
    pub fn click(&mut self, axis: SliceAxis, pane: (u32, u32), p: DVec2) {
        let fit = self.fit(axis, pane);
        let f = fit.fractions(p).clamp(DVec2::ZERO, DVec2::ONE);
        let u = self.plane(axis).extended_point(&fit, fit.point(f));
        self.view.crosshair = u.clamp(DVec3::ZERO, DVec3::ONE);
    }

    /// Moves `axis`'s slice by `slices` voxels along its normal, onto voxel centres, within
    /// the volume (a wheel notch is one slice, as in the clinical tools).
    pub fn scroll(&mut self, axis: SliceAxis, slices: i32) {
        let a = axis.normal();
        let n = f64::from(self.dims[a].max(1));
        let index = (self.view.crosshair[a] * n - 0.5).round() + f64::from(slices);
        self.view.crosshair[a] = (index.clamp(0.0, n - 1.0) + 0.5) / n;
    }

    /// The slice index (0-based) `axis`'s pane shows, nearest the crosshair.
    pub fn slice_index(&self, axis: SliceAxis) -> u32 {
        let a = axis.normal();
        let n = f64::from(self.dims[a].max(1));
        (self.view.crosshair[a] * n - 0.5).round().clamp(0.0, n - 1.0) as u32
    }

    /// Slices along `axis`'s normal.
    pub fn slice_count(&self, axis: SliceAxis) -> u32 {
        self.dims[axis.normal()]
    }

    /// The crosshair in world space, where the 3D view draws its point.
    pub fn crosshair_world(&self) -> DVec3 {
        (self.view.crosshair - 0.5) * 2.0 * self.half_extent
    }

    /// The corners of `axis`'s plane where it cuts the volume box, in world space, in order
    /// around it: the outline the 3D view draws.
    pub fn plane_corners_world(&self, axis: SliceAxis) -> [DVec3; 4] {
        let [(c, _), (r, _)] = axis.pane_axes();
        [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)].map(|(a, b)| {
            let mut u = self.view.crosshair;
            u[c] = a;
            u[r] = b;
            (u - 0.5) * 2.0 * self.half_extent
        })
    }

    /// The voxel coordinate of the crosshair (voxel centres at integer + 0.5, as
    /// `volgraph_accel::probe`).
    pub fn crosshair_voxel(&self) -> DVec3 {
        self.view.crosshair * self.dims.as_dvec3()
    }

    /// Renders the panes at `pane` pixels each if what they should show changed since they
    /// last did; returns whether it rendered. Waits for the frame (it is the measured update).
    pub fn update(&mut self, pane: (u32, u32)) -> Result<bool, String> {
        let pane = (pane.0.max(1), pane.1.max(1));
        if self.rendered == Some((self.view, pane)) {
            return Ok(false);
        }
        let start = Instant::now();
        let mut options = CompileOptions::new(pane.0, pane.1);
        for axis in SliceAxis::ALL {
            let pass = axis.name();
            let set = |options: &mut CompileOptions, name: &str, value: f64| {
                options.param_overrides.insert(format!("{pass}.{name}"), ron::Value::from(value as f32));
            };
            set(&mut options, "position", self.view.crosshair[axis.normal()]);
            set(&mut options, "window_center", self.view.window.center);
            set(&mut options, "window_width", self.view.window.width.max(1e-6));
        }
        let plan = volgraph_core::compile(self.graph.0, self.graph.1, &self.registry, &options)
            .map_err(|d| format!("the slice panes' graph: {d}"))?;
        self.runtime.apply(plan, &self.registry).map_err(|e| format!("the slice panes: {e}"))?;
        self.runtime
            .render(CameraData::from_orbit(&Default::default(), pane))
            .map_err(|e| format!("the slice panes: {e}"))?;
        self.rendered = Some((self.view, pane));
        self.last_update_ms = Some(start.elapsed().as_secs_f64() * 1e3);
        Ok(true)
    }

    /// Whether a label map lies over the panes.
    pub fn labelled(&self) -> bool {
        self.graph.0 == LABELLED_SLICES_GRAPH
    }

    /// A new table for the label map over the panes (a label hidden or recoloured in the list):
    /// one upload, the panes rendered again at the next update.
    pub fn set_label_table(&mut self, table: &[[f32; 4]]) -> Result<(), String> {
        if !self.labelled() {
            return Ok(());
        }
        if self.runtime.bind_label_table("label_table", table).map_err(|e| format!("the slice panes: {e}"))? {
            self.rendered = None;
        }
        Ok(())
    }

    /// Draws the three panes as last rendered onto a window's surface, each in its region
    /// (x, y, width, height), over what the surface holds.
    pub fn present(
        &mut self,
        view: &wgpu::TextureView,
        format: wgpu::TextureFormat,
        size: (u32, u32),
        regions: &[[u32; 4]; 3],
    ) -> Result<(), String> {
        for (axis, region) in SliceAxis::ALL.iter().zip(regions) {
            let target = PresentTarget { view, format, size, output: axis.name(), region: Some(*region), load: true };
            self.runtime.present(&target).map_err(|e| format!("the slice panes: {e}"))?;
        }
        Ok(())
    }

    /// `axis`'s pane as last rendered (tests, benchmarks).
    pub fn read(&mut self, axis: SliceAxis) -> Result<Image, String> {
        self.runtime.read_output(axis.name()).map_err(|e| e.to_string())
    }
}

/// Where the image region's parts go with the slice panes open: four equal cells, the 3D view
/// top left, then axial, coronal and sagittal (the clinical tools' four-up layout). Regions are
/// (x, y, width, height) in pixels of the surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FourUp {
    /// The 3D view.
    pub view: [u32; 4],
    /// Axial, coronal, sagittal.
    pub panes: [[u32; 4]; 3],
}

impl FourUp {
    /// The layout of an image region of `image` pixels at the surface's top left.
    pub fn of(image: (u32, u32)) -> Self {
        let (w, h) = ((image.0 / 2).max(1), (image.1 / 2).max(1));
        Self { view: [0, 0, w, h], panes: [[w, 0, w, h], [0, h, w, h], [w, h, w, h]] }
    }

    /// Each pane's size.
    pub fn pane(&self) -> (u32, u32) {
        (self.view[2], self.view[3])
    }

    /// The pane under surface point `p` (pixels) and the point within it.
    pub fn pane_at(&self, p: DVec2) -> Option<(SliceAxis, DVec2)> {
        SliceAxis::ALL.into_iter().zip(self.panes).find_map(|(axis, [x, y, w, h])| {
            let local = p - DVec2::new(f64::from(x), f64::from(y));
            let inside = local.x >= 0.0 && local.y >= 0.0 && local.x < f64::from(w) && local.y < f64::from(h);
            inside.then_some((axis, local))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn four_up_puts_the_3d_view_top_left_and_finds_the_pane_under_the_pointer() {
        let layout = FourUp::of((801, 600));
        assert_eq!(layout.view, [0, 0, 400, 300]);
        assert_eq!(layout.panes[2], [400, 300, 400, 300]);
        assert_eq!(layout.pane_at(DVec2::new(10.0, 10.0)), None);
        assert_eq!(layout.pane_at(DVec2::new(410.0, 20.0)), Some((SliceAxis::Axial, DVec2::new(10.0, 20.0))));
        assert_eq!(layout.pane_at(DVec2::new(5.0, 305.0)).map(|(a, _)| a), Some(SliceAxis::Coronal));
        assert_eq!(layout.pane_at(DVec2::new(799.0, 599.0)).map(|(a, _)| a), Some(SliceAxis::Sagittal));
    }
}
