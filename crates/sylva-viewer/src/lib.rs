//! `sylva view`: a window onto a scene, with a control panel (egui) for the wind, the LODs,
//! the scene, live figures and plots, and tree picking. Keys: [`input`]'s table (F1 shows it).
//!
//! Time is honest: the figures come from the real frame time, and the simulation keeps real
//! time in fixed substeps of [`state::SUBSTEP`], at most [`state::MAX_SUBSTEPS`] a frame;
//! a slower frame runs the simulation in slow motion, and the panel says so.
//!
//! The window layer here only moves events and pixels: the viewer's state and its changes
//! ([`state`]), the key and mouse mapping ([`input`]) and the panel ([`panel`]) run without a
//! window, which is how they are tested.

pub mod input;
pub mod panel;
pub mod state;
#[cfg(test)]
mod tests;

use std::sync::Arc;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use sylva_forest::{Forest, SceneSpec};
use sylva_render::{Gpu, GpuTimer, PanelFrame, PanelPass, Renderer, wgpu};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::PhysicalKey;
use winit::window::{Window, WindowId};

use input::{Controls, Input};
use state::{Action, Finished, Viewer};

#[derive(Debug, Args)]
pub struct ViewArgs {
    /// Scene: a built-in name (small, A, B, C, D, E) or a scene file (.toml).
    #[arg(long, default_value = "A")]
    pub scene: String,
    /// Geometry-LOD threshold h₀ (see `sylva render --help`). Default: the scene's on a
    /// GPU, 1 on a software rasteriser such as lavapipe (only trees filling the image at
    /// full detail, the rest impostors).
    #[arg(value_parser = sylva_frames::finite::<f32>, long)]
    pub lod_fraction: Option<f32>,
    /// Wind instead of the scene's: a preset (calm, breeze, strong, storm), a steady speed
    /// in m/s, or a wind file (.swf, .npy, .zarr).
    #[arg(long)]
    pub wind: Option<sylva_forest::WindSource>,
    /// Start without the control panel (Tab shows it; the figures then stay in the title).
    #[arg(long)]
    pub no_panel: bool,
    /// A camera path to replay with P (a TOML file of `[[camera_path]]` entries, as R
    /// records and as scene files hold); default: the scene's.
    #[arg(long)]
    pub camera_path: Option<std::path::PathBuf>,
    #[command(flatten)]
    pub lod: sylva_frames::render::LodArgs,
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
    panel: PanelPass,
    egui: egui_winit::State,
    /// The panel's last output; its texture changes wait here until a frame draws them
    /// (a frame can be skipped while the window is resized).
    pending: PanelFrame,
    /// The GPU's time on each frame, taken off the frame loop.
    timer: GpuTimer,
    /// Minimised or wholly covered: no frames are requested, so the loop sleeps until the
    /// window shows again.
    hidden: bool,
    /// The window's title as last set.
    title: String,
}

impl Drop for Surface {
    fn drop(&mut self) {
        // Texture changes not yet drawn are dropped with the window, deliberately.
        self.pending.textures.clear();
    }
}

/// A clip being recorded: its own offscreen renderer and `sylva render`'s writer.
struct Clip {
    headless: sylva_render::Headless,
    writer: sylva_frames::render::ClipWriter,
    dir: std::path::PathBuf,
}

