//! The viewer without its window: the forest, the camera, the clock, the settings the panel
//! edits and the figures it shows. Every change arrives as an [`Action`], from the panel, the
//! keyboard or a test, so the panel's logic runs without a window or a GPU.

use std::collections::VecDeque;
use std::sync::mpsc::{Receiver, channel};
use std::time::Instant;

pub use sylva_forest::Orbit;
pub use sylva_forest::clock::{Clock, MAX_SUBSTEPS, SUBSTEP};
use sylva_forest::{CameraKey, Forest, FrameData, LodSettings, SceneSpec};

/// Seconds between the keys of a recorded camera path.
pub const RECORD_EVERY_S: f32 = 0.25;
/// Seconds of history the plots keep.
pub const HISTORY_S: f64 = 30.0;

/// Built-in scenes the panel offers.
pub const SCENES: [&str; 5] = ["small", "A", "B", "C", "D"];
/// Wind presets the panel offers.
pub const PRESETS: [&str; 4] = ["calm", "breeze", "strong", "storm"];

/// One change to the viewer.
#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    /// Speed multiplier (≥ 0) of the wind, live.
    WindGain(f32),
    /// Extra turn of the wind direction, degrees, live.
    WindTurn(f32),
    /// A wind preset (calm, breeze, strong, storm) or a steady speed, m/s: re-synthesised in
    /// the background.
    Wind(String),
    /// Friction velocity U*, m/s, of a preset: re-synthesised in the background.
    UStar(f64),
    /// Taylor advection on or off: re-synthesised in the background.
    Advection(bool),
    /// The mean wind profile of a preset: re-synthesised in the background.
    Profile(sylva_wind::Profile),
    /// Simulated seconds per real second (0.05 … 4).
    TimeScale(f32),
    /// Pause or run the simulation.
    Pause(bool),
    /// While paused: advance one substep.
    Step,
    /// Geometry and animation LOD settings, live.
    Lod(LodSettings),
    /// The wind-field LOD (instance groups by distance): the scene is rebuilt.
    WindLod(bool),
    /// Another scene (built-in name or file), tree count, seed and species mix (empty: the
    /// scene's own): rebuilt in the background.
    Scene { scene: String, trees: usize, seed: u64, species: Vec<sylva_forest::SpeciesShare> },
    /// Select a tree (or none) for the panel's figures and plot.
    Select(Option<usize>),
    /// Show or hide the control panel.
    Panel(bool),
    /// Show or hide the key help.
    Help(bool),
    /// Tint the trees by geometry level or instance group, or not.
    Overlay(sylva_render::Overlay),
    /// Time each part of the frame on the GPU (shadows, trees, impostors, ground, sky) for
    /// the panel, or stop.
    GpuPasses(bool),
    /// Save the next frame as a PNG.
    Screenshot,
    /// Start (true) or stop recording a clip of the 3-D view (PNG frames, GIF, MP4 through
    /// ffmpeg: `sylva render`'s encoder) into a new `clip-<simulated ms>` folder.
    Clip(bool),
    /// Start (true) or stop recording the camera; stopping writes the path
    /// ([`Viewer::path_file`]) and makes it the one to replay.
    Record(bool),
    /// Play (true) or stop the camera path: the recorded one, the `--camera-path` file's,
    /// or the scene's.
    Replay(bool),
    /// Close the viewer.
    Quit,
}

/// Settings the panel edits (what the forest was last asked for).
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// Wind preset or steady speed.
    pub wind: String,
    /// U* of a preset, m/s (`None`: the preset's).
    pub u_star: Option<f64>,
    /// Taylor advection.
    pub advection: bool,
    /// Mean profile replacing the preset's (`None`: the preset's).
    pub profile: Option<sylva_wind::Profile>,
    /// Simulated seconds per real second.
    pub time_scale: f32,
    /// Simulation paused.
    pub paused: bool,
    /// Scene name or file.
    pub scene: String,
    /// Trees in the scene.
    pub trees: usize,
    /// Scene seed.
    pub seed: u64,
    /// Species mix (empty: the scene's own).
    pub species: Vec<sylva_forest::SpeciesShare>,
    /// Wind-field LOD (instance groups).
    pub wind_lod: bool,
}

