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

/// Where the NVIDIA driver installs its Vulkan driver manifest (ICD file) on Linux.
const NVIDIA_ICD_FILES: [&str; 2] =
    ["/usr/share/vulkan/icd.d/nvidia_icd.json", "/etc/vulkan/icd.d/nvidia_icd.json"];

/// What to add to the no-adapter message where an NVIDIA Vulkan driver is installed
/// (`nvidia`) and gave no adapter, and the loader was not pointed at a driver by hand
/// (`chosen`: `VK_ICD_FILENAMES` or `VK_DRIVER_FILES` set). The manifest names the
/// driver's GLX library, which does not start on a machine without a display (the loader
/// then says it "could not get 'vkCreateInstance'"); the driver's EGL library carries the
/// same Vulkan driver and does.
fn nvidia_hint(nvidia: bool, chosen: bool) -> Option<&'static str> {
    (nvidia && !chosen).then_some(
        "; an NVIDIA driver is installed: on a machine without a display, point the Vulkan \
         loader at its EGL library instead of its GLX one, with a file holding \
         {\"file_format_version\":\"1.0.0\",\"ICD\":{\"library_path\":\"libEGL_nvidia.so.0\",\"api_version\":\"1.3\"}} \
         named in VK_ICD_FILENAMES",
    )
}

/// An adapter, its device and queue.
#[derive(Debug, Clone)]
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
    /// A `Gpu` on an application's own handles (wgpu's are cheap clones of shared ones):
    /// the renderer then creates its buffers, textures and pipelines on the application's
    /// device, writes through its queue, and draws into its encoders
    /// ([`Renderer::encode_over`](crate::Renderer::encode_over)).
    pub fn from_host(
        instance: &wgpu::Instance,
        adapter: &wgpu::Adapter,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Gpu {
        Gpu {
            instance: instance.clone(),
            adapter: adapter.clone(),
            device: device.clone(),
            queue: queue.clone(),
        }
    }

    /// Open the best adapter (a surface, when given, must be presentable by it).
    pub fn new(
        instance: wgpu::Instance,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Gpu, RenderError> {
        Gpu::open(instance, surface, |_| {})
    }

    /// An offscreen adapter whose device allows storage bindings of at most `max_binding`
    /// bytes (to exercise what a smaller GPU would impose).
    pub fn headless_limited(max_binding: u64) -> Result<Gpu, RenderError> {
        Gpu::headless_with_limits(|limits| {
            limits.max_storage_buffer_binding_size =
                limits.max_storage_buffer_binding_size.min(max_binding);
        })
    }

    /// An offscreen adapter whose device has the adapter's limits as `adjust` lowers them
    /// (to exercise what a smaller device imposes: with no storage buffers in vertex
    /// shaders, as on WebGL2, the renderer keeps its palettes in a texture).
    pub fn headless_with_limits(
        adjust: impl FnOnce(&mut wgpu::Limits),
    ) -> Result<Gpu, RenderError> {
        Gpu::open(Gpu::instance(), None, adjust)
    }

    fn open(
        instance: wgpu::Instance,
        surface: Option<&wgpu::Surface<'_>>,
        adjust: impl FnOnce(&mut wgpu::Limits),
    ) -> Result<Gpu, RenderError> {
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: surface,
            apply_limit_buckets: false,
        }))
        .map_err(|e| {
            let nvidia = NVIDIA_ICD_FILES.iter().any(|f| std::path::Path::new(f).exists());
            let chosen = std::env::var_os("VK_ICD_FILENAMES").is_some()
                || std::env::var_os("VK_DRIVER_FILES").is_some();
            RenderError::NoAdapter(format!("{e}{}", nvidia_hint(nvidia, chosen).unwrap_or("")))
        })?;
        let mut limits = adapter.limits();
        adjust(&mut limits);
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("sylva"),
            // Timestamps where the adapter has them, for `Renderer::time_passes`.
            required_features: adapter.features() & crate::passtimes::PassTimes::FEATURES,
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

#[cfg(test)]
mod tests {
    use super::nvidia_hint;

    #[test]
    fn an_installed_nvidia_driver_that_gave_no_adapter_is_pointed_at_its_egl_library() {
        let hint = nvidia_hint(true, false).expect("a hint where NVIDIA's driver is installed");
        assert!(hint.contains("libEGL_nvidia.so.0") && hint.contains("VK_ICD_FILENAMES"));
        // Without NVIDIA's driver, or with a driver already chosen by hand, no hint.
        assert_eq!(nvidia_hint(false, false), None);
        assert_eq!(nvidia_hint(true, true), None);
    }
}
