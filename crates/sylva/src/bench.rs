//! `sylva bench …`: scene-scale benchmarks. Figures are medians of several runs, measured
//! side by side in one process, printed with the machine they ran on.

use std::time::Instant;

use anyhow::Context;
use clap::{Args, Subcommand};
use sylva_wind::{Grid, Method, SynthParams, WindField, WindParams};

#[derive(Debug, Subcommand)]
pub enum BenchCommand {
    /// Wind synthesis: 100×100 cells on one core, Separable vs Cholesky at 40×40, and
    /// (with --large) 1000×1000 cells × 1024 frames with peak memory.
    Wind(WindBench),
    /// Sway: per-step cost of stepping many instances of each preset on one core, springs
    /// and palette composition included, and joint updates per second.
    Sway(SwayBench),
}

#[derive(Debug, Args)]
pub struct SwayBench {
    /// Instances of each species stepped together.
    #[arg(long, default_value_t = 1000)]
    instances: usize,
    /// Steps timed per species (the median step is reported).
    #[arg(long, default_value_t = 10)]
    steps: usize,
    /// Species to run, comma-separated (default: every preset).
    #[arg(long, value_delimiter = ',')]
    species: Option<Vec<String>>,
    /// Seed of the generated trees.
    #[arg(long, default_value_t = 1)]
    seed: u64,
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
        let winds: Vec<[f32; 3]> =
            (0..a.instances).map(|i| [6.0 + (i % 5) as f32, (i % 3) as f32 - 1.0, 0.0]).collect();
        let times = one.install(|| {
            batch.step(1.0 / 60.0, &winds);
            (0..a.steps.max(1))
                .map(|_| {
                    let t0 = Instant::now();
                    batch.step(1.0 / 60.0, &winds);
                    t0.elapsed().as_secs_f64()
                })
                .collect::<Vec<f64>>()
        });
        std::hint::black_box(batch.all_palettes());
        let step = median(times);
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
    /// Repetitions of each timed case (the median is reported).
    #[arg(long, default_value_t = 5)]
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
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn time_generate(grid: &Grid, method: Method, runs: usize) -> anyhow::Result<f64> {
    let params = WindParams::default();
    let mut t = Vec::new();
    for seed in 0..runs.max(1) as u64 {
        let t0 = Instant::now();
        let f = WindField::generate(&params, grid, SynthParams { seed, method }, &|_| {})?;
        t.push(t0.elapsed().as_secs_f64());
        std::hint::black_box(&f.data);
    }
    Ok(median(t))
}

fn machine() -> String {
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
