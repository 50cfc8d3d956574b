//! The engine as the page drives it: one [`App`] per canvas.
//!
//! The page calls [`App::create`] once, then [`App::frame`] from each animation frame with
//! the real time since the last; the camera, wind, level-of-detail and scene calls come from
//! its controls. Work that takes long (growing a scene, synthesising a wind) runs inside the
//! call, on the page's one thread: the page shows what it is doing before it calls.

use sylva_forest::clock::{Clock, SUBSTEP};
use sylva_forest::{Forest, FrameData, Orbit, SceneSpec, WindSource};
use sylva_render::{Gpu, Renderer, wgpu};
use sylva_tree::Species;
use wasm_bindgen::prelude::*;

use crate::files::{Dropped, close_up, read_dropped};

/// Errors reach the console with the panic's message and place (a panic still stops the
/// module: the page reports it as a failure).
#[wasm_bindgen(start)]
pub fn init() {
    std::panic::set_hook(Box::new(|info| {
        // The JavaScript stack names the WebAssembly functions on the way to the panic.
        let stack = js_sys::Reflect::get(&js_sys::Error::new(""), &"stack".into())
            .ok()
            .and_then(|s| s.as_string())
            .unwrap_or_default();
        web_sys::console::error_1(&JsValue::from_str(&format!("sylva: {info}\n{stack}")));
    }));
}

fn now_ms() -> f64 {
    web_sys::window().and_then(|w| w.performance()).map_or(0.0, |p| p.now())
}

fn js(e: impl std::fmt::Display) -> JsError {
    JsError::new(&e.to_string())
}

/// A forest drawn on a canvas.
#[wasm_bindgen]
#[derive(Debug)]
pub struct App {
    gpu: Gpu,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    /// The format the renderer draws in: the surface's, as sRGB.
    view_format: wgpu::TextureFormat,
    /// Where the surface is not sRGB itself (WebGPU): the sRGB image the renderer resolves
    /// into, copied onto the canvas's texture each frame.
    resolved: Option<wgpu::Texture>,
    renderer: Renderer,
    forest: Forest,
    frame: FrameData,
    orbit: Orbit,
    clock: Clock,
    /// Species files read from the page, by file name (scenes may name them).
    species: Vec<(String, Species)>,
    /// The last frame's simulation (all its substeps) and frame building, ms.
    sim_ms: f64,
    build_ms: f64,
    /// Whether the adapter is a software rasteriser (fewer full-detail trees by default).
    software: bool,
    /// What the last scene change did or failed with, for the panel.
    message: Option<String>,
    error: Option<String>,
}

