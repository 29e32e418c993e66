//! Several volumes in one march (issue "several volumes"): the single-pass raycasters
//! (`raycast`, `raycast_compute`) classify each sample from the frame volume and, with `fusion`
//! set, a second volume sampled at the same patient-frame point — a segmentation over its scan, a
//! PET over a CT on another grid, a second channel — and combine them per sample, not as images
//! composited afterwards (wrong wherever semi-transparent volumes interleave). Label maps are
//! sampled without mixing label numbers (nearest, or each label's indicator interpolated) and
//! coloured through a `LabelTable` input. The model, in f64, is `volgraph_accel::fusion`; the
//! shader is `shaders/common/fusion.wgsl`, compiled in only when `fusion` is set.
//!
//! Leaping over the frame volume's empty space stays lossless where a sample's opacity is at
//! most the frame volume's (`tint`, `inside`); elsewhere a wired leap is refused.

use volgraph_accel::fusion::Combine;
use volgraph_compiler::declare::ParamChoice;
use volgraph_compiler::{Params, PortKind, PortSpec};
#[cfg(feature = "gpu")]
use volgraph_core::runtime::{CreateContext, PassError, RecordContext};

use crate::defines;
use crate::raycast_params::is_iso;

volgraph_compiler::param_choice! {
    /// What one sample of several volumes is (`volgraph_accel::fusion::Combine`).
    pub enum FusionMode {
        /// One volume.
        None = "none",
        /// The frame volume is a label map, coloured through `label_table`.
        Labels = "labels",
        /// The scan by its TF, coloured by the visible label of `second` (a label map).
        Tint = "tint",
        /// The scan by its TF, only inside the visible labels of `second`.
        Inside = "inside",
        /// Two scalar volumes, each by its TF, as two media in one place.
        Fuse = "fuse",
        /// Two scalar volumes (channels), colours added.
        Add = "add",
    }
}

volgraph_compiler::param_choice! {
    /// A label map over a fused pair (`volgraph_accel::fusion::Overlay`).
    pub enum OverlayMode {
        /// None.
        None = "none",
        /// The pair's sample coloured by the visible label of `overlay`.
        Tint = "tint",
        /// The pair's sample only inside the visible labels of `overlay`.
        Inside = "inside",
    }
}

volgraph_compiler::param_choice! {
    /// How a label map is sampled between voxel centres.
    pub enum LabelFilterChoice {
        /// Each label's indicator interpolated; the largest wins (round boundaries).
        Smooth = "smooth",
        /// The nearest voxel's label (voxel stairs).
        Nearest = "nearest",
    }
}

volgraph_compiler::pass_params! {
    /// The fusion of several volumes; a change rebuilds (ports and `#if`s change).
    pub struct FusionSettings {
        fusion: FusionMode = None,
            "none: one volume; labels: the volume is a label map coloured by `label_table`; tint: the scan by its TF, \
             coloured by the visible label of `second`; inside: the scan only inside the visible labels of `second`; \
             fuse: `second` by `second_tf` and the volume by `tf` as two media in one place; add: their colours added \
             (channels)";
        label_filter: LabelFilterChoice = Smooth,
            "smooth: each label's indicator interpolated, the largest wins (round boundaries); nearest: the nearest \
             voxel's label";
        channels: u32 = 2, 2..=4,
            "with fusion fuse or add, how many scalar volumes: the volume and `second`, then `third` and `fourth` \
             (a microscope's channels), each by its own TF (`second_tf`, `third_tf`, `fourth_tf`)";
        overlay: OverlayMode = None,
            "with fusion fuse or add, a third volume: the label map `overlay` (through `label_table`) over the pair — \
             tint: coloured by the visible label; inside: only inside the visible labels (PET/CT inside an organ)";
    }
}

