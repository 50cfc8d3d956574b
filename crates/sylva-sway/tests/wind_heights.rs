//! Wind that differs with height: per joint, a factor on an instance's wind in the open and
//! inside a canopy, mixed by the instance's shelter (`SwaySpecies::set_wind_heights`,
//! `SwayBatch::set_shelter`).

use sylva_sway::{SwayBatch, SwayParams, SwaySpecies};
use sylva_tree::Species;

fn aspen() -> SwaySpecies {
    let tree = Species::preset("quaking_aspen").expect("preset").generate(1).expect("tree");
    SwaySpecies::new(&tree.skeleton, SwayParams::default()).expect("params")
}

/// Every joint's angles of instance `i`, after `steps` steps of 1/60 s in `wind`.
fn angles(b: &SwayBatch, i: usize) -> Vec<[f32; 2]> {
    (0..b.species().len()).map(|j| b.angles(i, j)).collect()
}

#[test]
fn an_instance_in_the_open_feels_its_wind_times_the_open_factor_and_inside_times_the_inside_one() {
    // Open factor 2 at every joint, inside 1: an instance of shelter 0 moves exactly as one
    // without factors in twice the wind, and one of shelter 1 as one in the wind itself.
    // A batch of 16 (one group of lanes) and a batch of one (the single-lane kernel).
    for instances in [16usize, 1] {
        let sp = aspen();
        let n = sp.len();
        let mut with = SwayBatch::new(sp.clone(), instances);
        with.set_wind_heights(&vec![2.0; n], &vec![1.0; n]).expect("factors");
        let mut plain = SwayBatch::new(sp, instances);
        let u = [7.0f32, 1.5, 0.3];
        let wind = vec![u; instances];
        let mut doubled = wind.clone();
        doubled[0] = [2.0 * u[0], 2.0 * u[1], 2.0 * u[2]];
        with.set_shelter(0, 0.0);
        for _ in 0..120 {
            with.step(1.0 / 60.0, &wind);
            plain.step(1.0 / 60.0, &doubled);
        }
        for i in 0..instances {
            assert_eq!(angles(&with, i), angles(&plain, i), "instance {i} of {instances}");
        }
        // And the factors did something: the instance in the open bends further.
        let bend = |b: &SwayBatch, i: usize| b.angles(i, 0)[0].hypot(b.angles(i, 0)[1]);
        if instances > 1 {
            assert!(bend(&with, 0) > 1.5 * bend(&with, 1), "{} {}", bend(&with, 0), bend(&with, 1));
        }
    }
}

#[test]
fn wind_only_over_the_upper_crown_bends_the_trunk_less_than_wind_over_the_whole_tree() {
    // The trunk's bend at its base carries the moment of every joint's drag: with the wind
    // only above half the tree's height (factor 0 below) it is smaller, but not zero; with
    // the wind only below, smaller again (short lever arms, little foliage).
    let sp = aspen();
    let n = sp.len();
    let heights: Vec<f32> = sp.pressure_centres().iter().map(|c| c[2]).collect();
    let top = heights.iter().cloned().fold(0.0f32, f32::max);
    let upper: Vec<f32> = heights.iter().map(|&z| if z > 0.5 * top { 1.0 } else { 0.0 }).collect();
    let lower: Vec<f32> = upper.iter().map(|f| 1.0 - f).collect();
    let mean_bend = |factors: Option<&[f32]>| {
        let mut b = SwayBatch::new(sp.clone(), 1);
        if let Some(f) = factors {
            b.set_wind_heights(f, f).expect("factors");
        }
        let wind = [[8.0f32, 0.0, 0.0]];
        let mut sum = 0.0f64;
        for k in 0..600 {
            b.step(1.0 / 60.0, &wind);
            if k >= 300 {
                let a = b.angles(0, 0);
                sum += (a[0] as f64).hypot(a[1] as f64);
            }
        }
        sum / 300.0
    };
    let (whole, above, below) = (mean_bend(None), mean_bend(Some(&upper)), mean_bend(Some(&lower)));
    assert_eq!(n, heights.len());
    assert!(above < 0.95 * whole && above > 0.3 * whole, "{above} against {whole}");
    assert!(below < above, "{below} against {above}");
    assert!(below > 0.0);
}

#[test]
fn height_factors_are_checked_and_named() {
    let mut sp = aspen();
    let n = sp.len();
    let e = sp.set_wind_heights(&vec![1.0; n - 1], &vec![1.0; n]).expect_err("short");
    assert_eq!(e.field, "wind_open");
    let mut bad = vec![1.0; n];
    bad[3] = f32::NAN;
    let e = sp.set_wind_heights(&vec![1.0; n], &bad).expect_err("NaN");
    assert_eq!(e.field, "wind_inside");
    bad[3] = -0.5;
    assert_eq!(sp.set_wind_heights(&bad, &vec![1.0; n]).expect_err("negative").field, "wind_open");
    assert!(!sp.has_wind_heights());
    sp.set_wind_heights(&vec![0.5; n], &vec![1.0; n]).expect("valid");
    assert!(sp.has_wind_heights());
    sp.set_wind_heights(&[], &[]).expect("cleared");
    assert!(!sp.has_wind_heights());
}

#[test]
fn gusts_take_their_own_factor_and_the_mean_its_own() {
    // Mean factors 1, gust factors 0: an instance in a gusty wind u whose mean is ū moves
    // exactly as one without factors in ū itself. Gust factors 2: as one in ū + 2 (u − ū).
    let sp = aspen();
    let n = sp.len();
    let mean = [6.0f32, 1.0, 0.0];
    let gusty = |k: usize| {
        let s = (k as f32 * 0.37).sin();
        [mean[0] + 2.0 * s, mean[1] - 1.5 * s, 0.8 * s]
    };
    for (gust, scale) in [(0.0f32, 0.0f32), (2.0, 2.0)] {
        let mut with = SwayBatch::new(sp.clone(), 1);
        with.set_wind_heights(&vec![1.0; n], &vec![1.0; n]).expect("mean factors");
        with.set_gust_heights(&vec![gust; n], &vec![gust; n]).expect("gust factors");
        with.set_mean_wind(0, mean);
        let mut plain = SwayBatch::new(sp.clone(), 1);
        for k in 0..90 {
            let u = gusty(k);
            with.step(1.0 / 60.0, &[u]);
            let felt: [f32; 3] = std::array::from_fn(|c| mean[c] + scale * (u[c] - mean[c]));
            plain.step(1.0 / 60.0, &[felt]);
        }
        let (a, b) = (angles(&with, 0), angles(&plain, 0));
        let worst = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x[0] - y[0]).abs().max((x[1] - y[1]).abs()))
            .fold(0.0f32, f32::max);
        // The same but for rounding (the factors and the mean are applied in another order).
        assert!(worst < 1e-4, "gust factor {gust}: {worst} rad apart");
    }
    // Gust factors without mean factors are refused.
    let mut bare = aspen();
    assert_eq!(
        bare.set_gust_heights(&vec![1.0; n], &vec![1.0; n]).expect_err("no mean").field,
        "gust_open"
    );
}
