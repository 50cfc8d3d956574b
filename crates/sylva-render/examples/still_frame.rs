//! A scene's frame with all its LODs in the rest pose, from the camera at its path's end:
//! the frame `sylva bench table3` writes as `SCENE-still-all-LODs.png` and compares with
//! full detail (`SCENE-still-full-detail.png`, the same camera) for the geometry LOD's own
//! image error. Full detail of the large scenes takes many minutes a frame on a software
//! rasteriser; this frame takes seconds, so a change to the impostors can be measured
//! against a full-detail still kept from one table3 run:
//!
//! `cargo run --release -p sylva-render --example still_frame -- SCENE OUT.png [--time]`,
//! then `tools/image_error.py out/table3/SCENE-still-full-detail.png OUT.png`.
//!
//! SCENE is a built-in scene (`A` … `D`) or a scene file; `--time` renders the frame five
//! more times and prints the median rendering time.

use sylva_forest::{Forest, FrameData, SceneSpec};
use sylva_render::Headless;

const W: u32 = 1024;
const H: u32 = 768;

fn main() {
    if let Err(e) = run() {
        eprintln!("still_frame: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(scene), Some(out)) = (args.first(), args.get(1)) else {
        return Err("usage: still_frame SCENE OUT.png [--time]".into());
    };
    let time = match args.get(2).map(String::as_str) {
        None => false,
        Some("--time") => true,
        Some(other) => return Err(format!("{other}: the only option is --time").into()),
    };
    let spec = SceneSpec::load(scene)?;
    let forest = Forest::new(&spec)?;
    // The path's end, as table3's last timed frame.
    let path = if spec.camera_path.is_empty() {
        sylva_forest::default_camera_path(&spec, forest.radius)
    } else {
        spec.camera_path.clone()
    };
    let camera = forest.camera_at(path.last().map_or(0.0, |k| k.t));
    let mut gpu = Headless::new(&forest, W, H)?;
    let mut frame = FrameData::default();
    forest.frame(&camera, W as f32 / H as f32, &mut frame);
    eprintln!(
        "{}: {} trees drawn, {} impostors, {} triangles",
        spec.name, frame.stats.drawn, frame.stats.impostors, frame.stats.triangles
    );
    let mut rgba = gpu.render(&frame, &camera)?;
    if time {
        let mut ms = Vec::new();
        for _ in 0..5 {
            let start = std::time::Instant::now();
            rgba = gpu.render(&frame, &camera)?;
            ms.push(start.elapsed().as_secs_f64() * 1e3);
        }
        ms.sort_by(f64::total_cmp);
        eprintln!("rendering: {:.0} ms (median of 5), {:.0} … {:.0}", ms[2], ms[0], ms[4]);
    }
    let file = std::io::BufWriter::new(std::fs::File::create(out)?);
    let mut e = png::Encoder::new(file, W, H);
    e.set_color(png::ColorType::Rgba);
    e.set_depth(png::BitDepth::Eight);
    e.write_header()?.write_image_data(&rgba)?;
    Ok(())
}