impl FusionSettings {
    /// The settings of `params` (no fusion for a kind without the block, or in mode iso).
    pub fn of(params: &Params) -> Self {
        let settings = Self::try_from_params(params).unwrap_or(Self {
            fusion: FusionMode::None,
            label_filter: LabelFilterChoice::Smooth,
            channels: 2,
            overlay: OverlayMode::None,
        });
        if is_iso(params) { Self { fusion: FusionMode::None, ..settings } } else { settings }
    }

    /// The model's combination, `None` for one volume.
    pub fn combine(&self) -> Option<Combine> {
        Some(match self.fusion {
            FusionMode::None => return None,
            FusionMode::Labels => Combine::Labels,
            FusionMode::Tint => Combine::Tint,
            FusionMode::Inside => Combine::Inside,
            FusionMode::Fuse => Combine::Fuse,
            FusionMode::Add => Combine::Add,
        })
    }

    /// The label map over a fused pair, `Tint` or `Inside` (only with `fuse` and `add`).
    pub fn overlay(&self) -> Option<Combine> {
        match (self.combine()?, self.overlay) {
            (Combine::Fuse | Combine::Add, OverlayMode::Tint) => Some(Combine::Tint),
            (Combine::Fuse | Combine::Add, OverlayMode::Inside) => Some(Combine::Inside),
            _ => None,
        }
    }

    /// The scalar volumes beside the frame volume, by port and TF port (`fuse`, `add`).
    pub fn scalar_partners(&self) -> &'static [(&'static str, &'static str)] {
        const PARTNERS: [(&str, &str); 3] = [("second", "second_tf"), ("third", "third_tf"), ("fourth", "fourth_tf")];
        match self.combine() {
            Some(Combine::Fuse | Combine::Add) => &PARTNERS[..(self.channels.clamp(2, 4) - 1) as usize],
            _ => &[],
        }
    }

    /// Whether a label map is sampled (the frame volume, the second or the overlay).
    fn reads_labels(&self) -> bool {
        self.overlay().is_some() || self.combine().is_some_and(|c| !matches!(c, Combine::Fuse | Combine::Add))
    }

    /// The `#if` names: FUSION and what the volumes are.
    pub fn defines(&self) -> Vec<&'static str> {
        let Some(combine) = self.combine() else { return Vec::new() };
        let mut out = vec![defines::FUSION];
        out.push(match combine {
            Combine::Labels => defines::FUSION_LABELS,
            Combine::Tint | Combine::Inside => defines::FUSION_LABEL_MAP,
            Combine::Fuse | Combine::Add => defines::FUSION_SCALAR,
        });
        let partners = self.scalar_partners().len();
        if partners >= 2 {
            out.push(defines::FUSION_THIRD);
        }
        if partners >= 3 {
            out.push(defines::FUSION_FOURTH);
        }
        if self.overlay().is_some() {
            out.push(defines::FUSION_OVERLAY);
        }
        if self.reads_labels() {
            out.push(defines::FUSION_LABEL_READS);
            if self.label_filter == LabelFilterChoice::Nearest {
                out.push(defines::LABELS_NEAREST);
            }
        }
        out
    }

    /// The ports fusion adds: `second` (and `second_tf` for a scalar one), `label_table`, and
    /// `overlay` for a label map over a scalar pair.
    pub fn ports(&self) -> Vec<PortSpec> {
        let Some(combine) = self.combine() else { return Vec::new() };
        let mut ports = Vec::new();
        if let Combine::Tint | Combine::Inside = combine {
            ports.push(PortSpec::read("second", PortKind::Volume));
        }
        for (volume, tf) in self.scalar_partners() {
            ports.push(PortSpec::read(volume, PortKind::Volume));
            ports.push(PortSpec::read(tf, PortKind::TransferFunction));
        }
        if self.overlay().is_some() {
            ports.push(PortSpec::read("overlay", PortKind::Volume));
        }
        if self.reads_labels() {
            ports.push(PortSpec::read("label_table", PortKind::LabelTable));
        }
        ports
    }
}

