//! The per-frame contract between the application, the runtime and the passes: the viewport,
//! this frame's and the previous frame's camera, the frame counters and the bound volume's
//! description. The application gives the camera; the runtime fills in the rest and uploads it
//! as the `frame` uniform block every pass may bind (`shaders/common/frame.wgsl`).

use glam::{DMat4, DVec3, UVec3};
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::cuts::{Cuts, MAX_CLIP_PLANES};
use volgraph_accel::volume::Volume;

use super::footprint::{Coverage, FAN_VERTICES, Footprint};

/// One frame's camera, as both the GPU passes and the f64 reference use it
/// (`docs/rendering_model.md`, "Camera").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraData {
    /// World → clip.
    pub clip_from_world: DMat4,
    /// Clip → world.
    pub world_from_clip: DMat4,
    /// Eye position (world).
    pub eye: DVec3,
    /// Unit forward direction (world).
    pub forward: DVec3,
    /// Near-plane distance.
    pub near: f64,
}

impl CameraData {
    /// The camera data of an orbit camera for a `viewport`.
    pub fn from_orbit(camera: &OrbitCamera, viewport: (u32, u32)) -> Self {
        let f = camera.frame(viewport.0, viewport.1);
        Self {
            clip_from_world: f.clip_from_world,
            world_from_clip: f.world_from_clip,
            eye: f.eye,
            forward: f.forward,
            near: camera.near,
        }
    }
}

impl CameraData {
    /// The same camera in a world moved by `offset` (every point p becomes p + offset): what a
    /// process holding a window of the volume sees, its box centred at its own origin.
    pub fn translated(&self, offset: DVec3) -> Self {
        let moved_from = DMat4::from_translation(-offset);
        Self {
            clip_from_world: self.clip_from_world * moved_from,
            world_from_clip: DMat4::from_translation(offset) * self.world_from_clip,
            eye: self.eye + offset,
            ..*self
        }
    }
}

/// What the frame contract knows of the bound volume.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeDesc {
    /// Voxels per axis.
    pub dims: UVec3,
    /// Half size of the volume box in world units (longest side 1).
    pub half_extent: DVec3,
    /// World length of the smallest voxel side: the unit of `step_voxels`.
    pub unit_step: f64,
    /// The transfer function's opacity is per this many voxel units of distance (the scene's
    /// opacity reference length): 1 for "per voxel", `1 / unit_step` for "per world unit".
    pub opacity_unit_voxels: f64,
    /// Where the bound voxels sit in a larger volume ([`VolumeWindow`]); `None` for a whole
    /// volume.
    pub window: Option<WindowBoxes>,
}

/// The bound voxels are a sub-box of a larger volume: sort-last rendering (`docs/scaling.md`),
/// where each process holds its box of the volume plus the apron its filters reach into.
/// Voxel coordinates of the whole volume; boxes are half-open `[lo, hi)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VolumeWindow {
    /// The whole volume's voxels per axis.
    pub whole_dims: UVec3,
    /// The whole volume's voxel spacing per axis (its world size follows from it).
    pub whole_spacing: [u64; 3],
    /// The first voxel the bound texture holds (its dims are the bound volume's).
    pub origin: UVec3,
    /// The box whose samples this process takes: every sample of a ray belongs to exactly one
    /// process's box, so the images composite to the single-process one.
    pub own_lo: UVec3,
    /// See `own_lo`.
    pub own_hi: UVec3,
}

impl VolumeWindow {
    /// The whole volume's spacing.
    pub fn spacing(&self) -> DVec3 {
        DVec3::from_array(self.whole_spacing.map(f64::from_bits))
    }

    /// A window over `whole_dims` voxels of `spacing`.
    pub fn new(whole_dims: UVec3, spacing: DVec3, origin: UVec3, own_lo: UVec3, own_hi: UVec3) -> Self {
        Self { whole_dims, whole_spacing: spacing.to_array().map(f64::to_bits), origin, own_lo, own_hi }
    }
}

/// A window's boxes in the bound texture's coordinates (`[0,1]³` is the bound texture) and the
/// world offset of the bound box's centre from the whole volume's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WindowBoxes {
    /// The whole volume's box: rays are met with it, so every process's samples lie on the
    /// step grid of the single-process march.
    pub grid: (DVec3, DVec3),
    /// The box whose samples this process takes.
    pub own: (DVec3, DVec3),
    /// World position of the bound box's centre in the whole volume's world (whose centre is
    /// the origin); cameras are moved by minus this.
    pub centre_world: DVec3,
}

