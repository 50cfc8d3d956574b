//! `sylva forest`: a scene's trees, swaying, as one animated glTF.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use sylva_forest::{Forest, SceneSpec, WindSource};
use sylva_tree::gltf::{ForestTree, JointAnimation, MAX_GLTF_JOINTS, forest_to_glb};

#[derive(Debug, Subcommand)]
pub enum ForestCommand {
    /// Write a scene's trees as one animated glTF (.glb): per species one mesh at full
    /// detail, per tree its own skeleton placed in the scene and a rotation channel per
    /// joint sampled from the forest's simulation (trees sharing a simulation sway alike).
    Export(ExportArgs),
}

#[derive(Debug, Args)]
pub struct ExportArgs {
    /// Built-in scene (small, A, B, C, D, E) or a scene file (.toml).
    #[arg(long, default_value = "small")]
    scene: String,
    /// Wind instead of the scene's: a preset, a steady speed in m/s, or a wind file.
    #[arg(long)]
    wind: Option<WindSource>,
    /// Length of the clip, s.
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = 4.0)]
    seconds: f64,
    /// Samples per second.
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = 30.0)]
    fps: f64,
    /// Seconds simulated before the clip starts.
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = 5.0)]
    warmup: f64,
    /// The trees nearest the scene's centre to export (the scene's layout orders them so).
    #[arg(long, default_value_t = 50)]
    max_trees: usize,
    /// Most joints exported and animated per tree, 1 … 65535.
    #[arg(long, default_value_t = 256)]
    max_joints: usize,
    /// Keyframe reduction, mm (as `tree animate`: no point farther than this from the
    /// simulation at any sample time; 0 keeps every sample).
    #[arg(value_parser = crate::finite::<f32>, long, default_value_t = 10.0)]
    max_error_mm: f32,
    /// Output file (.glb).
    #[arg(long, default_value = "out/forest.glb")]
    out: PathBuf,
}

pub fn run(cmd: ForestCommand) -> anyhow::Result<()> {
    let ForestCommand::Export(a) = cmd;
    if !(a.fps > 0.0 && a.fps <= 1000.0) {
        bail!("--fps {}: must be in (0, 1000]", a.fps);
    }
    if !(a.seconds > 0.0 && a.seconds <= 600.0) {
        bail!("--seconds {}: must be in (0, 600]", a.seconds);
    }
    if !(0.0..=36_000.0).contains(&a.warmup) {
        bail!("--warmup {}: must be in [0, 36000]", a.warmup);
    }
    if a.max_joints == 0 || a.max_joints > MAX_GLTF_JOINTS {
        bail!("--max-joints {}: must be 1 … {MAX_GLTF_JOINTS}", a.max_joints);
    }
    if a.max_trees == 0 || a.max_trees > 10_000 {
        bail!("--max-trees {}: must be 1 … 10000", a.max_trees);
    }
    if !(0.0..=1000.0).contains(&a.max_error_mm) {
        bail!("--max-error-mm {}: 0 … 1000 mm", a.max_error_mm);
    }
    let started = Instant::now();
    let mut spec = SceneSpec::load(&a.scene)?;
    if let Some(w) = &a.wind {
        spec.set_wind(w);
    }
    // Every joint of every simulated tree is stepped: nothing here is out of view.
    spec.lod.animation = false;
    let mut forest = Forest::new(&spec)?;
    let chosen = forest.nearest_centre(a.max_trees);
    let trees = chosen.len();
    let joints: Vec<Vec<usize>> =
        forest.species.iter().map(|s| s.model.exported_joints(0, a.max_joints)).collect();
    let samples = (a.seconds * a.fps).round().max(1.0) as usize;
    let dt = (a.seconds / samples as f64) as f32;
    let sub = (dt * 60.0).ceil().max(1.0) as usize;
    for _ in 0..(a.warmup * 60.0).round() as usize {
        forest.step(1.0 / 60.0);
    }
    // Per tree, per sample: the rotations of its species' exported joints.
    let mut rotations: Vec<Vec<Vec<[f32; 9]>>> = vec![Vec::with_capacity(samples + 1); trees];
    let mut flutter: Vec<Vec<[f32; 2]>> = vec![Vec::with_capacity(samples + 1); trees];
    for k in 0..=samples {
        if k > 0 {
            for _ in 0..sub {
                forest.step(dt / sub as f32);
            }
        }
        for (&t, (rot, leaves)) in chosen.iter().zip(rotations.iter_mut().zip(&mut flutter)) {
            let s = forest.placement(t).map_or(0, |p| p.species as usize);
            let pose = forest.tree_palettes(t, &joints[s]);
            rot.push(pose.iter().map(sylva_sway::rotation_of).collect());
            let l = forest.tree_leaves(t).unwrap_or_default();
            leaves.push([l.amplitude, l.phase]);
        }
    }
    let times: Vec<f32> = (0..=samples).map(|k| k as f32 * dt).collect();
    let name = format!("{} in {}", spec.name, spec.wind);
    let list: Vec<ForestTree> = rotations
        .into_iter()
        .zip(flutter)
        .zip(&chosen)
        .filter_map(|((rotations, flutter), &t)| {
            let p = forest.placement(t)?;
            Some(ForestTree {
                species: p.species as usize,
                position: p.position,
                yaw: p.yaw,
                scale: p.scale,
                animation: Some(JointAnimation {
                    name: name.clone(),
                    times: times.clone(),
                    joints: joints[p.species as usize].clone(),
                    rotations,
                    max_error: a.max_error_mm / 1000.0,
                    flutter,
                }),
            })
        })
        .collect();
    let models: Vec<&sylva_tree::TreeModel> = forest.species.iter().map(|s| &s.model).collect();
    let bytes = forest_to_glb(&models, &list, a.max_joints, &spec.name);
    if let Some(dir) = a.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    sylva_wind::io::atomic::write_atomic(&a.out, &bytes)
        .with_context(|| format!("writing {}", a.out.display()))?;
    println!(
        "wrote {} ({:.2} MB: {trees} of {} trees, {} species, up to {} joints a tree, {:.2} s at \
         {} samples/s, played back within {} mm of the simulation); {:.1} s",
        a.out.display(),
        bytes.len() as f64 / 1e6,
        forest.trees(),
        forest.species.len(),
        a.max_joints,
        a.seconds,
        a.fps,
        a.max_error_mm,
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
