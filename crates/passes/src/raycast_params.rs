//! Parameters shared by the fragment and compute raycasters, and their GPU twin.

use volgraph_accel::reference::{Phong, RaycastSettings, RenderMode};
use volgraph_core::{ParamSpec, Params};

/// The declared parameters (docs/rendering_model.md for their meaning).
pub fn raycast_param_specs() -> Vec<ParamSpec> {
    vec![
        ParamSpec::float("step_voxels", 0.5, 0.01, 16.0, "sample distance in units of the smallest voxel side"),
        ParamSpec::float(
            "threshold",
            1.0,
            0.0,
            1.0,
            "early ray termination once accumulated alpha reaches this (1 = off, lossless)",
        ),
        ParamSpec::uint("max_steps", 4096, 1, 1 << 20, "upper bound on samples per ray"),
        ParamSpec::boolean(
            "jitter",
            false,
            "offset each ray's first sample by a per-pixel hash (trades banding for noise)",
        ),
        ParamSpec::boolean(
            "jitter_per_frame",
            false,
            "with jitter: move the offsets every frame (frame 0 keeps the stable ones), for accumulation",
        ),
        ParamSpec::choice("mode", "dvr", &["dvr", "iso"], "direct volume rendering or first-hit isosurface"),
        ParamSpec::float("iso_value", 0.5, 0.0, 1.0, "isovalue in normalized scalar units (mode \"iso\")"),
        ParamSpec::float("ambient", 0.15, 0.0, 1.0, "Blinn–Phong ambient coefficient (mode \"iso\")"),
        ParamSpec::float("diffuse", 0.75, 0.0, 1.0, "Blinn–Phong diffuse coefficient (mode \"iso\")"),
        ParamSpec::float("specular", 0.25, 0.0, 1.0, "Blinn–Phong specular coefficient (mode \"iso\")"),
        ParamSpec::float("shininess", 32.0, 1.0, 512.0, "Blinn–Phong exponent (mode \"iso\")"),
    ]
}

/// Rust twin of `struct RaycastParams` in `shaders/common/raycast_params.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct RaycastParamsGpu {
    /// Sample distance in voxels.
    pub step_voxels: f32,
    /// Termination threshold.
    pub threshold: f32,
    /// Max samples per ray.
    pub max_steps: u32,
    /// 1 = jitter.
    pub jitter: u32,
    /// Isovalue.
    pub iso_value: f32,
    /// Phong ambient.
    pub ambient: f32,
    /// Phong diffuse.
    pub diffuse: f32,
    /// Phong specular.
    pub specular: f32,
    /// Phong exponent.
    pub shininess: f32,
    /// Klein et al. 2005 §4.2: samples a leap hit is moved back (the `step_back` parameter, or
    /// the conservative count the node computes for the bound volume).
    pub step_back: f32,
    /// Padding.
    pub _pad: [f32; 2],
}

const _: () = assert!(std::mem::size_of::<RaycastParamsGpu>() == 48);

impl RaycastParamsGpu {
    /// From checked pass parameters.
    pub fn from_params(p: &Params) -> Self {
        // The raycasters share this block but declare only the parameters they use: what a
        // kind does not declare is a value its shader never reads (0, as the block's padding).
        Self {
            step_voxels: p.float("step_voxels") as f32,
            threshold: p.float_or("threshold", 1.0) as f32,
            max_steps: p.uint("max_steps") as u32,
            jitter: p.boolean_or("jitter", false) as u32,
            iso_value: p.float_or("iso_value", 0.0) as f32,
            ambient: p.float_or("ambient", 0.0) as f32,
            diffuse: p.float_or("diffuse", 0.0) as f32,
            specular: p.float_or("specular", 0.0) as f32,
            shininess: p.float_or("shininess", 0.0) as f32,
            step_back: p.uint_or("step_back", 0) as f32,
            _pad: [0.0; 2],
        }
    }
}

/// Whether the parameters ask for the isosurface.
pub fn is_iso(p: &Params) -> bool {
    p.choice_or("mode", "dvr") == "iso"
}

/// The CPU reference settings equivalent to a raycast pass's parameters, so tests render the
/// same integral on both sides.
pub fn reference_settings(p: &Params) -> RaycastSettings {
    RaycastSettings {
        step_voxels: p.float("step_voxels"),
        threshold: p.float_or("threshold", 1.0),
        max_steps: p.uint("max_steps") as u32,
        jitter: p.boolean_or("jitter", false),
        effects: volgraph_accel::reference::Effects {
            shading: p.boolean_or("shading", false),
            preintegration: p.boolean_or("preintegration", false),
            tricubic: p.boolean_or("tricubic", false),
        },
        dvr_shading: Phong {
            ambient: p.float_or("ambient", 0.0),
            diffuse: p.float_or("diffuse", 0.0),
            specular: p.float_or("specular", 0.0),
            shininess: p.float_or("shininess", 0.0),
        },
        opacity_unit_voxels: 1.0,
        mode: if is_iso(p) {
            RenderMode::Isosurface {
                iso: p.float_or("iso_value", 0.0),
                shading: Phong {
                    ambient: p.float_or("ambient", 0.0),
                    diffuse: p.float_or("diffuse", 0.0),
                    specular: p.float_or("specular", 0.0),
                    shininess: p.float_or("shininess", 0.0),
                },
            }
        } else {
            RenderMode::Dvr
        },
    }
}