/// `use` with the `fusion` uniform declared when `params` set fusion (the march's shader use).
pub fn with_fusion_uniform(use_: volgraph_compiler::ShaderUse, params: &Params) -> volgraph_compiler::ShaderUse {
    if FusionSettings::of(params).combine().is_some() { use_.uniform(FusionMap::layout()) } else { use_ }
}

/// The fusion block (a rebuild: ports and `#if`s).
pub fn fusion_block() -> volgraph_compiler::block::ParamBlock {
    FusionSettings::block(volgraph_compiler::block::OnChange::Rebuild).with_defines(|p| FusionSettings::of(p).defines())
}

volgraph_compiler::pass_params! {
    /// The `fusion` uniform of `shaders/common/fusion.wgsl`, computed from the bound volumes each
    /// frame ([`FusionMap::of_volumes`]).
    pub struct FusionMap {
        second_scale: [f32; 4] = computed, "xyz: the second volume's texture point is u · scale + offset.";
        second_offset: [f32; 4] = computed, "xyz: see second_scale.";
        first_labels: [f32; 4] = computed, "x, y: a label of the frame volume is round(x + texel · y).";
        second_labels: [f32; 4] = computed, "x, y: a label of the second volume is round(x + texel · y).";
        third_scale: [f32; 4] = computed, "xyz: the third volume's texture point is u · scale + offset.";
        third_offset: [f32; 4] = computed, "xyz: see third_scale.";
        fourth_scale: [f32; 4] = computed, "xyz: the fourth volume's texture point is u · scale + offset.";
        fourth_offset: [f32; 4] = computed, "xyz: see fourth_scale.";
        march_lo: [f32; 4] = computed, "xyz: the box rays cross, in the volume's texture space (fusion::march_box).";
        march_hi: [f32; 4] = computed, "xyz: see march_lo.";
        overlay_scale: [f32; 4] = computed, "xyz: the overlay's texture point is u · scale + offset.";
        overlay_offset: [f32; 4] = computed, "xyz: see overlay_scale.";
        overlay_labels: [f32; 4] = computed, "x, y: a label of the overlay is round(x + texel · y).";
        combine: u32 = computed, "1 labels, 2 tint, 3 inside, 4 fuse, 5 add.";
        overlay_combine: u32 = computed, "0 none, 2 tint, 3 inside.";
        label_block: u32 = computed, "The edge in voxels of the label map's blocks in label_cubes (volgraph_accel::labels::cubes::LABEL_BLOCK).";
    }
}

impl FusionMap {
    /// The block as the march's shader use declares it (bound as `fusion`); the node writes it.
    pub fn layout() -> volgraph_compiler::UniformLayout {
        Self::bound_as_with("fusion", Vec::new(), |_| Self::identity(Combine::Labels).uniform_bytes())
    }

    fn identity(combine: Combine) -> Self {
        Self {
            second_scale: [1.0; 4],
            second_offset: [0.0; 4],
            first_labels: [0.0, 255.0, 0.0, 0.0],
            second_labels: [0.0, 255.0, 0.0, 0.0],
            third_scale: [1.0; 4],
            third_offset: [0.0; 4],
            fourth_scale: [1.0; 4],
            fourth_offset: [0.0; 4],
            march_lo: [0.0; 4],
            march_hi: [1.0; 4],
            overlay_scale: [1.0; 4],
            overlay_offset: [0.0; 4],
            overlay_labels: [0.0, 255.0, 0.0, 0.0],
            combine: combine as u32 + 1,
            overlay_combine: 0,
            label_block: volgraph_accel::labels::cubes::LABEL_BLOCK,
        }
    }