#[wasm_bindgen]
impl App {
    /// Open the GPU on `canvas` (WebGPU where the browser has it, else WebGL2; WebGL2 alone
    /// with `webgl2`) and grow the
    /// built-in scene `scene` (`small`, `A` … `D`) in `wind` (as [`App::set_wind`] takes it).
    pub async fn create(
        canvas: web_sys::HtmlCanvasElement,
        scene: String,
        wind: String,
        webgl2: bool,
    ) -> Result<App, JsError> {
        let (width, height) = (canvas.width().max(1), canvas.height().max(1));
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = if webgl2 {
            wgpu::Backends::GL
        } else {
            wgpu::Backends::BROWSER_WEBGPU | wgpu::Backends::GL
        };
        let instance = wgpu::util::new_instance_with_webgpu_detection(desc).await;
        let surface = instance.create_surface(wgpu::SurfaceTarget::Canvas(canvas)).map_err(js)?;
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter: false,
                compatible_surface: Some(&surface),
                apply_limit_buckets: false,
            })
            .await
            .map_err(|e| js(format!("no WebGPU or WebGL2 adapter: {e}")))?;
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("sylva"),
                required_features: wgpu::Features::empty(),
                required_limits: adapter.limits(),
                experimental_features: wgpu::ExperimentalFeatures::disabled(),
                memory_hints: wgpu::MemoryHints::Performance,
                trace: wgpu::Trace::Off,
            })
            .await
            .map_err(|e| js(format!("the adapter refused a device: {e}")))?;
        let gpu = Gpu::from_host(&instance, &adapter, &device, &queue);
        let mut config = surface
            .get_default_config(&adapter, width, height)
            .ok_or_else(|| js("the adapter cannot draw on this canvas"))?;
        // The renderer writes linear colour into an sRGB target. A WebGPU canvas holds only
        // plain formats (wgpu may report the sRGB one): the renderer resolves into an sRGB
        // texture of its own, copied onto the canvas's (formats that differ only in sRGB
        // copy as they are). Resolving straight into an sRGB view of the canvas's texture
        // stores the linear values in Chromium (on SwiftShader at least): a dark image.
        // WebGL2's surface is sRGB itself, drawn into directly.
        if adapter.get_info().backend == wgpu::Backend::BrowserWebGpu {
            config.format = config.format.remove_srgb_suffix();
            config.usage |= wgpu::TextureUsages::COPY_DST;
        }
        let view_format = config.format.add_srgb_suffix();
        surface.configure(&device, &config);
        let resolved = (view_format != config.format)
            .then(|| resolve_texture(&device, view_format, width, height));
        let software = adapter.get_info().device_type == wgpu::DeviceType::Cpu;
        let mut spec = SceneSpec::builtin(&scene).map_err(js)?;
        spec.set_wind(&page_wind(&wind).map_err(js)?);
        let forest = grow(&spec, &[], software)?;
        let renderer = Renderer::for_forest_async(&gpu, &forest, view_format, width, height)
            .await
            .map_err(js)?;
        let orbit = Orbit::from_camera(&forest.default_camera());
        Ok(App {
            gpu,
            surface,
            config,
            view_format,
            resolved,
            renderer,
            forest,
            frame: FrameData::default(),
            orbit,
            clock: Clock::default(),
            species: Vec::new(),
            sim_ms: 0.0,
            build_ms: 0.0,
            software,
            message: None,
            error: None,
        })
    }

    /// The adapter: its backend (WebGPU or WebGL2) and name.
    pub fn backend(&self) -> String {
        let info = self.gpu.adapter.get_info();
        let api = match info.backend {
            wgpu::Backend::BrowserWebGpu => "WebGPU",
            wgpu::Backend::Gl => "WebGL2",
            other => return format!("{other:?} ({})", info.name),
        };
        if info.name.is_empty() { api.to_string() } else { format!("{api} ({})", info.name) }
    }

    /// Advance the simulation by `dt` seconds of real time (in substeps of 1/60 s, at most
    /// 0.2 s a frame), build the frame for the camera and draw it.
    pub fn frame(&mut self, dt: f32) {
        let steps = self.clock.advance(dt, 1.0);
        let t0 = now_ms();
        for _ in 0..steps {
            self.forest.step(SUBSTEP);
        }
        let t1 = now_ms();
        let camera = self.orbit.camera();
        let aspect = self.config.width as f32 / self.config.height as f32;
        self.forest.frame(&camera, aspect, &mut self.frame);
        let t2 = now_ms();
        (self.sim_ms, self.build_ms) = (t1 - t0, t2 - t1);
        let texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&self.gpu.device, &self.config);
                return;
            }
            _ => return,
        };
        let target = self.resolved.as_ref().unwrap_or(&texture.texture);
        let view = target.create_view(&wgpu::TextureViewDescriptor::default());
        let mut enc = self
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });
        self.renderer.encode(&self.gpu, &mut enc, &self.frame, &camera, &view);
        if let Some(resolved) = &self.resolved {
            enc.copy_texture_to_texture(
                resolved.as_image_copy(),
                texture.texture.as_image_copy(),
                resolved.size(),
            );
        }
        self.gpu.queue.submit([enc.finish()]);
        self.gpu.queue.present(texture);
    }

    /// The canvas changed size (device pixels).
    pub fn resize(&mut self, width: u32, height: u32) {
        let (width, height) = (width.max(1), height.max(1));
        if (width, height) != (self.config.width, self.config.height) {
            self.config.width = width;
            self.config.height = height;
            self.surface.configure(&self.gpu.device, &self.config);
            self.renderer.resize(&self.gpu, width, height);
            if self.resolved.is_some() {
                let format = self.view_format;
                self.resolved = Some(resolve_texture(&self.gpu.device, format, width, height));
            }
        }
    }

    /// A pointer dragged by (`dx`, `dy`) pixels: orbit the camera.
    pub fn drag(&mut self, dx: f32, dy: f32) {
        self.orbit.drag(dx, dy);
    }

    /// Zoom by `steps` wheel lines (positive: towards the target).
    pub fn zoom(&mut self, steps: f32) {
        self.orbit.zoom(steps);
    }

    /// Move the camera's target (keys: forward, right, up, each −1 … 1) over `dt` seconds.
    pub fn travel(&mut self, forward: f32, right: f32, up: f32, dt: f32) {
        self.orbit.travel(forward, right, up, dt);
    }

    /// A new wind: a preset (`calm`, `breeze`, `strong`, `storm`) or a steady speed in m/s,
    /// synthesised over the forest's ground (as `sylva view` does).
    pub fn set_wind(&mut self, wind: &str) -> Result<(), JsError> {
        let source = page_wind(wind).map_err(js)?;
        let mut spec = self.forest.spec.clone();
        spec.set_wind(&source);
        let field = sylva_forest::wind_field_over(&spec, self.forest.radius, self.forest.stand())
            .map_err(js)?;
        self.forest.set_wind_field(field);
        self.forest.spec = spec;
        Ok(())
    }

    /// The wind's strength as a multiple of the field's (0 … 20).
    pub fn set_wind_gain(&mut self, gain: f32) {
        let (_, turn) = self.forest.wind_control();
        self.forest.set_wind_control(gain.clamp(0.0, 20.0), turn);
    }

    /// The levels of detail: geometry (mesh levels and impostors) and animation (fewer
    /// joints far away). Both off: every tree at full detail, every joint simulated.
    pub fn set_lod(&mut self, geometry: bool, animation: bool) {
        let lod = self.forest.lod();
        self.forest.set_lod(sylva_forest::LodSettings { geometry, animation, ..lod });
    }

    /// Grow the built-in scene `name` in `wind` (as [`App::set_wind`] takes it) and look at
    /// it from its camera. The app is handed over and back (the impostors' bake is awaited);
    /// what failed is kept for [`App::take_error`], the app unchanged.
    pub async fn set_scene(mut self, name: String, wind: String) -> App {
        let outcome = self.builtin_scene(&name, &wind).await;
        self.report(outcome)
    }

    /// Show one tree of the species `name` (a preset, or a species file read by
    /// [`App::read_file`]) close up, in the current wind (handed over and back as
    /// [`App::set_scene`]).
    pub async fn show_species(mut self, name: String) -> App {
        let outcome = self.close_up(&name).await;
        self.report(outcome)
    }

    /// A file dropped onto the page, `file` its name: a scene is grown (its species may be
    /// species files read before, by file name), a species is shown close up (handed over
    /// and back as [`App::set_scene`]). A bad file's error names the file and the line or
    /// field, as `sylva` does.
    pub async fn read_file(mut self, file: String, text: String) -> App {
        let outcome = self.dropped(&file, &text).await;
        self.report(outcome)
    }

    /// What the last scene change failed with, if it did (taken: asked again, `None`).
    pub fn take_error(&mut self) -> Option<String> {
        self.error.take()
    }

    /// What the last scene change did, for the panel (taken).
    pub fn take_message(&mut self) -> Option<String> {
        self.message.take()
    }

    /// Trees in the scene.
    pub fn trees(&self) -> usize {
        self.frame.stats.trees
    }

    /// Trees drawn in the last frame.
    pub fn drawn(&self) -> usize {
        self.frame.stats.drawn
    }

    /// Triangles drawn in the last frame.
    pub fn triangles(&self) -> usize {
        self.frame.stats.triangles
    }

    /// Trees drawn as impostors in the last frame.
    pub fn impostors(&self) -> usize {
        self.frame.stats.impostors
    }

    /// Simulation time of the last frame (all its substeps), ms.
    pub fn sim_ms(&self) -> f64 {
        self.sim_ms
    }

    /// Frame building time of the last frame (culling, levels, palettes), ms.
    pub fn build_ms(&self) -> f64 {
        self.build_ms
    }

    /// Simulated seconds since the scene was grown.
    pub fn time(&self) -> f64 {
        self.forest.time()
    }

    /// The scene's name.
    pub fn scene(&self) -> String {
        self.forest.spec.name.clone()
    }
}

