//! Steps a scene along its default camera path and builds every frame, as `sylva bench
//! table3` does on the CPU side, and prints the median simulation and frame-building ms
//! with a checksum of everything the frames hold for the renderer (instances, palettes,
//! buckets, figures). Two builds that print the same checksum built the same frames, bit
//! for bit: the check behind changes meant to change only speed.
//!
//! ```text
//! cargo run --release -p sylva-forest --example frame_checksum -- D[:PATH] 300 [all|no-geometry|no-animation|no-wind] [time-only]
//! ```
//! (scene name or file, and after a colon one of its camera paths, e.g. `E:walk` (default:
//! the fly-in); frames along the path; the configuration; the checksum is Rust's
//! default hasher, the same for builds of one toolchain. Hashing a frame takes as long as
//! building it, or longer, and the idle threads meanwhile fall asleep: `time-only` leaves
//! it out, for timings as a frame loop that does nothing else would see them.)

use std::hash::{DefaultHasher, Hash, Hasher};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use sylva_forest::{Forest, FrameData, SceneSpec};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene = args.first().map_or("D", String::as_str);
    let (name, path) = match scene.split_once(':') {
        Some((name, path)) => (name, Some(path)),
        None => (scene, None),
    };
    let frames: usize = match args.get(1) {
        Some(n) => n.parse().with_context(|| format!("frames: {n:?} is not a count"))?,
        None => 300,
    };
    if frames < 2 {
        bail!("frames: at least 2");
    }
    let mut spec = SceneSpec::load(name)?;
    if let Some(path) = path {
        spec.path = path.to_string();
    }
    match args.get(2).map_or("all", String::as_str) {
        "all" => {}
        "no-geometry" => spec.lod.geometry = false,
        "no-animation" => spec.lod.animation = false,
        "no-wind" => spec.lod.wind = false,
        other => bail!("configuration {other:?}: all, no-geometry, no-animation or no-wind"),
    }
    let checksum = match args.get(3).map(String::as_str) {
        None => true,
        Some("time-only") => false,
        Some(other) => bail!("{other:?}: time-only or nothing"),
    };
    let mut forest = Forest::new(&spec)?;
    let duration = forest.path_duration();
    let mut frame = FrameData::default();
    let (mut sim, mut build) = (Vec::new(), Vec::new());
    let mut hasher = DefaultHasher::new();
    for i in 0..frames {
        let camera = forest.camera_at(duration * i as f32 / (frames - 1) as f32);
        let t = Instant::now();
        forest.step(0.1);
        sim.push(t.elapsed().as_secs_f64() * 1e3);
        let t = Instant::now();
        forest.frame(&camera, 4.0 / 3.0, &mut frame);
        build.push(t.elapsed().as_secs_f64() * 1e3);
        if !checksum {
            continue;
        }
        bytemuck::cast_slice::<_, u8>(&frame.instances).hash(&mut hasher);
        bytemuck::cast_slice::<_, u8>(&frame.palettes).hash(&mut hasher);
        format!("{:?}", frame.buckets).hash(&mut hasher);
        // The figures, less the step's wall time.
        let stats = sylva_forest::FrameStats { sim_ms: 0.0, ..frame.stats };
        format!("{stats:?}").hash(&mut hasher);
    }
    for v in [&mut sim, &mut build] {
        v.sort_by(f64::total_cmp);
    }
    let sum =
        if checksum { format!("checksum {:016x}", hasher.finish()) } else { "no checksum".into() };
    println!(
        "{name}{}: simulation {:.3} ms, frame {:.3} ms (medians of {frames}; slowest frame \
         {:.3} ms), {sum}",
        path.map_or(String::new(), |p| format!(" {p}")),
        sim[frames / 2],
        build[frames / 2],
        build[frames - 1],
    );
    Ok(())
}
