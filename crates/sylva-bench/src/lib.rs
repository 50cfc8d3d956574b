//! `sylva bench …`: scene-scale benchmarks. Figures are medians of several runs, measured
//! side by side in one process, printed with the machine they ran on.

pub mod table3;

use std::time::Instant;

use anyhow::Context;
use clap::{Args, Subcommand};

use sylva_frames::render::median;
use sylva_wind::{CoherenceSpeed, Grid, Method, SynthParams, WindField, WindParams};

#[derive(Debug, Subcommand)]
pub enum BenchCommand {
    /// Wind synthesis: 100×100 cells on one core, Separable vs Cholesky at 40×40, and
    /// (with --large) 1000×1000 cells × 1024 frames with peak memory.
    Wind(WindBench),
    /// Sway: per-step cost of stepping many instances of each preset on one core, springs
    /// and palette composition included, and joint updates per second.
    Sway(SwayBench),
    /// Tree generation on one core: skeleton, LOD-0 mesh and leaf clusters per preset
    /// (median of runs), the full LOD chain and textures, triangles per level.
    Tree(TreeBench),
    /// Rendering a scene headless: simulation and rendering ms per frame (medians) and
    /// triangles per frame, on whatever adapter the machine has.
    Render(RenderBench),
    /// The paper's Table 3: scenes A–D with all LODs and each LOD off in turn, along the
    /// camera path; FPS, ms split, triangles, draws, joints, uploads, image error; writes
    /// Markdown, CSV and a PNG chart.
    Table3(crate::table3::Table3Bench),
}