/// What a transfer function's opacity is per (a scene setting).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum OpacityReference {
    /// Per voxel of distance (the smallest voxel side): the default, independent of the volume's
    /// world size.
    #[default]
    Voxel,
    /// Per world unit (the volume's longest side is 1): the look stays the same when the
    /// resolution changes.
    World,
}

impl VolumeDesc {
    /// The description of `volume`, opacity per voxel.
    pub fn of(volume: &Volume) -> Self {
        Self {
            dims: volume.dims,
            half_extent: volume.half_extent_world(),
            unit_step: volume.unit_step_world(),
            opacity_unit_voxels: 1.0,
            window: None,
        }
    }

    /// The description of a volume of `dims` voxels of `spacing` that is not in memory (a
    /// pyramid streamed brick by brick), as [`VolumeDesc::of`] gives it for one that is.
    pub fn of_box(dims: UVec3, spacing: DVec3) -> Self {
        let extent = dims.as_dvec3() * spacing;
        let longest = extent.max_element();
        Self {
            dims,
            half_extent: extent / (2.0 * longest),
            unit_step: (spacing / longest).min_element(),
            opacity_unit_voxels: 1.0,
            window: None,
        }
    }

    /// The description of `dims` bound voxels that are `window` of a larger volume: world sizes
    /// are the whole volume's (its longest side 1), the boxes are in the bound texture's
    /// coordinates.
    pub fn of_window(dims: UVec3, window: &VolumeWindow) -> Self {
        let whole = window.whole_dims.as_dvec3();
        let extent = whole * window.spacing();
        let scale = 1.0 / extent.max_element();
        let whole_half = extent * scale / 2.0;
        let voxel_world = window.spacing() * scale;
        let n = dims.as_dvec3().max(DVec3::ONE);
        let origin = window.origin.as_dvec3();
        let local = |v: DVec3| (v - origin) / n;
        let centre = (origin + 0.5 * dims.as_dvec3()) * voxel_world - whole_half;
        Self {
            dims,
            half_extent: dims.as_dvec3() * voxel_world / 2.0,
            unit_step: voxel_world.min_element(),
            opacity_unit_voxels: 1.0,
            window: Some(WindowBoxes {
                grid: (local(DVec3::ZERO), local(whole)),
                own: (local(window.own_lo.as_dvec3()), local(window.own_hi.as_dvec3())),
                centre_world: centre,
            }),
        }
    }

    /// The same volume with opacity per `reference`.
    pub fn with_opacity_reference(self, reference: OpacityReference) -> Self {
        let opacity_unit_voxels = match reference {
            OpacityReference::Voxel => 1.0,
            OpacityReference::World if self.unit_step > 0.0 => 1.0 / self.unit_step,
            OpacityReference::World => 1.0,
        };
        Self { opacity_unit_voxels, ..self }
    }

    /// The box diagonal in unit steps: the longest ray through the volume, in voxels. Graphs read
    /// it as the scene value [`LONGEST_RAY_VOXELS`] (K of Krüger & Westermann 2003 §3 is this
    /// over the step); 0 for a degenerate volume.
    pub fn longest_ray_voxels(&self) -> f64 {
        // A window's rays cross the whole volume's box.
        let box_size = self.window.map_or(DVec3::ONE, |w| w.grid.1 - w.grid.0);
        let k = 2.0 * (self.half_extent * box_size).length() / self.unit_step;
        if k.is_finite() && k > 0.0 { k } else { 0.0 }
    }
}

/// The scene value every graph may read for the bound volume: its box diagonal in voxels.
pub const LONGEST_RAY_VOXELS: &str = "longest_ray_voxels";

/// The scene value a graph's `block_size` input takes when the user sets none: the edge, in
/// voxels, of the empty-space blocks (Krüger & Westermann 2003 §2.3) for the bound volume
/// ([`VolumeDesc::block_size`]).
pub const BLOCK_SIZE: &str = "block_size";

impl VolumeDesc {
    /// The empty-space block edge for this volume: the smallest of 2, 3 and 4 voxels whose grid
    /// has at most 64 blocks along the longest axis (2 up to 128 voxels, 4 from 193 on). Finer
    /// blocks leave fewer invisible samples in the blocks a ray marches through (hydrogen 128³:
    /// 16.6 samples per pixel at 2 against 19.0 at 4, 7 % less time on llvmpipe:
    /// bench/one-march-final.md), but the grid is rebuilt after every transfer-function edit,
    /// and 64³ blocks is what the viewer's edit-to-frame goal was measured with
    /// (bench/workbench.md, the engine at 4); coarser than 4 loses on every peer dataset
    /// (bench/peer-ablation.md).
    pub fn block_size(&self) -> f64 {
        let longest = self.dims.max_element().max(1);
        f64::from(longest.div_ceil(64).clamp(2, 4))
    }
}

