//! `sylva tree …` and `sylva sway probe`: species files, generated skeletons, and a probe
//! that records how a tree sways.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use sylva_forest::WindSource;
use sylva_sway::probe::{bend_and_release, free_decay};
use sylva_sway::{CrownLean, SwayBatch, SwayParams, SwaySpecies, transform};
use sylva_tree::{PARAMS, PRESETS, Species, species::Scope};

#[derive(Debug, Subcommand)]
pub enum TreeCommand {
    /// List the shipped species.
    List,
    /// Document every species-file parameter: meaning, unit, valid range, default.
    Params,
    /// Generate a tree and print its figures.
    Stats(StatsArgs),
    /// Generate a tree and write it as glTF 2.0 (.glb): skinned branches, alpha-masked
    /// leaf clusters, textures embedded.
    Generate(GenerateArgs),
    /// Generate a tree, sway it in a wind and write it as an animated glTF (.glb): the tree
    /// of `generate` plus one animation, a rotation channel per exported joint sampled from
    /// the sway simulation, and the leaves' flutter as two morph targets.
    Animate(AnimateArgs),
    /// Write a species' procedural textures as PNG: bark.png and leaves.png (the
    /// leaf-cluster atlas, drawn to scale: one cell spans the size its card is shown at).
    Textures(TexturesArgs),
    /// Print a species file (a preset's, to start your own from).
    Show {
        /// Preset name or species file.
        species: String,
    },
}

#[derive(Debug, Args)]
pub struct StatsArgs {
    /// Preset name (see `sylva tree list`) or a species file (.toml).
    #[arg(long)]
    species: String,
    /// Seed of the random variations.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

#[derive(Debug, Args)]
pub struct TexturesArgs {
    /// Preset name (see `sylva tree list`) or a species file (.toml).
    #[arg(long)]
    species: String,
    /// Seed of the random variations.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output folder.
    #[arg(long, default_value = "out/textures")]
    out: PathBuf,
}

#[derive(Debug, Args)]
pub struct GenerateArgs {
    /// Preset name (see `sylva tree list`) or a species file (.toml).
    #[arg(long)]
    species: String,
    /// Seed of the random variations.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Level of detail to export: a number (0 = full detail), or `all` for one file per
    /// level (`NAME.lod0.glb`, `NAME.lod1.glb`, … beside --out), since editors import every
    /// scene of a file at once.
    #[arg(long, default_value = "0")]
    lod: String,
    /// Most joints to export, 1 … 65535 (glTF's 16-bit joint indices); lighter joints fold
    /// into their nearest exported ancestor. The default suits editors: Blender's importer
    /// takes about a minute for 4096 bones and far longer for the willow's 36 000.
    #[arg(long, default_value_t = 1024)]
    max_joints: usize,
    /// Output file (.glb).
    #[arg(long, default_value = "out/tree.glb")]
    out: PathBuf,
}

#[derive(Debug, Args)]
pub struct AnimateArgs {
    /// Preset name (see `sylva tree list`) or a species file (.toml).
    #[arg(long)]
    species: String,
    /// Seed of the tree and of a preset wind.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Wind: a preset (calm, breeze, strong, storm), a steady speed in m/s along +x, or a
    /// wind file (.swf, .npy, .zarr) sampled at the crown.
    #[arg(long, default_value = "breeze")]
    wind: WindSource,
    /// Length of the clip, s (with --loop: the period of the synthesised wind, rounded to
    /// 0.1 s; a wind file's own period).
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = 10.0)]
    seconds: f64,
    /// Samples (keyframes before reduction) per second.
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = 30.0)]
    fps: f64,
    /// Seconds simulated in the wind before the clip starts (a looping clip: at least three
    /// periods, so the sway has settled into the wind's loop).
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = 10.0)]
    warmup: f64,
    /// Loop seamlessly: the clip is one period of the wind, its last key its first.
    #[arg(long = "loop")]
    looped: bool,
    /// Level of detail to export (0 = full detail).
    #[arg(long, default_value_t = 0)]
    lod: usize,
    /// Most joints to export and animate, 1 … 65535 (as for `generate`).
    #[arg(long, default_value_t = 1024)]
    max_joints: usize,
    /// Keyframe reduction, mm: keys are dropped where interpolation reproduces the sway so
    /// closely that, played back, no point of the tree is farther than this from where the
    /// simulation put it at any sample time (0 keeps every sample).
    #[arg(value_parser = crate::finite::<f32>, long, default_value_t = 10.0)]
    max_error_mm: f32,
    /// Output file (.glb).
    #[arg(long, default_value = "out/tree-animated.glb")]
    out: PathBuf,
    /// Also write, as JSON, the world positions (glTF axes: +Y up) of a few exported joints
    /// at every sample time, from the simulation's palettes — to check a client's playback.
    #[arg(long)]
    samples: Option<PathBuf>,
}

