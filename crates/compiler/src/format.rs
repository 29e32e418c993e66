//! Pixel formats a graph may declare for its targets.

use serde::{Deserialize, Serialize};

/// The formats of transient and history targets. Each maps to one `wgpu::TextureFormat`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum TargetFormat {
    /// One 32-bit float channel.
    R32Float,
    /// Two 32-bit float channels.
    Rg32Float,
    /// Four 16-bit float channels.
    Rgba16Float,
    /// Four 32-bit float channels.
    Rgba32Float,
    /// 32-bit float depth (the early-z target of Krüger–Westermann §2.1).
    Depth32Float,
    /// Four 8-bit unsigned normalized channels (display images).
    Rgba8Unorm,
    /// One 8-bit unsigned normalized channel (flags, masks).
    R8Unorm,
}

/// The float precision a scene asks for its colour, accumulation and history targets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Precision {
    /// Rgba16Float: half the memory and bandwidth, 11 significant bits.
    F16,
    /// Rgba32Float: 24 significant bits (blending into it needs FLOAT32_BLENDABLE).
    F32,
}

impl Precision {
    /// The RGBA target format of this precision.
    pub fn rgba(self) -> TargetFormat {
        match self {
            Precision::F16 => TargetFormat::Rgba16Float,
            Precision::F32 => TargetFormat::Rgba32Float,
        }
    }

    /// `f16` / `f32`.
    pub fn name(self) -> &'static str {
        match self {
            Precision::F16 => "f16",
            Precision::F32 => "f32",
        }
    }

    /// The precision named `name` (`f16`, `f32`).
    pub fn from_name(name: &str) -> Option<Precision> {
        [Precision::F16, Precision::F32].into_iter().find(|p| p.name() == name)
    }
}

impl TargetFormat {
    /// Every format, in declaration order (used to list the alternatives in errors).
    pub const ALL: [TargetFormat; 7] = [
        TargetFormat::R32Float,
        TargetFormat::Rg32Float,
        TargetFormat::Rgba16Float,
        TargetFormat::Rgba32Float,
        TargetFormat::Depth32Float,
        TargetFormat::Rgba8Unorm,
        TargetFormat::R8Unorm,
    ];

    /// Bytes per pixel.
    pub fn bytes_per_pixel(self) -> u64 {
        match self {
            TargetFormat::R8Unorm => 1,
            TargetFormat::R32Float | TargetFormat::Depth32Float | TargetFormat::Rgba8Unorm => 4,
            TargetFormat::Rg32Float | TargetFormat::Rgba16Float => 8,
            TargetFormat::Rgba32Float => 16,
        }
    }

    /// Whether this is a depth format (bound as a depth attachment, never sampled as colour).
    pub fn is_depth(self) -> bool {
        matches!(self, TargetFormat::Depth32Float)
    }

    /// The wgpu format.
    pub fn wgpu(self) -> wgpu_types::TextureFormat {
        match self {
            TargetFormat::R32Float => wgpu_types::TextureFormat::R32Float,
            TargetFormat::Rg32Float => wgpu_types::TextureFormat::Rg32Float,
            TargetFormat::Rgba16Float => wgpu_types::TextureFormat::Rgba16Float,
            TargetFormat::Rgba32Float => wgpu_types::TextureFormat::Rgba32Float,
            TargetFormat::Depth32Float => wgpu_types::TextureFormat::Depth32Float,
            TargetFormat::Rgba8Unorm => wgpu_types::TextureFormat::Rgba8Unorm,
            TargetFormat::R8Unorm => wgpu_types::TextureFormat::R8Unorm,
        }
    }

    /// The name as written in graph files.
    pub fn name(self) -> &'static str {
        match self {
            TargetFormat::R32Float => "R32Float",
            TargetFormat::Rg32Float => "Rg32Float",
            TargetFormat::Rgba16Float => "Rgba16Float",
            TargetFormat::Rgba32Float => "Rgba32Float",
            TargetFormat::Depth32Float => "Depth32Float",
            TargetFormat::Rgba8Unorm => "Rgba8Unorm",
            TargetFormat::R8Unorm => "R8Unorm",
        }
    }
}

impl std::fmt::Display for TargetFormat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The size of a target: relative to the viewport, or absolute pixels.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum TargetSize {
    /// `scale × viewport`, rounded up, at least 1 pixel.
    Viewport(f32),
    /// A fixed size in pixels.
    Absolute(u32, u32),
}

impl Default for TargetSize {
    fn default() -> Self {
        TargetSize::Viewport(1.0)
    }
}

impl TargetSize {
    /// The size in pixels for a viewport.
    pub fn resolve(self, viewport: (u32, u32)) -> (u32, u32) {
        match self {
            TargetSize::Viewport(s) => {
                let f = |v: u32| ((v as f64 * s as f64).ceil() as u32).max(1);
                (f(viewport.0), f(viewport.1))
            }
            TargetSize::Absolute(w, h) => (w.max(1), h.max(1)),
        }
    }
}

impl std::fmt::Display for TargetSize {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TargetSize::Viewport(s) => write!(f, "Viewport({s})"),
            TargetSize::Absolute(w, h) => write!(f, "Absolute({w}, {h})"),
        }
    }
}