/// The scene values a volume gives graphs ([`CompileOptions::scene`](crate::CompileOptions)):
/// computed here and nowhere else. A Scalar graph input takes the scene value of its name when
/// the user sets none ([`LONGEST_RAY_VOXELS`] for repeat counts, [`BLOCK_SIZE`]).
pub fn scene_values_of(volume: &VolumeDesc) -> std::collections::BTreeMap<String, f64> {
    std::collections::BTreeMap::from([
        (LONGEST_RAY_VOXELS.to_string(), volume.longest_ray_voxels()),
        (BLOCK_SIZE.to_string(), volume.block_size()),
    ])
}

/// Everything a pass may know about the frame it records.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameData {
    /// Viewport in pixels.
    pub viewport: (u32, u32),
    /// This frame's camera.
    pub camera: CameraData,
    /// The previous frame's camera (`None` on the first frame and after history invalidation):
    /// what Klein et al. 2005 reproject last frame's hits with.
    pub previous_camera: Option<CameraData>,
    /// Frames the runtime has submitted before this one.
    pub frame_index: u64,
    /// Frames since history was last invalidated: 0 when history holds initial values.
    pub history_age: u64,
    /// The bound volume, if any.
    pub volume: Option<VolumeDesc>,
    /// GPU memory a pass that streams data may hold (`--gpu-memory-mb`), in bytes; `None`: as
    /// much as the adapter allows.
    pub gpu_memory_budget: Option<u64>,
    /// The scene's crop box and clip planes (volume fractions of the whole volume).
    pub cuts: Cuts,
    /// The scene's lights (`volgraph_accel::light`).
    pub lights: volgraph_accel::light::Lights,
    /// Whether the scene has an environment map (bound as `environment_map`).
    pub environment: bool,
}

/// The pixel rays of a camera in texture space: pixel centre (x, y) (pixels, row 0 at the top)
/// looks along `base + x·dx + y·dy` from the eye, with the world direction scaled to advance one
/// unit along the camera's forward axis per unit of the ray parameter. Affine in the pixel
/// because every point of the near plane has the same clip w.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelRays {
    /// The ray of pixel centre (0, 0) — the corner, not a pixel centre.
    pub base: DVec3,
    /// Change per pixel in x.
    pub dx: DVec3,
    /// Change per pixel in y.
    pub dy: DVec3,
}

impl PixelRays {
    /// The rays of `camera` at `viewport` for a volume box of half size `half`.
    pub fn of(camera: &CameraData, viewport: (u32, u32), half: DVec3) -> Self {
        let (w, h) = (viewport.0.max(1) as f64, viewport.1.max(1) as f64);
        // The world direction through pixel centre (x, y), scaled to unit forward distance.
        let world = |x: f64, y: f64| {
            let ndc = glam::DVec4::new(2.0 * x / w - 1.0, 1.0 - 2.0 * y / h, 0.0, 1.0);
            let p = camera.world_from_clip * ndc;
            let d = p.truncate() / p.w - camera.eye;
            d / d.dot(camera.forward)
        };
        let to_texture = |d: DVec3| d / (2.0 * half);
        let base = world(0.0, 0.0);
        Self { base: to_texture(base), dx: to_texture(world(1.0, 0.0) - base), dy: to_texture(world(0.0, 1.0) - base) }
    }
}

