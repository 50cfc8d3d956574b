//! `sylva view`: a window onto a scene. Orbit with the left mouse button, zoom with the
//! wheel, move with W A S D (Q / E down / up); arrow keys change the wind live (↑ ↓ speed
//! ×1.25, ← → direction ∓15°); Space pauses. The title shows frames per second, trees drawn
//! of the total, triangles and the wind.

use std::sync::Arc;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use sylva_forest::{Camera, Forest, FrameData, SceneSpec};
use sylva_render::{Gpu, Renderer, wgpu};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

#[derive(Debug, Args)]
pub struct ViewArgs {
    /// Scene: a built-in name (small, A, B, C, D) or a scene file (.toml).
    #[arg(long, default_value = "A")]
    pub scene: String,
    /// Geometry-LOD threshold h₀ (see `sylva render --help`). Default: the scene's on a
    /// GPU, 3 on a software rasteriser such as lavapipe.
    #[arg(value_parser = crate::finite::<f32>, long)]
    pub lod_fraction: Option<f32>,
    /// Wind instead of the scene's: a preset (calm, breeze, strong, storm), a steady speed
    /// in m/s, or a wind file (.swf, .npy, .zarr).
    #[arg(long)]
    pub wind: Option<sylva_forest::WindSource>,
    #[command(flatten)]
    pub lod: crate::render::LodArgs,
}

/// Whether a window can be opened here (a display server is named in the environment).
pub fn display_available() -> bool {
    if cfg!(any(target_os = "windows", target_os = "macos")) {
        return true;
    }
    ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|s| !s.is_empty()))
}

struct Surface {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    gpu: Gpu,
    config: wgpu::SurfaceConfiguration,
    renderer: Renderer,
}

/// Orbit camera: yaw and pitch about a target, at a distance.
struct Orbit {
    target: [f32; 3],
    yaw: f32,
    pitch: f32,
    distance: f32,
    fov: f32,
    far: f32,
}

impl Orbit {
    fn from_camera(c: &Camera) -> Orbit {
        let d = [c.eye[0] - c.target[0], c.eye[1] - c.target[1], c.eye[2] - c.target[2]];
        let distance = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        Orbit {
            target: c.target,
            yaw: d[1].atan2(d[0]),
            pitch: (d[2] / distance).asin(),
            distance,
            fov: c.fov_deg,
            far: c.far,
        }
    }

    fn camera(&self) -> Camera {
        let (cp, sp) = (self.pitch.cos(), self.pitch.sin());
        let eye = [
            self.target[0] + self.distance * cp * self.yaw.cos(),
            self.target[1] + self.distance * cp * self.yaw.sin(),
            self.target[2] + self.distance * sp,
        ];
        Camera { eye, target: self.target, fov_deg: self.fov, near: 0.5, far: self.far }
    }
}

struct App {
    forest: Forest,
    frame: FrameData,
    orbit: Orbit,
    surface: Option<Surface>,
    error: Option<anyhow::Error>,
    held: std::collections::HashSet<KeyCode>,
    dragging: bool,
    cursor: Option<(f64, f64)>,
    last: Instant,
    fps: f32,
    paused: bool,
    lod_fraction: Option<f32>,
}

impl App {
    fn open(&mut self, el: &ActiveEventLoop) -> anyhow::Result<()> {
        let window = Arc::new(
            el.create_window(
                Window::default_attributes()
                    .with_title("sylva")
                    .with_inner_size(winit::dpi::LogicalSize::new(1280, 800)),
            )
            .context("opening a window")?,
        );
        let instance = Gpu::instance();
        let surface = instance.create_surface(window.clone()).context("creating a surface")?;
        let gpu = Gpu::new(instance, Some(&surface))?;
        let size = window.inner_size();
        let mut config = surface
            .get_default_config(&gpu.adapter, size.width.max(1), size.height.max(1))
            .context("the adapter cannot present to this window")?;
        let caps = surface.get_capabilities(&gpu.adapter);
        if let Some(f) = caps.formats.iter().find(|f| f.is_srgb()) {
            config.format = *f;
        }
        surface.configure(&gpu.device, &config);
        let software = gpu.adapter.get_info().device_type == wgpu::DeviceType::Cpu;
        let scene_h0 = self.forest.lod().fraction;
        let h0 = self.lod_fraction.unwrap_or(if software { 3.0 } else { scene_h0 });
        self.forest.set_lod_fraction(h0);
        let renderer =
            Renderer::for_forest(&gpu, &self.forest, config.format, config.width, config.height)?;
        println!("sylva view: {} ({}× MSAA)", gpu.describe(), renderer.samples());
        self.surface = Some(Surface { window, surface, gpu, config, renderer });
        Ok(())
    }