    /// From the frame volume `first`, the `second` (when there is one), the `more` scalar
    /// volumes (a third and fourth channel) and the label map over them with what it does (when
    /// there is one).
    pub fn of_volumes(
        combine: Combine,
        first: &volgraph_accel::volume::Volume,
        second: Option<&volgraph_accel::volume::Volume>,
        more: &[&volgraph_accel::volume::Volume],
        overlay: Option<(Combine, &volgraph_accel::volume::Volume)>,
    ) -> Result<Self, volgraph_accel::fusion::FrameMismatch> {
        // A texel holds (v - lo) / (hi - lo) (`Volume::normalized`), so v = lo + texel · (hi - lo).
        let decode = |v: &volgraph_accel::volume::Volume| {
            let (lo, hi) = v.value_range;
            [lo as f32, (hi - lo) as f32, 0.0, 0.0]
        };
        // A texture map as the uniform's (scale, offset) pair.
        let uniform = |m: volgraph_accel::fusion::TextureMap| {
            (m.scale.as_vec3().extend(0.0).to_array(), m.offset.as_vec3().extend(0.0).to_array())
        };
        let between = |v: &volgraph_accel::volume::Volume| volgraph_accel::fusion::TextureMap::between(first, v);
        let mut map = Self { first_labels: decode(first), ..Self::identity(combine) };
        let second_map = second.map(between).transpose()?;
        let more_maps = more.iter().map(|v| between(v)).collect::<Result<Vec<_>, _>>()?;
        if let (Some(second), Some(m)) = (second, second_map) {
            (map.second_scale, map.second_offset) = uniform(m);
            map.second_labels = decode(second);
        }
        if let Some(&m) = more_maps.first() {
            (map.third_scale, map.third_offset) = uniform(m);
        }
        if let Some(&m) = more_maps.get(1) {
            (map.fourth_scale, map.fourth_offset) = uniform(m);
        }
        let (lo, hi) = volgraph_accel::fusion::march_box(combine, second_map.into_iter().chain(more_maps));
        (map.march_lo, map.march_hi) = (lo.as_vec3().extend(0.0).to_array(), hi.as_vec3().extend(0.0).to_array());
        if let Some((what, labels)) = overlay {
            (map.overlay_scale, map.overlay_offset) = uniform(between(labels)?);
            map.overlay_labels = decode(labels);
            map.overlay_combine = what as u32 + 1;
        }
        Ok(map)
    }
}

#[cfg(feature = "gpu")]
/// What a raycaster node keeps for fusion: the `fusion` uniform, written when a bound volume
/// changes.
pub struct FusionState {
    combine: Option<Combine>,
    /// The ports of the scalar volumes past the second (`third`, `fourth`).
    more: Vec<&'static str>,
    overlay: Option<Combine>,
    buffer: Option<wgpu::Buffer>,
    versions: Option<Vec<Option<u64>>>,
    /// What is made from the label map on the CPU, and the version of the map it was made from.
    derived: Option<(LabelMapTextures, Option<u64>)>,
    smooth: bool,
}

