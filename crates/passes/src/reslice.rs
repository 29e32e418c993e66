//! `reslice`: multi-planar reformatting — an axial, coronal or sagittal slice of the volume
//! resampled into a pane (the target's size) and mapped to grey through a window in data units
//! (HU for CT), as the clinical viewers show beside their 3D view. The slice keeps its physical
//! aspect, centred in the pane; pixels beside it are transparent black. Orientation, fit and
//! window are `volgraph_accel::reslice`'s, the f64 twin this pass is tested against
//! (`crates/passes/tests/reslice.rs`). Any graph may use it; `graphs/clinical/slices.ron` is the
//! viewer's three panes. Shader: `shaders/reslice.wgsl`.

use volgraph_accel::reslice::SliceAxis;
use volgraph_compiler::block::{OnChange, ParamBlock};
use volgraph_compiler::{Params, PassDecl, PortKind, PortSpec, ShaderUse, TargetFormat};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{ComputePassPipeline, ComputePipelineSpec, CreateContext, Gpu, PassError, RecordContext};
#[cfg(feature = "gpu")]
use volgraph_core::{PassNode, PassPlugin};

/// The plugin.
pub struct Reslice;

volgraph_compiler::param_choice! {
    /// Which plane (`volgraph_accel::reslice::SliceAxis`).
    pub enum PlaneChoice {
        /// Normal to z (superior–inferior), seen from the feet.
        Axial = "axial",
        /// Normal to y (anterior–posterior), seen from the front.
        Coronal = "coronal",
        /// Normal to x (left–right), seen from the patient's left.
        Sagittal = "sagittal",
    }
}

impl PlaneChoice {
    /// The model's axis.
    pub fn axis(self) -> SliceAxis {
        match self {
            PlaneChoice::Axial => SliceAxis::Axial,
            PlaneChoice::Coronal => SliceAxis::Coronal,
            PlaneChoice::Sagittal => SliceAxis::Sagittal,
        }
    }
}

volgraph_compiler::pass_params! {
    /// The slice and its window, in the units a user thinks in.
    pub struct ResliceSettings {
        plane: PlaneChoice = Axial,
            "axial: normal to z, seen from the feet (the patient's right on the left, anterior up); coronal: normal to \
             y, seen from the front; sagittal: normal to x, anterior on the left";
        position: f32 = 0.5, 0.0..=1.0,
            "where the plane cuts the volume along its normal: 0 at the first face, 1 at the last (voxel k's centre at \
             (k + 0.5) / n)";
        window_center: f32 = 0.0, -1000000000.0..=1000000000.0,
            "the window's centre in data units (HU for CT): black at center − width/2, white at center + width/2";
        window_width: f32 = 0.0, 0.0..=1000000000.0,
            "the window's width in data units; 0: the file's window (DICOM WindowCenter/Width, NIfTI cal_min/cal_max), \
             else the whole value range";
        label_opacity: f32 = 0.5, 0.0..=1.0,
            "with labels: how strongly a label's colour covers the grey (times its opacity in the table)";
    }
}

volgraph_compiler::pass_params! {
    /// Whether a label map lies over the slice; a change rebuilds (ports and `#if`s change).
    pub struct ResliceLabels {
        labels: bool = false,
            "overlay the label map `labels` (the volume's patient frame, any grid of it) coloured by `label_table`: \
             each pixel the nearest voxel's label";
    }
}

volgraph_compiler::pass_params! {
    /// The `slice_map` uniform of `shaders/reslice.wgsl`: the pane-to-texture map and the window,
    /// computed by the node from the bound volume ([`SliceMap::of`]).
    pub struct SliceMap {
        origin: [f32; 4] = computed, "xyz: the texture point at pixel (0, 0) of the pane (its corner).";
        per_column: [f32; 4] = computed, "xyz: the texture point's change per pixel to the right.";
        per_row: [f32; 4] = computed, "xyz: the texture point's change per pixel down.";
        fit: [f32; 4] = computed, "the slice's rectangle in the pane, pixels: x0, y0, x1, y1.";
        window: [f32; 4] = computed, "x: the normalized value shown black; y: 1 / (white − black).";
        label_scale: [f32; 4] = computed, "xyz: the label map's texture point is u · scale + offset.";
        label_offset: [f32; 4] = computed, "xyz: see label_scale.";
        label_decode: [f32; 4] = computed, "x, y: a label is round(x + texel · y); z: the labels' cover.";
    }
}

