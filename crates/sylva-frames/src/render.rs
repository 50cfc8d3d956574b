//! `sylva render` and the forest half of `sylva demo`: headless frames of a scene.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, bail};
use clap::Args;
use sylva_forest::{Forest, FrameData, SceneSpec, WindSource};
use sylva_render::Headless;
use sylva_wind::io::atomic::AtomicFile;

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Scene: a built-in name (small, A, B, C, D, E) or a scene file (.toml).
    #[arg(long, default_value = "A")]
    pub scene: String,
    /// Seconds of simulated time to render.
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = 5.0)]
    pub seconds: f64,
    /// Frames per second (the fixed simulation step is 1/fps).
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = 12.0)]
    pub fps: f64,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "1024x768")]
    pub size: String,
    /// Output folder: frame_0000.png …, forest.gif (and forest.mp4 with ffmpeg).
    #[arg(long, default_value = "out/render")]
    pub out: PathBuf,
    /// Wind instead of the scene's: a preset (calm, breeze, strong, storm), a steady speed
    /// in m/s, or a wind file (.swf, .npy, .zarr).
    #[arg(long)]
    pub wind: Option<WindSource>,
    /// Geometry-LOD threshold h₀: full detail only for trees taller than this fraction of
    /// the image; one level coarser per factor 3 smaller. Larger is coarser and faster.
    /// Default: the scene's (`[lod] fraction`, 0.2 unless set).
    #[arg(value_parser = crate::finite::<f32>, long)]
    pub lod_fraction: Option<f32>,
    /// Skip the animated GIF.
    #[arg(long)]
    pub no_gif: bool,
    /// Follow the scene's camera path (its default fly-in when it has none). Scenes with a
    /// path follow it anyway.
    #[arg(long)]
    pub camera_path: bool,
    /// Also read the GPU's time in each part of every frame (timestamp queries between the
    /// renderer's passes: shadows, trees, impostors, ground, sky) and report their medians.
    #[arg(long)]
    pub gpu_passes: bool,
    #[command(flatten)]
    pub lod: LodArgs,
}

/// The LOD switches of `render`, `view` and `bench` (each overrides the scene's `[lod]`), and
/// the memory cap of the forest's animation state.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct LodArgs {
    /// Geometry LOD off: every tree at full detail (no coarser meshes, no impostors).
    #[arg(long)]
    pub no_geometry_lod: bool,
    /// Animation LOD off: every joint of every simulated tree stepped every frame.
    #[arg(long)]
    pub no_animation_lod: bool,
    /// Wind-field LOD off: every tree simulated on its own (no instance groups).
    #[arg(long)]
    pub no_wind_lod: bool,
    /// Occlusion culling on: trees hidden behind nearer trunks and crowns are not drawn
    /// (default: the scene's `[lod] occlusion`, off).
    #[arg(long)]
    pub occlusion: bool,
    /// First LOD level drawn as an impostor (1 … 6; the scene's, default 1: full detail,
    /// then the impostor).
    #[arg(long)]
    pub far_level: Option<u32>,
    /// Screen-space error budget of the mesh levels, pixels (0 … 64): a tree nearer than its
    /// impostor is drawn at the coarsest mesh level whose geometric error against full
    /// detail spans at most this many pixels, the impostor still placed by the image-height
    /// fraction (0: every level by the fraction). Default: the scene's (`[lod] error_px`).
    #[arg(long, value_parser = crate::finite::<f32>)]
    pub lod_error: Option<f32>,
    /// Thinning of far impostors, pixels (0 … 256; 0: off): trees drawn as impostors and
    /// shorter in the image than this are thinned out stochastically, the ones kept drawn
    /// wider so the far canopy covers the image as before. Default: the scene's (`[lod]
    /// thin_px`).
    #[arg(long, value_parser = crate::finite::<f32>)]
    pub thin_px: Option<f32>,
    /// Memory the forest's animation state may take, GB (replaces the scene's
    /// `max_state_mb`). Without it the cap is the scene's, and at most three quarters of
    /// the memory this machine has free.
    #[arg(long, value_parser = crate::finite::<f64>)]
    pub max_memory: Option<f64>,
}

