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
pub const PILLAR: ([f32; 3], [f32; 3]) = ([4.0, 2.0, -1.0], [7.0, 5.0, 15.0]);
/// The pillar's shader: its 36 corners from the vertex index (face, triangle corner), a
/// box from `lo` to `hi`, each face shaded by its index.
fn shader() -> String {
    let ((lo, hi), v) = (PILLAR, |p: [f32; 3]| format!("vec3({:?}, {:?}, {:?})", p[0], p[1], p[2]));
    format!(
        "@group(0) @binding(0) var<uniform> view_proj: mat4x4<f32>;
struct Out {{ @builtin(position) pos: vec4<f32>, @location(0) shade: f32 }};
@vertex fn vs(@builtin(vertex_index) i: u32) -> Out {{
    var faces = array(vec4(0u, 1u, 3u, 2u), vec4(4u, 6u, 7u, 5u), vec4(0u, 4u, 5u, 1u),
                      vec4(2u, 3u, 7u, 6u), vec4(0u, 2u, 6u, 4u), vec4(1u, 5u, 7u, 3u));
    var corner = array(0u, 1u, 2u, 0u, 2u, 3u);
    let c = faces[i / 6u][corner[i % 6u]];
    let p = mix({}, {}, vec3<f32>(vec3(c & 1u, (c >> 1u) & 1u, c >> 2u)));
    return Out(view_proj * vec4(p, 1.0), 0.3 + 0.13 * f32(i / 6u));
}}
@fragment fn fs(o: Out) -> @location(0) vec4<f32> {{ return vec4(o.shade, 0.1, o.shade, 1.0); }}",
        v(lo),
        v(hi)
    )
}

/// Everything the host draws with: its pillar, its targets, and Sylva's forest.
struct Scene {
    gpu: Gpu,
    forest: Forest,
    frame: FrameData,
    renderer: Renderer,
    pipeline: wgpu::RenderPipeline,
    uniform: wgpu::Buffer,
    bind: wgpu::BindGroup,
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
        let uniform = dev.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: 64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind = dev.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("pillar"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() }],
        });
        let targets = renderer.host_targets(&gpu, size.0, size.1);
        let frame = FrameData::with_rows(size.1);
        Scene {
            gpu,
            forest,
            frame,
            renderer,
            pipeline,
            uniform,
            bind,
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
                ..Default::default()
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.bind, &[]);
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

/// Corner `i` of the pillar (bit 0: x, bit 1: y, bit 2: z at the high side).
pub fn corner(i: usize) -> [f32; 3] {
    let (lo, hi) = PILLAR;
    std::array::from_fn(|k| if i >> k & 1 == 0 { lo[k] } else { hi[k] })
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
pub fn offscreen(size: (u32, u32), frames: usize, pillar: bool) -> Vec<u8> {
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
    sylva_render::read_texture(&scene.gpu, &target).expect("read back")
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
