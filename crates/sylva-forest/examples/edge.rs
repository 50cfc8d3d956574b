//! A forest's windward edge: how much more the trees there sway than those inside. A stand
//! of aspens in the `strong` preset blowing along +x, every tree simulated on its own (the
//! wind-field LOD off), with the canopy wind and, for comparison, without; each tree's
//! trunk-top displacement recorded at 30 Hz after 10 s; its mean and 99th percentile
//! averaged over bands of fetch (the distance the wind has blown through the forest to
//! reach the tree), as ratios to the interior's (fetch beyond seven canopy heights).
//!
//!     cargo run --release -p sylva-forest --example edge -- [SECONDS]
//!
//! Beside them, ForestGALES' edge factor on the maximum bending moment at the band's middle
//! fetch x (Hale et al. 2015, from the wind-tunnel measurements of Gardiner et al. 1997;
//! as in the `fgr` package's `edge_gap_factor`, open ground upwind): with s = spacing / h,
//! A = 2.7193 s − 0.061, B = 0.9701 − 1.273 s, c = 1.1127 s + 0.0311, the factor is
//! (A + B c^(x/h)) / A (its interior term c^9 neglected).

use anyhow::Result;
use sylva_forest::{Forest, SceneSpec};

const DT: f32 = 1.0 / 30.0;
/// Bands of fetch, in canopy heights.
const BANDS: [f64; 7] = [0.0, 0.5, 1.0, 2.0, 4.0, 7.0, f64::INFINITY];

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
    let h = stand.height;
    let spacing = (std::f64::consts::PI * (on.radius as f64).powi(2) / on.trees() as f64).sqrt();
    println!(
        "stand: h {h:.1} m, leaf area index {:.2}, attenuation a {:.2}, mean spacing \
         {spacing:.1} m",
        stand.lai,
        sylva_wind::canopy_attenuation(stand.lai, sylva_forest::canopy::FOLIAGE_DRAG),
    );
    let s = (spacing / h).clamp(0.075, 0.45);
    let (a, b, c) = (2.7193 * s - 0.061, 0.9701 - 1.273 * s, 1.1127 * s + 0.0311);
    let gales = |x: f64| (a + b * c.powf(x / h)) / a;
    let fetch: Vec<f64> = (0..on.trees()).map(|t| on.fetch_of(t).unwrap_or(0.0)).collect();
    let mut table = Vec::new();
    for mut forest in [on, Forest::new(&scene(false)?)?] {
        let n = forest.trees();
        for _ in 0..(10.0 / DT) as usize {
            forest.step(DT);
        }
        let frames = (seconds / DT) as usize;
        let mut rec = vec![Vec::with_capacity(frames); n];
        for _ in 0..frames {
            forest.step(DT);
            for (t, r) in rec.iter_mut().enumerate() {
                r.push(forest.trunk_top_displacement(t).unwrap_or(0.0) as f64);
            }
        }
        let stats: Vec<(f64, f64)> = rec
            .iter_mut()
            .map(|r| {
                let mean = r.iter().sum::<f64>() / frames as f64;
                r.sort_by(f64::total_cmp);
                (mean, r[(0.99 * (frames - 1) as f64) as usize])
            })
            .collect();
        let band = |lo: f64, hi: f64| {
            let ts: Vec<usize> = (0..n).filter(|&t| fetch[t] >= lo && fetch[t] < hi).collect();
            let k = ts.len().max(1) as f64;
            let mean = ts.iter().map(|&t| stats[t].0).sum::<f64>() / k;
            let top = ts.iter().map(|&t| stats[t].1).sum::<f64>() / k;
            (ts.len(), mean, top)
        };
        let inside = band(7.0 * h, f64::INFINITY);
        let mut col = Vec::new();
        for w in BANDS.windows(2) {
            let (k, mean, top) = band(w[0] * h, w[1] * h);
            col.push((k, mean, mean / inside.1, top / inside.2));
        }
        table.push(col);
    }
    println!(
        "| fetch (h) | trees | mean m | mean / interior | 99th pct / interior | \
         without canopy wind: mean / interior, 99th / interior | ForestGALES max moment / interior |"
    );
    println!("|---|---|---|---|---|---|---|");
    for (i, w) in BANDS.windows(2).enumerate() {
        let (k, mean, r, p) = table[0][i];
        let (_, _, r0, p0) = table[1][i];
        let mid = if w[1].is_finite() { 0.5 * (w[0] + w[1]) } else { 2.0 * w[0] };
        let upper = if w[1].is_finite() { format!("{}", w[1]) } else { "…".into() };
        println!(
            "| {}–{upper} | {k} | {mean:.3} | {r:.2} | {p:.2} | {r0:.2}, {p0:.2} | {:.2} |",
            w[0],
            gales(mid * h)
        );
    }
    Ok(())
}