impl LodArgs {
    /// Apply to `spec` (validated: `far_level` in 1 … 6, `max_memory` in (0, 1000] GB).
    pub fn apply(&self, spec: &mut SceneSpec) -> anyhow::Result<()> {
        if let Some(f) = self.far_level {
            if !(1..=6).contains(&f) {
                bail!("--far-level {f}: must be 1 … 6");
            }
            spec.lod.far_level = f;
        }
        if let Some(px) = self.lod_error {
            if !(0.0..=64.0).contains(&px) {
                bail!("--lod-error {px}: must be 0 … 64 pixels");
            }
            spec.lod.error_px = px;
        }
        if let Some(px) = self.thin_px {
            if !(0.0..=256.0).contains(&px) {
                bail!("--thin-px {px}: must be 0 … 256 pixels");
            }
            spec.lod.thin_px = px;
        }
        apply_max_memory(spec, self.max_memory)?;
        spec.lod.geometry &= !self.no_geometry_lod;
        spec.lod.animation &= !self.no_animation_lod;
        spec.lod.wind &= !self.no_wind_lod;
        spec.lod.occlusion |= self.occlusion;
        Ok(())
    }
}

/// Set the cap on `spec`'s animation state from `--max-memory` (GB, in (0, 1000]); without
/// it, lower the scene's cap to three quarters of the memory this machine has free.
pub fn apply_max_memory(spec: &mut SceneSpec, max_memory: Option<f64>) -> anyhow::Result<()> {
    match max_memory {
        Some(gb) => {
            if !(gb > 0.0 && gb <= 1000.0) {
                bail!("--max-memory {gb}: a memory budget must be in (0, 1000] GB");
            }
            spec.max_state_mb = ((gb * 1000.0) as usize).max(1);
        }
        None => {
            if let Some(free) = crate::available_memory() {
                let mb = (0.75 * free / 1e6) as usize;
                spec.max_state_mb = spec.max_state_mb.min(mb.max(1));
            }
        }
    }
    Ok(())
}

pub fn parse_size(s: &str) -> anyhow::Result<(u32, u32)> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .with_context(|| format!("--size `{s}`: expected WIDTHxHEIGHT, e.g. 1024x768"))?;
    let w: u32 =
        w.trim().parse().with_context(|| format!("--size `{s}`: width is not a whole number"))?;
    let h: u32 =
        h.trim().parse().with_context(|| format!("--size `{s}`: height is not a whole number"))?;
    if !(16..=8192).contains(&w) || !(16..=8192).contains(&h) {
        bail!("--size `{s}`: each side must be 16 … 8192");
    }
    Ok((w, h))
}

/// Median of `v` (reordered); NaN when empty.
pub fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Each part's median over frames of the GPU's time by part (`--gpu-passes`); `None`
/// without frames.
pub fn part_medians(
    frames: &[[f64; sylva_render::PASS_PARTS.len()]],
) -> Option<[f64; sylva_render::PASS_PARTS.len()]> {
    (!frames.is_empty()).then(|| {
        std::array::from_fn(|k| median(&mut frames.iter().map(|p| p[k]).collect::<Vec<f64>>()))
    })
}

/// Write an RGBA image as PNG, atomically (the previous file stays whole until the new one is).
pub fn write_png(path: &Path, w: u32, h: u32, rgba: &[u8]) -> anyhow::Result<()> {
    let mut file =
        AtomicFile::create(path).with_context(|| format!("creating {}", path.display()))?;
    let mut enc = png::Encoder::new(&mut file, w, h);
    enc.set_color(png::ColorType::Rgba);
    enc.set_depth(png::BitDepth::Eight);
    let mut wr = enc.write_header()?;
    wr.write_image_data(rgba)?;
    wr.finish()?;
    file.commit().with_context(|| format!("writing {}", path.display()))
}

