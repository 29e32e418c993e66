//! Turning CPU scene data (volume, transfer function, orbit camera) into what the executor
//! binds: frame uniforms and input textures (`docs/rendering_model.md`).

use volgraph_accel::camera::OrbitCamera;
use volgraph_accel::volume::{Volume, VoxelData};
use volgraph_core::executor::{
    FrameUniforms, Gpu, GpuFault, UploadError, UploadedVolume, VolumeTexels, upload_lut, upload_volume,
};

fn mat(m: glam::DMat4) -> [[f32; 4]; 4] {
    m.as_mat4().to_cols_array_2d()
}

/// The frame uniforms for `camera` looking at `volume` in a `viewport`.
pub fn frame_uniforms(camera: &OrbitCamera, volume: &Volume, viewport: (u32, u32)) -> FrameUniforms {
    let f = camera.frame(viewport.0, viewport.1);
    let half = volume.half_extent_world();
    let eye_inside = f.eye.abs().cmple(half).all();
    FrameUniforms {
        clip_from_world: mat(f.clip_from_world),
        world_from_clip: mat(f.world_from_clip),
        eye_world: [f.eye.x as f32, f.eye.y as f32, f.eye.z as f32, if eye_inside { 1.0 } else { 0.0 }],
        half_extent: [half.x as f32, half.y as f32, half.z as f32, volume.unit_step_world() as f32],
        volume_dims: [volume.dims.x as f32, volume.dims.y as f32, volume.dims.z as f32, 0.0],
        viewport: [viewport.0 as f32, viewport.1 as f32, 1.0 / viewport.0 as f32, 1.0 / viewport.1 as f32],
        camera_forward: [f.forward.x as f32, f.forward.y as f32, f.forward.z as f32, camera.near as f32],
        frame_index: 0,
        _pad: [0; 3],
    }
}

/// Uploads a volume as the 3D texture the shaders sample (normalized values,
/// `docs/rendering_model.md`): u8 → `v / 255`, u16 → `v / 65535`, i16 → `(v + 32768) / 65535`,
/// f32 → normalized by the value range. The texture format is the device's best for the data
/// ([`volgraph_core::executor::volume_format_for`]).
pub fn upload_volume_texture(gpu: &Gpu, volume: &Volume) -> Result<UploadedVolume, UploadError> {
    let dims = [volume.dims.x, volume.dims.y, volume.dims.z];
    match &volume.data {
        VoxelData::U8(v) => upload_volume(gpu, &volume.name, dims, &VolumeTexels::Unorm8(v)),
        VoxelData::U16(v) => upload_volume(gpu, &volume.name, dims, &VolumeTexels::Unorm16(v)),
        VoxelData::I16(v) => {
            let shifted: Vec<u16> = v.iter().map(|x| (*x as i32 + 32768) as u16).collect();
            upload_volume(gpu, &volume.name, dims, &VolumeTexels::Unorm16(&shifted))
        }
        VoxelData::F32(_) => upload_volume(gpu, &volume.name, dims, &VolumeTexels::Float(&volume.normalized_f32())),
    }
}

/// Uploads a transfer-function LUT.
pub fn upload_lut_texture(gpu: &Gpu, lut: &[[f32; 4]]) -> Result<wgpu::Texture, GpuFault> {
    upload_lut(gpu, "transfer function", lut)
}

/// K of Krüger & Westermann 2003 §3: the number of steps of `step_voxels` along the longest ray
/// through `volume`'s box, its diagonal (`|2·half|` in world units over `step_voxels ·
/// unit_world`). A segment loop of `ceil(K / M)` passes of M samples covers every ray: a ray of
/// texture length L takes at most `ceil(L / step)` samples (jitter included), and `L / step ≤ K`.
/// Feed it to a graph as the scene scalar `longest_ray_steps`
/// (`CompileOptions::with_scalar("longest_ray_steps", k)`). 0 for a degenerate volume or step.
pub fn longest_ray_steps(volume: &Volume, step_voxels: f64) -> f64 {
    let diagonal = 2.0 * volume.half_extent_world().length();
    let step_world = step_voxels * volume.unit_step_world();
    let k = diagonal / step_world;
    if k.is_finite() && k > 0.0 { k } else { 0.0 }
}