/// Rust twin of `struct Frame` in `shaders/common/frame.wgsl`; keep both in step.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FrameUniforms {
    /// World → clip.
    pub clip_from_world: [[f32; 4]; 4],
    /// Clip → world.
    pub world_from_clip: [[f32; 4]; 4],
    /// The previous frame's world → clip (this frame's when there is none).
    pub prev_clip_from_world: [[f32; 4]; 4],
    /// Eye position (xyz); w = 1 when the eye is inside the volume box.
    pub eye_world: [f32; 4],
    /// Half size of the volume box (xyz); w = unit step in world units.
    pub half_extent: [f32; 4],
    /// Volume dimensions in voxels (xyz); w = the opacity unit in voxels.
    pub volume_dims: [f32; 4],
    /// Viewport width, height, 1/width, 1/height.
    pub viewport: [f32; 4],
    /// Unit camera forward (xyz); w = near-plane distance.
    pub camera_forward: [f32; 4],
    /// Eye position in texture space (xyz).
    pub eye_texture: [f32; 4],
    /// The texture-space pixel ray: pixel centre (x, y) looks along
    /// `ray_base + x·ray_dx + y·ray_dy` (xyz), scaled so that its world direction advances one
    /// world unit along `camera_forward` per unit of the ray parameter — the near plane is at
    /// parameter `near` (`shaders/common/ray_box.wgsl`).
    pub ray_base_texture: [f32; 4],
    /// See `ray_base_texture`.
    pub ray_dx_texture: [f32; 4],
    /// See `ray_base_texture`.
    pub ray_dy_texture: [f32; 4],
    /// Frames submitted before this one (wraps).
    pub frame_index: u32,
    /// Frames since history was invalidated (saturates).
    pub history_age: u32,
    /// Padding to 16 bytes.
    pub _pad: [u32; 2],
    /// The box rays are met with, whose entry anchors the step grid (xyz, texture space); w = 1
    /// when the bound voxels are a window of a larger volume ([`VolumeWindow`]), else 0 and
    /// the boxes are `[0,1]³`.
    pub grid_lo: [f32; 4],
    /// See `grid_lo`.
    pub grid_hi: [f32; 4],
    /// The box whose samples this frame takes (xyz, texture space).
    pub own_lo: [f32; 4],
    /// See `own_lo`.
    pub own_hi: [f32; 4],
    /// The scene's crop box in the bound texture's coordinates (xyz); read under `#if CROP`. w:
    /// which crop faces are cuts (bit a: the low face of axis a, bit 3 + a: the high one).
    pub crop_lo: [f32; 4],
    /// See `crop_lo`.
    pub crop_hi: [f32; 4],
    /// The scene's clip planes in the bound texture's coordinates: keep `u` with
    /// `dot(xyz, u) >= w`; unused planes are `(0, 0, 0, -1)`. Read under `#if CLIP`.
    pub clip_planes: [[f32; 4]; MAX_CLIP_PLANES],
    /// The screen footprint of the volume grown by [`FOOTPRINT_GROW`] pixels
    /// ([`super::footprint`]): the vertices of a convex polygon in pixels (row 0 at the top),
    /// two per entry (xy, zw), that a footprint draw covers with a fan of triangles.
    pub footprint: [[f32; 4]; FAN_VERTICES / 2],
    /// How many `footprint` vertices there are; 0: no pixel's ray meets the box;
    /// [`FOOTPRINT_WHOLE`]: the draw covers the whole viewport.
    pub footprint_vertices: u32,
    /// How many of `lights` the scene has (1 to [`volgraph_accel::light::MAX_LIGHTS`]).
    pub light_count: u32,
    /// Padding to 16 bytes.
    pub _pad_lights: [u32; 2],
    /// The scene's lights ([`light_world`]): w = 0 the headlight (each ray's own
    /// `-direction`), w = 1 the unit world direction toward a directional light (xyz), w = 2 a
    /// point light's position.
    pub lights: [[f32; 4]; volgraph_accel::light::MAX_LIGHTS],
}

const _: () = assert!(std::mem::size_of::<FrameUniforms>() == 704);

/// [`FrameUniforms::footprint_vertices`] of a footprint draw that covers the whole viewport.
pub const FOOTPRINT_WHOLE: u32 = u32::MAX;

/// How far (pixels) a footprint draw's polygon lies outside the footprint: rays through pixel
/// centres, met with the box in f32, leave it by far less, so the rasterizer covers every
/// pixel whose ray meets the box.
pub const FOOTPRINT_GROW: f64 = 1.0;

/// A plane that keeps every point (fills the unused clip-plane slots).
const KEEP_ALL: [f32; 4] = [0.0, 0.0, 0.0, -1.0];

fn mat(m: DMat4) -> [[f32; 4]; 4] {
    m.as_mat4().to_cols_array_2d()
}

impl FrameUniforms {
    /// The uniform block of `frame`.
    pub fn of(frame: &FrameData) -> Self {
        Self::and_footprint(frame).0
    }

    /// The uniform block of `frame` and the volume's screen footprint it carries, computed once
    /// per frame: the runtime hands it to every node (`RecordContext::footprint`).
    pub fn and_footprint(frame: &FrameData) -> (Self, Footprint) {
        let uniforms = Self::without_footprint(frame);
        let footprint = super::footprint::footprint(&uniforms);
        (uniforms.with_footprint(&footprint), footprint)
    }

