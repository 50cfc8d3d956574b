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
use sylva_render::{Gpu, Renderer, host_depth_state, wgpu};
use wgpu::{LoadOp, Operations, StoreOp};
use winit::{application::ApplicationHandler, event::ElementState, event::WindowEvent};
use winit::{event_loop::ActiveEventLoop, event_loop::EventLoop, keyboard::KeyCode};
use winit::{keyboard::PhysicalKey, window::Window, window::WindowId};

/// The host's own object: a pillar 3 m square and 16 m tall, among the trees.
pub const PILLAR: ([f32; 3], [f32; 3]) = ([4.0, 2.0, -1.0], [7.0, 5.0, 15.0]);

/// The pillar's shader: a box from `lo` to `hi` drawn as one strip of 14 corners picked
/// from the vertex index's bits, each face shaded by its normal.
fn shader() -> String {
    let ((lo, hi), v) = (PILLAR, |p: [f32; 3]| format!("vec3({:?}, {:?}, {:?})", p[0], p[1], p[2]));
    format!(
        "@group(0) @binding(0) var<uniform> view_proj: mat4x4<f32>;
struct Out {{ @builtin(position) pos: vec4<f32>, @location(0) p: vec3<f32> }};
@vertex fn vs(@builtin(vertex_index) i: u32) -> Out {{
    let b = 1u << i;
    let p = mix({}, {}, vec3<f32>(vec3((0x287au & b) != 0u, (0x02afu & b) != 0u, (0x31e3u & b) != 0u)));
    return Out(view_proj * vec4(p, 1.0), p);
}}
@fragment fn fs(o: Out) -> @location(0) vec4<f32> {{
    let n = abs(normalize(cross(dpdx(o.p), dpdy(o.p))));
    let s = 0.3 + 0.3 * n.x + 0.6 * n.y;
    return vec4(s, 0.1, s, 1.0);
}}",
        v(lo),
        v(hi)
    )
}

/// Everything the host draws with: Sylva's forest; its pillar's pipeline, view–projection
/// uniform and their binding; its multisampled colour target (none without MSAA) and the
/// depth target it shares; its camera's orbit angle and wind gain; whether the pillar is
/// drawn (the test compares the frame without it).
pub(crate) struct Scene {
    pub(crate) gpu: Gpu,
    pub(crate) forest: Forest,
    pub(crate) frame: FrameData,
    pub(crate) renderer: Renderer,
    host: (wgpu::RenderPipeline, wgpu::Buffer, wgpu::BindGroup),
    targets: (Option<wgpu::TextureView>, wgpu::TextureView),
    angle: f32,
    gain: f32,
    pub(crate) pillar: bool,
}

impl Scene {
    pub(crate) fn new(gpu: Gpu, format: wgpu::TextureFormat, size: (u32, u32)) -> Scene {
        let forest = Forest::new(&SceneSpec::builtin("small").expect("scene")).expect("forest");
        let renderer =
            Renderer::for_forest(&gpu, &forest, format, size.0, size.1).expect("renderer");
        let dev = &gpu.device;
        let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("pillar"),
            source: wgpu::ShaderSource::Wgsl(shader().into()),
        });
        let pipeline = dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("pillar"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(format.into())],
            }),
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleStrip,
                ..Default::default()
            },
            depth_stencil: Some(host_depth_state()),
            multisample: wgpu::MultisampleState { count: renderer.samples(), ..Default::default() },
            multiview_mask: None,
            cache: None,
        });
        let usage = wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST;
        let desc =
            wgpu::BufferDescriptor { label: None, size: 64, usage, mapped_at_creation: false };
        let uniform = dev.create_buffer(&desc);
        let bind = dev.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("pillar"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() }],
        });
        let targets = renderer.host_targets(&gpu, size.0, size.1);
        let (frame, host) = (FrameData::with_rows(size.1), (pipeline, uniform, bind));
        Scene { gpu, forest, frame, renderer, host, targets, angle: 0.0, gain: 1.0, pillar: true }
    }

    /// The host's camera: an orbit about the forest's middle.
    pub(crate) fn camera(&self) -> Camera {
        let (s, c) = (self.angle - 2.3).sin_cos();
        let eye = [40.0 * c, 40.0 * s, 9.0];
        Camera { eye, target: [0.0, 0.0, 7.0], ..self.forest.default_camera() }
    }

    /// Step the forest by `dt` s and draw the frame into `target`: the pillar first, onto the
    /// host's colour and depth, then the forest over them.
    pub(crate) fn draw(&mut self, dt: f32, target: &wgpu::TextureView) -> wgpu::SubmissionIndex {
        self.forest.set_wind_control(self.gain, 0.0);
        self.forest.step(dt);
        let ((w, h), camera) = (self.renderer.size(), self.camera());
        let aspect = w as f32 / h as f32;
        self.forest.frame(&camera, aspect, &mut self.frame);
        let vp = camera.view_projection(aspect);
        let bytes: Vec<u8> = vp.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
        self.gpu.queue.write_buffer(&self.host.1, 0, &bytes);
        let (color, resolve) =
            self.targets.0.as_ref().map_or((target, None), |m| (m, Some(target)));
        let depth = &self.targets.1;
        let mut enc = self.gpu.device.create_command_encoder(&Default::default());
        {
            let clear =
                Operations { load: LoadOp::Clear(wgpu::Color::BLACK), store: StoreOp::Store };
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: color,
                    depth_slice: None,
                    resolve_target: None,
                    ops: clear,
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: depth,
                    depth_ops: Some(Operations { load: LoadOp::Clear(1.0), store: StoreOp::Store }),
                    stencil_ops: None,
                }),
                ..Default::default()
            });
            pass.set_pipeline(&self.host.0);
            pass.set_bind_group(0, &self.host.2, &[]);
            pass.draw(0..if self.pillar { 14 } else { 0 }, 0..1);
        }
        let (gpu, frame) = (&self.gpu, &self.frame);
        self.renderer.encode_over(gpu, &mut enc, frame, &camera, (color, resolve), depth);
        self.gpu.queue.submit([enc.finish()])
    }
}

