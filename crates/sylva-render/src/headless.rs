//! Offscreen rendering to RGBA8 images.

use sylva_forest::{Camera, Forest, FrameData};

use crate::gpu::{Gpu, RenderError};
use crate::renderer::Renderer;

/// A renderer with its own offscreen target and read-back buffer.
#[derive(Debug)]
pub struct Headless {
    /// Adapter, device and queue.
    pub gpu: Gpu,
    renderer: Renderer,
    target: wgpu::Texture,
    view: wgpu::TextureView,
    readback: wgpu::Buffer,
    width: u32,
    height: u32,
    padded_row: u32,
}

/// Colour format of captured frames (sRGB-encoded RGBA8).
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

impl Headless {
    /// Open an adapter and prepare to draw `forest` at `width × height`.
    pub fn new(forest: &Forest, width: u32, height: u32) -> Result<Headless, RenderError> {
        Headless::with_gpu(Gpu::headless()?, forest, width, height)
    }

    /// Prepare to draw `forest` at `width × height` on `gpu` (e.g. one opened with
    /// [`Gpu::headless_limited`]).
    pub fn with_gpu(
        gpu: Gpu,
        forest: &Forest,
        width: u32,
        height: u32,
    ) -> Result<Headless, RenderError> {
        let max = gpu.device.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(RenderError::Size(width, height, max));
        }
        let renderer = Renderer::for_forest(&gpu, forest, FORMAT, width, height)?;
        let target = capture_texture(&gpu.device, (width, height), FORMAT, "capture");
        let view = target.create_view(&wgpu::TextureViewDescriptor::default());
        let padded_row = (width * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let readback = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: (padded_row * height) as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        Ok(Headless { gpu, renderer, target, view, readback, width, height, padded_row })
    }

    /// The renderer (sample count, format).
    pub fn renderer(&self) -> &Renderer {
        &self.renderer
    }

    /// The renderer, to change its settings (lighting, overlay).
    pub fn renderer_mut(&mut self) -> &mut Renderer {
        &mut self.renderer
    }

    /// Draw `frame` from `camera` and return the image, RGBA8 rows top first.
    pub fn render(&mut self, frame: &FrameData, camera: &Camera) -> Result<Vec<u8>, RenderError> {
        self.render_with(frame, camera, |_, _| {})
    }

    /// Colour format of the captured image (sRGB RGBA8), for passes drawn over it.
    pub fn format(&self) -> wgpu::TextureFormat {
        FORMAT
    }

    /// As [`render`](Self::render), with `overlay` drawing over the finished frame (as the
    /// viewer's panel does) before it is read back.
    pub fn render_with(
        &mut self,
        frame: &FrameData,
        camera: &Camera,
        overlay: impl FnOnce(&Gpu, &wgpu::TextureView),
    ) -> Result<Vec<u8>, RenderError> {
        self.renderer.render(&self.gpu, frame, camera, &self.view);
        overlay(&self.gpu, &self.view);
        self.read_back()
    }

    /// Draw `frame` from `camera` over what a host draws first, as an application that owns
    /// the frame does, and return the image: `host` records its own passes into the
    /// encoder it is given, onto a colour target (the renderer's format and sample count)
    /// and a depth target ([`DEPTH`](crate::DEPTH), same samples) that it must
    /// clear; the forest is then recorded over them with [`Renderer::encode_over`], so the
    /// host's objects and the trees hide each other, and the result is resolved into the
    /// capture target.
    pub fn render_over(
        &mut self,
        frame: &FrameData,
        camera: &Camera,
        host: impl FnOnce(&Gpu, &mut wgpu::CommandEncoder, &wgpu::TextureView, &wgpu::TextureView),
    ) -> Result<Vec<u8>, RenderError> {
        // Targets as the renderer makes its own: the host's, here.
        let samples = self.renderer.samples();
        let (msaa, depth) =
            crate::renderer::targets(&self.gpu.device, FORMAT, samples, self.width, self.height);
        let (color, resolve) = match &msaa {
            Some(m) => (m, Some(&self.view)),
            None => (&self.view, None),
        };
        let mut enc = self
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("host") });
        host(&self.gpu, &mut enc, color, &depth);
        self.renderer.encode_over(&self.gpu, &mut enc, frame, camera, (color, resolve), &depth);
        self.gpu.queue.submit([enc.finish()]);
        self.read_back()
    }

    /// Draw `frame` from `camera` and wait until the GPU has finished it, without reading
    /// it back: what an interactive frame costs before presentation (benchmarks time this;
    /// [`read_back`](Self::read_back) then fetches the image when one is wanted).
    pub fn draw(&mut self, frame: &FrameData, camera: &Camera) -> Result<(), RenderError> {
        let index = self.submit(frame, camera);
        self.wait(index)
    }

    /// Start drawing `frame` from `camera` and return without waiting: the CPU may build
    /// the next frame while the GPU draws this one, as an interactive loop does
    /// ([`wait`](Self::wait) for it before reading anything back).
    pub fn submit(&mut self, frame: &FrameData, camera: &Camera) -> wgpu::SubmissionIndex {
        self.renderer.render(&self.gpu, frame, camera, &self.view)
    }

    /// Wait until the GPU has finished the submission `index` (and all before it).
    pub fn wait(&self, index: wgpu::SubmissionIndex) -> Result<(), RenderError> {
        self.gpu
            .device
            .poll(wgpu::PollType::Wait { submission_index: Some(index), timeout: None })
            .map_err(|e| RenderError::Wait(e.to_string()))?;
        Ok(())
    }

    /// Time each part of every frame on the GPU ([`Renderer::time_passes`]); false where
    /// the device cannot.
    pub fn time_passes(&mut self) -> bool {
        self.renderer.time_passes(&self.gpu)
    }

    /// The GPU's time (ms) in each part of the last frame drawn ([`Renderer::pass_times`]).
    pub fn pass_times(&self) -> Result<Option<[f64; crate::PASS_PARTS.len()]>, RenderError> {
        self.renderer.pass_times(&self.gpu)
    }

    /// The image last drawn, RGBA8 rows top first.
    pub fn read_back(&mut self) -> Result<Vec<u8>, RenderError> {
        copy_out(&self.gpu, &self.target, &self.readback, self.padded_row)
    }
}