    /// Every field but the footprint's (a draw of the whole viewport).
    fn without_footprint(frame: &FrameData) -> Self {
        let c = &frame.camera;
        let (half, unit, dims, opacity_unit) = match &frame.volume {
            Some(v) => (v.half_extent, v.unit_step, v.dims.as_dvec3(), v.opacity_unit_voxels),
            None => (DVec3::splat(0.5), 1.0, DVec3::ONE, 1.0),
        };
        let window = frame.volume.and_then(|v| v.window);
        let (grid, own) = window.map_or(((DVec3::ZERO, DVec3::ONE), (DVec3::ZERO, DVec3::ONE)), |w| (w.grid, w.own));
        let eye_texture = c.eye / (2.0 * half) + DVec3::splat(0.5);
        let eye_inside = eye_texture.cmpge(grid.0).all() && eye_texture.cmple(grid.1).all();
        let (w, h) = (frame.viewport.0.max(1) as f32, frame.viewport.1.max(1) as f32);
        let ray = PixelRays::of(c, frame.viewport, half);
        let v4 = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32, 0.0];
        Self {
            clip_from_world: mat(c.clip_from_world),
            world_from_clip: mat(c.world_from_clip),
            prev_clip_from_world: mat(frame.previous_camera.unwrap_or(*c).clip_from_world),
            eye_world: [c.eye.x as f32, c.eye.y as f32, c.eye.z as f32, if eye_inside { 1.0 } else { 0.0 }],
            half_extent: [half.x as f32, half.y as f32, half.z as f32, unit as f32],
            volume_dims: [dims.x as f32, dims.y as f32, dims.z as f32, opacity_unit as f32],
            viewport: [w, h, 1.0 / w, 1.0 / h],
            camera_forward: [c.forward.x as f32, c.forward.y as f32, c.forward.z as f32, c.near as f32],
            eye_texture: v4(eye_texture),
            ray_base_texture: v4(ray.base),
            ray_dx_texture: v4(ray.dx),
            ray_dy_texture: v4(ray.dy),
            frame_index: frame.frame_index as u32,
            history_age: frame.history_age.min(u32::MAX as u64) as u32,
            _pad: [0; 2],
            grid_lo: with_w(grid.0, if window.is_some() { 1.0 } else { 0.0 }),
            grid_hi: with_w(grid.1, 0.0),
            own_lo: with_w(own.0, 0.0),
            own_hi: with_w(own.1, 0.0),
            crop_lo: with_w(grid.0, 0.0),
            crop_hi: with_w(grid.1, 0.0),
            clip_planes: [KEEP_ALL; MAX_CLIP_PLANES],
            footprint: [[0.0; 4]; FAN_VERTICES / 2],
            footprint_vertices: FOOTPRINT_WHOLE,
            light_count: frame.lights.as_slice().len() as u32,
            _pad_lights: [0; 2],
            lights: {
                let mut lights = [[0.0; 4]; volgraph_accel::light::MAX_LIGHTS];
                for (slot, light) in lights.iter_mut().zip(frame.lights.as_slice()) {
                    *slot = light_world(light, window.map(|w| w.centre_world));
                }
                lights
            },
        }
        .with_cuts(&frame.cuts, grid)
    }

    /// `footprint`, of the rays, boxes and cuts already set ([`super::footprint`]), as the
    /// polygon a footprint draw covers.
    fn with_footprint(mut self, footprint: &Footprint) -> Self {
        match footprint.coverage(FOOTPRINT_GROW) {
            Coverage::Nothing => self.footprint_vertices = 0,
            Coverage::Whole => self.footprint_vertices = FOOTPRINT_WHOLE,
            Coverage::Polygon(vertices) => {
                for (i, v) in vertices.iter().enumerate() {
                    self.footprint[i / 2][2 * (i % 2)] = v.x as f32;
                    self.footprint[i / 2][2 * (i % 2) + 1] = v.y as f32;
                }
                self.footprint_vertices = vertices.len() as u32;
            }
        }
        self
    }

    /// The cuts (volume fractions of the whole volume) in the bound texture's coordinates, where
    /// the whole volume is the box `grid`: `u = lo + f·size`.
    fn with_cuts(mut self, cuts: &Cuts, grid: (DVec3, DVec3)) -> Self {
        let (lo, size) = (grid.0, grid.1 - grid.0);
        if let Some(c) = cuts.crop() {
            // crop_lo.w: which faces are cuts, not the volume's own faces (bit a: the low face
            // of axis a, bit 3 + a: the high one), decided here in f64 as `Cuts::cap_normal`
            // decides it, for the shader's capping.
            let mut faces = 0u32;
            for a in 0..3 {
                faces |= u32::from(c.lo[a] > 0.0) << a;
                faces |= u32::from(c.hi[a] < 1.0) << (3 + a);
            }
            self.crop_lo = with_w(lo + c.lo * size, faces as f32);
            self.crop_hi = with_w(lo + c.hi * size, 0.0);
        }
        for (slot, p) in self.clip_planes.iter_mut().zip(cuts.planes()) {
            // n·f >= d with f = (u - lo)/size  <=>  (n/size)·u >= d + (n/size)·lo.
            let n = p.normal / size;
            *slot = with_w(n, (p.offset + n.dot(lo)) as f32);
        }
        self
    }
}