#[derive(Debug, Args)]
pub struct TreeBench {
    /// Runs per preset (the median is reported; at least 1).
    #[arg(long, default_value_t = 7, value_parser = sylva_frames::at_least_one)]
    runs: usize,
    /// Seed of the generated trees.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

#[derive(Debug, Args)]
pub struct RenderBench {
    /// Scene: built-in name or file.
    #[arg(long, default_value = "A")]
    scene: String,
    /// Image size.
    #[arg(long, default_value = "1024x768")]
    size: String,
    /// Frames timed (after one warm-up frame; at least 1).
    #[arg(long, default_value_t = 10, value_parser = sylva_frames::at_least_one)]
    frames: usize,
    /// Geometry-LOD threshold h₀ (see `sylva render --help`; default: the scene's).
    #[arg(value_parser = sylva_frames::finite::<f32>, long)]
    lod_fraction: Option<f32>,
    /// Also the GPU's time in each part of the frame (timestamp queries between the
    /// renderer's passes: shadows, trees, impostors, ground, sky), medians.
    #[arg(long)]
    gpu_passes: bool,
    #[command(flatten)]
    lod: sylva_frames::render::LodArgs,
}

fn tree(a: TreeBench) -> anyhow::Result<()> {
    use sylva_tree::mesh::{LOD_LEVELS, lod_chain};
    use sylva_tree::texture::{bark, leaf_atlas};
    use sylva_tree::{PRESETS, Species};
    println!("machine: {}", machine());
    println!(
        "{:<22}{:>10}{:>12}{:>10}{:>12}{:>12}  triangles per LOD",
        "preset", "joints", "LOD0 ms", "LOD0 tris", "chain ms", "textures ms"
    );
    let runs = a.runs;
    for (name, _) in PRESETS {
        let sp = Species::preset(name).expect("shipped preset");
        let atlas = leaf_atlas(&sp, a.seed, sylva_tree::mesh::ATLAS_SIZE);
        let mut lod0 = Vec::new();
        let mut chain = Vec::new();
        let mut tex = Vec::new();
        let mut last = None;
        for _ in 0..runs {
            let t = Instant::now();
            let tree = sp.generate(a.seed)?;
            let l = lod_chain(&tree, &sp, &atlas, a.seed, 1);
            lod0.push(t.elapsed().as_secs_f64());
            std::hint::black_box(&l);
            let t = Instant::now();
            let tree = sp.generate(a.seed)?;
            let l = lod_chain(&tree, &sp, &atlas, a.seed, LOD_LEVELS);
            chain.push(t.elapsed().as_secs_f64());
            let t = Instant::now();
            std::hint::black_box((
                bark(&sp, a.seed, sylva_tree::mesh::BARK_SIZE),
                leaf_atlas(&sp, a.seed, sylva_tree::mesh::ATLAS_SIZE),
            ));
            tex.push(t.elapsed().as_secs_f64());
            last = Some((tree, l));
        }
        let Some((tree, lods)) = last else { continue };
        let t0 = median(&mut lod0);
        let tris: Vec<String> = lods.iter().map(|l| l.triangles().to_string()).collect();
        println!(
            "{name:<22}{:>10}{:>12.2}{:>10}{:>12.2}{:>12.2}  {}",
            tree.skeleton.len(),
            t0 * 1e3,
            lods[0].triangles(),
            median(&mut chain) * 1e3,
            median(&mut tex) * 1e3,
            tris.join(" / ")
        );
    }
    Ok(())
}

fn render_bench(a: RenderBench) -> anyhow::Result<()> {
    let args = sylva_frames::render::RenderArgs {
        scene: a.scene,
        seconds: (a.frames + 1) as f64 / 10.0,
        fps: 10.0,
        size: a.size,
        out: std::path::PathBuf::from("out/bench-render"),
        wind: None,
        lod_fraction: a.lod_fraction,
        no_gif: true,
        camera_path: false,
        gpu_passes: a.gpu_passes,
        lod: a.lod,
    };
    println!("machine: {}", machine());
    let r = sylva_frames::render::render(&args, 1)?;
    println!(
        "{} frames at {}: simulation {:.1} ms (sway step {:.1} ms) + rendering {:.1} ms per frame (medians; rendering = upload, draw, read back), {:.2} M triangles per frame, {} simulated trees, {} joints per step, adapter {}",
        r.frames,
        args.size,
        r.sim_ms,
        r.step_ms,
        r.render_ms,
        r.triangles / 1e6,
        r.simulated,
        r.joints,
        r.adapter
    );
    if let Some(line) = sylva_frames::render::passes_line(&r) {
        println!("{line}");
    }
    Ok(())
}

#[derive(Debug, Args)]
pub struct SwayBench {
    /// Instances of each species stepped together (at least 1).
    #[arg(long, default_value_t = 1000, value_parser = sylva_frames::at_least_one)]
    instances: usize,
    /// Steps timed per species (the median step is reported; at least 1).
    #[arg(long, default_value_t = 10, value_parser = sylva_frames::at_least_one)]
    steps: usize,
    /// Species to run, comma-separated (default: every preset).
    #[arg(long, value_delimiter = ',')]
    species: Option<Vec<String>>,
    /// Seed of the generated trees.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Mean wind speed, m/s (instances get this plus 0 … 4 m/s, and a small cross-wind).
    #[arg(value_parser = sylva_frames::finite::<f32>, long, default_value_t = 6.0)]
    wind: f32,
}

fn sway(a: SwayBench) -> anyhow::Result<()> {
    use sylva_sway::{SwayBatch, SwayParams, SwaySpecies};
    use sylva_tree::{PRESETS, Species};
    println!("machine: {}", machine());
    let names: Vec<String> =
        a.species.clone().unwrap_or_else(|| PRESETS.iter().map(|(n, _)| n.to_string()).collect());
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().context("thread pool")?;
    println!(
        "{:<22}{:>9}{:>11}{:>14}{:>14}{:>16}",
        "species", "joints", "instances", "ms per step", "ns per joint", "M joints / s"
    );
    for name in names {
        let species = Species::preset(&name).with_context(|| format!("no preset named {name}"))?;
        let tree = species.generate(a.seed)?;
        let n = tree.skeleton.len();
        let sp = SwaySpecies::new(&tree.skeleton, SwayParams::default())?;
        let mut batch = SwayBatch::new(sp, a.instances);
        let winds: Vec<[f32; 3]> = (0..a.instances)
            .map(|i| [a.wind + (i % 5) as f32, (i % 3) as f32 - 1.0, 0.0])
            .collect();
        let mut times = one.install(|| {
            batch.step(1.0 / 60.0, &winds);
            (0..a.steps)
                .map(|_| {
                    let t0 = Instant::now();
                    batch.step(1.0 / 60.0, &winds);
                    t0.elapsed().as_secs_f64()
                })
                .collect::<Vec<f64>>()
        });
        std::hint::black_box(batch.group_palettes(0));
        let step = median(&mut times);
        let joints = (n * a.instances) as f64;
        println!(
            "{:<22}{:>9}{:>11}{:>14.1}{:>14.1}{:>16.1}",
            name,
            n,
            a.instances,
            step * 1e3,
            step * 1e9 / joints,
            joints / step / 1e6
        );
    }
    Ok(())
}

#[derive(Debug, Args)]
pub struct WindBench {
    /// Repetitions of each timed case (the median is reported; at least 1).
    #[arg(long, default_value_t = 5, value_parser = sylva_frames::at_least_one)]
    runs: usize,
    /// Also run 1000×1000 cells × 3 components × 1024 frames (about 12 GiB of output).
    #[arg(long)]
    large: bool,
    /// Frames of the Separable-vs-Cholesky comparison (the dense method is O(N n³)).
    #[arg(long, default_value_t = 16)]
    cholesky_frames: usize,
}

pub fn run(cmd: BenchCommand) -> anyhow::Result<()> {
    match cmd {
        BenchCommand::Wind(a) => wind(a),
        BenchCommand::Sway(a) => sway(a),
        BenchCommand::Tree(a) => tree(a),
        BenchCommand::Render(a) => render_bench(a),
        BenchCommand::Table3(a) => crate::table3::run(a),
    }
}

fn time_generate(grid: &Grid, method: Method, runs: usize) -> anyhow::Result<f64> {
    time_generate_with(&WindParams::default(), grid, method, runs)
}

fn time_generate_with(
    params: &WindParams,
    grid: &Grid,
    method: Method,
    runs: usize,
) -> anyhow::Result<f64> {
    let mut t = Vec::new();
    for seed in 0..runs as u64 {
        let t0 = Instant::now();
        let f = WindField::generate(params, grid, SynthParams { seed, method }, &|_| {})?;
        t.push(t0.elapsed().as_secs_f64());
        std::hint::black_box(&f.data);
    }
    Ok(median(&mut t))
}

pub fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    format!("{cpu}, {cores} logical cores")
}

