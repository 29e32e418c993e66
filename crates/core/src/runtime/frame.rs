//! The per-frame contract between the application, the runtime and the passes: the viewport,
//! this frame's and the previous frame's camera, the frame counters and the bound volume's
//! description. The application gives the camera; the runtime fills in the rest and uploads it
//! as the `frame` uniform block every pass may bind (`shaders/common/frame.wgsl`).

use glam::{DMat4, DVec3, UVec3};
use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::volume::Volume;

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

/// What the frame contract knows of the bound volume.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeDesc {
    /// Voxels per axis.
    pub dims: UVec3,
    /// Half size of the volume box in world units (longest side 1).
    pub half_extent: DVec3,
    /// World length of the smallest voxel side: the unit of `step_voxels`.
    pub unit_step: f64,
}

impl VolumeDesc {
    /// The description of `volume`.
    pub fn of(volume: &Volume) -> Self {
        Self { dims: volume.dims, half_extent: volume.half_extent_world(), unit_step: volume.unit_step_world() }
    }

    /// The box diagonal in unit steps: the longest ray through the volume, in voxels. Graphs read
    /// it as the scene value [`LONGEST_RAY_VOXELS`] (K of Krüger & Westermann 2003 §3 is this
    /// over the step); 0 for a degenerate volume.
    pub fn longest_ray_voxels(&self) -> f64 {
        let k = 2.0 * self.half_extent.length() / self.unit_step;
        if k.is_finite() && k > 0.0 { k } else { 0.0 }
    }
}

/// The scene value every graph may read for the bound volume: its box diagonal in voxels.
pub const LONGEST_RAY_VOXELS: &str = "longest_ray_voxels";

/// The scene values a volume gives graphs ([`CompileOptions::scene`](crate::CompileOptions)):
/// computed here and nowhere else.
pub fn scene_values_of(volume: &VolumeDesc) -> std::collections::BTreeMap<String, f64> {
    std::collections::BTreeMap::from([(LONGEST_RAY_VOXELS.to_string(), volume.longest_ray_voxels())])
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
    /// Volume dimensions in voxels (xyz).
    pub volume_dims: [f32; 4],
    /// Viewport width, height, 1/width, 1/height.
    pub viewport: [f32; 4],
    /// Unit camera forward (xyz); w = near-plane distance.
    pub camera_forward: [f32; 4],
    /// Frames submitted before this one (wraps).
    pub frame_index: u32,
    /// Frames since history was invalidated (saturates).
    pub history_age: u32,
    /// Padding to 16 bytes.
    pub _pad: [u32; 2],
}

const _: () = assert!(std::mem::size_of::<FrameUniforms>() == 288);

fn mat(m: DMat4) -> [[f32; 4]; 4] {
    m.as_mat4().to_cols_array_2d()
}

impl FrameUniforms {
    /// The uniform block of `frame`.
    pub fn of(frame: &FrameData) -> Self {
        let c = &frame.camera;
        let (half, unit, dims) = match &frame.volume {
            Some(v) => (v.half_extent, v.unit_step, v.dims.as_dvec3()),
            None => (DVec3::splat(0.5), 1.0, DVec3::ONE),
        };
        let eye_inside = c.eye.abs().cmple(half).all();
        let (w, h) = (frame.viewport.0.max(1) as f32, frame.viewport.1.max(1) as f32);
        Self {
            clip_from_world: mat(c.clip_from_world),
            world_from_clip: mat(c.world_from_clip),
            prev_clip_from_world: mat(frame.previous_camera.unwrap_or(*c).clip_from_world),
            eye_world: [c.eye.x as f32, c.eye.y as f32, c.eye.z as f32, if eye_inside { 1.0 } else { 0.0 }],
            half_extent: [half.x as f32, half.y as f32, half.z as f32, unit as f32],
            volume_dims: [dims.x as f32, dims.y as f32, dims.z as f32, 0.0],
            viewport: [w, h, 1.0 / w, 1.0 / h],
            camera_forward: [c.forward.x as f32, c.forward.y as f32, c.forward.z as f32, c.near as f32],
            frame_index: frame.frame_index as u32,
            history_age: frame.history_age.min(u32::MAX as u64) as u32,
            _pad: [0; 2],
        }
    }
}