#[derive(Debug, Subcommand)]
pub enum SwayCommand {
    /// Record the sway of one tree in wind to CSV; with --release, bend it under a steady
    /// load, let go and measure the trunk's frequency and damping ratio.
    Probe(ProbeArgs),
}

#[derive(Debug, Args)]
pub struct ProbeArgs {
    /// Preset name or species file (.toml).
    #[arg(long)]
    species: String,
    /// Seed of the tree.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Wind: a preset (calm, breeze, strong, storm: turbulent, from `sylva-wind`), a steady
    /// speed in m/s along +x, or a wind file (.swf, .npy, .zarr) sampled at the crown.
    #[arg(long, default_value = "breeze")]
    wind: WindSource,
    /// Seconds to simulate.
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = 60.0)]
    seconds: f64,
    /// Frames per second of the simulation.
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = 60.0)]
    fps: f64,
    /// CSV output: time, wind at the crown, trunk-top and branch-tip displacements.
    #[arg(long, default_value = "out/probe.csv")]
    csv: PathBuf,
    /// Free-decay test: steady load for 20 s, then still air; prints the measured trunk
    /// frequency and damping ratio.
    #[arg(long)]
    release: bool,
}

pub fn run_tree(cmd: TreeCommand) -> anyhow::Result<()> {
    match cmd {
        TreeCommand::List => {
            for (name, text) in PRESETS {
                let about = text.lines().next().unwrap_or("").trim_start_matches("# ");
                println!("{name:<22} {about}");
            }
        }
        TreeCommand::Params => {
            println!(
                "{:<16}{:<8}{:<12}{:>10}{:>10}{:>9}  meaning",
                "key", "scope", "unit", "min", "max", "default"
            );
            for p in PARAMS {
                let scope = if p.scope == Scope::Level { "0–3" } else { "tree" };
                let key = if p.scope == Scope::Level {
                    format!("n{}", p.name)
                } else {
                    p.name.to_string()
                };
                println!(
                    "{key:<16}{scope:<8}{:<12}{:>10}{:>10}{:>9}  {}",
                    p.unit, p.min, p.max, p.default, p.doc
                );
            }
            println!(
                "\nPer-level keys carry the level digit first: 0Length (trunk), 1DownAngle, …"
            );
        }
        TreeCommand::Generate(a) => generate(a)?,
        TreeCommand::Animate(a) => animate(a)?,
        TreeCommand::Textures(a) => {
            let sp = Species::load(&a.species)?;
            std::fs::create_dir_all(&a.out)
                .with_context(|| format!("creating {}", a.out.display()))?;
            let bark = sylva_tree::texture::bark(&sp, a.seed, sylva_tree::mesh::BARK_SIZE);
            let atlas = sylva_tree::texture::leaf_atlas(&sp, a.seed, sylva_tree::mesh::ATLAS_SIZE);
            for (name, img) in [("bark.png", &bark), ("leaves.png", &atlas.image)] {
                let path = a.out.join(name);
                sylva_frames::render::write_png(&path, img.width, img.height, &img.rgba)?;
                println!("wrote {}", path.display());
            }
            println!(
                "leaf cells: {} a side, each {:.3} m across; leaves per cell {:?}; coverage {:?}",
                atlas.cells,
                atlas.span,
                atlas.leaves,
                atlas.coverage.iter().map(|c| (c * 100.0).round() / 100.0).collect::<Vec<_>>()
            );
        }
        TreeCommand::Show { species } => print!("{}", Species::load(&species)?.to_toml()),
        TreeCommand::Stats(a) => stats(a)?,
    }
    Ok(())
}

