//! A program of its own with a Sylva forest in its frame: it owns the wgpu device, the
//! frame loop and the depth buffer, draws a pillar of its own among the trees, orbits its
//! own camera and turns the wind up and down from its own keys.
//!
//!     cargo run --release -p sylva-render --example embed                  # a window
//!     cargo run --release -p sylva-render --example embed -- --png out.png # offscreen
//!
//! Keys: ← → orbit, W / S wind stronger / weaker, Esc quits.

use std::sync::Arc;

use sylva_forest::{Camera, Forest, FrameData, SceneSpec};
use sylva_render::{DEPTH, Gpu, Renderer, wgpu};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

/// The host's own object: a pillar 3 m square and 16 m tall, among the trees.
const PILLAR: ([f32; 3], [f32; 3]) = ([4.0, 2.0, -1.0], [7.0, 5.0, 15.0]);
const SHADER: &str = "
@group(0) @binding(0) var<uniform> view_proj: mat4x4<f32>;
struct Out { @builtin(position) pos: vec4<f32>, @location(0) shade: f32 };
@vertex fn vs(@location(0) p: vec3<f32>, @location(1) shade: f32) -> Out {
    return Out(view_proj * vec4(p, 1.0), shade);
}
@fragment fn fs(o: Out) -> @location(0) vec4<f32> { return vec4(o.shade, 0.1, o.shade, 1.0); }";

/// Everything the host draws with: its pillar, its targets, and Sylva's forest.
struct Scene {
    gpu: Gpu,
    forest: Forest,
    frame: FrameData,
    renderer: Renderer,
    pipeline: wgpu::RenderPipeline,
    uniform: wgpu::Buffer,
    bind: wgpu::BindGroup,
    vertices: wgpu::Buffer,
    targets: (Option<wgpu::TextureView>, wgpu::TextureView),
    size: (u32, u32),
    angle: f32,
    gain: f32,
    /// Whether the pillar is drawn (the test compares the frame without it).
    pillar: bool,
}

impl Scene {
    fn new(gpu: Gpu, format: wgpu::TextureFormat, size: (u32, u32)) -> Scene {
        let forest = Forest::new(&SceneSpec::builtin("small").expect("scene")).expect("forest");
        let renderer =
            Renderer::for_forest(&gpu, &forest, format, size.0, size.1).expect("renderer");
        let dev = &gpu.device;
        let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("pillar"),
            source: wgpu::ShaderSource::Wgsl(SHADER.into()),
        });
        let vertex = wgpu::VertexBufferLayout {
            array_stride: 16,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32],
        };
        let pipeline = dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("pillar"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[Some(vertex)],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(format.into())],
            }),
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: wgpu::MultisampleState { count: renderer.samples(), ..Default::default() },
            multiview_mask: None,
            cache: None,
        });
        let uniform = buffer(dev, &[0u8; 64], wgpu::BufferUsages::UNIFORM);
        let bind = dev.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("pillar"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() }],
        });
        let vertices = buffer(dev, &pillar_triangles(), wgpu::BufferUsages::VERTEX);
        let targets = targets(&gpu, format, renderer.samples(), size);
        let frame = FrameData::with_rows(size.1);
        Scene {
            gpu,
            forest,
            frame,
            renderer,
            pipeline,
            uniform,
            bind,
            vertices,
            targets,
            size,
            angle: 0.0,
            gain: 1.0,
            pillar: true,
        }
    }

    /// The host's camera: an orbit about the forest's middle.
    fn camera(&self) -> Camera {
        let (s, c) = (self.angle - 2.3).sin_cos();
        Camera {
            eye: [40.0 * c, 40.0 * s, 9.0],
            target: [0.0, 0.0, 7.0],
            ..self.forest.default_camera()
        }
    }

    /// Step the forest by `dt` s and draw the frame into `target`: the pillar first, onto the
    /// host's colour and depth, then the forest over them.
    fn draw(&mut self, dt: f32, target: &wgpu::TextureView) {
        self.forest.set_wind_control(self.gain, 0.0);
        self.forest.step(dt);
        let camera = self.camera();
        let aspect = self.size.0 as f32 / self.size.1 as f32;
        self.forest.frame(&camera, aspect, &mut self.frame);
        let vp = camera.view_projection(aspect);
        let bytes: Vec<u8> = vp.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
        self.gpu.queue.write_buffer(&self.uniform, 0, &bytes);
        let (color, resolve) = match &self.targets.0 {
            Some(m) => (m, Some(target)),
            None => (target, None),
        };
        let dev = &self.gpu.device;
        let mut enc =
            dev.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("host") });
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("pillar"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: color,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.targets.1,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.bind, &[]);
            pass.set_vertex_buffer(0, self.vertices.slice(..));
            pass.draw(0..if self.pillar { 36 } else { 0 }, 0..1);
        }
        let depth = &self.targets.1;
        self.renderer.encode_over(
            &self.gpu,
            &mut enc,
            &self.frame,
            &camera,
            (color, resolve),
            depth,
        );
        self.gpu.queue.submit([enc.finish()]);
    }
}