/// The host's window: its surface and the scene drawn into it.
#[derive(Default)]
struct App {
    window: Option<(Arc<Window>, wgpu::Surface<'static>, Scene)>,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        let None = self.window else { return };
        let attributes = Window::default_attributes().with_title("embed");
        let window = Arc::new(el.create_window(attributes).expect("window"));
        let instance = wgpu::Instance::default();
        let surface = instance.create_surface(window.clone()).expect("surface");
        let gpu = open(&instance, Some(&surface));
        let size = window.inner_size();
        let (w, h) = (size.width.max(1), size.height.max(1));
        let config = surface.get_default_config(&gpu.adapter, w, h).expect("config");
        surface.configure(&gpu.device, &config);
        let scene = Scene::new(gpu, config.format, (config.width, config.height));
        self.window = Some((window, surface, scene));
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some((window, surface, scene)) = self.window.as_mut() else { return };
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
                if let wgpu::CurrentSurfaceTexture::Success(f) = surface.get_current_texture() {
                    scene.draw(1.0 / 60.0, &f.texture.create_view(&Default::default()));
                    scene.gpu.queue.present(f);
                }
                window.request_redraw();
            }
            _ => {}
        }
    }
}

/// The host's own adapter and device (on `surface`'s adapter where there is one), lent to
/// Sylva as a [`Gpu`].
pub fn open(instance: &wgpu::Instance, surface: Option<&wgpu::Surface<'_>>) -> Gpu {
    let options = wgpu::RequestAdapterOptions { compatible_surface: surface, ..Default::default() };
    let adapter = pollster::block_on(instance.request_adapter(&options)).expect("an adapter");
    let desc = wgpu::DeviceDescriptor { required_limits: adapter.limits(), ..Default::default() };
    let (device, queue) = pollster::block_on(adapter.request_device(&desc)).expect("a device");
    Gpu::from_host(instance, &adapter, &device, &queue)
}

/// Offscreen: `frames` frames of 1/30 s drawn into a texture of the host's, the last one
/// read back as RGBA8, rows top first.
pub fn offscreen(size: (u32, u32), frames: usize, pillar: bool) -> Vec<u8> {
    let format = wgpu::TextureFormat::Rgba8UnormSrgb;
    let mut scene = Scene::new(open(&wgpu::Instance::default(), None), format, size);
    scene.pillar = pillar;
    let target = sylva_render::capture_texture(&scene.gpu.device, size, format, "host");
    let view = target.create_view(&Default::default());
    for _ in 0..frames {
        scene.draw(1.0 / 30.0, &view);
    }
    sylva_render::read_texture(&scene.gpu, &target).expect("read back")
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(i) = args.iter().position(|a| a == "--png") {
        let ((w, h), frames) = ((512, 384), 30);
        let rgba = offscreen((w, h), frames, true);
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