struct App {
    clip: Option<Clip>,
    viewer: Viewer,
    controls: Controls,
    draft: panel::Draft,
    surface: Option<Surface>,
    error: Option<anyhow::Error>,
    last: Instant,
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
        let forest = &mut self.viewer.forest;
        let h0 = self.lod_fraction.unwrap_or(if software { 1.0 } else { forest.lod().fraction });
        forest.set_lod_fraction(h0);
        let renderer =
            Renderer::for_forest(&gpu, forest, config.format, config.width, config.height)?;
        println!("sylva view: {} ({}× MSAA)", gpu.describe(), renderer.samples());
        let panel = PanelPass::new(&gpu, config.format);
        let ctx = egui::Context::default();
        let max_side = gpu.device.limits().max_texture_dimension_2d as usize;
        let egui = egui_winit::State::new(
            ctx,
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(max_side),
        );
        let pending = PanelFrame::default();
        let timer = GpuTimer::new(gpu.device.clone());
        self.surface = Some(Surface {
            window,
            surface,
            gpu,
            config,
            renderer,
            panel,
            egui,
            pending,
            timer,
            hidden: false,
            title: String::new(),
        });
        Ok(())
    }

    fn redraw(&mut self) {
        let now = Instant::now();
        let real_dt = now.duration_since(self.last).as_secs_f32();
        self.last = now;
        let v = &mut self.viewer;
        if v.poll(false) == Finished::Scene
            && let Some(s) = self.surface.as_mut()
        {
            match Renderer::for_forest(
                &s.gpu,
                &v.forest,
                s.config.format,
                s.config.width,
                s.config.height,
            ) {
                Ok(r) => s.renderer = r,
                Err(e) => v.error = Some(format!("renderer: {e}")),
            }
            self.draft = panel::Draft::of(v);
        }
        self.controls.fly(v, real_dt.min(0.2));
        v.advance(real_dt);
        let Some(s) = self.surface.as_mut() else { return };
        let (w, h) = (s.config.width, s.config.height);
        v.frame.image_rows = h;
        v.build_frame(w as f32 / h as f32);
        // The panel first; what it asks for applies now, and shows from the next frame on.
        let mut actions = Vec::new();
        let with_panel = v.panel || v.help || v.clock.slow;
        if !v.panel {
            v.view_shift = 0.0;
        }
        if with_panel {
            let raw = s.egui.take_egui_input(&s.window);
            let ctx = s.egui.egui_ctx().clone();
            let mut panel_width = 0.0;
            let full = ctx.run_ui(raw, |ui| {
                panel_width = panel::show(ui, v, &mut self.draft, &mut actions);
            });
            // The scene centred in what the panel leaves free.
            v.view_shift = (panel_width * full.pixels_per_point / w as f32).clamp(0.0, 0.9);
            s.egui.handle_platform_output(&s.window, full.platform_output);
            s.pending.primitives = ctx.tessellate(full.shapes, full.pixels_per_point);
            s.pending.textures.append(full.textures_delta);
            s.pending.pixels_per_point = full.pixels_per_point;
        }
        for a in actions {
            v.apply(a);
        }
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
        let camera = v.orbit.camera();
        let began = Instant::now();
        s.renderer.set_overlay(v.overlay);
        s.renderer.set_view_shift(v.view_shift);
        if v.gpu_passes {
            s.renderer.time_passes(&s.gpu);
        } else {
            s.renderer.stop_timing_passes();
        }
        s.renderer.render(&s.gpu, &v.frame, &camera, &view);
        if with_panel {
            s.panel.draw(&s.gpu, &view, [w, h], &mut s.pending);
        }
        // Not waited for: the GPU draws this frame while the next one is simulated and
        // built (the surface holds the loop back once its frame latency is reached). The
        // timer's thread measures the GPU's time; the figure is the latest frame finished.
        s.timer.submitted(s.gpu.queue.submit([]), began);
        v.figures.render_ms = s.timer.last_ms();
        v.figures.passes = s.renderer.latest_pass_times();
        s.gpu.queue.present(texture);
        if std::mem::take(&mut v.screenshot) {
            match screenshot(v, w, h) {
                Ok(path) => println!("wrote {path}"),
                Err(e) => v.error = Some(format!("screenshot: {e:#}")),
            }
        }
        let title = if !v.panel {
            let st = v.frame.stats;
            let (gain, turn) = v.forest.wind_control();
            format!(
                "sylva — {:.1} fps — {} of {} trees — {:.2} M triangles — wind ×{gain:.2} {turn:+.0}° — sim {:.1} ms{}{}",
                v.figures.fps,
                st.drawn,
                st.trees,
                st.triangles as f64 / 1e6,
                v.figures.sim_ms,
                if v.settings.paused { " — paused" } else { "" },
                if v.clock.slow { " — slow motion" } else { "" }
            )
        } else {
            "sylva".to_string()
        };
        if title != s.title {
            if window_call(|| s.window.set_title(&title)).is_none() {
                self.error = Some(anyhow::anyhow!(DISPLAY_LOST));
                return;
            }
            s.title = title;
        }
        self.clip_frame(w, h);
    }
}

