//! The headless GPU: Vulkan preferred, Mesa lavapipe (software Vulkan) where there is no GPU.

/// Why no GPU could be opened.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter at all.
    #[error(
        "no GPU adapter found ({0}); install a Vulkan driver — on Debian without a GPU: \
         apt-get install mesa-vulkan-drivers libvulkan1 (Mesa lavapipe)"
    )]
    NoAdapter(String),
    /// The adapter refused the device.
    #[error("the GPU adapter \"{adapter}\" refused a device: {reason}")]
    Device {
        /// Adapter name.
        adapter: String,
        /// wgpu's reason.
        reason: String,
    },
}

/// Device, queue and what the adapter can do.
pub struct Gpu {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Adapter name and backend, for reports (`"llvmpipe (LLVM 15.0.6, 256 bits) / Vulkan"`).
    pub adapter_name: String,
    /// Whether per-pass GPU timestamps are available.
    pub has_timestamps: bool,
    /// Whether 32-bit float textures can be linearly filtered (R32Float volumes, f32 LUTs).
    pub float32_filterable: bool,
    /// Whether 32-bit float targets can be blended into.
    pub float32_blendable: bool,
    /// Whether fragment shaders may force early depth tests (`@early_depth_test(force)`,
    /// Vulkan only): needed where a shader with side effects, such as a debug counter, must
    /// still be skipped by early-z (Krüger–Westermann 2003 §2.1).
    pub early_depth_test: bool,
    /// The device limits.
    pub limits: wgpu::Limits,
}

impl Gpu {
    /// Opens the first adapter (honouring `WGPU_BACKEND` / `WGPU_ADAPTER_NAME`), requesting the
    /// optional features volgraph uses where present.
    pub fn new_headless() -> Result<Self, GpuError> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        if std::env::var_os("WGPU_BACKEND").is_none() {
            desc.backends = wgpu::Backends::VULKAN | wgpu::Backends::METAL | wgpu::Backends::DX12;
        }
        let instance = wgpu::Instance::new(desc);
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            ..Default::default()
        }))
        .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        let adapter_name = format!("{} / {:?}", info.name, info.backend);
        let wanted = wgpu::Features::TIMESTAMP_QUERY
            | wgpu::Features::FLOAT32_FILTERABLE
            | wgpu::Features::FLOAT32_BLENDABLE
            | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS
            | wgpu::Features::SHADER_EARLY_DEPTH_TEST;
        let features = adapter.features() & wanted;
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("volgraph"),
            required_features: features,
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device { adapter: adapter_name.clone(), reason: e.to_string() })?;
        Ok(Self {
            device,
            queue,
            adapter_name,
            has_timestamps: features.contains(wgpu::Features::TIMESTAMP_QUERY),
            float32_filterable: features.contains(wgpu::Features::FLOAT32_FILTERABLE),
            float32_blendable: features.contains(wgpu::Features::FLOAT32_BLENDABLE),
            early_depth_test: features.contains(wgpu::Features::SHADER_EARLY_DEPTH_TEST),
            limits,
        })
    }

    /// Whether textures of `format` may be sampled with a filtering sampler on this device.
    pub fn filterable(&self, format: wgpu::TextureFormat) -> bool {
        use wgpu::TextureFormat as F;
        match format {
            F::R32Float | F::Rg32Float | F::Rgba32Float => self.float32_filterable,
            F::Depth32Float => false,
            _ => true,
        }
    }

    /// Blocks until all submitted work is done.
    pub fn wait_idle(&self) {
        // An error here means the device was lost; the next call reports it.
        let _ = self.device.poll(wgpu::PollType::wait_indefinitely());
    }
}
