//! Running one configuration of one scene along its path: timings, counts and its last frame.

use super::*;

/// The paper's Table 3 (FPS; GeForce 6600 GT, Athlon XP 3000+, 1024×768): rows in
/// [`CONFIGS`] order, columns A–D.
pub(super) const PAPER: [[f64; 4]; 4] =
    [[20.0, 14.5, 8.3, 2.2], [15.3, 9.5, 3.9, 1.0], [14.9, 11.6, 7.4, 2.1], [7.8, 3.4, 1.1, 0.2]];

/// (row label, geometry, animation, wind-field LOD).
pub(super) const CONFIGS: [(&str, bool, bool, bool); 4] = [
    ("with all LODs", true, true, true),
    ("without geometry LOD", false, true, true),
    ("without animation LOD", true, false, true),
    ("without wind-field LOD", true, true, false),
];

/// What one configuration measured.
#[derive(Debug, Clone, Default)]
pub(super) struct Cell {
    pub(super) note: String,
    pub(super) sim_ms: f64,
    pub(super) frame_ms: f64,
    /// The slowest timed frame's simulation + frame building (a hitch the medians hide:
    /// a lane group's memory growing, say).
    pub(super) cpu_max_ms: f64,
    pub(super) render_ms: Option<f64>,
    /// Frames per second with the CPU's work on a frame overlapping the GPU's on the one
    /// before (`--overlapped`; each round's, the median reported).
    pub(super) overlapped: Vec<f64>,
    pub(super) triangles: f64,
    pub(super) draws: f64,
    pub(super) joints: f64,
    pub(super) upload_mb: f64,
    /// The most uploaded in one timed frame (the target is per frame).
    pub(super) upload_max_mb: f64,
    /// The most animation state held in one timed frame, MB.
    pub(super) state_mb: f64,
    /// The most lane groups the memory cap held back in one timed frame.
    pub(super) capped: usize,
    pub(super) simulated: usize,
    pub(super) impostors: f64,
    /// Trees out of view cast into the shadow map only, mean per timed frame.
    pub(super) shadow_only: f64,
    /// Trees in the view cone hidden by nearer trees (not drawn), mean per timed frame.
    pub(super) occluded: f64,
    /// Trees drawn (in view and not hidden), mean per timed frame.
    pub(super) drawn: f64,
    pub(super) ssim: Option<f64>,
    pub(super) flip: Option<f64>,
    pub(super) image: Option<Vec<u8>>,
    /// The frame before the last, when asked for (the reference's motion floor).
    pub(super) previous: Option<Vec<u8>>,
    /// The timed frames' simulation, frame-building and rendering times, ms (every
    /// round's, pooled for the medians).
    pub(super) samples: [Vec<f64>; 3],
    /// Each round's median simulation + frame building, ms.
    pub(super) round_cpu: Vec<f64>,
    /// The GPU's time in each part of every timed frame (`--gpu-passes`), ms, in the order
    /// of [`sylva_render::PASS_PARTS`] (every round's, pooled).
    pub(super) passes: Vec<[f64; PARTS]>,
}

/// Parts of a frame timed on the GPU.
pub(super) const PARTS: usize = sylva_render::PASS_PARTS.len();

impl Cell {
    /// The median GPU time of each part of the frame, ms (`--gpu-passes`).
    pub(super) fn pass_medians(&self) -> Option<[f64; PARTS]> {
        sylva_frames::render::part_medians(&self.passes)
    }

