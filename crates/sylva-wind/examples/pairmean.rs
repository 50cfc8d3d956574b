//! Times the separable method (reference speed) against the embedding (the paper's pair-mean
//! speed) on one grid of several heights, side by side: `pairmean [RUNS] [NX] [HEIGHTS…]`.

use std::time::Instant;

use sylva_wind::{CoherenceSpeed, Grid, Method, SynthParams, WindField, WindParams};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("bits") {
        bits();
        return;
    }
    let runs: usize = args.first().and_then(|a| a.parse().ok()).unwrap_or(3);
    let n: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(100);
    let heights: Vec<f64> = args.iter().skip(2).filter_map(|a| a.parse().ok()).collect();
    let heights = if heights.is_empty() { vec![15.0, 20.0, 30.0] } else { heights };
    let grid = Grid::regular(n, n, 4.0, &heights, 2048, 0.1);
    let pm = WindParams { coherence_speed: CoherenceSpeed::PairMean, ..WindParams::default() };
    let time = |params: &WindParams, method: Method, seed: u64| {
        let t0 = Instant::now();
        let f = WindField::generate(params, &grid, SynthParams { seed, method }, &|_| {})
            .expect("synthesis");
        std::hint::black_box(&f.data);
        t0.elapsed().as_secs_f64()
    };
    for seed in 0..runs as u64 {
        let sep = if std::env::var_os("ONLY_EMBEDDING").is_some() {
            f64::NAN
        } else {
            time(&WindParams::default(), Method::Separable, seed)
        };
        let emb = time(&pm, Method::Embedding, seed);
        println!("separable {sep:.3} s, embedding {emb:.3} s, ratio {:.2}", emb / sep);
    }
}

/// Hashes of the embedding's output bits on grids that exercise its paths (semidefinite
/// blocks, projected blocks, one height, ten heights), to compare builds bit for bit.
fn bits() {
    let pm = WindParams { coherence_speed: CoherenceSpeed::PairMean, ..WindParams::default() };
    for (nx, ny, gap, zs) in [
        (24, 24, 4.0, vec![15.0, 20.0, 30.0]),
        (17, 9, 5.0, vec![20.0]),
        (12, 10, 4.0, vec![12.0, 15.0, 20.0, 25.0, 30.0, 35.0, 40.0, 50.0, 60.0, 70.0]),
    ] {
        let grid = Grid::regular(nx, ny, gap, &zs, 2048, 0.1);
        let f = WindField::generate(
            &pm,
            &grid,
            SynthParams { seed: 7, method: Method::Embedding },
            &|_| {},
        )
        .expect("synthesis");
        let h = f.data.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, v| {
            (h ^ u64::from(v.to_bits())).wrapping_mul(0x100_0000_01b3)
        });
        println!("{nx}×{ny}×{}: {h:016x}, coherence error {:.3e}", zs.len(), f.coherence_error);
    }
    let grid = Grid::regular(20, 12, 4.0, &[15.0, 20.0, 30.0], 512, 0.1);
    let f = WindField::generate(
        &WindParams::default(),
        &grid,
        SynthParams { seed: 7, method: Method::Separable },
        &|_| {},
    )
    .expect("synthesis");
    let h = f.data.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, v| {
        (h ^ u64::from(v.to_bits())).wrapping_mul(0x100_0000_01b3)
    });
    println!("separable 20×12×3: {h:016x}");
}
