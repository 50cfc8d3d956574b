//! A scene's frame with all its LODs from the camera at its path's end, as `sylva bench
//! table3` renders it: at rest (`SCENE-still-all-LODs.png`, compared there with full
//! detail at rest, `SCENE-still-full-detail.png`) or, with `--walk N`, after walking the
//! path in N steps of 0.1 s (`SCENE-with-all-LODs.png` of a run with `--warmup 1 --frames
//! N-1`, compared with `SCENE-full-detail.png`). Full detail of the large scenes takes many
//! minutes a frame on a software rasteriser; this frame takes seconds, so a change to the
//! impostors can be measured against the full-detail frames one table3 run wrote:
//!
//! `cargo run --release -p sylva-render --example lod_frame -- SCENE OUT.png [--walk N] [--time]`,
//! then `tools/image_error.py out/table3/SCENE-still-full-detail.png OUT.png`.
//!
//! SCENE is a built-in scene (`A` … `D`) or a scene file; `--at SECONDS` takes the camera
//! at that time along the path instead of its end (at rest). `--time` renders the frame
//! five more times and prints the median rendering time, then five more with the GPU's
//! time in each part of the frame (where the adapter has timestamps inside passes; on
//! lavapipe the split inside the image pass is not to be trusted, its sum is).
//! `--supersample N` renders the frame at
//! N times the width and height and averages each N × N block (in linear light) down to
//! 1024 × 768: N² times the samples a pixel, a reference nearer the converged image than
//! the 4× MSAA frame (the levels are chosen as at 1024 × 768: by the share of the image's
//! height a tree takes). A copy of the scene's file with
//! `[lod] geometry = false` and `animation = false` renders table3's full-detail frame
//! itself (the wind-field LOD stays on: table3's reference keeps the instance groups).

use sylva_forest::{Forest, FrameData, SceneSpec};
use sylva_render::Headless;

const W: u32 = 1024;
const H: u32 = 768;

fn main() {
    if let Err(e) = run() {
        eprintln!("lod_frame: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let time = take_flag(&mut args, "--time");
    let ss = match take_value(&mut args, "--supersample")? {
        None => 1,
        Some(v) => match v.parse::<u32>() {
            Ok(n) if (1..=4).contains(&n) => n,
            _ => return Err(format!("--supersample {v}: a whole number from 1 to 4").into()),
        },
    };
    let walk = match take_value(&mut args, "--walk")? {
        None => None,
        Some(v) => match v.parse::<usize>() {
            Ok(n) if n >= 2 => Some(n),
            _ => return Err(format!("--walk {v}: a whole number of steps, at least 2").into()),
        },
    };
    let at = match take_value(&mut args, "--at")? {
        None => None,
        Some(v) => match v.parse::<f32>() {
            Ok(t) if t.is_finite() && t >= 0.0 => Some(t),
            _ => return Err(format!("--at {v}: a time along the path, s, at least 0").into()),
        },
    };
    if walk.is_some() && at.is_some() {
        return Err("--walk ends at the path's end: give it or --at, not both".into());
    }
    let [scene, out] = &args[..] else {
        return Err(
            "usage: lod_frame SCENE OUT.png [--walk N | --at SECONDS] [--time] [--supersample N]"
                .into(),
        );
    };
    let spec = SceneSpec::load(scene)?;
    let mut forest = Forest::new(&spec)?;
    let duration = forest.path_duration();
    let aspect = W as f32 / H as f32;
    let mut gpu = Headless::new(&forest, W * ss, H * ss)?;
    let mut frame = FrameData::default();
    let camera = match walk {
        None => {
            let camera = forest.camera_at(at.unwrap_or(duration));
            forest.frame(&camera, aspect, &mut frame);
            camera
        }
        Some(n) => {
            // As table3: the path's cameras evenly spaced, the frame built for each of
            // them last to first, then each step of 0.1 s followed by its frame.
            let cameras: Vec<_> =
                (0..n).map(|i| forest.camera_at(duration * i as f32 / (n - 1) as f32)).collect();
            for camera in cameras.iter().rev() {
                forest.frame(camera, aspect, &mut frame);
            }
            for camera in &cameras {
                forest.step(0.1);
                forest.frame(camera, aspect, &mut frame);
            }
            cameras[n - 1]
        }
    };
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
        // Then five more with the GPU's timestamps between the frame's parts (their own
        // frames: the queries add a little work).
        if gpu.time_passes() {
            let mut parts = vec![Vec::new(); sylva_render::PASS_PARTS.len()];
            for _ in 0..5 {
                gpu.draw(&frame, &camera)?;
                if let Some(p) = gpu.pass_times()? {
                    for (v, t) in parts.iter_mut().zip(p) {
                        v.push(t);
                    }
                }
            }
            let medians: Vec<String> = parts
                .iter_mut()
                .zip(sylva_render::PASS_PARTS)
                .filter(|(v, _)| !v.is_empty())
                .map(|(v, name)| {
                    v.sort_by(f64::total_cmp);
                    format!("{name} {:.0}", v[v.len() / 2])
                })
                .collect();
            eprintln!("GPU ms by part (medians): {}", medians.join(", "));
        }
    }
    if ss > 1 {
        rgba = downsample(&rgba, ss);
    }
    let file = std::io::BufWriter::new(std::fs::File::create(out)?);
    let mut e = png::Encoder::new(file, W, H);
    e.set_color(png::ColorType::Rgba);
    e.set_depth(png::BitDepth::Eight);
    e.write_header()?.write_image_data(&rgba)?;
    Ok(())
}

/// The `W·n × H·n` RGBA8 (sRGB) frame `rgba` averaged over `n × n` blocks to `W × H`, the
/// colour in linear light (as an MSAA resolve averages), alpha as stored.
fn downsample(rgba: &[u8], n: u32) -> Vec<u8> {
    let to_linear = |c: u8| {
        let c = c as f64 / 255.0;
        if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
    };
    let to_srgb = |l: f64| {
        let c = if l <= 0.0031308 { 12.92 * l } else { 1.055 * l.powf(1.0 / 2.4) - 0.055 };
        (c * 255.0).round().clamp(0.0, 255.0) as u8
    };
    let wide = (W * n) as usize;
    let mut out = vec![0u8; (W * H * 4) as usize];
    for y in 0..H as usize {
        for x in 0..W as usize {
            let mut sum = [0.0f64; 4];
            for dy in 0..n as usize {
                for dx in 0..n as usize {
                    let i = 4 * ((y * n as usize + dy) * wide + x * n as usize + dx);
                    for c in 0..3 {
                        sum[c] += to_linear(rgba[i + c]);
                    }
                    sum[3] += rgba[i + 3] as f64;
                }
            }
            let k = (n * n) as f64;
            let o = 4 * (y * W as usize + x);
            for c in 0..3 {
                out[o + c] = to_srgb(sum[c] / k);
            }
            out[o + 3] = (sum[3] / k).round() as u8;
        }
    }
    out
}

fn take_flag(args: &mut Vec<String>, name: &str) -> bool {
    let before = args.len();
    args.retain(|a| a != name);
    args.len() != before
}

fn take_value(args: &mut Vec<String>, name: &str) -> Result<Option<String>, String> {
    let Some(i) = args.iter().position(|a| a == name) else { return Ok(None) };
    if i + 1 >= args.len() {
        return Err(format!("{name} needs a value"));
    }
    let v = args.remove(i + 1);
    args.remove(i);
    Ok(Some(v))
}