/// Half-size (or smaller) copy for the GIF: box filter by `k`.
pub fn shrink(rgba: &[u8], w: u32, h: u32, k: u32) -> (Vec<u8>, u32, u32) {
    let (nw, nh) = (w / k, h / k);
    let mut out = vec![0u8; (nw * nh * 4) as usize];
    for y in 0..nh {
        for x in 0..nw {
            for c in 0..4 {
                let mut s = 0u32;
                for dy in 0..k {
                    for dx in 0..k {
                        s += rgba[(((y * k + dy) * w + x * k + dx) * 4 + c) as usize] as u32;
                    }
                }
                out[((y * nw + x) * 4 + c) as usize] = (s / (k * k)) as u8;
            }
        }
    }
    (out, nw, nh)
}

/// What a render run measured.
#[derive(Debug)]
pub struct RenderReport {
    pub frames: usize,
    pub sim_ms: f64,
    /// Of which the sway step (wind sampling, springs, palettes).
    pub step_ms: f64,
    pub render_ms: f64,
    pub triangles: f64,
    /// Median GPU time of each part of the frame, ms (`--gpu-passes`).
    pub passes: Option<[f64; sylva_render::PASS_PARTS.len()]>,
    pub simulated: usize,
    pub joints: usize,
    pub adapter: String,
    pub gif: Option<PathBuf>,
    pub mp4: Option<PathBuf>,
}

/// Remove what an earlier clip left in `dir`: its frames (`frame_NNNN.png`), `forest.gif`
/// and `forest.mp4`. Nothing else in the folder is touched.
fn remove_earlier_clip(dir: &Path) -> anyhow::Result<()> {
    let entries = std::fs::read_dir(dir).with_context(|| format!("listing {}", dir.display()))?;
    for e in entries.flatten() {
        let name = e.file_name();
        let name = name.to_string_lossy();
        let frame = name
            .strip_prefix("frame_")
            .and_then(|r| r.strip_suffix(".png"))
            .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()));
        if frame || name == "forest.gif" || name == "forest.mp4" {
            std::fs::remove_file(e.path())
                .with_context(|| format!("removing the earlier clip's {}", e.path().display()))?;
        }
    }
    Ok(())
}

/// A clip as `sylva render` writes it: numbered PNG frames (`frame_0000.png` …), a looping
/// GIF at most 480 px wide (`forest.gif`), and an MP4 through ffmpeg when it is installed
/// (`forest.mp4`, at the clip's mean frame rate).
pub struct ClipWriter {
    dir: std::path::PathBuf,
    w: u32,
    h: u32,
    k: u32,
    gif: Option<gif::Encoder<AtomicFile>>,
    frames: usize,
    seconds: f64,
}

impl std::fmt::Debug for ClipWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ClipWriter")
            .field("dir", &self.dir)
            .field("size", &(self.w, self.h))
            .field("frames", &self.frames)
            .field("seconds", &self.seconds)
            .finish_non_exhaustive()
    }
}

impl ClipWriter {
    /// Start a clip of `w × h` frames in `dir` (created), with a GIF unless `gif` is false.
    /// A clip written into a folder holding an earlier one replaces it: the earlier clip's
    /// frames, GIF and MP4 are removed first, so the folder never mixes two runs.
    pub fn new(dir: &Path, w: u32, h: u32, gif: bool) -> anyhow::Result<ClipWriter> {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        remove_earlier_clip(dir)?;
        let k = (w / 480).max(1);
        let gif = if gif {
            let path = dir.join("forest.gif");
            let f = AtomicFile::create(&path)
                .with_context(|| format!("creating {}", path.display()))?;
            let mut e = gif::Encoder::new(f, (w / k) as u16, (h / k) as u16, &[])?;
            e.set_repeat(gif::Repeat::Infinite)?;
            Some(e)
        } else {
            None
        };
        Ok(ClipWriter { dir: dir.to_path_buf(), w, h, k, gif, frames: 0, seconds: 0.0 })
    }