/// Per-frame figures, as the panel shows them.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Figures {
    /// Frames per second from the real frame time (smoothed).
    pub fps: f32,
    /// Real time of the last frame, ms.
    pub frame_ms: f32,
    /// Simulation, ms (all substeps of the last frame).
    pub sim_ms: f32,
    /// Building `FrameData`, ms.
    pub build_ms: f32,
    /// Rendering: the GPU's time on the latest frame it finished, ms (the frame loop does
    /// not wait for it; [`sylva_render::GpuTimer`]).
    pub render_ms: f32,
    /// The GPU's time in each part of the latest frame read back, ms, in the order of
    /// [`sylva_render::PASS_PARTS`] (when asked for and the adapter can: timestamp queries).
    pub passes: Option<[f64; sylva_render::PASS_PARTS.len()]>,
    /// Substeps run in the last frame.
    pub substeps: u32,
}

/// What the background is working on.
#[derive(Debug)]
pub enum Job {
    /// A wind field for the current forest.
    Wind(Receiver<Result<sylva_forest::SceneWind, String>>, Instant),
    /// A whole forest.
    Scene(Receiver<Result<Box<Forest>, String>>, Instant),
}

/// What [`Viewer::poll`] found finished.
#[derive(Debug, PartialEq, Eq)]
pub enum Finished {
    /// Nothing.
    Nothing,
    /// The wind was replaced.
    Wind,
    /// The forest was replaced: the renderer must be rebuilt for it.
    Scene,
}

/// The viewer's state.
#[derive(Debug)]
pub struct Viewer {
    /// The forest in wind.
    pub forest: Forest,
    /// The last frame built.
    pub frame: FrameData,
    /// The camera.
    pub orbit: Orbit,
    /// Substep clock.
    pub clock: Clock,
    /// What the panel edits.
    pub settings: Settings,
    /// Per-frame figures.
    pub figures: Figures,
    /// (simulated time, wind speed at the probe m/s, selected tree's trunk-top
    /// displacement m) over the last [`HISTORY_S`].
    pub history: VecDeque<(f64, f32, f32)>,
    /// The selected tree.
    pub selected: Option<usize>,
    /// Background work under way.
    pub job: Option<Job>,
    /// The last background error, shown in the panel.
    pub error: Option<String>,
    /// Panel shown.
    pub panel: bool,
    /// Where the 3-D view's centre lies, in clip-space x: the panel's share of the window's
    /// width while it shows (so the scene is centred beside it), else 0
    /// (`Renderer::set_view_shift`; picking takes it off the cursor).
    pub view_shift: f32,
    /// Key help shown.
    pub help: bool,
    /// The renderer's colour overlay.
    pub overlay: sylva_render::Overlay,
    /// The GPU's time by part of the frame asked for ([`Figures::passes`]).
    pub gpu_passes: bool,
    /// A screenshot was asked for.
    pub screenshot: bool,
    /// A clip is being recorded (the window layer renders and writes its frames).
    pub clip: bool,
    /// Close asked for.
    pub quit: bool,
    /// The scene argument the current forest was built from.
    loaded: String,
    /// The camera path to replay (recorded, read, or the scene's).
    pub path: Vec<CameraKey>,
    /// Where a recorded path is written.
    pub path_file: std::path::PathBuf,
    /// Recording: the keys so far and the real time since the start, s.
    pub recording: Option<(Vec<CameraKey>, f32)>,
    /// Replaying: real time into the path, s.
    pub replaying: Option<f32>,
    /// A line for the panel (what was written, what failed).
    pub status: Option<String>,
}

impl Viewer {
    /// A viewer on `forest` (built from the scene `scene`: a built-in name or a file), from
    /// its default viewpoint.
    pub fn new(forest: Forest, scene: &str) -> Viewer {
        let orbit = Orbit::from_camera(&forest.default_camera());
        let spec = &forest.spec;
        let settings = Settings {
            wind: spec.wind.clone(),
            u_star: spec.u_star,
            advection: spec.wind_advection.unwrap_or(true),
            profile: spec.wind_profile,
            time_scale: 1.0,
            paused: false,
            scene: scene.to_string(),
            trees: spec.trees,
            seed: spec.seed,
            species: Vec::new(),
            wind_lod: spec.lod.wind,
        };
        Viewer {
            forest,
            frame: FrameData::default(),
            orbit,
            clock: Clock::default(),
            settings,
            figures: Figures::default(),
            history: VecDeque::new(),
            selected: None,
            job: None,
            error: None,
            panel: true,
            view_shift: 0.0,
            help: false,
            overlay: sylva_render::Overlay::Off,
            gpu_passes: false,
            screenshot: false,
            clip: false,
            quit: false,
            loaded: scene.to_string(),
            path: Vec::new(),
            path_file: "camera-path.toml".into(),
            recording: None,
            replaying: None,
            status: None,
        }
        .with_scene_path()
    }

