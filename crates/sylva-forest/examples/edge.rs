//! A forest's windward edge: how much more the trees there sway than those inside. A stand
//! of aspens in the `strong` preset blowing along +x, every tree simulated on its own (the
//! wind-field LOD off), the canopy wind on (and, for comparison, off); each tree's trunk-top
//! displacement recorded at 30 Hz after 10 s; its RMS and mean averaged over bands of fetch
//! (the distance the wind has blown through the forest to reach the tree).
//!
//!     cargo run --release -p sylva-forest --example edge -- [SECONDS]
//!
//! Prints, per band of fetch: trees, RMS and mean trunk-top displacement (m) and the RMS
//! over the interior's (fetch beyond three canopy-drag lengths), with the canopy wind on and
//! off.

use anyhow::Result;
use sylva_forest::{Forest, SceneSpec};

const DT: f32 = 1.0 / 30.0;
/// Bands of fetch, m.
const BANDS: [f64; 7] = [0.0, 8.0, 16.0, 32.0, 64.0, 128.0, f64::INFINITY];

fn main() -> Result<()> {
    let seconds: f32 = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(60.0);
    let scene = |canopy: bool| {
        SceneSpec::from_toml(
            "edge.toml",
            &format!(
                "name = \"edge\"\nseed = 5\ntrees = 900\nspacing = 6.0\nterrain_amplitude = 0.0\n\
                 wind = \"strong\"\nwind_direction_deg = 0.0\nscale_variation = 0.0\n\
                 canopy_wind = {canopy}\nspecies = [{{ name = \"quaking_aspen\" }}]\n\
                 [lod]\nwind = false\n"
            ),
        )
    };
    let on = Forest::new(&scene(true)?)?;
    let stand = on.stand().expect("canopy wind on");
    let length = stand.height / (sylva_forest::canopy::FOLIAGE_DRAG * stand.lai);
    println!(
        "stand: h {:.1} m, leaf area index {:.2}, attenuation a {:.2}, canopy-drag length {:.1} m",
        stand.height,
        stand.lai,
        sylva_wind::canopy_attenuation(stand.lai, sylva_forest::canopy::FOLIAGE_DRAG),
        length
    );
    let fetch: Vec<f64> = (0..on.trees()).map(|t| on.fetch_of(t).unwrap_or(0.0)).collect();
    let mut rows = Vec::new();
    for (label, mut forest) in [("on", on), ("off", Forest::new(&scene(false)?)?)] {
        let n = forest.trees();
        for _ in 0..(10.0 / DT) as usize {
            forest.step(DT);
        }
        let frames = (seconds / DT) as usize;
        let (mut sq, mut sum) = (vec![0.0f64; n], vec![0.0f64; n]);
        for _ in 0..frames {
            forest.step(DT);
            for t in 0..n {
                let d = forest.trunk_top_displacement(t).unwrap_or(0.0) as f64;
                sq[t] += d * d;
                sum[t] += d;
            }
        }
        let band = |lo: f64, hi: f64| {
            let ts: Vec<usize> = (0..n).filter(|&t| fetch[t] >= lo && fetch[t] < hi).collect();
            let k = ts.len().max(1) as f64;
            let rms = ts.iter().map(|&t| (sq[t] / frames as f64).sqrt()).sum::<f64>() / k;
            let mean = ts.iter().map(|&t| sum[t] / frames as f64).sum::<f64>() / k;
            (ts.len(), rms, mean)
        };
        let interior = band(3.0 * length, f64::INFINITY).1;
        for w in BANDS.windows(2) {
            let (k, rms, mean) = band(w[0], w[1]);
            rows.push(format!(
                "| {label} | {:.0}–{} | {k} | {rms:.3} | {mean:.3} | {:.2} |",
                w[0],
                if w[1].is_finite() { format!("{:.0}", w[1]) } else { "…".into() },
                rms / interior
            ));
        }
    }
    println!("| canopy wind | fetch m | trees | RMS m | mean m | RMS / interior's |");
    println!("|---|---|---|---|---|---|");
    for r in rows {
        println!("{r}");
    }
    Ok(())
}