    /// Add a frame (RGBA8, rows top first) shown for `seconds`.
    pub fn frame(&mut self, rgba: &[u8], seconds: f64) -> anyhow::Result<()> {
        let (w, h) = (self.w, self.h);
        write_png(&self.dir.join(format!("frame_{:04}.png", self.frames)), w, h, rgba)?;
        if let Some(e) = self.gif.as_mut() {
            let (mut small, sw, sh) = shrink(rgba, w, h, self.k);
            let mut f = gif::Frame::from_rgba_speed(sw as u16, sh as u16, &mut small, 20);
            f.delay = (100.0 * seconds).round().clamp(1.0, 65535.0) as u16;
            e.write_frame(&f)?;
        }
        self.frames += 1;
        self.seconds += seconds;
        Ok(())
    }

    /// Frames written so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Close the GIF and encode the MP4: the paths of those written.
    pub fn finish(
        self,
    ) -> anyhow::Result<(Option<std::path::PathBuf>, Option<std::path::PathBuf>)> {
        let gif_path = self.dir.join("forest.gif");
        let gif = match self.gif {
            Some(e) => {
                let f =
                    e.into_inner().with_context(|| format!("writing {}", gif_path.display()))?;
                f.commit().with_context(|| format!("writing {}", gif_path.display()))?;
                Some(gif_path)
            }
            None => None,
        };
        if self.frames == 0 {
            return Ok((gif, None));
        }
        // ffmpeg writes to the temporary name (with the container named by `-f`); the clip
        // replaces forest.mp4 only when the encoder succeeded.
        let fps = self.frames as f64 / self.seconds.max(1e-3);
        let mp4 = self.dir.join("forest.mp4");
        let mp4_file =
            AtomicFile::create(&mp4).with_context(|| format!("creating {}", mp4.display()))?;
        let made = std::process::Command::new("ffmpeg")
            .args(["-y", "-loglevel", "error", "-framerate"])
            .arg(format!("{fps}"))
            .arg("-i")
            .arg(self.dir.join("frame_%04d.png"))
            .args(["-pix_fmt", "yuv420p", "-vf", "scale=trunc(iw/2)*2:trunc(ih/2)*2", "-f", "mp4"])
            .arg(mp4_file.temp_path())
            .status()
            .map(|s| s.success())
            .unwrap_or(false);
        Ok((gif, (made && mp4_file.commit().is_ok()).then_some(mp4)))
    }
}