    /// The scene's own camera path as the one to replay (when it has one).
    fn with_scene_path(mut self) -> Viewer {
        self.path = self.forest.spec.camera_path.clone();
        self.prime();
        self
    }

    /// Build a first frame for the camera before the forest is stepped, so that the first
    /// step already follows the animation LOD (a forest never drawn simulates every joint
    /// of every simulation). The aspect is a guess; the next drawn frame sets it.
    fn prime(&mut self) {
        self.forest.frame(&self.orbit.camera(), 1.5, &mut self.frame);
    }

    /// Apply one change.
    pub fn apply(&mut self, action: Action) {
        let (gain, turn) = self.forest.wind_control();
        match action {
            Action::WindGain(g) => self.forest.set_wind_control(g.clamp(0.0, 20.0), turn),
            Action::WindTurn(t) => self.forest.set_wind_control(gain, t),
            Action::Wind(w) => {
                if sylva_forest::WindSource::parse(&w).is_err() {
                    self.error = Some(format!("wind `{w}`: a preset, a speed or a file"));
                    return;
                }
                // U* and the profile belong to a preset; a new wind starts from its own.
                self.settings.wind = w;
                self.settings.u_star = None;
                self.settings.profile = None;
                self.resynthesise();
            }
            Action::UStar(u) => {
                self.settings.u_star = Some(u.clamp(0.05, 20.0));
                self.resynthesise();
            }
            Action::Advection(a) => {
                self.settings.advection = a;
                self.resynthesise();
            }
            Action::Profile(p) => {
                let check = sylva_wind::WindParams { profile: p, ..Default::default() };
                if let Err(e) = check.validate() {
                    self.error = Some(format!("wind profile: {e}"));
                    return;
                }
                self.settings.profile = Some(p);
                self.resynthesise();
            }
            Action::TimeScale(s) => self.settings.time_scale = s.clamp(0.05, 4.0),
            Action::Pause(p) => self.settings.paused = p,
            Action::Step => {
                if self.settings.paused {
                    self.forest.step(SUBSTEP);
                }
            }
            Action::Lod(l) => self.forest.set_lod(l),
            Action::WindLod(on) => {
                self.settings.wind_lod = on;
                self.rebuild();
            }
            Action::Scene { scene, trees, seed, species } => {
                if !species.is_empty() && !species.iter().any(|s| s.weight > 0.0) {
                    self.error = Some("species mix: give some species a weight above 0".into());
                    return;
                }
                self.settings.scene = scene;
                self.settings.trees = trees;
                self.settings.seed = seed;
                self.settings.species = species.into_iter().filter(|s| s.weight > 0.0).collect();
                self.rebuild();
            }
            Action::Select(t) => {
                self.selected = t.filter(|&t| t < self.forest.trees());
                self.history.clear();
            }
            Action::Panel(on) => self.panel = on,
            Action::Help(on) => self.help = on,
            Action::Overlay(o) => self.overlay = o,
            Action::GpuPasses(on) => {
                self.gpu_passes = on;
                self.figures.passes = None;
            }
            Action::Screenshot => self.screenshot = true,
            Action::Clip(on) => self.clip = on,
            Action::Record(true) => {
                self.replaying = None;
                self.recording = Some((Vec::new(), 0.0));
                self.key_camera();
            }
            Action::Record(false) => {
                let Some((keys, _)) = self.recording.take() else { return };
                if keys.len() < 2 {
                    self.status = Some("camera path: too short to keep (under 0.25 s)".into());
                    return;
                }
                let text = sylva_forest::camera_path_to_toml(&keys);
                self.status = Some(
                    match sylva_wind::io::atomic::write_atomic(&self.path_file, text.as_bytes()) {
                        Ok(()) => format!(
                            "camera path: {} keys, {:.1} s, written to {}",
                            keys.len(),
                            keys.last().map_or(0.0, |k| k.t),
                            self.path_file.display()
                        ),
                        Err(e) => format!("camera path: writing {}: {e}", self.path_file.display()),
                    },
                );
                self.path = keys;
            }
            Action::Replay(on) => {
                self.replaying = (on && !self.path.is_empty()).then_some(0.0);
                if on && self.path.is_empty() {
                    self.status =
                        Some("no camera path: record one (R) or give --camera-path".into());
                }
            }
            Action::Quit => self.quit = true,
        }
    }