/// `sylva tree generate`: a tree written as glTF, one file per LOD asked for.
fn generate(a: GenerateArgs) -> anyhow::Result<()> {
    let sp = Species::load(&a.species)?;
    if a.max_joints == 0 || a.max_joints > sylva_tree::gltf::MAX_GLTF_JOINTS {
        bail!("--max-joints {}: must be 1 … {}", a.max_joints, sylva_tree::gltf::MAX_GLTF_JOINTS);
    }
    let model = sp.model(a.seed, sylva_tree::mesh::LOD_LEVELS)?;
    let last = model.lods.len() - 1;
    // (level, file) pairs.
    let files: Vec<(usize, PathBuf)> = if a.lod == "all" {
        let stem = a.out.file_stem().and_then(|s| s.to_str()).unwrap_or("tree");
        (0..=last).map(|l| (l, a.out.with_file_name(format!("{stem}.lod{l}.glb")))).collect()
    } else {
        let l: usize = a
            .lod
            .parse()
            .ok()
            .filter(|&l| l <= last)
            .with_context(|| format!("--lod {}: a level 0 … {last}, or `all`", a.lod))?;
        vec![(l, a.out.clone())]
    };
    if let Some(dir) = a.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    for (l, path) in files {
        let opts = sylva_tree::gltf::GltfOptions {
            lods: vec![l],
            max_joints: a.max_joints,
            name: sp.name.clone(),
            animation: None,
        };
        let bytes = model.to_glb(&opts);
        sylva_wind::io::atomic::write_atomic(&path, &bytes)
            .with_context(|| format!("writing {}", path.display()))?;
        println!(
            "wrote {} (LOD {l}: {:.1} MB, skeleton of {} joints, at most {} exported, {} \
             triangles)",
            path.display(),
            bytes.len() as f64 / 1e6,
            model.tree.skeleton.len(),
            a.max_joints,
            model.lods[l].triangles()
        );
    }
    Ok(())
}

/// `sylva tree stats`: a tree grown and its figures printed, level by level.
fn stats(a: StatsArgs) -> anyhow::Result<()> {
    let sp = Species::load(&a.species)?;
    let t0 = Instant::now();
    let model = sp.model(a.seed, sylva_tree::mesh::LOD_LEVELS)?;
    let secs = t0.elapsed().as_secs_f64();
    let tree = &model.tree;
    let sk = &tree.skeleton;
    let s = tree.stats;
    println!("species          {}", sp.name);
    println!("levels           {}", sp.levels);
    println!("stems            {}", s.stems);
    println!("joints           {}", sk.len());
    println!("leaves           {} ({:.1} m² one-sided)", s.leaves, s.leaf_area);
    println!("height           {:.2} m", s.height);
    println!(
        "trunk            {:.2} m long, {:.1} cm base diameter, DBH {:.1} cm",
        s.trunk_length,
        200.0 * s.trunk_radius,
        200.0 * sk.radius_at_height(1.3)
    );
    println!(
        "crown width      {:.2} m × {:.2} m (leaf area index {:.1})",
        s.crown_width[0],
        s.crown_width[1],
        s.leaf_area_index()
    );
    println!(
        "crown base       {:.2} m ({:.0} % of the height in crown)",
        s.crown_base,
        100.0 * (1.0 - s.crown_base / s.height.max(1e-6))
    );
    println!("mass             {:.0} kg", sk.carried_mass(0));
    println!("generation       {:.2} ms (skeleton, meshes, LOD chain, textures)", secs * 1e3);
    println!("LOD  triangles  branch tris  clusters  leaf area m²  min radius cm");
    for l in &model.lods {
        println!(
            "{:<4} {:>9}  {:>11}  {:>8}  {:>12.1}  {:>13.2}",
            l.level,
            l.triangles(),
            l.branches.triangles(),
            l.clusters.len(),
            l.leaf_area(),
            100.0 * l.min_radius
        );
    }
    Ok(())
}