/// The pillar's 12 triangles: (position, shade) per vertex, sides shaded by facing.
fn pillar_triangles() -> Vec<u8> {
    let (lo, hi) = PILLAR;
    let corner = |i: usize| {
        [
            if i & 1 == 0 { lo[0] } else { hi[0] },
            if i & 2 == 0 { lo[1] } else { hi[1] },
            if i & 4 == 0 { lo[2] } else { hi[2] },
        ]
    };
    let faces: [([usize; 4], f32); 6] = [
        ([0, 1, 3, 2], 0.3),
        ([4, 6, 7, 5], 1.0),
        ([0, 4, 5, 1], 0.6),
        ([2, 3, 7, 6], 0.8),
        ([0, 2, 6, 4], 0.5),
        ([1, 5, 7, 3], 0.9),
    ];
    let mut out = Vec::new();
    for (q, shade) in faces {
        for k in [0, 1, 2, 0, 2, 3] {
            for v in corner(q[k]).into_iter().chain([shade]) {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    out
}

fn buffer(dev: &wgpu::Device, bytes: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    let b = dev.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: bytes.len() as u64,
        usage: usage | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: true,
    });
    b.slice(..).get_mapped_range_mut().expect("mapped at creation").copy_from_slice(bytes);
    b.unmap();
    b
}

fn targets(
    gpu: &Gpu,
    format: wgpu::TextureFormat,
    samples: u32,
    (w, h): (u32, u32),
) -> (Option<wgpu::TextureView>, wgpu::TextureView) {
    let make = |format| {
        gpu.device
            .create_texture(&wgpu::TextureDescriptor {
                label: None,
                size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: samples,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                view_formats: &[],
            })
            .create_view(&wgpu::TextureViewDescriptor::default())
    };
    ((samples > 1).then(|| make(format)), make(DEPTH))
}

/// The host's window: its surface and the scene drawn into it.
#[derive(Default)]
struct App {
    window: Option<(Arc<Window>, wgpu::Surface<'static>, wgpu::SurfaceConfiguration, Scene)>,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        let window = Arc::new(
            el.create_window(Window::default_attributes().with_title("embed")).expect("window"),
        );
        let instance = wgpu::Instance::default();
        let surface = instance.create_surface(window.clone()).expect("surface");
        let (adapter, device, queue) = open(&instance, Some(&surface));
        let size = window.inner_size();
        let config = surface
            .get_default_config(&adapter, size.width.max(1), size.height.max(1))
            .expect("config");
        surface.configure(&device, &config);
        let gpu = Gpu::from_host(&instance, &adapter, &device, &queue);
        let scene = Scene::new(gpu, config.format, (config.width, config.height));
        self.window = Some((window, surface, config, scene));
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some((window, surface, _, scene)) = self.window.as_mut() else { return };
        match event {
            WindowEvent::CloseRequested => el.exit(),
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                match event.physical_key {
                    PhysicalKey::Code(KeyCode::ArrowLeft) => scene.angle -= 0.1,
                    PhysicalKey::Code(KeyCode::ArrowRight) => scene.angle += 0.1,
                    PhysicalKey::Code(KeyCode::KeyW) => scene.gain *= 1.25,
                    PhysicalKey::Code(KeyCode::KeyS) => scene.gain /= 1.25,
                    PhysicalKey::Code(KeyCode::Escape) => el.exit(),
                    _ => {}
                }
            }
            WindowEvent::RedrawRequested => {
                let wgpu::CurrentSurfaceTexture::Success(frame) = surface.get_current_texture()
                else {
                    return;
                };
                let view = frame.texture.create_view(&wgpu::TextureViewDescriptor::default());
                scene.draw(1.0 / 60.0, &view);
                scene.gpu.queue.present(frame);
                window.request_redraw();
            }
            _ => {}
        }
    }
}

/// The host's own adapter and device (on `surface`'s adapter where there is one).
fn open(
    instance: &wgpu::Instance,
    surface: Option<&wgpu::Surface<'_>>,
) -> (wgpu::Adapter, wgpu::Device, wgpu::Queue) {
    let options = wgpu::RequestAdapterOptions { compatible_surface: surface, ..Default::default() };
    let adapter = pollster::block_on(instance.request_adapter(&options)).expect("an adapter");
    let limits = adapter.limits();
    let desc = wgpu::DeviceDescriptor { required_limits: limits, ..Default::default() };
    let (device, queue) = pollster::block_on(adapter.request_device(&desc)).expect("a device");
    (adapter, device, queue)
}