/// Peak resident memory of this process (VmHWM), bytes.
fn peak_rss() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

fn wind(a: WindBench) -> anyhow::Result<()> {
    println!("machine: {}", machine());
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().context("thread pool")?;
    one.install(|| -> anyhow::Result<()> {
        let g = Grid::regular(100, 100, 4.0, &[20.0], 2048, 0.1);
        let s = time_generate(&g, Method::Separable, a.runs)?;
        println!(
            "separable, 100×100 points × 3 components × 2048 frames, 1 core: {:.3} s median of {} → {:.3} ms per frame (paper: 50 ms)",
            s,
            a.runs,
            s * 1e3 / 2048.0
        );
        let g = Grid::regular(40, 40, 4.0, &[20.0], a.cholesky_frames, 0.1);
        let sep = time_generate(&g, Method::Separable, a.runs)?;
        let cho = time_generate(&g, Method::Cholesky, 1)?;
        println!(
            "40×40 points × 3 × {} frames, 1 core: separable {:.4} s (median of {}), cholesky {:.2} s → ratio {:.0}",
            a.cholesky_frames,
            sep,
            a.runs,
            cho,
            cho / sep
        );
        Ok(())
    })?;
    // Several heights, all cores: one reference speed (separable) against the paper's pair
    // mean (embedding), side by side on the same grid.
    for heights in
        [&[15.0, 20.0, 30.0][..], &[12.0, 15.0, 20.0, 25.0, 30.0, 35.0, 40.0, 50.0, 60.0, 70.0]]
    {
        let g = Grid::regular(100, 100, 4.0, heights, 2048, 0.1);
        let runs = if heights.len() > 3 { 1 } else { a.runs.min(3) };
        let sep = time_generate(&g, Method::Separable, runs)?;
        let pm = WindParams { coherence_speed: CoherenceSpeed::PairMean, ..WindParams::default() };
        let emb = time_generate_with(&pm, &g, Method::Embedding, runs)?;
        println!(
            "100×100 points × {} heights × 3 × 2048 frames, all cores: separable (reference speed) \
             {sep:.2} s, embedding (pair mean) {emb:.2} s → ratio {:.1} (median of {runs})",
            heights.len(),
            emb / sep
        );
    }
    if a.large {
        let g = Grid::regular(1000, 1000, 4.0, &[20.0], 1024, 0.1);
        let out_bytes = (g.points() * 3 * g.frames * 4) as f64;
        let t0 = Instant::now();
        let f = WindField::generate(&WindParams::default(), &g, SynthParams::default(), &|_| {})?;
        let secs = t0.elapsed().as_secs_f64();
        std::hint::black_box(&f.data);
        let peak = peak_rss().map(|b| b as f64).unwrap_or(f64::NAN);
        println!(
            "1000×1000 points × 3 × 1024 frames, all cores: {:.1} s; output {:.2} GiB, peak resident {:.2} GiB ({:.2}× the output)",
            secs,
            out_bytes / (1u64 << 30) as f64,
            peak / (1u64 << 30) as f64,
            peak / out_bytes
        );
    }
    Ok(())
}