impl App {
    /// Grow `spec` (with the species files read so far) and rebuild the renderer for it;
    /// on failure nothing changes.
    async fn replace(&mut self, spec: &SceneSpec) -> Result<(), String> {
        let forest = grow(spec, &self.species, self.software).map_err(|e| e.to_string())?;
        let (w, h) = (self.config.width, self.config.height);
        self.renderer = Renderer::for_forest_async(&self.gpu, &forest, self.view_format, w, h)
            .await
            .map_err(|e| e.to_string())?;
        self.forest = forest;
        self.frame = FrameData::default();
        self.clock = Clock::default();
        Ok(())
    }

    /// The built-in scene `name` in `wind`, seen from its camera.
    async fn builtin_scene(&mut self, name: &str, wind: &str) -> Result<String, String> {
        let mut spec = SceneSpec::builtin(name).map_err(|e| e.to_string())?;
        spec.set_wind(&page_wind(wind)?);
        self.replace(&spec).await?;
        self.orbit = Orbit::from_camera(&self.forest.default_camera());
        Ok(format!("scene {}", spec.name))
    }

    /// The file `file` holding `text`: a scene grown, or a species kept and shown close up.
    async fn dropped(&mut self, file: &str, text: &str) -> Result<String, String> {
        match read_dropped(file, text)? {
            Dropped::Scene(spec) => {
                self.replace(&spec).await?;
                self.orbit = Orbit::from_camera(&self.forest.default_camera());
                Ok(format!("scene {}: {} trees", spec.name, self.forest.trees()))
            }
            Dropped::Species(name, species) => {
                self.species.retain(|(n, _)| *n != name);
                self.species.push((name.clone(), *species));
                self.close_up(&name).await
            }
        }
    }