/// A single-sampled texture of `size` pixels to draw into and read back
/// ([`read_texture`]): a render attachment that copies out.
pub fn capture_texture(
    device: &wgpu::Device,
    (width, height): (u32, u32),
    format: wgpu::TextureFormat,
    label: &str,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

/// An RGBA8 texture's texels (a host's own target, `COPY_SRC`), rows top first: copied to
/// a buffer of its own and read back, waiting for the GPU.
pub fn read_texture(gpu: &Gpu, texture: &wgpu::Texture) -> Result<Vec<u8>, RenderError> {
    let row = (texture.width() * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read texture"),
        size: u64::from(row) * u64::from(texture.height()),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    copy_out(gpu, texture, &buffer, row)
}

/// Copy `texture` into `buffer` (rows `padded_row` bytes apart) and read it back.
fn copy_out(
    gpu: &Gpu,
    texture: &wgpu::Texture,
    buffer: &wgpu::Buffer,
    padded_row: u32,
) -> Result<Vec<u8>, RenderError> {
    let (width, height) = (texture.width(), texture.height());
    let mut enc =
        gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("copy") });
    enc.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded_row),
                rows_per_image: Some(height),
            },
        },
        wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
    );
    gpu.queue.submit([enc.finish()]);
    map_rows(gpu, buffer, width, padded_row)
}

/// Wait for the GPU, map `buffer` and read its rows (`padded_row` bytes apart) of `width`
/// RGBA8 texels each, unpadded; the buffer is unmapped again.
pub(crate) fn map_rows(
    gpu: &Gpu,
    buffer: &wgpu::Buffer,
    width: u32,
    padded_row: u32,
) -> Result<Vec<u8>, RenderError> {
    pollster::block_on(map_rows_async(gpu, buffer, width, padded_row))
}

/// [`map_rows`] as a future: natively it is ready at once (the device is polled until the
/// mapping is done); on the web it is ready once the browser has mapped the buffer, the
/// page's event loop running meanwhile.
pub(crate) async fn map_rows_async(
    gpu: &Gpu,
    buffer: &wgpu::Buffer,
    width: u32,
    padded_row: u32,
) -> Result<Vec<u8>, RenderError> {
    let slice = buffer.slice(..);
    let (done, mapped) = crate::oneshot::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| done.send(r));
    #[cfg(not(target_arch = "wasm32"))]
    {
        gpu.device
            .poll(wgpu::PollType::Wait { submission_index: None, timeout: None })
            .map_err(|e| RenderError::Readback(e.to_string()))?;
        mapped.await.map_err(|e| RenderError::Readback(e.to_string()))?;
    }
    // The page cannot block: poll, and give the browser a turn until the mapping is done
    // (WebGPU maps on its own; WebGL2 through wgpu's polling of its fences).
    #[cfg(target_arch = "wasm32")]
    loop {
        let _ = gpu.device.poll(wgpu::PollType::Poll);
        if let Some(r) = mapped.try_take() {
            r.map_err(|e| RenderError::Readback(e.to_string()))?;
            break;
        }
        crate::oneshot::next_task().await;
    }
    let mut out =
        Vec::with_capacity((width * 4) as usize * (buffer.size() / u64::from(padded_row)) as usize);
    {
        let data = slice.get_mapped_range().map_err(|e| RenderError::Readback(e.to_string()))?;
        for row in data.chunks(padded_row as usize) {
            out.extend_from_slice(&row[..(width * 4) as usize]);
        }
    }
    buffer.unmap();
    Ok(out)
}
