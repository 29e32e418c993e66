//! The headless GPU: Vulkan preferred, Mesa lavapipe (software Vulkan) where there is no GPU.
//!
//! wgpu's default error handler panics on any validation or out-of-memory error. volgraph never
//! lets it: [`Gpu`] installs a handler that records such errors, and every place that creates or
//! submits GPU work runs it through [`Gpu::checked`], which captures the error in error scopes
//! and returns it as a [`GpuFault`] naming what was being done (the pass, the resource).

use std::sync::{Arc, Mutex};

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

/// What kind of error the GPU reported.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GpuFaultKind {
    /// The work broke a WebGPU rule (a wrong format, a missing feature, a bad binding).
    Validation,
    /// The GPU ran out of memory.
    OutOfMemory,
    /// The driver failed internally.
    Internal,
}

/// The GPU rejected a piece of work: what was being done, and wgpu's message.
#[derive(Clone, Debug, thiserror::Error, PartialEq, Eq)]
#[error("{what}: {}: {message}", match .kind {
    GpuFaultKind::Validation => "the GPU rejected it",
    GpuFaultKind::OutOfMemory => "the GPU ran out of memory; use a smaller viewport or volume",
    GpuFaultKind::Internal => "the GPU driver failed",
})]
pub struct GpuFault {
    /// What was being done, naming the pass and resource (`pass "march": creating target slot 2`).
    pub what: String,
    /// The kind of error.
    pub kind: GpuFaultKind,
    /// wgpu's message.
    pub message: String,
}

impl GpuFault {
    fn from_wgpu(what: String, error: &wgpu::Error) -> Self {
        let kind = match error {
            wgpu::Error::OutOfMemory { .. } => GpuFaultKind::OutOfMemory,
            wgpu::Error::Validation { .. } => GpuFaultKind::Validation,
            wgpu::Error::Internal { .. } => GpuFaultKind::Internal,
        };
        let message = match error {
            wgpu::Error::Validation { description, .. } => description.trim().to_string(),
            other => other.to_string().trim().to_string(),
        };
        Self { what, kind, message }
    }
}

/// The `#if` name of a device whose shaders may use subgroup operations ([`Gpu::subgroups`]).
pub const SUBGROUPS_DEFINE: &str = "SUBGROUPS";

/// Options for opening the GPU.
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    /// Optional features not to request even where the adapter offers them (tests of fallback
    /// paths, e.g. a volume upload without `TEXTURE_FORMAT_16BIT_NORM`).
    pub without_features: wgpu::Features,
    /// A `max_buffer_size` below the adapter's (tests of the paths that split work by the
    /// device's buffer limit, with small data: a 1 MiB limit makes a 96³ volume "larger than the
    /// largest buffer").
    pub max_buffer_size: Option<u64>,
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
    /// Whether timestamps measure the work: false on CPU adapters (Mesa lavapipe), whose
    /// timestamps do not cover compute dispatches (a compute pass reads ~0 ms while the frame
    /// takes the full time on the wall clock); frame times there are wall time.
    pub timestamps_cover_work: bool,
    /// Whether 32-bit float textures can be linearly filtered (R32Float volumes, f32 LUTs).
    pub float32_filterable: bool,
    /// Whether 32-bit float targets can be blended into.
    pub float32_blendable: bool,
    /// Whether 16-bit normalized textures (R16Unorm) exist: 16-bit volumes are uploaded as they
    /// are; without it they are widened to 32-bit float.
    pub norm16: bool,
    /// Whether the adapter is a CPU rasterizer (Mesa lavapipe): some choices that cost the same
    /// on a GPU differ there (8-bit volumes go up as R16Unorm, upload.rs).
    pub is_cpu: bool,
    /// Whether fragment shaders may force early depth tests (`@early_depth_test(force)`,
    /// Vulkan only): needed where a shader with side effects, such as a debug counter, must
    /// still be skipped by early-z (Krüger–Westermann 2003 §2.1).
    pub early_depth_test: bool,
    /// Whether shaders may use subgroup operations (`subgroupAll`, …; wgpu's `SUBGROUP`): every
    /// module is then assembled with [`SUBGROUPS_DEFINE`] ([`Gpu::device_defines`]).
    pub subgroups: bool,
    /// The device limits.
    pub limits: wgpu::Limits,
    uncaptured: Arc<Mutex<Vec<wgpu::Error>>>,
}

impl Gpu {
    /// Opens the first adapter (honouring `WGPU_BACKEND` / `WGPU_ADAPTER_NAME`), requesting the
    /// optional features volgraph uses where present.
    pub fn new_headless() -> Result<Self, GpuError> {
        Self::new_headless_with(&GpuOptions::default())
    }

