//! Adapter and device selection, with a clear message where no GPU driver exists.

use thiserror::Error;

/// Why rendering could not start or finish.
#[derive(Debug, Error)]
pub enum RenderError {
    /// No adapter: no GPU driver and no software rasteriser.
    #[error(
        "no GPU adapter found ({0}). Without a GPU, install Mesa's software Vulkan driver \
         (lavapipe): `sudo apt-get install mesa-vulkan-drivers libvulkan1` on Debian/Ubuntu, \
         `sudo dnf install mesa-vulkan-drivers vulkan-loader` on Fedora"
    )]
    NoAdapter(String),
    /// The adapter refused a device.
    #[error("the GPU adapter refused a device: {0}")]
    Device(String),
    /// Reading the image back failed.
    #[error("reading the frame back failed: {0}")]
    Readback(String),
    /// Waiting for the GPU to finish a frame failed (device lost, say).
    #[error("waiting for the GPU to finish the frame failed: {0}")]
    Wait(String),
    /// A size of zero or beyond the adapter's limit.
    #[error("image size {0}×{1} is invalid (1 … {2} per side)")]
    Size(u32, u32, u32),
}

/// An adapter, its device and queue.
#[derive(Debug)]
pub struct Gpu {
    /// The wgpu instance.
    pub instance: wgpu::Instance,
    /// The adapter in use.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
}

impl Gpu {
    /// Open the best adapter (a surface, when given, must be presentable by it).
    pub fn new(
        instance: wgpu::Instance,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Gpu, RenderError> {
        Gpu::open(instance, surface, None)
    }

    /// An offscreen adapter whose device allows storage bindings of at most `max_binding`
    /// bytes (to exercise what a smaller GPU would impose).
    pub fn headless_limited(max_binding: u64) -> Result<Gpu, RenderError> {
        Gpu::open(Gpu::instance(), None, Some(max_binding))
    }

    fn open(
        instance: wgpu::Instance,
        surface: Option<&wgpu::Surface<'_>>,
        max_binding: Option<u64>,
    ) -> Result<Gpu, RenderError> {
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: surface,
            apply_limit_buckets: false,
        }))
        .map_err(|e| RenderError::NoAdapter(e.to_string()))?;
        let mut limits = adapter.limits();
        if let Some(m) = max_binding {
            let m = m.min(limits.max_storage_buffer_binding_size);
            limits.max_storage_buffer_binding_size = m;
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("sylva"),
            required_features: wgpu::Features::empty(),
            required_limits: limits,
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| RenderError::Device(e.to_string()))?;
        Ok(Gpu { instance, adapter, device, queue })
    }

    /// A Vulkan instance (lavapipe where no GPU exists), with wgpu's environment overrides.
    pub fn instance() -> wgpu::Instance {
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env())
    }

    /// Open an adapter for offscreen work.
    pub fn headless() -> Result<Gpu, RenderError> {
        Gpu::new(Gpu::instance(), None)
    }

    /// The adapter's name and backend, for reports.
    pub fn describe(&self) -> String {
        let i = self.adapter.get_info();
        format!("{} ({:?}, {:?})", i.name, i.backend, i.device_type)
    }
}
