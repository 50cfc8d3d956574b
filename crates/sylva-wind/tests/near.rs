//! The near field: a fine, periodic realisation of the same model, blended into a coarse
//! field near a centre without changing the mean or the variance the trees feel.

use sylva_wind::{
    Component, Grid, NearField, Preset, SynthParams, WindField, WindParams, spectrum,
};

const FRAMES: usize = 512;
const DT: f64 = 0.1;

fn params() -> WindParams {
    WindParams { direction_deg: 30.0, ..Preset::Strong.params() }
}

/// A coarse field 60 m between points, centred on the origin (as a forest's is).
fn coarse() -> WindField {
    let mut grid = Grid::regular(5, 5, 60.0, &[8.0, 22.0], FRAMES, DT);
    grid.xs = grid.xs.iter().map(|x| x - 120.0).collect();
    grid.ys = grid.xs.clone();
    WindField::generate(&params(), &grid, SynthParams { seed: 3, ..Default::default() }, &|_| {})
        .expect("valid coarse field")
}

fn near() -> NearField {
    let synth = SynthParams { seed: 4, ..Default::default() };
    NearField::generate(&params(), 24, 5.0, &[8.0, 22.0], FRAMES, DT, synth, 50.0, 12.0)
        .expect("valid near field")
}

/// Time mean and variance of the along-wind speed (the mean direction) over one loop.
fn along_wind_stats(f: impl Fn(f64) -> [f64; 3]) -> (f64, f64) {
    let [c, s] = params().direction();
    let u: Vec<f64> = (0..FRAMES)
        .map(|k| {
            let v = f(k as f64 * DT);
            v[0] * c + v[1] * s
        })
        .collect();
    let mean = u.iter().sum::<f64>() / u.len() as f64;
    (mean, u.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / u.len() as f64)
}

#[test]
fn the_tile_repeats_with_its_period_along_and_across_the_wind() {
    let near = near();
    let period = 23.0 * 5.0;
    let [c, s] = params().direction();
    let p = [13.7, -41.2, 12.0];
    for (along, across) in [(1.0, 0.0), (0.0, 1.0), (-2.0, 3.0)] {
        let q = [
            p[0] + period * (along * c - across * s),
            p[1] + period * (along * s + across * c),
            p[2],
        ];
        for t in [0.0, 7.35, 40.1] {
            let (a, b) = (near.sample(p, t), near.sample(q, t));
            for i in 0..3 {
                assert!(
                    (a[i] - b[i]).abs() < 1e-3,
                    "shift ({along}, {across}) t {t}: {a:?} vs {b:?}"
                );
            }
        }
    }
}

#[test]
fn the_weight_is_one_inside_zero_outside_and_falls_smoothly_between() {
    let near = near();
    assert_eq!((near.reach(), near.band()), (50.0, 12.0));
    assert_eq!(near.weight(0.0), 1.0);
    assert_eq!(near.weight(38.0), 1.0);
    assert_eq!(near.weight(50.0), 0.0);
    assert_eq!(near.weight(500.0), 0.0);
    let mut last = 1.0;
    for k in 0..=120 {
        let w = near.weight(38.0 + 0.1 * k as f64);
        assert!(w <= last && (last - w) < 0.02, "at {} m: {w} after {last}", 38.0 + 0.1 * k as f64);
        last = w;
    }
    // The reach is held within half the tile (the tile's neighbourhood holds one seam a side).
    let synth = SynthParams { seed: 4, ..Default::default() };
    let wide =
        NearField::generate(&params(), 8, 5.0, &[8.0], 16, DT, synth, 500.0, 900.0).expect("valid");
    assert_eq!((wide.reach(), wide.band()), (17.5, 17.5));
}

#[test]
fn blending_keeps_the_mean_and_restores_the_variance_the_coarse_grid_smears_out() {
    let (coarse, near) = (coarse(), near());
    let view = coarse.view();
    // On one of the grid's heights (between heights the interpolation smears as well).
    let z = 8.0;
    // The variance the loop holds of u at that height: what every grid record carries.
    let model = spectrum::discrete_variance(&params(), Component::U, z, FRAMES, DT);
    // The middles of the coarse grid's 16 cells: bilinear mixes of four partly coherent
    // records 60 m apart.
    let dir = params().direction();
    let middles: Vec<[f64; 3]> = (0..4)
        .flat_map(|i| (0..4).map(move |j| (i, j)))
        .map(|(i, j)| {
            let (x, y) = (coarse.grid.xs[i] + 30.0, coarse.grid.ys[j] + 30.0);
            [x * dir[0] - y * dir[1], x * dir[1] + y * dir[0], z]
        })
        .collect();
    let n = middles.len() as f64;
    let mut smeared = 0.0;
    let mut blended = [0.0; 3];
    let mut means = [0.0; 3];
    for &p in &middles {
        smeared += along_wind_stats(|t| view.sample(p, t)).1 / n;
        for (k, w) in [0.0, 0.5, 1.0].into_iter().enumerate() {
            let (m, v) = along_wind_stats(|t| near.blend(view.sample(p, t), p, t, w));
            blended[k] += v / n;
            means[k] += m / n;
        }
    }
    let speed = params().mean_speed(z);
    // The coarse grid's interpolation loses most of the variance between its points (a tree
    // there would feel a fifth of the gustiness).
    assert!(smeared < 0.6 * model, "cell middles {smeared:.2} vs the loop's {model:.2} (m/s)²");
    // Fully near, the variance is the model's again.
    let fine = blended[2];
    assert!((fine / model - 1.0).abs() < 0.25, "near: {fine:.2} vs the loop's {model:.2} (m/s)²");
    // Half-way through the fade the two independent realisations' variances average (a
    // plain linear mix would give a quarter of their sum).
    let half = blended[1];
    let avg = 0.5 * (smeared + fine);
    assert!(
        (half / avg - 1.0).abs() < 0.15,
        "weight ½: {half:.2} vs their average {avg:.2} (m/s)²"
    );
    // Weight 0 is the coarse field itself, and no weight moves the mean.
    assert!((blended[0] - smeared).abs() < 1e-9);
    for m in means {
        assert!((m - speed).abs() < 0.02 * speed, "mean {m:.3} vs the profile's {speed:.3} m/s");
    }
}