    /// Like [`Self::new_headless`], leaving out `options.without_features`.
    pub fn new_headless_with(options: &GpuOptions) -> Result<Self, GpuError> {
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
        Self::from_adapter(&adapter, options)
    }

    /// Opens a device on `adapter` (a window's surface-compatible adapter, or the headless one),
    /// requesting the optional features volgraph uses where present.
    pub fn from_adapter(adapter: &wgpu::Adapter, options: &GpuOptions) -> Result<Self, GpuError> {
        let info = adapter.get_info();
        let adapter_name = format!("{} / {:?}", info.name, info.backend);
        let wanted = wgpu::Features::TIMESTAMP_QUERY
            | wgpu::Features::FLOAT32_FILTERABLE
            | wgpu::Features::FLOAT32_BLENDABLE
            | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS
            | wgpu::Features::TEXTURE_FORMAT_16BIT_NORM
            | wgpu::Features::SHADER_EARLY_DEPTH_TEST
            | wgpu::Features::SUBGROUP;
        let features = adapter.features() & wanted & !options.without_features;
        let mut limits = adapter.limits();
        if let Some(cap) = options.max_buffer_size {
            limits.max_buffer_size = limits.max_buffer_size.min(cap);
            limits.max_storage_buffer_binding_size = limits.max_storage_buffer_binding_size.min(cap);
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("volgraph"),
            required_features: features,
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device { adapter: adapter_name.clone(), reason: e.to_string() })?;
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let sink = uncaptured.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut errors) = sink.lock() {
                errors.push(e);
            }
        }));
        Ok(Self {
            device,
            queue,
            adapter_name,
            has_timestamps: features.contains(wgpu::Features::TIMESTAMP_QUERY),
            timestamps_cover_work: features.contains(wgpu::Features::TIMESTAMP_QUERY)
                && info.device_type != wgpu::DeviceType::Cpu,
            float32_filterable: features.contains(wgpu::Features::FLOAT32_FILTERABLE),
            float32_blendable: features.contains(wgpu::Features::FLOAT32_BLENDABLE),
            norm16: features.contains(wgpu::Features::TEXTURE_FORMAT_16BIT_NORM),
            is_cpu: info.device_type == wgpu::DeviceType::Cpu,
            early_depth_test: features.contains(wgpu::Features::SHADER_EARLY_DEPTH_TEST),
            subgroups: features.contains(wgpu::Features::SUBGROUP),
            limits,
            uncaptured,
        })
    }

    /// The `#if` names of what this device can do, turned on in every module the runtime builds
    /// (`CreateContext`): [`SUBGROUPS_DEFINE`] where shaders may use subgroup operations.
    pub fn device_defines(&self) -> &'static [&'static str] {
        if self.subgroups { &[SUBGROUPS_DEFINE] } else { &[] }
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

    /// Runs `work` inside validation, out-of-memory and internal error scopes. An error wgpu
    /// reports for it (or one that reached the uncaptured handler meanwhile) comes back as a
    /// [`GpuFault`] naming `what` instead of a panic.
    pub fn checked<T>(&self, what: impl FnOnce() -> String, work: impl FnOnce() -> T) -> Result<T, GpuFault> {
        let internal = self.device.push_error_scope(wgpu::ErrorFilter::Internal);
        let memory = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let value = work();
        let errors = [
            pollster::block_on(validation.pop()),
            pollster::block_on(memory.pop()),
            pollster::block_on(internal.pop()),
        ];
        let what = what();
        if let Some(e) = errors.into_iter().flatten().next() {
            return Err(GpuFault::from_wgpu(what, &e));
        }
        self.take_uncaptured(|| what)?;
        Ok(value)
    }

    /// The first error that reached the uncaptured-error handler since the last call (errors
    /// raised outside any [`Self::checked`] scope, e.g. by a dropped resource), as a fault naming
    /// `what`.
    pub fn take_uncaptured(&self, what: impl FnOnce() -> String) -> Result<(), GpuFault> {
        let first = self.uncaptured.lock().ok().and_then(|mut errors| {
            let first = (!errors.is_empty()).then(|| errors.remove(0));
            errors.clear();
            first
        });
        match first {
            Some(e) => Err(GpuFault::from_wgpu(what(), &e)),
            None => Ok(()),
        }
    }

    /// Blocks until all submitted work is done.
    pub fn wait_idle(&self) {
        // An error here means the device was lost; the next call reports it.
        let _ = self.device.poll(wgpu::PollType::wait_indefinitely());
    }
}