#[cfg(feature = "gpu")]
impl FusionState {
    /// From the node's parameters; a leap over the frame volume's empty space is refused where
    /// the combination can be visible where the frame volume is empty.
    pub fn new(ctx: &CreateContext<'_>) -> Result<Self, PassError> {
        let combine = FusionSettings::of(ctx.params).combine();
        let wired = ctx.wired();
        if let Some(c) = combine
            && !c.bounded_by_first()
            && (wired.contains(&"empty") || wired.contains(&"distance"))
        {
            return Err(PassError {
                pass: ctx.pass_id.to_string(),
                message: format!(
                    "fusion \"{}\" can be visible where the volume is empty, so leaping over the volume's empty \
                     space would lose it; unwire \"empty\"/\"distance\" (tint and inside leap losslessly)",
                    FusionSettings::of(ctx.params).fusion.name()
                ),
            });
        }
        let settings = FusionSettings::of(ctx.params);
        if settings.overlay != OverlayMode::None && settings.overlay().is_none() {
            return Err(PassError {
                pass: ctx.pass_id.to_string(),
                message: format!(
                    "overlay \"{}\" lies a label map over two fused scalar volumes, so it needs fusion \"fuse\" or \
                     \"add\" (here \"{}\"); for one scan and its label map use fusion \"tint\" or \"inside\"",
                    settings.overlay.name(),
                    settings.fusion.name()
                ),
            });
        }
        if settings.channels != 2 && settings.scalar_partners().is_empty() {
            return Err(PassError {
                pass: ctx.pass_id.to_string(),
                message: format!(
                    "channels {} are scalar volumes fused with the volume, so it needs fusion \"fuse\" or \"add\" \
                     (here \"{}\"); leave channels at 2 otherwise",
                    settings.channels,
                    settings.fusion.name()
                ),
            });
        }
        // Pre-integration integrates a TF between two samples of a field: the scan's segment is
        // tinted or masked by a label map (its opacity stays the scan's), several scalar media
        // each integrate their own; label numbers have no segment between two of them.
        if combine == Some(Combine::Labels) && crate::effects::EffectFlags::of(ctx.params).preintegration {
            return Err(PassError {
                pass: ctx.pass_id.to_string(),
                message: "preintegration integrates a transfer function between two samples of a field, and fusion \
                          \"labels\" shows label numbers, which no segment lies between: turn preintegration off here \
                          (or use fusion \"tint\" or \"inside\" to pre-integrate a scan coloured or masked by its labels)"
                    .to_string(),
            });
        }
        let buffer = combine.map(|c| ctx.uniform_from_bytes("fusion", &FusionMap::identity(c).uniform_bytes()));
        let smooth = settings.label_filter == LabelFilterChoice::Smooth;
        let more = settings.scalar_partners().iter().skip(1).map(|(port, _)| *port).collect();
        Ok(Self { combine, more, overlay: settings.overlay(), buffer, versions: None, derived: None, smooth })
    }

    /// [`Self::new`] for a raycaster whose empty-space skipping reads the frame volume alone
    /// (`skipping`: what skips, for the message): only a fusion never more opaque than the scan
    /// (`tint`, `inside`) is drawn right there; the others are refused by name.
    pub fn bounded_by_the_scan(ctx: &CreateContext<'_>, kind: &str, skipping: &str) -> Result<Self, PassError> {
        let settings = FusionSettings::of(ctx.params);
        if let Some(combine) = settings.combine()
            && !combine.bounded_by_first()
        {
            return Err(PassError {
                pass: ctx.pass_id.to_string(),
                message: format!(
                    "fusion \"{}\" is not drawn by {} ({skipping} the volume alone): use fusion \"tint\" or \"inside\" \
                     here, or raycast_compute (graphs/multi/) for \"{0}\"",
                    settings.fusion.name(),
                    kind
                ),
            });
        }
        Self::new(ctx)
    }