/// Offscreen: `frames` frames of 1/30 s drawn into a texture of the host's, the last one
/// read back as RGBA8, rows top first.
fn offscreen(size: (u32, u32), frames: usize, pillar: bool) -> Vec<u8> {
    let instance = wgpu::Instance::default();
    let (adapter, device, queue) = open(&instance, None);
    let gpu = Gpu::from_host(&instance, &adapter, &device, &queue);
    let format = wgpu::TextureFormat::Rgba8UnormSrgb;
    let mut scene = Scene::new(gpu, format, size);
    scene.pillar = pillar;
    let target = device.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let view = target.create_view(&wgpu::TextureViewDescriptor::default());
    for _ in 0..frames {
        scene.draw(1.0 / 30.0, &view);
    }
    let row = (size.0 * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let read = buffer(&device, &vec![0; (row * size.1) as usize], wgpu::BufferUsages::MAP_READ);
    let mut enc = device.create_command_encoder(&Default::default());
    enc.copy_texture_to_buffer(
        target.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &read,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: None,
            },
        },
        wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
    );
    queue.submit([enc.finish()]);
    read.slice(..).map_async(wgpu::MapMode::Read, |r| r.expect("map"));
    device.poll(wgpu::PollType::Wait { submission_index: None, timeout: None }).expect("poll");
    let data = read.slice(..).get_mapped_range().expect("mapped");
    data.chunks(row as usize).flat_map(|r| r[..(size.0 * 4) as usize].to_vec()).collect()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(i) = args.iter().position(|a| a == "--png") {
        let (w, h) = (512, 384);
        let rgba = offscreen((w, h), 30, true);
        let path = args.get(i + 1).map_or("embed.png", String::as_str);
        let mut e = png::Encoder::new(std::fs::File::create(path).expect("png file"), w, h);
        e.set_color(png::ColorType::Rgba);
        e.write_header().and_then(|mut w| w.write_image_data(&rgba)).expect("png");
        println!("wrote {path}");
        return;
    }
    let event_loop = EventLoop::new().expect("an event loop (a display)");
    event_loop.run_app(&mut App::default()).expect("event loop");
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pillar and the trees hide each other: within the pillar's image some pixels are
    /// the pillar's and some are the forest's own (trees and ground in front of it), the
    /// same as in the frame drawn without the pillar.
    #[test]
    fn the_hosts_pillar_and_the_trees_hide_each_other() {
        let (w, h) = (256u32, 192u32);
        let (with, without) = (offscreen((w, h), 3, true), offscreen((w, h), 3, false));
        let scene_camera = Camera {
            eye: [40.0 * (-2.3f32).cos(), 40.0 * (-2.3f32).sin(), 9.0],
            target: [0.0, 0.0, 7.0],
            ..Forest::new(&SceneSpec::builtin("small").expect("scene"))
                .expect("forest")
                .default_camera()
        };
        let vp = scene_camera.view_projection(w as f32 / h as f32);
        let (lo, hi) = PILLAR;
        let (mut x0, mut x1, mut y0, mut y1) = (f32::MAX, f32::MIN, f32::MAX, f32::MIN);
        for i in 0..8 {
            let p = [
                if i & 1 == 0 { lo[0] } else { hi[0] },
                if i & 2 == 0 { lo[1] } else { hi[1] },
                if i & 4 == 0 { lo[2] } else { hi[2] },
            ];
            let c: Vec<f32> =
                (0..4).map(|r| (0..3).map(|k| vp[k][r] * p[k]).sum::<f32>() + vp[3][r]).collect();
            let (x, y) =
                ((c[0] / c[3] + 1.0) * 0.5 * w as f32, (1.0 - c[1] / c[3]) * 0.5 * h as f32);
            (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
        }
        let (mut pillar, mut forest, mut n) = (0, 0, 0);
        for y in y0.max(0.0) as u32 + 1..(y1 as u32).min(h - 1) {
            for x in x0.max(0.0) as u32 + 1..(x1 as u32).min(w - 1) {
                let i = ((y * w + x) * 4) as usize;
                let (a, b) = (&with[i..i + 3], &without[i..i + 3]);
                n += 1;
                let g = 2 * a[1].max(8) as u32;
                pillar += (a[0] as u32 > g && a[2] as u32 > g) as usize;
                forest += (a == b) as usize;
            }
        }
        assert!(n > 100, "the pillar covers {n} pixels");
        assert!(
            pillar > n / 10 && forest > n / 20,
            "pillar {pillar}, forest in front {forest} of {n}"
        );
    }
}