/// Renders the clip `a` asks for; the first `warmup` frames are written like the others but
/// left out of the report's medians and mean (`frames` counts the rest).
pub fn render(a: &RenderArgs, warmup: usize) -> anyhow::Result<RenderReport> {
    let mut spec = SceneSpec::load(&a.scene)?;
    if let Some(w) = &a.wind {
        spec.set_wind(w);
    }
    if !(a.fps > 0.0 && a.fps <= 1000.0) {
        bail!("--fps {}: must be in (0, 1000]", a.fps);
    }
    if !(a.seconds > 0.0 && a.seconds <= 3600.0) {
        bail!("--seconds {}: must be in (0, 3600]", a.seconds);
    }
    a.lod.apply(&mut spec)?;
    if let Some(h0) = a.lod_fraction {
        if !(h0 > 0.0 && h0 <= 100.0) {
            bail!("--lod-fraction {h0}: must be in (0, 100]");
        }
        spec.lod.fraction = h0;
    }
    let (w, h) = parse_size(&a.size)?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let t0 = Instant::now();
    let mut forest = Forest::new(&spec)?;
    println!(
        "scene {}: {} trees, {} species, {}, built in {:.2} s",
        spec.name,
        forest.trees(),
        forest.species.len(),
        forest.wind_summary(),
        t0.elapsed().as_secs_f64()
    );
    let mut gpu = Headless::new(&forest, w, h)?;
    let adapter = gpu.gpu.describe();
    println!("adapter {adapter}, {}× MSAA, {w}×{h}", gpu.renderer().samples());
    if a.gpu_passes && !gpu.time_passes() {
        println!("--gpu-passes: this adapter has no timestamps inside passes");
    }
    let follow = a.camera_path || !spec.camera_path.is_empty();
    let fixed = forest.default_camera();
    let frames = (a.seconds * a.fps).round().max(1.0) as usize;
    let dt = (1.0 / a.fps) as f32;
    let mut clip = ClipWriter::new(&a.out, w, h, !a.no_gif)?;
    let mut frame = FrameData::with_rows(h);
    let (mut sim, mut draw, mut tris) = (Vec::new(), Vec::new(), Vec::new());
    let mut step = Vec::new();
    let mut passes: Vec<[f64; sylva_render::PASS_PARTS.len()]> = Vec::new();
    let bar = indicatif::ProgressBar::new(frames as u64);
    let aspect = w as f32 / h as f32;
    // A frame for the first camera before the first step: the animation LOD then simulates
    // (and stores) from the start only what is drawn.
    let first = if follow { forest.camera_at(dt) } else { fixed };
    forest.frame(&first, aspect, &mut frame);
    for i in 0..frames {
        let camera = if follow { forest.camera_at((i + 1) as f32 * dt) } else { fixed };
        let t = Instant::now();
        forest.step(dt);
        forest.frame(&camera, aspect, &mut frame);
        sim.push(t.elapsed().as_secs_f64() * 1e3);
        step.push(frame.stats.sim_ms);
        let t = Instant::now();
        let rgba = gpu.render(&frame, &camera)?;
        draw.push(t.elapsed().as_secs_f64() * 1e3);
        if let Some(p) = gpu.pass_times()? {
            passes.push(p);
        }
        tris.push(frame.stats.triangles as f64);
        clip.frame(&rgba, dt as f64)?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    let (gif, mp4) = clip.finish()?;
    let skip = warmup.min(frames - 1);
    for timings in [&mut sim, &mut step, &mut draw, &mut tris] {
        timings.drain(..skip);
    }
    passes.drain(..skip.min(passes.len()));
    Ok(RenderReport {
        frames: frames - skip,
        sim_ms: median(&mut sim),
        step_ms: median(&mut step),
        render_ms: median(&mut draw),
        triangles: tris.iter().sum::<f64>() / tris.len() as f64,
        passes: part_medians(&passes),
        simulated: frame.stats.simulated,
        joints: frame.stats.joints,
        adapter,
        gif,
        mp4,
    })
}

pub fn print_report(a: &RenderArgs, r: &RenderReport) {
    println!(
        "{} frames: simulation {:.1} ms (sway step {:.1} ms), rendering {:.1} ms per frame (medians), {:.0} triangles per frame",
        r.frames, r.sim_ms, r.step_ms, r.render_ms, r.triangles
    );
    println!(
        "{} simulated trees (instance groups), {} joints stepped per frame; adapter {}",
        r.simulated, r.joints, r.adapter
    );
    if let Some(line) = passes_line(r) {
        println!("{line}");
    }
    println!("wrote {}/frame_0000.png … frame_{:04}.png", a.out.display(), r.frames - 1);
    if let Some(g) = &r.gif {
        println!("wrote {}", g.display());
    }
    if let Some(m) = &r.mp4 {
        println!("wrote {}", m.display());
    }
}

/// The GPU's median time in each part of the frame, one line (`--gpu-passes`).
pub fn passes_line(r: &RenderReport) -> Option<String> {
    r.passes.map(|p| format!("GPU ms by part (medians): {}", parts_text(&p)))
}

/// The GPU's time by part, each named, and their sum: `shadows 0.72 · … · sum 13.08`.
pub fn parts_text(p: &[f64; sylva_render::PASS_PARTS.len()]) -> String {
    let parts: Vec<String> =
        sylva_render::PASS_PARTS.iter().zip(p).map(|(n, t)| format!("{n} {t:.2}")).collect();
    format!("{} · sum {:.2}", parts.join(" · "), p.iter().sum::<f64>())
}
