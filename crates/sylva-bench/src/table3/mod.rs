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

use sylva_frames::render::{median, parse_size, write_png};

mod measure;
mod metrics;
mod popping;
mod report;

use measure::*;
use metrics::*;
use popping::popping;
use report::write_outputs;

/// Defaults of `--max-triangles`, `--max-image-triangles` and `--popping-frames`.
const MAX_TRIANGLES: f64 = 12e6;
const MAX_IMAGE_TRIANGLES: f64 = 80e6;
const POPPING_FRAMES: usize = 40;

#[derive(Debug, Args)]
pub struct Table3Bench {
    /// Scenes, comma-separated (built-in names or scene files).
    #[arg(long, default_value = "A,B,C,D")]
    scenes: String,
    /// Camera paths each scene runs along, comma-separated: fly-in (the scene's own, or
    /// the default fly-in), walk (eye height through the forest), low-flight (across the
    /// canopy), a name of the scene's `paths`, or all (the three built in and the scene's own). A scene on a
    /// path other than the fly-in is reported as "SCENE PATH", and a summary gives each
    /// scene's worst path.
    #[arg(long, default_value = "fly-in")]
    path: String,
    /// Image size.
    #[arg(long, default_value = "1024x768")]
    size: String,
    /// Frames timed per configuration (after the warm-up), spread along the camera path
    /// (at least 1).
    #[arg(long, default_value_t = 6, value_parser = sylva_frames::at_least_one)]
    frames: usize,
    /// Warm-up frames, not timed.
    #[arg(long, default_value_t = 2)]
    warmup: usize,
    /// Configurations drawing more triangles per frame are timed on the CPU side only.
    #[arg(value_parser = sylva_frames::finite::<f64>, long, default_value_t = MAX_TRIANGLES)]
    max_triangles: f64,
    /// Their last frame is still rendered for the image error below this many triangles.
    #[arg(value_parser = sylva_frames::finite::<f64>, long, default_value_t = MAX_IMAGE_TRIANGLES)]
    max_image_triangles: f64,
    /// First LOD level drawn as an impostor (1 … 6; default: the scene's).
    #[arg(long)]
    far_level: Option<u32>,
    /// Geometry-LOD threshold h₀ (default: the scene's).
    #[arg(value_parser = sylva_frames::finite::<f32>, long)]
    lod_fraction: Option<f32>,
    /// Screen-space error budget, pixels (0 … 64; 0: levels by fraction; default: the
    /// scene's).
    #[arg(value_parser = sylva_frames::finite::<f32>, long)]
    lod_error: Option<f32>,
    /// Thinning of far impostors, pixels (0 … 256; 0: off): trees drawn as impostors and
    /// shorter in the image than this are thinned out, the ones kept drawn wider (default:
    /// the scene's, off).
    #[arg(value_parser = sylva_frames::finite::<f32>, long)]
    thin_px: Option<f32>,
    /// Occlusion culling on in every configuration: trees hidden behind nearer trunks and
    /// crowns are not drawn (default: the scene's, off).
    #[arg(long)]
    occlusion: bool,
    /// Memory the animation state may take, GB (default: the scene's cap, at most three
    /// quarters of the free memory). Over it, lane groups are kept at coarser prefixes (a
    /// note says how many); without the animation LOD the forest is refused.
    #[arg(value_parser = sylva_frames::finite::<f64>, long)]
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

pub fn run(a: Table3Bench) -> anyhow::Result<()> {
    let (w, h) = parse_size(&a.size)?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let machine = crate::machine();
    println!("machine: {machine}");
    let names: Vec<String> = a.scenes.split(',').map(|s| s.trim().to_string()).collect();
    let mut results: Vec<(String, usize, Vec<Cell>)> = Vec::new();
    let mut floors: Vec<Floor> = Vec::new();
    let mut adapter = String::new();
    let mut jobs = Vec::new();
    for name in &names {
        let base = SceneSpec::load(name)?;
        // `all`: the three built in, then the scene's own named paths.
        let paths: Vec<&str> = if a.path.trim() == "all" {
            let own = base.paths.keys().map(String::as_str);
            let own = own.filter(|p| !sylva_forest::BUILTIN_PATHS.contains(p));
            sylva_forest::BUILTIN_PATHS.iter().copied().chain(own).collect()
        } else {
            a.path.split(',').map(str::trim).collect()
        };
        for &path in &paths {
            jobs.push(on_path(&base, path)?);
        }
    }
    for spec in &jobs {
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
                let cell = run_config(spec, &mut gpu, &a, (w, h), (g, an, wi), false)?;
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
                    println!("    GPU ms by part: {}", sylva_frames::render::parts_text(&p));
                }
                rounds[k].push(cell);
            }
        }
        let mut cells: Vec<Cell> = rounds.into_iter().map(Cell::pooled).collect();
        let thinning = match gpu.as_mut() {
            Some(g) => thinning_error(spec, g, &a, (w, h))?,
            None => None,
        };
        if let Some(t) = thinning {
            println!(
                "  thinning alone (rest pose), against every far tree drawn: mean FLIP {:.3}, SSIM {:.3}; that frame a quarter pixel aside: mean FLIP {:.3}",
                t.lod.0, t.lod.1, t.sampling.0
            );
        }
        // Reference: full detail (geometry and animation LODs off), same instance groups.
        let reference =
            run_config(spec, &mut gpu, &a, (w, h), (false, false, true), !a.all_lods_only)?;
        if let Some(g) = &gpu {
            adapter = g.gpu.describe();
        }
        let Some(ref_img) = reference.image.as_ref() else {
            println!("  image error: reference not rendered ({})", reference.note);
            if thinning.is_some() {
                floors.push(Floor {
                    scene: spec.name.clone(),
                    motion: None,
                    still: None,
                    thinning,
                });
            }
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
            Some(g) => still_error(spec, g, &a, (w, h))?,
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
        floors.push(Floor { scene: spec.name.clone(), motion: floor, still, thinning });
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

/// Scene `base` on camera path `path`: named "SCENE PATH" unless it is the fly-in.
fn on_path(base: &SceneSpec, path: &str) -> anyhow::Result<SceneSpec> {
    if !base.has_path(path) {
        anyhow::bail!(
            "--path {path}: scene {} has fly-in, walk, low-flight{}",
            base.name,
            base.paths.keys().map(|k| format!(", {k}")).collect::<String>()
        );
    }
    let mut spec = base.clone();
    spec.path = path.to_string();
    if path != sylva_forest::FLY_IN {
        spec.name = format!("{} {path}", base.name);
    }
    Ok(spec)
}

#[cfg(test)]
mod tests;
