//! `sylva bench table3`: the paper's Table 3 (§5.2) on this machine. For each scene, the
//! forest runs along its camera path (the default fly-in for A–D) with all three LODs,
//! then with each LOD off in turn; per configuration: frames per second, ms per frame split
//! into simulation (wind sample + sway step), frame building (culling, levels, buckets,
//! palette copy) and rendering (upload, draw, wait for the GPU to finish;
//! the read-back of kept frames is not timed), triangles, draw calls, joint
//! updates, bytes uploaded, animation state held (and lane groups the memory cap kept
//! coarser, in the note), simulated trees, and the image error (mean FLIP through the
//! `nv-flip` crate, SSIM through `image-compare`) of the last frame against the
//! full-detail frame at the same time and camera. Warm-up frames are excluded from the medians.
//!
//! The full-detail reference keeps the scene's instance groups (the wind-field LOD): with
//! it off every tree turns to its own yaw, so images would differ by layout, not by LOD.
//! A configuration whose frames exceed `--max-triangles` is timed on the CPU only and its
//! last frame rendered once (when under `--max-image-triangles`) for the image error.
//!
//! Frames per second add simulation, frame building and rendering, each waited for: a
//! bound from below. With `--overlapped` each rendered configuration also runs its timed
//! frames as an interactive loop does, the CPU building a frame while the GPU draws the ones
//! before (up to `--in-flight` frames queued on the GPU: two by default, as the viewer's
//! surface allows), and reports those frames per second beside them. With `--gpu-passes`
//! the GPU's time in each part of the frame (shadows, trees, impostors, ground, sky) is
//! read from timestamp queries and reported too.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use sylva_forest::{Camera, Forest, FrameData, SceneSpec};
use sylva_render::Headless;
use sylva_wind::io::atomic::write_atomic;

use crate::render::{median, parse_size, write_png};

mod popping;
use popping::popping;

/// Defaults of `--max-triangles`, `--max-image-triangles` and `--popping-frames`.
const MAX_TRIANGLES: f64 = 12e6;
const MAX_IMAGE_TRIANGLES: f64 = 80e6;
const POPPING_FRAMES: usize = 40;

#[derive(Debug, Args)]
pub struct Table3Bench {
    /// Scenes, comma-separated (built-in names or scene files).
    #[arg(long, default_value = "A,B,C,D")]
    scenes: String,
    /// Image size.
    #[arg(long, default_value = "1024x768")]
    size: String,
    /// Frames timed per configuration (after the warm-up), spread along the camera path
    /// (at least 1).
    #[arg(long, default_value_t = 6, value_parser = crate::at_least_one)]
    frames: usize,
    /// Warm-up frames, not timed.
    #[arg(long, default_value_t = 2)]
    warmup: usize,
    /// Configurations drawing more triangles per frame are timed on the CPU side only.
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = MAX_TRIANGLES)]
    max_triangles: f64,
    /// Their last frame is still rendered for the image error below this many triangles.
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = MAX_IMAGE_TRIANGLES)]
    max_image_triangles: f64,
    /// First LOD level drawn as an impostor (1 … 6; default: the scene's).
    #[arg(long)]
    far_level: Option<u32>,
    /// Geometry-LOD threshold h₀ (default: the scene's).
    #[arg(value_parser = crate::finite::<f32>, long)]
    lod_fraction: Option<f32>,
    /// Memory the animation state may take, GB (default: the scene's cap, at most three
    /// quarters of the free memory). Over it, lane groups are kept at coarser prefixes (a
    /// note says how many); without the animation LOD the forest is refused.
    #[arg(value_parser = crate::finite::<f64>, long)]
    max_memory: Option<f64>,
    /// Run only the configuration with all LODs, and its image error against full detail
    /// (without the motion floor's second full-detail frame): how a threshold or level
    /// choice trades triangles for error, at a third of the full run's cost or less.
    #[arg(long)]
    all_lods_only: bool,
    /// Rounds: every configuration runs this many times, in turn (each once, then each
    /// again), so the machine's drift falls on all of them alike. Times are medians over
    /// every round's timed frames; each CPU speed-up is given with its range over the
    /// rounds. Counts, images and errors are the last round's (the same in every round).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100))]
    rounds: u32,
    /// Also time the rendered configurations as an interactive loop runs: each frame's
    /// simulation and frame building while the GPU still draws the frames before (up to
    /// `--in-flight` of them), the same timed frames again. Their frames per second are
    /// then set by the slower of the CPU's and the GPU's work, not by their sum.
    #[arg(long)]
    overlapped: bool,
    /// Frames the overlapped loop lets the GPU hold at once: 1 waits for each frame before
    /// submitting the next (the GPU idles while a frame's commands are recorded and
    /// submitted); 2 submits the next while the one before still draws, as the viewer does
    /// (its surface holds up to two frames: wgpu's default frame latency).
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=4))]
    in_flight: u32,
    /// Also read the GPU's time in each part of every timed frame (timestamp queries
    /// between the renderer's passes: shadows, trees, impostors, ground, sky and the MSAA
    /// resolve), reported as medians per configuration. Where the adapter has no
    /// timestamps inside passes, a line says so and nothing else changes.
    #[arg(long)]
    gpu_passes: bool,
    /// Frames of the popping measurement (scene `small`, calm, along its fly-in; 0: skip).
    #[arg(long, default_value_t = POPPING_FRAMES)]
    popping_frames: usize,
    /// Output folder: table3.md, table3.csv, table3.png and each configuration's last frame.
    #[arg(long, default_value = "out/table3")]
    out: PathBuf,
}