/// `sylva tree animate`: a tree swayed in a wind and written as an animated glTF.
fn animate(a: AnimateArgs) -> anyhow::Result<()> {
    use sylva_forest::clip::{ClipSettings, PointWind, record};
    if a.max_joints == 0 || a.max_joints > sylva_tree::gltf::MAX_GLTF_JOINTS {
        bail!("--max-joints {}: must be 1 … {}", a.max_joints, sylva_tree::gltf::MAX_GLTF_JOINTS);
    }
    if !(0.0..=1000.0).contains(&a.max_error_mm) {
        bail!("--max-error-mm {}: 0 … 1000 mm", a.max_error_mm);
    }
    let sp = Species::load(&a.species)?;
    let model = sp.model(a.seed, sylva_tree::mesh::LOD_LEVELS)?;
    let last = model.lods.len() - 1;
    if a.lod > last {
        bail!("--lod {}: a level 0 … {last}", a.lod);
    }
    let sk = &model.tree.skeleton;
    let crown = [0.0, 0.0, sylva_tree::WIND_SAMPLE_HEIGHT * model.tree.stats.height as f64];
    let started = Instant::now();
    let wind = PointWind::new(&a.wind, crown, a.seconds, a.seed, a.looped)?;
    let joints = model.exported_joints(a.lod, a.max_joints);
    let settings = ClipSettings {
        seconds: a.seconds,
        fps: a.fps,
        warmup: a.warmup,
        looped: a.looped,
        ..Default::default()
    };
    let params = SwayParams::for_leaves(sylva_tree::texture::is_needle(&sp));
    let clip = record(sk, params, &wind, &joints, &settings)?;
    let animation = sylva_tree::gltf::JointAnimation {
        name: format!("sway in {}", a.wind),
        times: clip.times.clone(),
        joints: clip.joints.clone(),
        rotations: clip.rotations(),
        max_error: a.max_error_mm / 1000.0,
        flutter: clip.flutter_track(),
    };
    let opts = sylva_tree::gltf::GltfOptions {
        lods: vec![a.lod],
        max_joints: a.max_joints,
        name: sp.name.clone(),
        animation: Some(animation),
    };
    let bytes = model.to_glb(&opts);
    if let Some(dir) = a.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    sylva_wind::io::atomic::write_atomic(&a.out, &bytes)
        .with_context(|| format!("writing {}", a.out.display()))?;
    let duration = clip.times.last().copied().unwrap_or(0.0);
    println!(
        "wrote {} ({:.2} MB: LOD {}, {} of {} joints animated, {:.2} s at {} samples/s, played back within {} mm of the simulation){}; {:.1} s",
        a.out.display(),
        bytes.len() as f64 / 1e6,
        a.lod,
        joints.len(),
        sk.len(),
        duration,
        a.fps,
        a.max_error_mm,
        if a.looped {
            format!(", loops (seam before closing: {:.3}°)", clip.seam_deg)
        } else {
            String::new()
        },
        started.elapsed().as_secs_f64()
    );
    if let Some(path) = &a.samples {
        write_samples(path, &model, a.lod, &joints, &clip, a.max_error_mm)?;
    }
    Ok(())
}

/// `--samples`: a few joints' and leaf corners' world positions at every sample time of
/// `clip` (glTF axes), for checking a client's playback of the `.glb` against the
/// simulation.
fn write_samples(
    path: &std::path::Path,
    model: &sylva_tree::mesh::TreeModel,
    lod: usize,
    joints: &[usize],
    clip: &sylva_forest::clip::SwayClip,
    max_error_mm: f32,
) -> anyhow::Result<()> {
    let sk = &model.tree.skeleton;
    // The trunk top and the ends of the three heaviest exported stems: their joint
    // nodes' world positions, M_j · o_j, in glTF's axes (x, z, −y).
    let exported: std::collections::HashSet<usize> = joints.iter().copied().collect();
    let mut picks = vec![sk.trunk_top()];
    let mut stems: Vec<usize> =
        joints.iter().copied().filter(|&j| j > 0 && !sk.joints()[j].continues).collect();
    stems.sort_by(|&x, &y| sk.carried_mass(y).total_cmp(&sk.carried_mass(x)));
    for s in stems.into_iter().take(3) {
        // The stem's last joint, or its nearest exported ancestor.
        let mut e = sk.stem_end(s);
        while !exported.contains(&e) {
            e = sk.joints()[e].parent as usize;
        }
        picks.push(e);
    }
    picks.retain(|j| exported.contains(j));
    picks.dedup();
    let slot = |j: usize| joints.iter().position(|&x| x == j);
    let series: Vec<serde_json::Value> = picks
        .iter()
        .filter_map(|&j| {
            let k = slot(j)?;
            let o = sk.joints()[j].origin;
            let pos: Vec<[f32; 3]> = clip
                .palettes
                .iter()
                .map(|s| {
                    let p = transform(&s[k], o);
                    [p[0], p[2], -p[1]]
                })
                .collect();
            Some(serde_json::json!({ "node": format!("joint{j}"), "positions": pos }))
        })
        .collect();
    // Four leaf-card corners on exported joints: where the file's flutter targets and
    // skin put them (the first-order flutter of sylva_tree::gltf::FLUTTER_TARGETS).
    let clusters = &model.lods[lod].clusters;
    let on_exported: Vec<usize> =
        (0..clusters.len()).filter(|&c| exported.contains(&(clusters[c].joint as usize))).collect();
    let leaves: Vec<serde_json::Value> = (0..4)
        .filter_map(|i| {
            let c = *on_exported.get(i * on_exported.len() / 4)?;
            let cl = &clusters[c];
            let k = slot(cl.joint as usize)?;
            let (corners, _) = sylva_tree::gltf::leaf_quad(cl);
            let [d0, d1] = sylva_tree::gltf::flutter_displacements(cl, &corners);
            let pos: Vec<[f32; 3]> = clip
                .palettes
                .iter()
                .zip(&clip.flutter)
                .map(|(s, l)| {
                    let (sn, cs) = l.phase.sin_cos();
                    let (w0, w1) = (l.amplitude * sn, l.amplitude * cs);
                    let q: [f32; 3] =
                        std::array::from_fn(|e| corners[0][e] + w0 * d0[0][e] + w1 * d1[0][e]);
                    let p = transform(&s[k], q);
                    [p[0], p[2], -p[1]]
                })
                .collect();
            Some(serde_json::json!({ "vertex": 4 * c, "positions": pos }))
        })
        .collect();
    let doc = serde_json::json!({
        "times": clip.times,
        "max_error_m": max_error_mm / 1000.0,
        "joints": series,
        "leaves": leaves
    });
    sylva_wind::io::atomic::write_atomic(path, doc.to_string().as_bytes())
        .with_context(|| format!("writing {}", path.display()))?;
    println!(
        "wrote {} ({} joints' and {} leaf corners' positions at {} times)",
        path.display(),
        picks.len(),
        leaves.len(),
        clip.times.len()
    );
    Ok(())
}