impl SliceMap {
    /// The block as the shader declares it (bound as `slice_map`); the node writes it.
    pub fn layout() -> volgraph_compiler::UniformLayout {
        Self::bound_as_with("slice_map", Vec::new(), |_| Self::zeroed().uniform_bytes())
    }

    fn zeroed() -> Self {
        Self {
            origin: [0.0; 4],
            per_column: [0.0; 4],
            per_row: [0.0; 4],
            fit: [0.0; 4],
            window: [0.0, 1.0, 0.0, 0.0],
            label_scale: [1.0; 4],
            label_offset: [0.0; 4],
            label_decode: [0.0, 255.0, 0.0, 0.0],
        }
    }

    /// The map of `settings` for `volume` in a pane of `pane` pixels: the same fit, orientation
    /// and window as `volgraph_accel::reslice`, as an affine map of the pixel.
    pub fn of(settings: &ResliceSettings, volume: &volgraph_accel::volume::Volume, pane: (u32, u32)) -> Self {
        use glam::{DVec2, DVec3};
        use volgraph_accel::reslice::{NormalizedWindow, PaneFit, SlicePlane, default_window};
        let axis = settings.plane.axis();
        let fit = PaneFit::of(axis, volume.dims, volume.spacing, pane);
        let plane = SlicePlane { axis, position: f64::from(settings.position) };
        // The map is affine: its value at three pane points gives it (the shader tests `fit`
        // before using it).
        let at = |p: DVec2| plane.extended_point(&fit, p);
        let origin = at(DVec2::ZERO);
        let per_column = at(DVec2::X) - origin;
        let per_row = at(DVec2::Y) - origin;
        let window = match settings.window_width {
            w if w > 0.0 => {
                volgraph_accel::volume_meta::Window { center: f64::from(settings.window_center), width: f64::from(w) }
            }
            _ => default_window(volume),
        };
        let window = NormalizedWindow::of(window, volume);
        let v4 = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32, 0.0];
        let end = fit.origin + fit.size;
        Self {
            origin: v4(origin),
            per_column: v4(per_column),
            per_row: v4(per_row),
            fit: [fit.origin.x as f32, fit.origin.y as f32, end.x as f32, end.y as f32],
            window: [window.low as f32, (1.0 / (window.high - window.low)) as f32, 0.0, 0.0],
            ..Self::zeroed()
        }
    }

    /// With `labels` over the slice: where the map's texture point of `volume`'s lies and how
    /// its texels decode to label values (`volgraph_accel::reslice::LabelOverlay`).
    pub fn with_labels(
        self,
        settings: &ResliceSettings,
        volume: &volgraph_accel::volume::Volume,
        labels: &volgraph_accel::volume::Volume,
    ) -> Result<Self, volgraph_accel::fusion::FrameMismatch> {
        let m = volgraph_accel::fusion::TextureMap::between(volume, labels)?;
        // A texel holds (v − lo) / (hi − lo) (`Volume::normalized`), so v = lo + texel · (hi − lo).
        let (lo, hi) = labels.value_range;
        Ok(Self {
            label_scale: [m.scale.x as f32, m.scale.y as f32, m.scale.z as f32, 0.0],
            label_offset: [m.offset.x as f32, m.offset.y as f32, m.offset.z as f32, 0.0],
            label_decode: [lo as f32, (hi - lo) as f32, settings.label_opacity, 0.0],
            ..self
        })
    }
}

/// Whether the pass lays a label map over its slice.
fn labelled(params: &Params) -> bool {
    ResliceLabels::try_from_params(params).is_some_and(|l| l.labels)
}

