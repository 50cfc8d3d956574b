//! The native side of the step comparison with WebAssembly (`.ci/wasm-step.mjs`): grow a
//! built-in scene, step it with a frame after each (as [`sylva_wasm::steps`] does), and print
//! the median milliseconds per step over five runs. Single-threaded, as a page without
//! threads runs:
//! `RAYON_NUM_THREADS=1 cargo run --release -p sylva-wasm --example step -- A 100`.

fn main() {
    let mut args = std::env::args().skip(1);
    let scene = args.next().unwrap_or_else(|| "A".into());
    let n: u32 = args.next().and_then(|s| s.parse().ok()).unwrap_or(100);
    let Some(trees) = sylva_wasm::prepare(&scene) else {
        eprintln!("no built-in scene `{scene}`");
        std::process::exit(2);
    };
    sylva_wasm::steps(10);
    let mut runs: Vec<f64> = (0..5)
        .map(|_| {
            let t = std::time::Instant::now();
            let sum = sylva_wasm::steps(n);
            assert!(sum.is_finite());
            t.elapsed().as_secs_f64() * 1e3 / f64::from(n)
        })
        .collect();
    runs.sort_by(f64::total_cmp);
    println!(
        "scene {scene} ({trees} trees), native: {:.3} ms per step (median of 5 × {n})",
        runs[2]
    );
}