/// The paper's Table 3 (FPS; GeForce 6600 GT, Athlon XP 3000+, 1024×768): rows in
/// [`CONFIGS`] order, columns A–D.
const PAPER: [[f64; 4]; 4] =
    [[20.0, 14.5, 8.3, 2.2], [15.3, 9.5, 3.9, 1.0], [14.9, 11.6, 7.4, 2.1], [7.8, 3.4, 1.1, 0.2]];

/// (row label, geometry, animation, wind-field LOD).
const CONFIGS: [(&str, bool, bool, bool); 4] = [
    ("with all LODs", true, true, true),
    ("without geometry LOD", false, true, true),
    ("without animation LOD", true, false, true),
    ("without wind-field LOD", true, true, false),
];

/// What one configuration measured.
#[derive(Debug, Clone, Default)]
struct Cell {
    note: String,
    sim_ms: f64,
    frame_ms: f64,
    /// The slowest timed frame's simulation + frame building (a hitch the medians hide:
    /// a lane group's memory growing, say).
    cpu_max_ms: f64,
    render_ms: Option<f64>,
    /// Frames per second with the CPU's work on a frame overlapping the GPU's on the one
    /// before (`--overlapped`; each round's, the median reported).
    overlapped: Vec<f64>,
    triangles: f64,
    draws: f64,
    joints: f64,
    upload_mb: f64,
    /// The most uploaded in one timed frame (the target is per frame).
    upload_max_mb: f64,
    /// The most animation state held in one timed frame, MB.
    state_mb: f64,
    /// The most lane groups the memory cap held back in one timed frame.
    capped: usize,
    simulated: usize,
    impostors: f64,
    /// Trees out of view cast into the shadow map only, mean per timed frame.
    shadow_only: f64,
    ssim: Option<f64>,
    flip: Option<f64>,
    image: Option<Vec<u8>>,
    /// The frame before the last, when asked for (the reference's motion floor).
    previous: Option<Vec<u8>>,
    /// The timed frames' simulation, frame-building and rendering times, ms (every
    /// round's, pooled for the medians).
    samples: [Vec<f64>; 3],
    /// Each round's median simulation + frame building, ms.
    round_cpu: Vec<f64>,
    /// The GPU's time in each part of every timed frame (`--gpu-passes`), ms, in the order
    /// of [`sylva_render::PASS_PARTS`] (every round's, pooled).
    passes: Vec<[f64; PARTS]>,
}

/// Parts of a frame timed on the GPU.
const PARTS: usize = sylva_render::PASS_PARTS.len();

impl Cell {
    /// The median GPU time of each part of the frame, ms (`--gpu-passes`).
    fn pass_medians(&self) -> Option<[f64; PARTS]> {
        crate::render::part_medians(&self.passes)
    }

    /// Pool the rounds `cells` (in order) into one: medians over all their timed frames,
    /// the slowest frame of any, each round's CPU median; the rest from the last round.
    fn pooled(cells: Vec<Cell>) -> Cell {
        let mut samples: [Vec<f64>; 3] = Default::default();
        let (mut round_cpu, mut cpu_max, mut overlapped) = (Vec::new(), 0.0f64, Vec::new());
        let mut passes = Vec::new();
        for c in &cells {
            overlapped.extend_from_slice(&c.overlapped);
            passes.extend_from_slice(&c.passes);
            for (all, one) in samples.iter_mut().zip(&c.samples) {
                all.extend_from_slice(one);
            }
            round_cpu.extend_from_slice(&c.round_cpu);
            cpu_max = cpu_max.max(c.cpu_max_ms);
        }
        let Some(mut cell) = cells.into_iter().last() else { return Cell::default() };
        if !samples[0].is_empty() {
            cell.sim_ms = median(&mut samples[0].clone());
            cell.frame_ms = median(&mut samples[1].clone());
        }
        cell.render_ms = (!samples[2].is_empty()).then(|| median(&mut samples[2].clone()));
        cell.cpu_max_ms = cpu_max;
        cell.overlapped = overlapped;
        cell.passes = passes;
        cell.samples = samples;
        cell.round_cpu = round_cpu;
        cell
    }
}

impl Cell {
    fn fps(&self) -> Option<f64> {
        self.render_ms.map(|r| 1000.0 / (self.sim_ms + self.frame_ms + r))
    }

    /// The median over the rounds of the frames per second with CPU and GPU overlapped.
    fn overlapped_fps(&self) -> Option<f64> {
        (!self.overlapped.is_empty()).then(|| median(&mut self.overlapped.clone()))
    }
}

/// `spec` with the three LOD switches `lods` (geometry, animation, wind field) and the
/// command line's overrides.
fn configure(
    spec: &SceneSpec,
    a: &Table3Bench,
    (geometry, animation, wind): (bool, bool, bool),
) -> anyhow::Result<SceneSpec> {
    let mut spec = spec.clone();
    (spec.lod.geometry, spec.lod.animation, spec.lod.wind) = (geometry, animation, wind);
    if let Some(f) = a.far_level {
        anyhow::ensure!((1..=6).contains(&f), "--far-level {f}: must be 1 … 6");
        spec.lod.far_level = f;
    }
    if let Some(h0) = a.lod_fraction {
        anyhow::ensure!(h0 > 0.0 && h0 <= 100.0, "--lod-fraction {h0}: must be in (0, 100]");
        spec.lod.fraction = h0;
    }
    crate::render::apply_max_memory(&mut spec, a.max_memory)?;
    Ok(spec)
}