/// Most samples a sway probe records (its wind and every sample's row are held in memory):
/// a day at 115 samples a second.
const MAX_PROBE_SAMPLES: f64 = 1e7;

/// `--seconds` and `--fps` of a sway probe, whatever its wind: at most a day (as for a
/// preset's synthesised wind), at most 1000 samples a second, and at most
/// [`MAX_PROBE_SAMPLES`] samples, checked before anything is allocated.
fn check_probe_length(seconds: f64, fps: f64) -> anyhow::Result<()> {
    if !(seconds > 0.0 && seconds <= 86_400.0) {
        bail!("--seconds {seconds}: more than 0 and at most 86 400 (a day)");
    }
    if !(fps > 0.0 && fps <= 1000.0) {
        bail!("--fps {fps}: more than 0 and at most 1000");
    }
    if seconds * fps > MAX_PROBE_SAMPLES {
        bail!(
            "--seconds {seconds} at --fps {fps} is {:.0} samples: at most {MAX_PROBE_SAMPLES:.0} \
             (fewer seconds, or fewer samples a second)",
            seconds * fps
        );
    }
    Ok(())
}

/// `sylva sway`: a tree's sway probed in a wind (a CSV of its motion, or its free decay).
pub fn run_sway(cmd: SwayCommand) -> anyhow::Result<()> {
    let SwayCommand::Probe(a) = cmd;
    check_probe_length(a.seconds, a.fps)?;
    let species = Species::load(&a.species)?;
    let tree = species.generate(a.seed)?;
    let sk = &tree.skeleton;
    let crown = [0.0, 0.0, sylva_tree::WIND_SAMPLE_HEIGHT * tree.stats.height as f64];
    let dt = 1.0 / a.fps;
    let steps = (a.seconds * a.fps).ceil() as usize;
    // Wind at the crown per step: steady, or sampled from a synthesised or read field.
    let point = sylva_forest::clip::PointWind::new(&a.wind, crown, a.seconds, a.seed, false)?;
    let wind: Vec<[f32; 3]> = (0..steps).map(|k| point.at(k as f64 * dt)).collect();
    let sp =
        SwaySpecies::new(sk, SwayParams::for_leaves(sylva_tree::texture::is_needle(&species)))?;
    let lean = CrownLean::new(&sp, sk);
    let mut batch = SwayBatch::new(sp, 1);
    let top = sk.trunk_top();
    // Named branches: the three heaviest stems that start on the trunk.
    let mut branches: Vec<usize> = (1..sk.len()).filter(|&j| !sk.joints()[j].continues).collect();
    branches.sort_by(|&x, &y| sk.carried_mass(y).total_cmp(&sk.carried_mass(x)));
    branches.truncate(3);
    let ends: Vec<usize> = branches.iter().map(|&b| sk.stem_end(b)).collect();
    if let Some(dir) = a.csv.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let mut out = sylva_wind::io::atomic::AtomicFile::create(&a.csv)
        .with_context(|| format!("creating {}", a.csv.display()))?;
    write!(out, "time_s,wind_u,wind_v,wind_w,trunk_dx,trunk_dy")?;
    for k in 0..ends.len() {
        write!(out, ",branch{}_dx,branch{}_dy", k + 1, k + 1)?;
    }
    writeln!(out)?;
    // One CSV row per step: time, wind, trunk-top and branch-end displacements.
    let mut failure: Option<std::io::Error> = None;
    let mut row = |k: usize, w: [f32; 3], batch: &SwayBatch| {
        let disp = |j: usize| {
            let rest = sk.joints()[j].tip();
            let p = transform(&batch.palette(0, j), rest);
            (p[0] - rest[0], p[1] - rest[1])
        };
        let (tx, ty) = disp(top);
        let t = k as f64 * dt;
        let mut line = format!("{t:.4},{:.4},{:.4},{:.4},{tx:.5},{ty:.5}", w[0], w[1], w[2]);
        for &e in &ends {
            let (bx, by) = disp(e);
            line.push_str(&format!(",{bx:.5},{by:.5}"));
        }
        if failure.is_none()
            && let Err(e) = writeln!(out, "{line}")
        {
            failure = Some(e);
        }
    };
    // With --release: 20 s bent under a steady wind 4 m/s above the wind given, then free.
    let hold = if a.release { (20.0 * a.fps) as usize } else { 0 };
    let load = [wind[0][0].max(1.0) + 4.0, 0.0, 0.0];
    let decay = if a.release {
        Some(bend_and_release(&mut batch, sk, load, hold, steps, dt as f32, &mut row))
    } else {
        for (k, w) in wind.iter().enumerate() {
            batch.step(dt as f32, &[*w]);
            row(k, *w, &batch);
        }
        None
    };
    if let Some(e) = failure {
        return Err(e).with_context(|| format!("writing {}", a.csv.display()));
    }
    out.commit().with_context(|| format!("writing {}", a.csv.display()))?;
    println!(
        "{}: {:.1} m tall, {} joints; wrote {} ({} rows)",
        species.name,
        tree.stats.height,
        sk.len(),
        a.csv.display(),
        steps + hold
    );
    // The crown's static lean in the steady part of the wind (the mean over the run, or the
    // load held before the release): what the limbs off the trunk line add to the trunk's
    // own bend, and what an impostor of this tree is sheared with.
    let steady = match &decay {
        Some(_) => load,
        None => {
            let n = wind.len().max(1) as f32;
            std::array::from_fn(|c| wind.iter().map(|w| w[c]).sum::<f32>() / n)
        }
    };
    let [lx, ly] = lean.mean(steady);
    println!(
        "crown lean in a steady {:.1} m/s: {:.3} m (x {lx:.3}, y {ly:.3}; the leaves' mean, from the limbs off the trunk line)",
        steady[0].hypot(steady[1]),
        lx.hypot(ly)
    );
    // The same bends turn the leaves from the sky (what darkens a crown in wind).
    let [tx, ty, tz] = lean.tilt(steady);
    println!(
        "leaves turned by the same bends: their vertical on average {tz:.3} up, {:.3} across (x {tx:.3}, y {ty:.3}; below 1 up, turned from the sky)",
        tx.hypot(ty)
    );
    if let Some((xs, ys)) = decay {
        let (f, zeta) = free_decay(&xs, &ys, dt);
        let structural = SwayParams::default().damping_ratio;
        if zeta.is_finite() {
            println!(
                "trunk free decay: frequency {f:.3} Hz, damping ratio {zeta:.3} (structural ζ = {structural:.3} plus aerodynamic)"
            );
        } else {
            // Too few swings after the release to read a decay from.
            let need = if f > 0.0 {
                format!(" (about {:.0} s here)", (3.0 / f).ceil())
            } else {
                String::new()
            };
            println!(
                "trunk free decay: frequency {f:.3} Hz; damping ratio not measured: --seconds of free decay must span three swings or more{need}"
            );
        }
    }
    Ok(())
}
