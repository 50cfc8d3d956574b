//! How close impostors come to full detail, away from any camera path or motion: a stand
//! of 120 trees of scene B's species mix in calm air, seen from 70, 110 and 170 m off its
//! centre (crowns about 300, 200 and 130 pixels tall at 1024 × 768), rendered at full
//! detail (`full{i}.png`), with every tree an impostor (`impostor{i}.png`), and at full
//! detail from a quarter pixel aside (`aside{i}.png`, the sampling floor any comparison of
//! foliage has). Compare with `tools/image_error.py OUT/full2.png OUT/impostor2.png`.
//!
//! `cargo run --release -p sylva-render --example impostor_stand -- OUT [shadows: 1|0] [spacing m] [elevation °] [distance factor]`
//! (defaults: out/impostor-stand, shadows on, 7 m, the cameras about 8° above the stand's
//! centre; a wider spacing moves the cameras out and narrows their view in proportion, so
//! the crowns keep their size but stand apart; an elevation puts the cameras that many
//! degrees above the horizon seen from the stand's centre, at the same distances, as a
//! camera over a forest looks down on its nearer impostors; a distance factor moves the
//! cameras that many times farther, the view kept, so the crowns shrink as a forest's
//! middle distance shows them).

use std::path::Path;

use sylva_forest::{Camera, Forest, FrameData, SceneSpec};
use sylva_render::Headless;

const W: u32 = 1024;
const H: u32 = 768;
const FOV_DEG: f32 = 40.0;

fn write_png(path: &Path, rgba: &[u8]) -> Result<(), Box<dyn std::error::Error>> {
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    let mut e = png::Encoder::new(file, W, H);
    e.set_color(png::ColorType::Rgba);
    e.set_depth(png::BitDepth::Eight);
    e.write_header()?.write_image_data(rgba)?;
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let out = Path::new(args.get(1).map_or("out/impostor-stand", String::as_str)).to_path_buf();
    let shadows = args.get(2).is_none_or(|s| s != "0");
    let spacing: f32 = match args.get(3) {
        Some(s) => s.parse().map_err(|e| format!("spacing {s:?}: {e}"))?,
        None => 7.0,
    };
    let elevation: Option<f32> = match args.get(4) {
        Some(s) => Some(s.parse().map_err(|e| format!("elevation {s:?}: {e}"))?),
        None => None,
    };
    // The three distances times this, the field of view kept: smaller crowns.
    let farther: f32 = match args.get(5) {
        Some(s) => s.parse().map_err(|e| format!("distance factor {s:?}: {e}"))?,
        None => 1.0,
    };
    if !(farther.is_finite() && farther > 0.0) {
        return Err(format!("distance factor {farther}: must be a positive number").into());
    }
    std::fs::create_dir_all(&out)?;
    let mut spec = SceneSpec::builtin("B")?;
    spec.trees = 120;
    spec.spacing = spacing;
    spec.surround = Default::default();
    spec.wind = "calm".into();
    spec.camera_path = Vec::new();
    spec.lighting.shadows = shadows;
    let mut full = spec.clone();
    full.lod.geometry = false;
    spec.lod.fraction = 100.0;
    let k = spacing / 7.0;
    let fov = FOV_DEG / k;
    let cameras: Vec<Camera> = [70.0f32, 110.0, 170.0]
        .iter()
        .map(|&d| {
            let d = d * k * farther;
            let eye = match elevation {
                // Along the same horizontal bearing, `d` from the target, `e` above it.
                Some(e) => {
                    let (s, c) = e.to_radians().sin_cos();
                    let h = d * c / 1.0f32.hypot(0.35);
                    [-h, -0.35 * h, 6.0 + d * s]
                }
                None => [-d, -0.35 * d, 0.15 * d + 8.0],
            };
            Camera { eye, target: [0.0, 0.0, 6.0], fov_deg: fov, near: 0.5, far: 8000.0 }
        })
        .collect();
    let aspect = W as f32 / H as f32;
    for (name, s) in [("full", &full), ("impostor", &spec)] {
        let mut forest = Forest::new(s)?;
        let mut gpu = Headless::new(&forest, W, H)?;
        let mut frame = FrameData::default();
        forest.step(1.0 / 30.0);
        for (i, camera) in cameras.iter().enumerate() {
            forest.frame(camera, aspect, &mut frame);
            eprintln!(
                "{name} {i}: {} trees drawn, {} impostors",
                frame.stats.drawn, frame.stats.impostors
            );
            write_png(&out.join(format!("{name}{i}.png")), &gpu.render(&frame, camera)?)?;
            if s.lod.geometry {
                continue;
            }
            // A quarter pixel across the view, at the target's distance.
            let (dx, dy) = (camera.target[0] - camera.eye[0], camera.target[1] - camera.eye[1]);
            let dist = dx.hypot(dy);
            let range = dist.hypot(camera.target[2] - camera.eye[2]);
            let step = 0.25 * 2.0 * range * (0.5 * fov).to_radians().tan() / H as f32;
            let (rx, ry) = (dy / dist * step, -dx / dist * step);
            let mut aside = *camera;
            aside.eye[0] += rx;
            aside.eye[1] += ry;
            aside.target[0] += rx;
            aside.target[1] += ry;
            forest.frame(&aside, aspect, &mut frame);
            write_png(&out.join(format!("aside{i}.png")), &gpu.render(&frame, &aside)?)?;
        }
    }
    eprintln!("written to {}", out.display());
    Ok(())
}