/// The command that reproduces the run: its scenes, size and frame counts, and every option
/// set away from its default.
fn command_line(a: &Table3Bench, (w, h): (u32, u32)) -> String {
    let mut c = format!(
        "sylva bench table3 --scenes {} --size {w}x{h} --frames {} --warmup {}",
        a.scenes, a.frames, a.warmup
    );
    if a.max_triangles != MAX_TRIANGLES {
        let _ = write!(c, " --max-triangles {}", a.max_triangles);
    }
    if a.max_image_triangles != MAX_IMAGE_TRIANGLES {
        let _ = write!(c, " --max-image-triangles {}", a.max_image_triangles);
    }
    if let Some(f) = a.far_level {
        let _ = write!(c, " --far-level {f}");
    }
    if let Some(h0) = a.lod_fraction {
        let _ = write!(c, " --lod-fraction {h0}");
    }
    if let Some(m) = a.max_memory {
        let _ = write!(c, " --max-memory {m}");
    }
    if a.all_lods_only {
        c.push_str(" --all-lods-only");
    }
    if a.popping_frames != POPPING_FRAMES {
        let _ = write!(c, " --popping-frames {}", a.popping_frames);
    }
    if a.rounds != 1 {
        let _ = write!(c, " --rounds {}", a.rounds);
    }
    if a.overlapped {
        c.push_str(" --overlapped");
        if a.in_flight != 2 {
            let _ = write!(c, " --in-flight {}", a.in_flight);
        }
    }
    if a.gpu_passes {
        c.push_str(" --gpu-passes");
    }
    c
}

fn run_config(
    spec: &SceneSpec,
    gpu: &mut Option<Headless>,
    a: &Table3Bench,
    (w, h): (u32, u32),
    lods: (bool, bool, bool),
    keep_previous: bool,
) -> anyhow::Result<Cell> {
    let spec = configure(spec, a, lods)?;
    let mut forest = match Forest::new(&spec) {
        Ok(f) => f,
        Err(e) => return Ok(Cell { note: format!("not run: {e}"), ..Cell::default() }),
    };
    if gpu.is_none() {
        let mut g = Headless::new(&forest, w, h)?;
        if a.gpu_passes && !g.time_passes() {
            println!("  --gpu-passes: this adapter has no timestamps inside passes");
        }
        *gpu = Some(g);
    }
    let gpu = gpu.as_mut().context("renderer")?;
    let total = a.warmup + a.frames;
    let duration = forest.path_duration();
    let dt = 0.1f32;
    let cameras: Vec<_> = (0..total)
        .map(|i| forest.camera_at(duration * i as f32 / (total - 1).max(1) as f32))
        .collect();
    // The frame's arrays grow to the path's largest before timing: built once for each of
    // its cameras, last to first (so the level history ends where the path starts), no
    // timed frame pays for growing them.
    let mut frame = FrameData::default();
    for camera in cameras.iter().rev() {
        forest.frame(camera, w as f32 / h as f32, &mut frame);
    }
    let (mut sim, mut build, mut draw) = (Vec::new(), Vec::new(), Vec::new());
    let mut cell = Cell::default();
    let mut render_all = None;
    for i in 0..total {
        let camera = cameras[i];
        let t = Instant::now();
        forest.step(dt);
        let t_sim = t.elapsed().as_secs_f64() * 1e3;
        let t = Instant::now();
        forest.frame(&camera, w as f32 / h as f32, &mut frame);
        let t_frame = t.elapsed().as_secs_f64() * 1e3;
        let tris = frame.stats.triangles as f64;
        let render_this = *render_all.get_or_insert(tris <= a.max_triangles);
        let last = i + 1 == total;
        let wanted = last || (keep_previous && i + 2 == total);
        let image = if render_this || (wanted && tris <= a.max_image_triangles) {
            // Timed without the read-back, which an interactive frame does not pay.
            let t = Instant::now();
            gpu.draw(&frame, &camera)?;
            let t_draw = t.elapsed().as_secs_f64() * 1e3;
            if (i >= a.warmup && render_this) || (last && !render_this) {
                draw.push(t_draw);
                if a.gpu_passes
                    && let Some(p) = gpu.pass_times()?
                {
                    cell.passes.push(p);
                }
            }
            if wanted { Some(gpu.read_back()?) } else { None }
        } else {
            None
        };
        if i >= a.warmup {
            sim.push(t_sim);
            build.push(t_frame);
            cell.cpu_max_ms = cell.cpu_max_ms.max(t_sim + t_frame);
            cell.triangles += tris;
            cell.draws += frame.stats.draw_calls as f64;
            cell.joints += frame.stats.joints as f64;
            cell.upload_mb += frame.stats.uploaded_bytes as f64 / 1e6;
            cell.upload_max_mb = cell.upload_max_mb.max(frame.stats.uploaded_bytes as f64 / 1e6);
            cell.state_mb = cell.state_mb.max(frame.stats.state_bytes as f64 / 1e6);
            cell.capped = cell.capped.max(frame.stats.state_capped);
            cell.impostors += frame.stats.impostors as f64;
            cell.shadow_only += frame.stats.shadow_only as f64;
        }
        if last {
            cell.image = image;
        } else if keep_previous && i + 2 == total {
            cell.previous = image;
        }
    }
    if a.overlapped && render_all == Some(true) {
        cell.overlapped.push(overlapped(
            &mut forest,
            gpu,
            &cameras[a.warmup..],
            dt,
            (w, h),
            a.in_flight,
        )?);
    }
    let k = a.frames as f64;
    for v in [&mut cell.triangles, &mut cell.draws, &mut cell.joints, &mut cell.upload_mb] {
        *v /= k;
    }
    cell.impostors /= k;
    cell.shadow_only /= k;
    cell.sim_ms = median(&mut sim);
    cell.frame_ms = median(&mut build);
    cell.render_ms = (!draw.is_empty()).then(|| median(&mut draw));
    cell.round_cpu = vec![cell.sim_ms + cell.frame_ms];
    cell.samples = [sim, build, draw];
    cell.simulated = frame.stats.simulated;
    if cell.capped > 0 {
        cell.note = format!(
            "memory cap: up to {} lane groups kept coarser (raise --max-memory)",
            cell.capped
        );
    }
    if render_all == Some(false) {
        let why = std::mem::take(&mut cell.note);
        let sep = if why.is_empty() { "" } else { "; " };
        let what = match &cell.image {
            Some(_) => "over --max-triangles: rendered once (last frame)",
            None => "over --max-image-triangles: not rendered",
        };
        cell.note = format!("{what}{sep}{why}");
    }
    Ok(cell)
}