    /// The port of the label map the march reads, if any.
    fn label_map_port(&self) -> Option<&'static str> {
        match self.combine? {
            Combine::Labels => Some("volume"),
            Combine::Tint | Combine::Inside => Some("second"),
            Combine::Fuse | Combine::Add => self.overlay.map(|_| "overlay"),
        }
    }

    /// Makes the textures derived from the label map on `port` when it changed (none for
    /// nearest sampling on a device without subgroups: the map alone is read).
    fn update_label_map(&mut self, ctx: &RecordContext<'_>, port: &str) -> Result<(), PassError> {
        if !self.smooth && !ctx.gpu.subgroups {
            return Ok(());
        }
        let version = ctx.input_version(port);
        if self.derived.as_ref().is_some_and(|(_, v)| *v == version) {
            return Ok(());
        }
        let map = ctx.voxels(port)?;
        let textures = LabelMapTextures::of(ctx, map, self.smooth)
            .map_err(|e| PassError { pass: ctx.label.to_string(), message: e.to_string() })?;
        self.derived = Some((textures, version));
        Ok(())
    }

    /// Writes the uniform when the bound volumes changed.
    pub fn update(&mut self, ctx: &RecordContext<'_>) -> Result<(), PassError> {
        if let Some(port) = self.label_map_port() {
            self.update_label_map(ctx, port)?;
        }
        let (Some(combine), Some(buffer)) = (self.combine, &self.buffer) else { return Ok(()) };
        let versions: Vec<Option<u64>> = ["volume", "second", "overlay"]
            .iter()
            .chain(self.more.iter())
            .map(|port| ctx.input_version(port))
            .collect();
        if self.versions.as_ref() == Some(&versions) {
            return Ok(());
        }
        let first = ctx.voxels("volume")?;
        let second = if combine == Combine::Labels { None } else { Some(ctx.voxels("second")?) };
        let more = self.more.iter().map(|port| ctx.voxels(port)).collect::<Result<Vec<_>, _>>()?;
        let more: Vec<&volgraph_accel::volume::Volume> = more.iter().map(|v| v.as_ref()).collect();
        let overlay = match self.overlay {
            Some(what) => Some((what, ctx.voxels("overlay")?)),
            None => None,
        };
        let map = FusionMap::of_volumes(
            combine,
            first,
            second.as_ref().map(|v| v.as_ref()),
            &more,
            overlay.as_ref().map(|(what, v)| (*what, v.as_ref())),
        )
        .map_err(|e| PassError { pass: ctx.label.to_string(), message: e.to_string() })?;
        ctx.write_buffer(buffer, 0, &map.uniform_bytes());
        self.versions = Some(versions);
        Ok(())
    }

    /// The `fusion` binding.
    pub fn bindings(&self) -> Vec<(&'static str, wgpu::BindingResource<'_>)> {
        let derived = self.derived.iter().flat_map(|(textures, _)| textures.bindings());
        self.buffer.iter().map(|b| ("fusion", b.as_entire_binding())).chain(derived).collect()
    }
}

#[cfg(feature = "gpu")]
/// The textures a march reads a label map through besides the map itself, made from it on the
/// CPU: its blocks of one label (`label_cubes`, on a device with subgroups: stretches of samples
/// read nothing there) and, for smooth sampling, its 2 × 2 quads (`label_quads`: a sample's 8
/// corners in two reads).
struct LabelMapTextures {
    cubes: Option<wgpu::TextureView>,
    quads: Option<wgpu::TextureView>,
}

#[cfg(feature = "gpu")]
impl LabelMapTextures {
    fn of(
        ctx: &RecordContext<'_>,
        map: &volgraph_accel::volume::Volume,
        smooth: bool,
    ) -> Result<Self, volgraph_core::runtime::GpuFault> {
        use volgraph_core::runtime::upload::{upload_label_cubes, upload_label_quads};
        let view = |t: wgpu::Texture| t.create_view(&wgpu::TextureViewDescriptor::default());
        // Read only where subgroups let a march leave a stretch together (label_cubes.wgsl).
        let cubes = if ctx.gpu.subgroups {
            let cubes = volgraph_accel::labels::cubes::LabelCubes::of(map);
            Some(view(upload_label_cubes(ctx.gpu, "label_cubes", &cubes)?))
        } else {
            None
        };
        let quads = if smooth {
            let quads = volgraph_accel::labels::sample::label_quads(map);
            Some(view(upload_label_quads(ctx.gpu, "label_quads", map.dims.to_array(), &quads)?))
        } else {
            None
        };
        Ok(Self { cubes, quads })
    }

    fn bindings(&self) -> impl Iterator<Item = (&'static str, wgpu::BindingResource<'_>)> {
        let cubes = self.cubes.iter().map(|c| ("label_cubes", wgpu::BindingResource::TextureView(c)));
        cubes.chain(self.quads.iter().map(|q| ("label_quads", wgpu::BindingResource::TextureView(q))))
    }
}