    fn redraw(&mut self) {
        let now = Instant::now();
        let dt = now.duration_since(self.last).as_secs_f32().min(0.2);
        self.last = now;
        let now_fps = 1.0 / dt.max(1e-4);
        self.fps = if self.fps == 0.0 { now_fps } else { 0.9 * self.fps + 0.1 * now_fps };
        // Movement in the ground plane, relative to the view.
        let speed = 0.8 * self.orbit.distance.max(10.0) * dt;
        let (fx, fy) = (-self.orbit.yaw.cos(), -self.orbit.yaw.sin());
        let mut mv = [0.0f32; 3];
        for k in &self.held {
            match k {
                KeyCode::KeyW => mv = [mv[0] + fx, mv[1] + fy, mv[2]],
                KeyCode::KeyS => mv = [mv[0] - fx, mv[1] - fy, mv[2]],
                KeyCode::KeyA => mv = [mv[0] - fy, mv[1] + fx, mv[2]],
                KeyCode::KeyD => mv = [mv[0] + fy, mv[1] - fx, mv[2]],
                KeyCode::KeyQ => mv[2] -= 1.0,
                KeyCode::KeyE => mv[2] += 1.0,
                _ => {}
            }
        }
        for (t, m) in self.orbit.target.iter_mut().zip(mv) {
            *t += m * speed;
        }
        if !self.paused {
            self.forest.step(dt);
        }
        let Some(s) = self.surface.as_mut() else { return };
        let camera = self.orbit.camera();
        let aspect = s.config.width as f32 / s.config.height as f32;
        self.forest.frame(&camera, aspect, &mut self.frame);
        let texture = match s.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                s.surface.configure(&s.gpu.device, &s.config);
                return;
            }
            _ => return,
        };
        let view = texture.texture.create_view(&wgpu::TextureViewDescriptor::default());
        s.renderer.render(&s.gpu, &self.frame, &camera, &view);
        s.gpu.queue.present(texture);
        let st = self.frame.stats;
        let w = self.frame.wind;
        let (gain, turn) = self.forest.wind_control();
        s.window.set_title(&format!(
            "sylva — {:.1} fps — {} of {} trees — {:.2} M triangles — wind {:.1} m/s ×{gain:.2} {turn:+.0}° — sim {:.1} ms{}",
            self.fps,
            st.drawn,
            st.trees,
            st.triangles as f64 / 1e6,
            (w[0] * w[0] + w[1] * w[1]).sqrt(),
            st.sim_ms,
            if self.paused { " — paused" } else { "" }
        ));
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.surface.is_none()
            && let Err(e) = self.open(el)
        {
            self.error = Some(e);
            el.exit();
        }
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => el.exit(),
            WindowEvent::Resized(size) => {
                if let Some(s) = self.surface.as_mut()
                    && size.width > 0
                    && size.height > 0
                {
                    s.config.width = size.width;
                    s.config.height = size.height;
                    s.surface.configure(&s.gpu.device, &s.config);
                    s.renderer.resize(&s.gpu, size.width, size.height);
                }
            }
            WindowEvent::KeyboardInput { event, .. } => {
                let PhysicalKey::Code(code) = event.physical_key else { return };
                if event.state == ElementState::Released {
                    self.held.remove(&code);
                    return;
                }
                self.held.insert(code);
                let (gain, turn) = self.forest.wind_control();
                match code {
                    KeyCode::Escape => el.exit(),
                    KeyCode::ArrowUp => self.forest.set_wind_control(gain * 1.25, turn),
                    KeyCode::ArrowDown => self.forest.set_wind_control(gain / 1.25, turn),
                    KeyCode::ArrowLeft => self.forest.set_wind_control(gain, turn + 15.0),
                    KeyCode::ArrowRight => self.forest.set_wind_control(gain, turn - 15.0),
                    KeyCode::Space if !event.repeat => self.paused = !self.paused,
                    _ => {}
                }
            }
            WindowEvent::MouseInput { state, button: MouseButton::Left, .. } => {
                self.dragging = state == ElementState::Pressed;
            }
            WindowEvent::CursorMoved { position, .. } => {
                if let Some((x, y)) = self.cursor
                    && self.dragging
                {
                    self.orbit.yaw -= 0.005 * (position.x - x) as f32;
                    self.orbit.pitch =
                        (self.orbit.pitch + 0.005 * (position.y - y) as f32).clamp(-0.1, 1.5);
                }
                self.cursor = Some((position.x, position.y));
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                self.orbit.distance = (self.orbit.distance * 0.9f32.powf(lines)).clamp(2.0, 5000.0);
            }
            WindowEvent::RedrawRequested => self.redraw(),
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _el: &ActiveEventLoop) {
        if let Some(s) = &self.surface {
            s.window.request_redraw();
        }
    }
}

pub fn view(a: &ViewArgs) -> anyhow::Result<()> {
    let mut spec = SceneSpec::load(&a.scene)?;
    a.lod.apply(&mut spec)?;
    if let Some(w) = &a.wind {
        spec.set_wind(w);
    }
    if let Some(h0) = a.lod_fraction
        && !(h0 > 0.0 && h0.is_finite())
    {
        anyhow::bail!("--lod-fraction {h0}: must be > 0");
    }
    let forest = Forest::new(&spec)?;
    let orbit = Orbit::from_camera(&forest.default_camera());
    let event_loop = EventLoop::new().context("no window system: is a display available?")?;
    let mut app = App {
        forest,
        frame: FrameData::default(),
        orbit,
        surface: None,
        error: None,
        held: Default::default(),
        dragging: false,
        cursor: None,
        last: Instant::now(),
        fps: 0.0,
        paused: false,
        lod_fraction: a.lod_fraction,
    };
    event_loop.run_app(&mut app).context("window event loop")?;
    match app.error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}