/// Frames per second of `forest` stepped and drawn along `cameras` as an interactive loop
/// runs them: the simulation and frame building of each frame while the GPU draws the ones
/// before, then, where `limit` frames are already in flight, a wait for the oldest before
/// this one is submitted. The clock runs from the first step to the last frame's end on
/// the GPU.
fn overlapped(
    forest: &mut Forest,
    gpu: &mut Headless,
    cameras: &[Camera],
    dt: f32,
    (w, h): (u32, u32),
    limit: u32,
) -> anyhow::Result<f64> {
    let mut frame = FrameData::default();
    let mut in_flight = std::collections::VecDeque::new();
    let start = Instant::now();
    for camera in cameras {
        forest.step(dt);
        forest.frame(camera, w as f32 / h as f32, &mut frame);
        // One frame is submitted at a time, so at most the oldest need be waited for.
        if in_flight.len() >= limit.max(1) as usize
            && let Some(oldest) = in_flight.pop_front()
        {
            gpu.wait(oldest)?;
        }
        in_flight.push_back(gpu.submit(&frame, camera));
    }
    if let Some(index) = in_flight.pop_back() {
        gpu.wait(index)?;
    }
    Ok(cameras.len() as f64 / start.elapsed().as_secs_f64().max(1e-9))
}

/// Mean FLIP error (NVIDIA's perceptual difference, 0 same … 1; through the `nv-flip`
/// crate) of `test` against `reference` at the default 67 pixels per degree.
fn flip(test: &[u8], reference: &[u8], w: u32, h: u32) -> f64 {
    let rgb = |v: &[u8]| -> Vec<u8> { v.chunks(4).flat_map(|p| [p[0], p[1], p[2]]).collect() };
    let r = nv_flip::FlipImageRgb8::with_data(w, h, &rgb(reference));
    let t = nv_flip::FlipImageRgb8::with_data(w, h, &rgb(test));
    let map = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    nv_flip::FlipPool::from_image(&map).mean() as f64
}

fn ssim(a: &[u8], b: &[u8], w: u32, h: u32) -> anyhow::Result<f64> {
    use image_compare::prelude::RgbImage;
    let rgb = |v: &[u8]| -> Vec<u8> { v.chunks(4).flat_map(|p| [p[0], p[1], p[2]]).collect() };
    let ia = RgbImage::from_raw(w, h, rgb(a)).context("image size")?;
    let ib = RgbImage::from_raw(w, h, rgb(b)).context("image size")?;
    let s =
        image_compare::rgb_similarity_structure(&image_compare::Algorithm::MSSIMSimple, &ia, &ib)?;
    Ok(s.score)
}

/// What the geometry LOD's image error is measured against, rest pose ([`still_error`]).
#[derive(Debug, Clone, Copy)]
struct Still {
    /// Mean FLIP and SSIM of all LODs against full detail.
    lod: (f64, f64),
    /// Mean FLIP and SSIM of full detail against itself seen a quarter pixel aside: how much
    /// sampling alone moves per-pixel metrics where foliage is finer than a pixel.
    sampling: (f64, f64),
}

/// `camera` turned about its eye by a quarter of a pixel's angle (image `h` pixels tall),
/// to the right.
fn quarter_pixel_aside(camera: &Camera, h: u32) -> Camera {
    let f: [f32; 3] = std::array::from_fn(|i| camera.target[i] - camera.eye[i]);
    let dist = f.iter().map(|v| v * v).sum::<f32>().sqrt().max(1e-3);
    let right = [f[1], -f[0], 0.0];
    let rn = (right[0] * right[0] + right[1] * right[1]).sqrt().max(1e-6);
    let angle = 0.25 * camera.fov_deg.to_radians() / h.max(1) as f32;
    let shift = dist * angle.tan() / rn;
    Camera { target: std::array::from_fn(|i| camera.target[i] + right[i] * shift), ..*camera }
}