impl App {
    /// Start, feed or finish the clip the viewer asks for: each frame rendered offscreen
    /// (without the panel) and shown for the simulated time it advanced.
    fn clip_frame(&mut self, w: u32, h: u32) {
        let v = &mut self.viewer;
        match (&mut self.clip, v.clip) {
            (None, true) => {
                let dir = std::path::PathBuf::from(format!(
                    "clip-{:08}",
                    (v.forest.time() * 1e3).round() as u64
                ));
                let started = sylva_render::Headless::new(&v.forest, w, h)
                    .map_err(anyhow::Error::from)
                    .and_then(|headless| {
                        let writer = sylva_frames::render::ClipWriter::new(&dir, w, h, true)?;
                        Ok(Clip { headless, writer, dir: dir.clone() })
                    });
                match started {
                    Ok(c) => {
                        v.status = Some(format!("recording a clip into {}", dir.display()));
                        self.clip = Some(c);
                    }
                    Err(e) => {
                        v.error = Some(format!("clip: {e:#}"));
                        v.clip = false;
                    }
                }
            }
            (Some(c), true) => {
                let seconds = (v.figures.substeps as f32 * state::SUBSTEP).max(1.0 / 60.0);
                let frame = c.headless.render(&v.frame, &v.orbit.camera());
                if let Err(e) = frame
                    .map_err(anyhow::Error::from)
                    .and_then(|rgba| c.writer.frame(&rgba, seconds as f64))
                {
                    v.error = Some(format!("clip: {e:#}"));
                    v.clip = false;
                }
            }
            (Some(_), false) => {
                if let Some(c) = self.clip.take() {
                    let frames = c.writer.frames();
                    v.status = Some(match c.writer.finish() {
                        Ok((gif, mp4)) => format!(
                            "clip: {frames} frames in {}{}{}",
                            c.dir.display(),
                            gif.map_or(String::new(), |p| format!(", {}", p.display())),
                            mp4.map_or(String::new(), |p| format!(", {}", p.display()))
                        ),
                        Err(e) => format!("clip: {e:#}"),
                    });
                }
            }
            (None, false) => {}
        }
    }
}