/// A light in the frame block's `lights`: (0, 0, 0, 0) for the headlight, the unit direction toward a
/// directional light with w = 1, a point light's position with w = 2 — in the bound box's own
/// world, which a sort-last window centres on its own origin (`window_centre`).
fn light_world(light: &volgraph_accel::light::Light, window_centre: Option<DVec3>) -> [f32; 4] {
    match *light {
        volgraph_accel::light::Light::Point { x, y, z } => {
            with_w(DVec3::new(x, y, z) - window_centre.unwrap_or(DVec3::ZERO), 2.0)
        }
        _ => light.toward().map_or([0.0; 4], |l| with_w(l, 1.0)),
    }
}

fn with_w(v: DVec3, w: f32) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The affine pixel rays point where the reference's per-pixel unprojection does, and put the
    /// near plane at parameter `near` (unit forward distance).
    #[test]
    fn pixel_rays_match_the_reference_rays() {
        let half = DVec3::new(0.5, 0.4, 0.25);
        for (azimuth, elevation, distance) in [(0.0, 0.0, 3.2), (35.0, 25.0, 2.6), (200.0, -60.0, 0.3)] {
            let orbit = OrbitCamera { azimuth_deg: azimuth, elevation_deg: elevation, distance, ..Default::default() };
            let viewport = (37, 23);
            let camera = CameraData::from_orbit(&orbit, viewport);
            let rays = PixelRays::of(&camera, viewport, half);
            let frame = orbit.frame(viewport.0, viewport.1);
            for (x, y) in [(0, 0), (36, 22), (18, 11), (5, 20)] {
                let d_tex = rays.base + (x as f64 + 0.5) * rays.dx + (y as f64 + 0.5) * rays.dy;
                let d_world = d_tex * (2.0 * half);
                let (_, reference) = frame.pixel_ray(x, y);
                assert!((d_world.normalize() - reference).length() < 1e-9, "pixel ({x}, {y}) of {orbit:?}");
                assert!((d_world.dot(camera.forward) - 1.0).abs() < 1e-9, "unit forward distance");
            }
        }
    }

    /// The block edge: 2 up to 128 voxels on the longest axis, 3 up to 192, then 4, whatever
    /// the other axes; a graph's `block_size` input reads it as a scene value.
    #[test]
    fn the_block_size_keeps_the_grid_within_64_blocks_from_2_to_4_voxels() {
        let edge = |x: u32, y: u32, z: u32| {
            let data = volgraph_accel::volume::VoxelData::U8(vec![0; (x * y * z) as usize]);
            let volume = volgraph_accel::volume::Volume::new("v", UVec3::new(x, y, z), DVec3::ONE, data);
            VolumeDesc::of(&volume).block_size()
        };
        assert_eq!(edge(1, 1, 1), 2.0);
        assert_eq!(edge(64, 64, 64), 2.0);
        assert_eq!(edge(128, 128, 128), 2.0);
        assert_eq!(edge(129, 16, 16), 3.0);
        assert_eq!(edge(16, 192, 16), 3.0);
        assert_eq!(edge(16, 16, 193), 4.0);
        assert_eq!(edge(256, 256, 256), 4.0);
        assert_eq!(edge(512, 64, 64), 4.0);
        let volume = volgraph_accel::generate::marschner_lobb(64);
        assert_eq!(scene_values_of(&VolumeDesc::of(&volume)).get(BLOCK_SIZE), Some(&2.0));
    }
}