/// The geometry LOD's own image error: the forest with all LODs and at full detail
/// (geometry and animation LODs off, the same instance groups) before any step, so every
/// tree stands in its rest pose and nothing but the drawn levels differs, seen from the
/// last timed frame's camera; and, for scale, full detail against itself turned a quarter
/// pixel aside. `None` where a configuration cannot be built or the full-detail frame is
/// over `--max-image-triangles`.
fn still_error(
    spec: &SceneSpec,
    gpu: &mut Headless,
    a: &Table3Bench,
    (w, h): (u32, u32),
) -> anyhow::Result<Option<Still>> {
    // Full detail first: where it is over the image limit, nothing is rendered.
    let mut images = Vec::new();
    for lods in [(false, false, true), (true, true, true)] {
        let spec = configure(spec, a, lods)?;
        let Ok(forest) = Forest::new(&spec) else { return Ok(None) };
        // The last timed frame's camera: the path's end (its start when one frame is run).
        let last = if a.warmup + a.frames > 1 { forest.path_duration() } else { 0.0 };
        let camera = forest.camera_at(last);
        let mut frame = FrameData::default();
        forest.frame(&camera, w as f32 / h as f32, &mut frame);
        if frame.stats.triangles as f64 > a.max_image_triangles {
            return Ok(None);
        }
        images.push(gpu.render(&frame, &camera)?);
        if !lods.0 {
            let aside = quarter_pixel_aside(&camera, h);
            forest.frame(&aside, w as f32 / h as f32, &mut frame);
            images.push(gpu.render(&frame, &aside)?);
        }
    }
    let [full, aside, lod] = &images[..] else { return Ok(None) };
    write_png(&a.out.join(format!("{}-still-all-LODs.png", spec.name)), w, h, lod)?;
    write_png(&a.out.join(format!("{}-still-full-detail.png", spec.name)), w, h, full)?;
    Ok(Some(Still {
        lod: (flip(lod, full, w, h), ssim(lod, full, w, h)?),
        sampling: (flip(aside, full, w, h), ssim(aside, full, w, h)?),
    }))
}

pub fn run(a: Table3Bench) -> anyhow::Result<()> {
    let (w, h) = parse_size(&a.size)?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let machine = crate::bench::machine();
    println!("machine: {machine}");
    let names: Vec<String> = a.scenes.split(',').map(|s| s.trim().to_string()).collect();
    let mut results: Vec<(String, usize, Vec<Cell>)> = Vec::new();
    let mut floors: Vec<Floor> = Vec::new();
    let mut adapter = String::new();
    for name in &names {
        let spec = SceneSpec::load(name)?;
        println!("scene {} ({} trees):", spec.name, spec.trees);
        let mut gpu: Option<Headless> = None;
        let mut rounds: Vec<Vec<Cell>> = vec![Vec::new(); CONFIGS.len()];
        for round in 0..a.rounds {
            if a.rounds > 1 {
                println!(" round {} of {}:", round + 1, a.rounds);
            }
            for (k, (label, g, an, wi)) in CONFIGS.into_iter().enumerate() {
                if a.all_lods_only && k > 0 {
                    let note = "not run (--all-lods-only)".into();
                    rounds[k].push(Cell { note, ..Cell::default() });
                    continue;
                }
                let cell = run_config(&spec, &mut gpu, &a, (w, h), (g, an, wi), false)?;
                println!(
                    "  {label:<24} {:>7} fps{}  sim {:>6.1} ms  frame {:>6.1} ms  (slowest {:.1})  render {:>8} ms  {:>7.2} M tris  {:>6.0} draws  {:>9.0} joints  {:>7.2} MB up (max {:.2})  {:>8.1} MB state  {}",
                    cell.fps().map_or("—".into(), |f| format!("{f:.2}")),
                    cell.overlapped_fps()
                        .map_or(String::new(), |f| format!(" ({f:.2} overlapped)")),
                    cell.sim_ms,
                    cell.frame_ms,
                    cell.cpu_max_ms,
                    cell.render_ms.map_or("—".into(), |r| format!("{r:.0}")),
                    cell.triangles / 1e6,
                    cell.draws,
                    cell.joints,
                    cell.upload_mb,
                    cell.upload_max_mb,
                    cell.state_mb,
                    cell.note
                );
                if let Some(p) = cell.pass_medians() {
                    println!("    GPU ms by part: {}", crate::render::parts_text(&p));
                }
                rounds[k].push(cell);
            }
        }
        let mut cells: Vec<Cell> = rounds.into_iter().map(Cell::pooled).collect();
        // Reference: full detail (geometry and animation LODs off), same instance groups.
        let reference =
            run_config(&spec, &mut gpu, &a, (w, h), (false, false, true), !a.all_lods_only)?;
        if let Some(g) = &gpu {
            adapter = g.gpu.describe();
        }
        let Some(ref_img) = reference.image.as_ref() else {
            println!("  image error: reference not rendered ({})", reference.note);
            results.push((spec.name.clone(), spec.trees, cells));
            continue;
        };
        write_png(&a.out.join(format!("{}-full-detail.png", spec.name)), w, h, ref_img)?;
        // The floor: how much one frame of wind changes the full-detail image.
        let floor = reference.previous.as_ref().map(|p| flip(p, ref_img, w, h));
        println!(
            "  full detail, one frame ({:.1} s) of motion: mean FLIP {}",
            0.1,
            floor.map_or("—".into(), |f| format!("{f:.3}"))
        );
        let still = match gpu.as_mut() {
            Some(g) => still_error(&spec, g, &a, (w, h))?,
            None => None,
        };
        println!(
            "  geometry LOD alone (rest pose, no motion), all LODs against full detail: {}",
            still
                .map_or("—".into(), |s| format!("mean FLIP {:.3}, SSIM {:.3}", s.lod.0, s.lod.1))
        );
        println!(
            "  sampling alone: full detail against itself a quarter pixel aside: {}",
            still.map_or("—".into(), |s| format!(
                "mean FLIP {:.3}, SSIM {:.3}",
                s.sampling.0, s.sampling.1
            ))
        );
        floors.push(Floor { scene: spec.name.clone(), motion: floor, still });
        for (cell, (label, ..)) in cells.iter_mut().zip(CONFIGS) {
            if let Some(img) = &cell.image {
                cell.ssim = Some(ssim(img, ref_img, w, h)?);
                cell.flip = Some(flip(img, ref_img, w, h));
                let file = format!("{}-{}.png", spec.name, label.replace(' ', "-"));
                write_png(&a.out.join(file), w, h, img)?;
            }
        }
        println!(
            "  SSIM against full detail, last frame: {}",
            cells
                .iter()
                .zip(CONFIGS)
                .map(|(c, (l, ..))| format!(
                    "{l}: {}",
                    c.ssim.map_or("—".into(), |s| format!("{s:.3}"))
                ))
                .collect::<Vec<_>>()
                .join(", ")
        );
        results.push((spec.name.clone(), spec.trees, cells));
    }
    let popping = if a.popping_frames >= 3 { Some(popping(&a)?) } else { None };
    write_outputs(&a, &machine, &adapter, (w, h), &results, &floors, popping.as_deref())
}