    /// Pool the rounds `cells` (in order) into one: medians over all their timed frames,
    /// the slowest frame of any, each round's CPU median; the rest from the last round.
    pub(super) fn pooled(cells: Vec<Cell>) -> Cell {
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
    pub(super) fn fps(&self) -> Option<f64> {
        self.render_ms.map(|r| 1000.0 / (self.sim_ms + self.frame_ms + r))
    }

    /// The median over the rounds of the frames per second with CPU and GPU overlapped.
    pub(super) fn overlapped_fps(&self) -> Option<f64> {
        (!self.overlapped.is_empty()).then(|| median(&mut self.overlapped.clone()))
    }
}

/// `spec` with the three LOD switches `lods` (geometry, animation, wind field) and the
/// command line's overrides.
pub(super) fn configure(
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
    if let Some(px) = a.lod_error {
        anyhow::ensure!((0.0..=64.0).contains(&px), "--lod-error {px}: must be 0 … 64 pixels");
        spec.lod.error_px = px;
    }
    if let Some(px) = a.thin_px {
        anyhow::ensure!((0.0..=256.0).contains(&px), "--thin-px {px}: must be 0 … 256 pixels");
        spec.lod.thin_px = px;
    }
    spec.lod.occlusion |= a.occlusion;
    sylva_frames::render::apply_max_memory(&mut spec, a.max_memory)?;
    Ok(spec)
}

/// The command that reproduces the run: its scenes, size and frame counts, and every option
/// set away from its default.
pub(super) fn command_line(a: &Table3Bench, (w, h): (u32, u32)) -> String {
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
    if let Some(px) = a.lod_error {
        let _ = write!(c, " --lod-error {px}");
    }
    if let Some(px) = a.thin_px {
        let _ = write!(c, " --thin-px {px}");
    }
    if let Some(m) = a.max_memory {
        let _ = write!(c, " --max-memory {m}");
    }
    if a.occlusion {
        c.push_str(" --occlusion");
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

impl Cell {
    /// One timed frame's figures: counts summed (their means taken by [`Cell::finish`]),
    /// maxima raised; `cpu_ms` its simulation + frame building.
    fn add_frame(&mut self, s: &sylva_forest::FrameStats, cpu_ms: f64) {
        self.cpu_max_ms = self.cpu_max_ms.max(cpu_ms);
        self.triangles += s.triangles as f64;
        self.draws += s.draw_calls as f64;
        self.joints += s.joints as f64;
        self.upload_mb += s.uploaded_bytes as f64 / 1e6;
        self.upload_max_mb = self.upload_max_mb.max(s.uploaded_bytes as f64 / 1e6);
        self.state_mb = self.state_mb.max(s.state_bytes as f64 / 1e6);
        self.capped = self.capped.max(s.state_capped);
        self.impostors += s.impostors as f64;
        self.shadow_only += s.shadow_only as f64;
        self.occluded += s.occluded as f64;
        self.drawn += s.drawn as f64;
    }

    /// After `frames` timed frames: the counts' means, the medians of the `samples`
    /// (simulation, frame building, rendering ms), and the notes (the memory cap; with
    /// `over_limit`, why the configuration was not rendered every frame).
    fn finish(&mut self, frames: usize, samples: [Vec<f64>; 3], over_limit: bool) {
        let k = frames as f64;
        for v in [&mut self.triangles, &mut self.draws, &mut self.joints, &mut self.upload_mb] {
            *v /= k;
        }
        self.impostors /= k;
        self.shadow_only /= k;
        self.occluded /= k;
        self.drawn /= k;
        let [mut sim, mut build, mut draw] = samples;
        self.sim_ms = median(&mut sim);
        self.frame_ms = median(&mut build);
        self.render_ms = (!draw.is_empty()).then(|| median(&mut draw));
        self.round_cpu = vec![self.sim_ms + self.frame_ms];
        self.samples = [sim, build, draw];
        if self.capped > 0 {
            self.note = format!(
                "memory cap: up to {} lane groups kept coarser (raise --max-memory)",
                self.capped
            );
        }
        if over_limit {
            let why = std::mem::take(&mut self.note);
            let sep = if why.is_empty() { "" } else { "; " };
            let what = match &self.image {
                Some(_) => "over --max-triangles: rendered once (last frame)",
                None => "over --max-image-triangles: not rendered",
            };
            self.note = format!("{what}{sep}{why}");
        }
    }
}

/// One configuration of one scene along its path: warm-up, timed frames (waited for, and
/// with `--overlapped` in flight), and the last frame kept for the image error.
pub(super) fn run_config(
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
    let mut frame = FrameData::with_rows(h);
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
            cell.add_frame(&frame.stats, t_sim + t_frame);
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
    cell.simulated = frame.stats.simulated;
    cell.finish(a.frames, [sim, build, draw], render_all == Some(false));
    Ok(cell)
}

/// Frames per second of `forest` stepped and drawn along `cameras` as an interactive loop
/// runs them: the simulation and frame building of each frame while the GPU draws the ones
/// before, then, where `limit` frames are already in flight, a wait for the oldest before
/// this one is submitted. The clock runs from the first step to the last frame's end on
/// the GPU.
pub(super) fn overlapped(
    forest: &mut Forest,
    gpu: &mut Headless,
    cameras: &[Camera],
    dt: f32,
    (w, h): (u32, u32),
    limit: u32,
) -> anyhow::Result<f64> {
    let mut frame = FrameData::with_rows(h);
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
