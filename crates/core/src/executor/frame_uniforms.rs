//! The frame-wide uniform block every pass may bind as `frame`.

/// Rust twin of `struct Frame` in `shaders/common/frame.wgsl`; keep both in step.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FrameUniforms {
    /// World → clip.
    pub clip_from_world: [[f32; 4]; 4],
    /// Clip → world.
    pub world_from_clip: [[f32; 4]; 4],
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
    /// Frames since the graph was (re)compiled.
    pub frame_index: u32,
    /// Padding to 16 bytes.
    pub _pad: [u32; 3],
}

const _: () = assert!(std::mem::size_of::<FrameUniforms>() == 224);