/// Its one pipeline, declared once.
fn shader() -> ShaderUse {
    ShaderUse::new("reslice.wgsl", "cs_reslice").uniform(SliceMap::layout())
}

impl PassDecl for Reslice {
    fn kind(&self) -> &'static str {
        "reslice"
    }

    fn summary(&self) -> &'static str {
        "an axial, coronal or sagittal slice resampled into a pane through a window in data units (multi-planar \
         reformatting, as clinical viewers show it)"
    }

    fn blocks(&self) -> Vec<ParamBlock> {
        // Every value goes into the uniform the node computes: an edit is written in place.
        vec![
            ResliceSettings::block(OnChange::InPlace),
            ResliceLabels::block(OnChange::Rebuild)
                .with_defines(|p| if labelled(p) { vec![crate::defines::RESLICE_LABELS] } else { Vec::new() }),
        ]
    }

    fn ports(&self, params: &Params) -> Vec<PortSpec> {
        let mut ports = vec![
            PortSpec::read("volume", PortKind::Volume),
            PortSpec::write("slice", PortKind::target(&[TargetFormat::Rgba8Unorm])),
        ];
        if labelled(params) {
            ports.push(PortSpec::read("labels", PortKind::Volume));
            ports.push(PortSpec::read("label_table", PortKind::LabelTable));
        }
        ports
    }

    fn shaders(&self, _params: &Params) -> Vec<ShaderUse> {
        vec![shader()]
    }
}

#[cfg(feature = "gpu")]
impl PassPlugin for Reslice {
    fn create(&self, ctx: &CreateContext<'_>) -> Result<Box<dyn PassNode>, PassError> {
        let pipeline = ctx.compute_pipeline(&ComputePipelineSpec {
            defines: &self.shader_defines(ctx.params),
            ..ComputePipelineSpec::of(&shader())
        })?;
        let buffer = ctx.uniform_from_bytes("slice_map", &SliceMap::zeroed().uniform_bytes());
        Ok(Box::new(ResliceNode {
            pipeline,
            buffer,
            settings: ResliceSettings::from_params(ctx.params),
            labelled: labelled(ctx.params),
            written: None,
        }))
    }
}

#[cfg(feature = "gpu")]
struct ResliceNode {
    pipeline: ComputePassPipeline,
    buffer: wgpu::Buffer,
    settings: ResliceSettings,
    labelled: bool,
    /// What the uniform holds: the map, and the versions of the volume and label map and the
    /// pane it was computed for.
    written: Option<(Vec<u8>, [Option<u64>; 2], (u32, u32))>,
}

#[cfg(feature = "gpu")]
impl PassNode for ResliceNode {
    fn record(&mut self, ctx: &mut RecordContext<'_>) -> Result<(), PassError> {
        let pane = ctx.extent("slice");
        let versions = [ctx.input_version("volume"), self.labelled.then(|| ctx.input_version("labels")).flatten()];
        let stale = self.written.as_ref().is_none_or(|(_, v, p)| *v != versions || *p != pane);
        if stale {
            let volume = ctx.voxels("volume")?;
            let mut map = SliceMap::of(&self.settings, volume, pane);
            if self.labelled {
                let labels = ctx.voxels("labels")?;
                map = map
                    .with_labels(&self.settings, volume, labels)
                    .map_err(|e| PassError { pass: ctx.label.to_string(), message: e.to_string() })?;
            }
            let bytes = map.uniform_bytes();
            ctx.write_buffer(&self.buffer, 0, &bytes);
            self.written = Some((bytes, versions, pane));
        }
        ctx.dispatch_over(&self.pipeline, &[("slice_map", self.buffer.as_entire_binding())], "slice", (8, 8))
    }

    fn update_params(&mut self, _gpu: &Gpu, params: &Params) {
        // Recomputed from the bound volume at the next record.
        self.settings = ResliceSettings::from_params(params);
        self.written = None;
    }
}