/// What to read a scene's image error against: one frame of motion at full detail, the
/// geometry LOD alone with nothing moving, and sampling alone.
struct Floor {
    scene: String,
    /// Mean FLIP between two consecutive full-detail frames.
    motion: Option<f64>,
    /// The geometry LOD's error and the sampling floor, rest pose ([`still_error`]).
    still: Option<Still>,
}

/// The lowest and highest of the rounds' CPU speed-ups (`off[r] / on[r]`, round by round);
/// `None` with fewer than two rounds.
fn speed_up_range(on: &[f64], off: &[f64]) -> Option<(f64, f64)> {
    if on.len() < 2 || on.len() != off.len() {
        return None;
    }
    let ratios = on.iter().zip(off).map(|(a, b)| b / a);
    Some(ratios.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), r| (lo.min(r), hi.max(r))))
}

/// "A 0.123, B —": one figure per scene, a dash where there is none.
fn per_scene(floors: &[Floor], figure: impl Fn(&Floor) -> Option<String>) -> String {
    floors
        .iter()
        .map(|f| format!("{} {}", f.scene, figure(f).unwrap_or_else(|| "—".into())))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Mean FLIP and SSIM as the Markdown writes them.
fn flip_ssim((flip, ssim): (f64, f64)) -> String {
    format!("FLIP {flip:.3} / SSIM {ssim:.3}")
}

fn write_outputs(
    a: &Table3Bench,
    machine: &str,
    adapter: &str,
    (w, h): (u32, u32),
    results: &[(String, usize, Vec<Cell>)],
    floors: &[Floor],
    popping: Option<&str>,
) -> anyhow::Result<()> {
    let mut md = String::new();
    let _ = writeln!(md, "# Table 3 on this machine\n");
    let _ =
        writeln!(md, "`{}`; machine: {machine}; adapter: {adapter}.\n", command_line(a, (w, h)));
    let _ = writeln!(
        md,
        "Frames per second (paper's figure in brackets: GeForce 6600 GT, 1024×768):\n"
    );
    let header: Vec<String> = results.iter().map(|(n, t, _)| format!("{n} ({t} trees)")).collect();
    let _ = writeln!(md, "| | {} |", header.join(" | "));
    let _ = writeln!(md, "|---|{}", "---|".repeat(results.len()));
    for (row, (label, ..)) in CONFIGS.iter().enumerate() {
        let cells: Vec<String> = results
            .iter()
            .map(|(name, _, cells)| {
                let col = ["A", "B", "C", "D"].iter().position(|s| s == name);
                let paper = col.map_or(String::new(), |c| format!(" ({})", PAPER[row][c]));
                let fps = cells[row].fps().map_or("—".into(), |f| format!("{f:.2}"));
                format!("{fps}{paper}")
            })
            .collect();
        let _ = writeln!(md, "| {label} | {} |", cells.join(" | "));
    }
    if results.iter().any(|(_, _, cells)| cells.iter().any(|c| !c.overlapped.is_empty())) {
        let _ = writeln!(
            md,
            "\nFrames per second with the CPU's work on each frame overlapping the GPU's on the ones before (`--overlapped`: {}, as an interactive loop runs; the figures above add the two):\n",
            match a.in_flight {
                1 => "one frame in flight".to_string(),
                n => format!("up to {n} frames in flight"),
            }
        );
        let _ = writeln!(md, "| | {} |", header.join(" | "));
        let _ = writeln!(md, "|---|{}", "---|".repeat(results.len()));
        for (row, (label, ..)) in CONFIGS.iter().enumerate() {
            let cells: Vec<String> = results
                .iter()
                .map(|(_, _, cells)| {
                    cells[row].overlapped_fps().map_or("—".into(), |f| format!("{f:.2}"))
                })
                .collect();
            let _ = writeln!(md, "| {label} | {} |", cells.join(" | "));
        }
    }
    if results.iter().any(|(_, _, cells)| cells.iter().any(|c| !c.passes.is_empty())) {
        let _ = writeln!(
            md,
            "\nThe GPU's time in each part of the frame, ms (`--gpu-passes`: timestamp queries between the renderer's passes; medians over the timed frames; a draw still running when the next part starts shares its time with it):\n"
        );
        let _ = writeln!(
            md,
            "| scene | configuration | {} | sum |",
            sylva_render::PASS_PARTS.join(" | ")
        );
        let _ = writeln!(md, "|---|---|{}---|", "---|".repeat(PARTS));
        for (name, _, cells) in results {
            for (c, (label, ..)) in cells.iter().zip(CONFIGS) {
                if let Some(p) = c.pass_medians() {
                    let parts: Vec<String> = p.iter().map(|t| format!("{t:.2}")).collect();
                    let sum: f64 = p.iter().sum();
                    let _ = writeln!(md, "| {name} | {label} | {} | {sum:.2} |", parts.join(" | "));
                }
            }
        }
    }
    let _ = writeln!(
        md,
        "\nPer configuration (medians over the timed frames, and the slowest frame's simulation + frame building; means for counts):\n"
    );
    let _ = writeln!(
        md,
        "| scene | configuration | sim ms | frame ms | slowest sim + frame ms | render ms | M triangles | draws | joint updates | MB uploaded: mean / max | MB animation state | simulated trees | impostors | shadow only | FLIP vs full detail | SSIM vs full detail | note |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let mut csv = String::from(
        "scene,trees,configuration,fps,sim_ms,frame_ms,render_ms,triangles,draws,joint_updates,uploaded_mb,uploaded_max_mb,state_mb,simulated,impostors,shadow_only,flip,ssim,cpu_max_ms,overlapped_fps,gpu_shadows_ms,gpu_trees_ms,gpu_impostors_ms,gpu_ground_ms,gpu_sky_resolve_ms\n",
    );
    for (name, trees, cells) in results {
        for (c, (label, ..)) in cells.iter().zip(CONFIGS) {
            let opt = |v: Option<f64>, p: usize| v.map_or("—".into(), |v| format!("{v:.p$}"));
            let _ = writeln!(
                md,
                "| {name} | {label} | {:.1} | {:.1} | {:.1} | {} | {:.2} | {:.0} | {:.0} | {:.2} / {:.2} | {:.1} | {} | {:.0} | {:.0} | {} | {} | {} |",
                c.sim_ms,
                c.frame_ms,
                c.cpu_max_ms,
                opt(c.render_ms, 0),
                c.triangles / 1e6,
                c.draws,
                c.joints,
                c.upload_mb,
                c.upload_max_mb,
                c.state_mb,
                c.simulated,
                c.impostors,
                c.shadow_only,
                opt(c.flip, 3),
                opt(c.ssim, 3),
                c.note
            );
            let _ = writeln!(
                csv,
                "{name},{trees},{label},{},{:.3},{:.3},{},{:.0},{:.0},{:.0},{:.3},{:.3},{:.3},{},{:.0},{:.0},{},{},{:.3},{},{}",
                c.fps().map_or(String::new(), |f| format!("{f:.3}")),
                c.sim_ms,
                c.frame_ms,
                c.render_ms.map_or(String::new(), |r| format!("{r:.1}")),
                c.triangles,
                c.draws,
                c.joints,
                c.upload_mb,
                c.upload_max_mb,
                c.state_mb,
                c.simulated,
                c.impostors,
                c.shadow_only,
                c.flip.map_or(String::new(), |s| format!("{s:.4}")),
                c.ssim.map_or(String::new(), |s| format!("{s:.4}")),
                c.cpu_max_ms,
                c.overlapped_fps().map_or(String::new(), |f| format!("{f:.3}")),
                match c.pass_medians() {
                    Some(p) => p.map(|t| format!("{t:.3}")).join(","),
                    None => ",".repeat(PARTS - 1),
                }
            );
        }
    }
    let _ = writeln!(
        md,
        "\nImage error floor — mean FLIP between two consecutive full-detail frames (0.1 s of wind): {}",
        per_scene(floors, |f| f.motion.map(|m| format!("{m:.3}")))
    );
    let _ = writeln!(
        md,
        "\nThe geometry LOD alone — all LODs against full detail before any step (every tree in its rest pose, nothing moving), the last timed frame's camera: {}",
        per_scene(floors, |f| f.still.map(|s| flip_ssim(s.lod)))
    );
    let _ = writeln!(
        md,
        "\nSampling alone — full detail in the rest pose against itself with the camera turned a quarter pixel aside (how much per-pixel metrics move where foliage is finer than a pixel): {}",
        per_scene(floors, |f| f.still.map(|s| flip_ssim(s.sampling)))
    );
    // Speed-up of each LOD: with all LODs against that one off, in frames per second, in
    // CPU time (simulation + frame building) and, with `--gpu-passes`, in the GPU's time
    // (the parts' sum), beside the paper's.
    let _ = writeln!(
        md,
        "\nSpeed-up of each LOD (all LODs ÷ that LOD off): FPS here · CPU ms here{}{} · FPS in the paper:\n",
        if a.rounds > 1 { " (lowest–highest of the rounds)" } else { "" },
        if a.gpu_passes { " · GPU ms here" } else { "" }
    );
    let _ = writeln!(md, "| LOD | {} |", header.join(" | "));
    let _ = writeln!(md, "|---|{}", "---|".repeat(results.len()));
    for (row, (label, ..)) in CONFIGS.iter().enumerate().skip(1) {
        let cells: Vec<String> = results
            .iter()
            .map(|(name, _, cells)| {
                let (on, off) = (&cells[0], &cells[row]);
                let fps = match (on.fps(), off.fps()) {
                    (Some(x), Some(y)) => format!("×{:.2}", x / y),
                    _ => "—".into(),
                };
                let cpu_off = off.sim_ms + off.frame_ms;
                let cpu = if cpu_off > 0.0 {
                    let ratio = format!("×{:.2}", cpu_off / (on.sim_ms + on.frame_ms));
                    match speed_up_range(&on.round_cpu, &off.round_cpu) {
                        Some((lo, hi)) => format!("{ratio} ({lo:.2}–{hi:.2})"),
                        None => ratio,
                    }
                } else {
                    "—".into()
                };
                let gpu_ms = |c: &Cell| c.pass_medians().map(|p| p.iter().sum::<f64>());
                let gpu = match (gpu_ms(on), gpu_ms(off)) {
                    (Some(x), Some(y)) if x > 0.0 => format!(" · ×{:.2}", y / x),
                    _ if a.gpu_passes => " · —".into(),
                    _ => String::new(),
                };
                let col = ["A", "B", "C", "D"].iter().position(|s| s == name);
                let paper =
                    col.map_or("—".into(), |c| format!("×{:.2}", PAPER[0][c] / PAPER[row][c]));
                format!("{fps} · {cpu}{gpu} · {paper}")
            })
            .collect();
        let _ =
            writeln!(md, "| {} | {} |", label.trim_start_matches("without "), cells.join(" | "));
    }
    if let Some(p) = popping {
        md.push_str(p);
    }
    write_atomic(&a.out.join("table3.md"), md.as_bytes())?;
    write_atomic(&a.out.join("table3.csv"), csv.as_bytes())?;
    // Chart: FPS against trees, one line per configuration (ours solid colours).
    let colours = [[30, 110, 40], [200, 60, 40], [40, 80, 200], [150, 120, 20]];
    let series = CONFIGS
        .iter()
        .enumerate()
        .map(|(row, (label, ..))| crate::plot::Series {
            label: label.to_uppercase(),
            color: colours[row],
            points: results
                .iter()
                .filter_map(|(_, trees, cells)| cells[row].fps().map(|f| (*trees as f64, f)))
                .collect(),
            markers: false,
        })
        .collect();
    let paper = CONFIGS
        .iter()
        .enumerate()
        .map(|(row, (label, ..))| crate::plot::Series {
            label: label.to_uppercase(),
            color: colours[row],
            points: [1000.0, 3000.0, 10000.0, 50000.0]
                .iter()
                .zip(PAPER[row])
                .map(|(t, f)| (*t, f))
                .collect(),
            markers: false,
        })
        .collect();
    let panels = [
        crate::plot::Panel {
            title: "FPS HERE".into(),
            x_label: "TREES".into(),
            y_label: "FRAMES PER SECOND".into(),
            log_x: true,
            log_y: true,
            y_range: None,
            series,
        },
        crate::plot::Panel {
            title: "FPS IN THE PAPER".into(),
            x_label: "TREES".into(),
            y_label: "FRAMES PER SECOND".into(),
            log_x: true,
            log_y: true,
            y_range: None,
            series: paper,
        },
    ];
    crate::plot::write_png(&a.out.join("table3.png"), &panels)?;
    println!("{md}");
    println!("wrote {}/table3.md, table3.csv, table3.png", a.out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{Cell, speed_up_range};

    /// A round's cell: its timed frames' simulation and frame-building times.
    fn round(sim: &[f64], build: &[f64], joints: f64) -> Cell {
        let mut cell = Cell { joints, ..Cell::default() };
        cell.sim_ms = super::median(&mut sim.to_vec());
        cell.frame_ms = super::median(&mut build.to_vec());
        cell.cpu_max_ms = sim.iter().zip(build).map(|(a, b)| a + b).fold(0.0, f64::max);
        cell.round_cpu = vec![cell.sim_ms + cell.frame_ms];
        cell.samples = [sim.to_vec(), build.to_vec(), Vec::new()];
        cell
    }

    /// Rounds pool into medians over every round's frames, not a median of the rounds'
    /// medians; the slowest frame is the slowest of any round; counts are the last round's.
    #[test]
    fn rounds_pool_their_frames_and_keep_each_rounds_cpu_time() {
        let a = round(&[10.0, 11.0, 30.0], &[1.0, 1.0, 1.0], 5.0);
        let b = round(&[12.0, 13.0, 14.0], &[2.0, 2.0, 2.0], 7.0);
        let c = Cell::pooled(vec![a, b]);
        // Pooled 10, 11, 12, 13, 14, 30: the upper median 13 (medians of the rounds: 11
        // and 13, whose mean would be 12).
        assert_eq!(c.sim_ms, 13.0);
        assert_eq!(c.frame_ms, 2.0);
        assert_eq!(c.cpu_max_ms, 31.0);
        assert_eq!(c.round_cpu, vec![12.0, 15.0]);
        assert_eq!(c.joints, 7.0);
        assert!(c.render_ms.is_none(), "nothing rendered in any round");
        // One round pools to itself.
        let one = Cell::pooled(vec![round(&[4.0, 5.0, 6.0], &[1.0, 2.0, 3.0], 1.0)]);
        assert_eq!((one.sim_ms, one.frame_ms, one.round_cpu.len()), (5.0, 2.0, 1));
    }

    /// A configuration's speed-up is taken round by round against the round's own run
    /// with all LODs, so a slow round slows both sides of its ratio.
    #[test]
    fn the_speed_up_range_pairs_rounds() {
        // All LODs: 10 then 20 ms (the machine twice as slow in round 2); the LOD off:
        // 15 then 30 ms. Round by round ×1.5 both times; unpaired, 15/20 to 30/10.
        assert_eq!(speed_up_range(&[10.0, 20.0], &[15.0, 30.0]), Some((1.5, 1.5)));
        assert_eq!(speed_up_range(&[10.0, 20.0], &[12.0, 30.0]), Some((1.2, 1.5)));
        assert_eq!(speed_up_range(&[10.0], &[15.0]), None, "one round: no range");
    }
}
