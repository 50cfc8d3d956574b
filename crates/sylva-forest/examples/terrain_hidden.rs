//! How many of the far impostors a frame draws the terrain hides: for six cameras along a
//! scene's path, the impostors whose top (their foot plus 30 m times their scale, above
//! every preset's height) lies below the terrain along the line of sight from the eye, at
//! 5 m steps with a metre to spare. Nothing is culled: this measures what culling by the
//! terrain could save.
//!
//!     cargo run --release -p sylva-forest --example terrain_hidden -- E:walk

use anyhow::{Context, Result};
use sylva_forest::{Forest, FrameData, SceneSpec};

/// An impostor's tag in its low four bits (see `Instance::tag`).
const IMPOSTOR: u32 = 15;

fn main() -> Result<()> {
    let arg = std::env::args().nth(1).unwrap_or_else(|| "E:walk".into());
    let (name, path) = arg.split_once(':').context("SCENE:PATH, e.g. E:walk")?;
    let mut spec = SceneSpec::load(name)?;
    spec.path = path.to_string();
    let mut forest = Forest::new(&spec)?;
    let duration = forest.path_duration();
    let mut frame = FrameData::default();
    for k in 0..6 {
        let t = duration * k as f32 / 5.0;
        let camera = forest.camera_at(t);
        forest.step(0.1);
        forest.frame(&camera, 4.0 / 3.0, &mut frame);
        let e = camera.eye;
        let (mut drawn, mut hidden) = (0usize, 0usize);
        for inst in frame.instances.iter().filter(|i| i.tag & 15 == IMPOSTOR) {
            drawn += 1;
            let p = inst.position;
            let top = p[2] + 30.0 * inst.scale.max(1.0);
            let (dx, dy) = (p[0] - e[0], p[1] - e[1]);
            let n = (((dx * dx + dy * dy).sqrt() / 5.0) as usize).max(2);
            hidden += (1..n).any(|s| {
                let f = s as f32 / n as f32;
                let line = e[2] + f * (top - e[2]);
                forest.terrain.height(e[0] + f * dx, e[1] + f * dy) > line + 1.0
            }) as usize;
        }
        println!(
            "t {t:.0} s, eye ({:.0}, {:.0}, {:.1}): {drawn} impostors drawn, {hidden} ({:.0} %) \
             wholly below the terrain",
            e[0],
            e[1],
            e[2],
            100.0 * hidden as f64 / drawn.max(1) as f64
        );
    }
    Ok(())
}
