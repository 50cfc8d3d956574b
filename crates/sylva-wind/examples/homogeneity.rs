//! Is the field the same at every x with advection on? The pooled co-coherence between
//! neighbouring heights over a grid's middle columns and over its edge columns, band by
//! band, against eq. 5 (pair-mean speed), over several seeds.
//!
//!     cargo run --release -p sylva-wind --example homogeneity -- [SEEDS]
//!
//! Grid: 24 × 24 points 5 m apart, heights 15, 20 and 30 m, 2048 frames of 0.1 s; middle
//! columns 10–13, edge columns 0–3 (45–57 m from the middle). Prints, per component and
//! pair of heights, each band with eq. 5 above 0.1: middle, edge, model, and the largest
//! |middle − edge| and |edge − model|.

use sylva_wind::stats::ensemble_stats_at;
use sylva_wind::{CoherenceSpeed, Grid, Method, SynthParams, WindField, WindParams};

fn main() {
    let seeds: u64 = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(8);
    let params = WindParams { coherence_speed: CoherenceSpeed::PairMean, ..WindParams::default() };
    let grid = Grid::regular(24, 24, 5.0, &[15.0, 20.0, 30.0], 2048, 0.1);
    let method = Method::fastest(&params, &grid);
    let fields: Vec<WindField> = (0..seeds)
        .map(|s| {
            WindField::generate(&params, &grid, SynthParams { seed: 100 + s, method }, &|_| {})
                .expect("valid setup")
        })
        .collect();
    let part = |cols: std::ops::Range<usize>| -> Vec<WindField> {
        fields.iter().map(|f| f.columns(cols.clone())).collect()
    };
    let (middle, edge) = (part(10..14), part(0..4));
    let (mut worst_split, mut worst_model) = (0.0f64, 0.0f64);
    for iz in 0..grid.nz() - 1 {
        let (m, e) =
            (ensemble_stats_at(&middle, Some(256), iz), ensemble_stats_at(&edge, Some(256), iz));
        for (cm, ce) in m.components.iter().zip(&e.components) {
            let z = |c: &sylva_wind::stats::ComponentStats| {
                c.coherence.iter().find(|r| r.axis == "z").expect("z row").bands.clone()
            };
            for (bm, be) in z(cm).iter().zip(&z(ce)).filter(|(b, _)| b.model > 0.1) {
                println!(
                    "{} z {}–{} m  {:.3} Hz  middle {:+.3}  edge {:+.3}  eq. 5 {:+.3}",
                    cm.component,
                    grid.zs[iz],
                    grid.zs[iz + 1],
                    bm.f,
                    bm.measured,
                    be.measured,
                    be.model
                );
                worst_split = worst_split.max((bm.measured - be.measured).abs());
                worst_model = worst_model.max((be.measured - be.model).abs());
            }
        }
    }
    println!(
        "{seeds} seeds: largest |middle − edge| {worst_split:.3}, largest |edge − eq. 5| {worst_model:.3}"
    );
}