/// Render the current frame offscreen (without the panel) and save it as
/// `sylva-<simulated ms>.png` in the working folder.
fn screenshot(v: &Viewer, w: u32, h: u32) -> anyhow::Result<String> {
    let mut headless = sylva_render::Headless::new(&v.forest, w, h)?;
    let rgba = headless.render(&v.frame, &v.orbit.camera())?;
    let path = format!("sylva-{:08}.png", (v.forest.time() * 1e3).round() as u64);
    sylva_frames::render::write_png(std::path::Path::new(&path), w, h, &rgba)?;
    Ok(path)
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
        let Some(s) = self.surface.as_mut() else { return };
        // The panel sees every event first; what it takes (a click on a slider, typing in a
        // field) goes no further. Keys reach it only while it edits text
        // (`input::panel_takes_key`): the viewer's shortcuts work whatever has the focus.
        let to_panel = match &event {
            WindowEvent::KeyboardInput { event, .. } => match event.physical_key {
                PhysicalKey::Code(code) => {
                    input::panel_takes_key(code, s.egui.egui_ctx().text_edit_focused())
                }
                _ => false,
            },
            _ => true,
        };
        let consumed = (self.viewer.panel || self.viewer.help)
            && to_panel
            && s.egui.on_window_event(&s.window, &event).consumed;
        let (w, h) = (s.config.width as f32, s.config.height as f32);
        // Clicks and the wheel by where the cursor is now, not where egui saw it last frame
        // (the help window floats anywhere: egui's answer stands while it shows).
        let consumed = match &event {
            WindowEvent::MouseInput { .. } | WindowEvent::MouseWheel { .. }
                if self.viewer.panel && !self.viewer.help =>
            {
                let dragging = s.egui.egui_ctx().dragged_id().is_some();
                let x = self.controls.cursor().map(|c| c.0);
                input::panel_takes_pointer(x, self.viewer.view_shift * w, dragging)
            }
            _ => consumed,
        };
        let input = match event {
            WindowEvent::CloseRequested => {
                el.exit();
                return;
            }
            WindowEvent::Occluded(covered) => {
                s.hidden = covered;
                if !covered {
                    s.window.request_redraw();
                }
                return;
            }
            WindowEvent::Resized(size) => {
                // A minimised window is resized to nothing on some systems.
                s.hidden = size.width == 0 || size.height == 0;
                if !s.hidden {
                    s.window.request_redraw();
                }
                if size.width > 0 && size.height > 0 {
                    s.config.width = size.width;
                    s.config.height = size.height;
                    s.surface.configure(&s.gpu.device, &s.config);
                    s.renderer.resize(&s.gpu, size.width, size.height);
                }
                return;
            }
            WindowEvent::RedrawRequested => {
                self.redraw();
                if self.viewer.quit || self.error.is_some() {
                    el.exit();
                }
                return;
            }
            _ if consumed => return,
            WindowEvent::KeyboardInput { event, .. } => {
                let PhysicalKey::Code(code) = event.physical_key else { return };
                Input::Key {
                    code,
                    pressed: event.state == ElementState::Pressed,
                    repeat: event.repeat,
                }
            }
            WindowEvent::MouseInput { state, button: MouseButton::Left, .. } => {
                Input::Left(state == ElementState::Pressed)
            }
            WindowEvent::CursorMoved { position, .. } => Input::Cursor(position.x, position.y),
            WindowEvent::MouseWheel { delta, .. } => Input::Wheel(match delta {
                MouseScrollDelta::LineDelta(_, y) => y,
                MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
            }),
            _ => return,
        };
        self.controls.handle(&mut self.viewer, input, w, h);
        if self.viewer.quit {
            el.exit();
        }
    }

    fn about_to_wait(&mut self, _el: &ActiveEventLoop) {
        // Frames back to back while the window shows; none while it is hidden, and the
        // event loop (ControlFlow::Wait, winit's default) sleeps until an event comes.
        if let Some(s) = self.surface.as_ref().filter(|s| !s.hidden) {
            s.window.request_redraw();
        }
    }
}

/// What the viewer says when the window system went away under it.
const DISPLAY_LOST: &str = "the connection to the display was lost; the viewer stopped";

std::thread_local! {
    /// Set while a [`window_call`] runs: its panic is expected and not printed.
    static QUIET: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Run a call into the window system that winit answers with a panic once the display has
/// gone (on X11 `set_title` panics with "Failed to set window title: Connection(…)"):
/// `None` if it panicked, and its panic is not printed ([`quiet_window_panics`]).
fn window_call<R>(f: impl FnOnce() -> R) -> Option<R> {
    QUIET.with(|q| q.set(true));
    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).ok();
    QUIET.with(|q| q.set(false));
    r
}

/// Keep the process's panic hook for every panic but those inside a [`window_call`].
fn quiet_window_panics() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET.with(|q| q.get()) {
                previous(info);
            }
        }));
    });
}

pub fn view(a: &ViewArgs) -> anyhow::Result<()> {
    quiet_window_panics();
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
    let mut viewer = Viewer::new(forest, &a.scene);
    viewer.apply(Action::Panel(!a.no_panel));
    if let Some(p) = &a.camera_path {
        let text =
            std::fs::read_to_string(p).with_context(|| format!("reading {}", p.display()))?;
        viewer.path = sylva_forest::camera_path_from_toml(&p.display().to_string(), &text)?;
    }
    let draft = panel::Draft::of(&viewer);
    let event_loop = EventLoop::new().context("no window system: is a display available?")?;
    let mut app = App {
        clip: None,
        viewer,
        controls: Controls::default(),
        draft,
        surface: None,
        error: None,
        last: Instant::now(),
        lod_fraction: a.lod_fraction,
    };
    event_loop.run_app(&mut app).context("window event loop")?;
    match app.error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}