    /// The scene as the settings describe it.
    fn spec(&self) -> Result<SceneSpec, String> {
        let mut spec = if self.settings.scene == self.loaded {
            self.forest.spec.clone()
        } else {
            SceneSpec::load(&self.settings.scene).map_err(|e| e.to_string())?
        };
        let wind = sylva_forest::WindSource::parse(&self.settings.wind)?;
        spec.set_wind(&wind);
        spec.u_star = if matches!(wind, sylva_forest::WindSource::Preset(_)) {
            self.settings.u_star
        } else {
            None
        };
        let preset = matches!(wind, sylva_forest::WindSource::Preset(_));
        spec.wind_advection = Some(self.settings.advection).filter(|a| !a && preset);
        spec.wind_profile = self.settings.profile.filter(|_| preset);
        spec.trees = self.settings.trees.max(1);
        if !self.settings.species.is_empty() {
            spec.species = self.settings.species.clone();
        }
        spec.seed = self.settings.seed;
        spec.lod.wind = self.settings.wind_lod;
        Ok(spec)
    }

    /// Run `work` on the scene the settings describe in a background thread; `None` (and
    /// the error shown) when the settings do not describe one.
    fn spawn<T: Send + 'static>(
        &mut self,
        work: impl FnOnce(SceneSpec) -> Result<T, String> + Send + 'static,
    ) -> Option<Receiver<Result<T, String>>> {
        match self.spec() {
            Ok(spec) => {
                let (tx, rx) = channel();
                std::thread::spawn(move || {
                    let _ = tx.send(work(spec));
                });
                Some(rx)
            }
            Err(e) => {
                self.error = Some(e);
                None
            }
        }
    }

    /// Synthesise the wind of the settings for the current forest in the background.
    fn resynthesise(&mut self) {
        let (radius, stand) = (self.forest.radius, self.forest.stand());
        let field = move |spec: SceneSpec| {
            sylva_forest::wind_field_over(&spec, radius, stand).map_err(|e| e.to_string())
        };
        if let Some(rx) = self.spawn(field) {
            self.job = Some(Job::Wind(rx, Instant::now()));
        }
    }

    /// Build the forest of the settings in the background.
    fn rebuild(&mut self) {
        let build = |spec: SceneSpec| Forest::new(&spec).map(Box::new).map_err(|e| e.to_string());
        if let Some(rx) = self.spawn(build) {
            self.job = Some(Job::Scene(rx, Instant::now()));
        }
    }

    /// Take finished background work. `wait`: block until it is done (tests).
    pub fn poll(&mut self, wait: bool) -> Finished {
        let done = match &self.job {
            None => return Finished::Nothing,
            Some(Job::Wind(rx, _)) => {
                match if wait { rx.recv().ok() } else { rx.try_recv().ok() } {
                    Some(Ok(wind)) => {
                        self.forest.set_wind_field(wind);
                        // The scene now carries this wind (for a later rebuild or export).
                        if let Ok(spec) = self.spec() {
                            self.forest.spec.wind = spec.wind;
                            self.forest.spec.u_star = spec.u_star;
                            self.forest.spec.wind_advection = spec.wind_advection;
                            self.forest.spec.wind_profile = spec.wind_profile;
                        }
                        Some(Finished::Wind)
                    }
                    Some(Err(e)) => {
                        self.error = Some(e);
                        Some(Finished::Nothing)
                    }
                    None => None,
                }
            }
            Some(Job::Scene(rx, _)) => match if wait { rx.recv().ok() } else { rx.try_recv().ok() }
            {
                Some(Ok(forest)) => {
                    let (gain, turn) = self.forest.wind_control();
                    let lod = self.forest.lod();
                    self.forest = *forest;
                    self.loaded = self.settings.scene.clone();
                    self.forest.set_wind_control(gain, turn);
                    self.forest.set_lod(lod);
                    self.frame = FrameData::default();
                    self.orbit = Orbit::from_camera(&self.forest.default_camera());
                    self.selected = None;
                    self.history.clear();
                    self.prime();
                    Some(Finished::Scene)
                }
                Some(Err(e)) => {
                    self.error = Some(e);
                    Some(Finished::Nothing)
                }
                None => None,
            },
        };
        match done {
            Some(f) => {
                self.job = None;
                if f != Finished::Nothing {
                    self.error = None;
                }
                f
            }
            None => Finished::Nothing,
        }
    }

    /// What the background is doing, and for how long (s), for the panel.
    pub fn busy(&self) -> Option<(&'static str, f32)> {
        match &self.job {
            Some(Job::Wind(_, t)) => Some(("synthesising the wind", t.elapsed().as_secs_f32())),
            Some(Job::Scene(_, t)) => Some(("building the scene", t.elapsed().as_secs_f32())),
            None => None,
        }
    }

    /// Add a key for the camera now to the recording (if any).
    fn key_camera(&mut self) {
        let c = self.orbit.camera();
        if let Some((keys, t)) = &mut self.recording
            && keys.last().is_none_or(|k| *t > k.t)
        {
            keys.push(CameraKey { t: *t, eye: c.eye, target: c.target });
        }
    }

    /// Move the camera along the path being replayed, and record; both in real time.
    fn camera_time(&mut self, real_dt: f32) {
        if let Some(t) = &mut self.replaying {
            *t += real_dt;
            let end = self.path.last().map_or(0.0, |k| k.t);
            let c = sylva_forest::camera_on_path(&self.path, t.min(end), &self.orbit.camera());
            self.orbit =
                Orbit { fov: self.orbit.fov, far: self.orbit.far, ..Orbit::from_camera(&c) };
            if *t >= end {
                self.replaying = None;
            }
        }
        if let Some((keys, t)) = &mut self.recording {
            *t += real_dt;
            if keys.last().is_none_or(|k| *t - k.t >= RECORD_EVERY_S) {
                self.key_camera();
            }
        }
    }

    /// Advance by `real_dt` seconds of real time: the camera path, fixed substeps (capped),
    /// then the plots' history. Figures: frame time, FPS, simulation time.
    pub fn advance(&mut self, real_dt: f32) {
        self.camera_time(real_dt.max(0.0));
        self.figures.frame_ms = 1e3 * real_dt;
        let fps = if real_dt > 0.0 { 1.0 / real_dt } else { 0.0 };
        self.figures.fps =
            if self.figures.fps == 0.0 { fps } else { 0.8 * self.figures.fps + 0.2 * fps };
        let steps = if self.settings.paused {
            self.clock.slow = false;
            0
        } else {
            self.clock.advance(real_dt, self.settings.time_scale)
        };
        let start = Instant::now();
        for _ in 0..steps {
            self.forest.step(SUBSTEP);
        }
        self.figures.sim_ms = 1e3 * start.elapsed().as_secs_f32();
        self.figures.substeps = steps;
        if steps > 0 {
            self.record();
        }
    }

    /// Probe point of the wind plot: the selected tree's crown, else the camera target at
    /// 20 m above ground.
    pub fn probe(&self) -> [f64; 3] {
        if let Some(p) = self.selected.and_then(|t| self.forest.placement(t)) {
            let h = self.selected.and_then(|t| self.forest.tree_info(t)).map_or(15.0, |i| i.height);
            return [
                p.position[0] as f64,
                p.position[1] as f64,
                (p.position[2] + sylva_tree::WIND_SAMPLE_HEIGHT as f32 * h) as f64,
            ];
        }
        let [x, y, _] = self.orbit.target;
        [x as f64, y as f64, (self.forest.terrain.height(x, y) + 20.0) as f64]
    }

    fn record(&mut self) {
        let w = self.forest.wind_sample(self.probe());
        let speed = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
        let sway = self.selected.and_then(|t| self.forest.trunk_top_displacement(t)).unwrap_or(0.0);
        let t = self.forest.time();
        self.history.push_back((t, speed, sway));
        while self.history.front().is_some_and(|&(t0, _, _)| t - t0 > HISTORY_S) {
            self.history.pop_front();
        }
    }

    /// Build this frame's `FrameData` for an image of `aspect`.
    pub fn build_frame(&mut self, aspect: f32) {
        let start = Instant::now();
        self.forest.frame(&self.orbit.camera(), aspect, &mut self.frame);
        self.figures.build_ms = 1e3 * start.elapsed().as_secs_f32();
    }
}