    /// One tree of species `name` close up, framed by its height.
    async fn close_up(&mut self, name: &str) -> Result<String, String> {
        let spec = close_up(name, &self.forest.spec.wind)?;
        self.replace(&spec).await?;
        let h = self.forest.species.first().map_or(10.0, |s| s.model.tree.stats.height);
        self.orbit = Orbit {
            target: [0.0, 0.0, 0.5 * h],
            yaw: -2.2,
            pitch: 0.12,
            distance: 1.6 * h + 4.0,
            ..self.orbit
        };
        Ok(format!("{}, close up", name.replace('_', " ")))
    }

    /// Keep `outcome` for the page and hand the app back.
    fn report(mut self, outcome: Result<String, String>) -> App {
        match outcome {
            Ok(m) => self.message = Some(m),
            Err(e) => self.error = Some(e),
        }
        self
    }
}

/// The sRGB image the renderer resolves into on WebGPU (see [`App::create`]).
fn resolve_texture(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
    width: u32,
    height: u32,
) -> wgpu::Texture {
    sylva_render::capture_texture(device, (width, height), format, "frame, sRGB")
}

/// A wind the page can make: a preset or a steady speed (a wind file cannot be read here).
fn page_wind(wind: &str) -> Result<WindSource, String> {
    match WindSource::parse(wind)? {
        WindSource::File(_) => {
            Err("the page cannot read a wind file: choose a preset or a speed in m/s".into())
        }
        source => Ok(source),
    }
}

/// Grow `spec`; on a software rasteriser the desktop viewer's default applies too: trees
/// under the whole image height take the coarser levels.
fn grow(
    spec: &SceneSpec,
    species: &[(String, Species)],
    software: bool,
) -> Result<Forest, sylva_forest::ForestError> {
    let mut forest = Forest::with_species(spec, species)?;
    if software {
        forest.set_lod_fraction(1.0);
    }
    Ok(forest)
}

/// The shipped species (the tree picker's list).
#[wasm_bindgen]
pub fn presets() -> Vec<String> {
    sylva_tree::PRESETS.iter().map(|(n, _)| n.to_string()).collect()
}
