//! What the `embed` example's frame costs against Sylva's own path (the viewer's and
//! `render`'s: `Renderer::render` onto its own targets), side by side on one device: the
//! same scene, camera and steps, frames taken in turns so that a busy machine slows both.
//! Prints triangles per frame and the medians of the CPU side (step, frame building,
//! recording and submitting) and of the whole frame (waiting for the GPU).
//!
//!     cargo run --release -p sylva-render --example embed_cost -- [FRAMES] [WIDTHxHEIGHT]

#[allow(dead_code)]
#[path = "embed.rs"]
mod embed;

use std::time::Instant;

use sylva_render::wgpu;

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let frames: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(30);
    let (w, h) = args
        .get(2)
        .and_then(|s| s.split_once('x'))
        .and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)))
        .unwrap_or((1024u32, 768u32));
    let format = wgpu::TextureFormat::Rgba8UnormSrgb;
    let gpu = embed::open(&wgpu::Instance::default(), None);
    // Two scenes on one device: the host's (pillar off, so both draw the same forest) and
    // Sylva's own path through the same kind of scene.
    let mut host = embed::Scene::new(gpu.clone(), format, (w, h));
    host.pillar = false;
    let mut own = embed::Scene::new(gpu.clone(), format, (w, h));
    let target = sylva_render::capture_texture(&gpu.device, (w, h), format, "cost");
    let view = target.create_view(&Default::default());
    let wait = |i| {
        gpu.device.poll(wgpu::PollType::Wait { submission_index: Some(i), timeout: None }).ok();
    };
    let (mut cpu, mut total) = ([Vec::new(), Vec::new()], [Vec::new(), Vec::new()]);
    let mut triangles = [0usize; 2];
    for k in 0..frames + 3 {
        for which in 0..2 {
            let t0 = Instant::now();
            let index = if which == 0 {
                host.draw(1.0 / 30.0, &view)
            } else {
                own.forest.step(1.0 / 30.0);
                let camera = own.camera();
                own.forest.frame(&camera, w as f32 / h as f32, &mut own.frame);
                own.renderer.render(&own.gpu, &own.frame, &camera, &view)
            };
            let t1 = Instant::now();
            wait(index);
            // The first frames compile pipelines and fill caches: not counted.
            if k >= 3 {
                cpu[which].push((t1 - t0).as_secs_f64() * 1e3);
                total[which].push(t0.elapsed().as_secs_f64() * 1e3);
            }
            let scene = if which == 0 { &host } else { &own };
            triangles[which] = scene.frame.stats.triangles;
        }
    }
    for (name, i) in [("embed (host encoder, host depth)", 0), ("Sylva's own path", 1)] {
        println!(
            "{name}: {} triangles, CPU {:.2} ms, frame {:.1} ms (medians of {frames})",
            triangles[i],
            median(&mut cpu[i]),
            median(&mut total[i])
        );
    }
}
