//! The canopy wind of a forest: the mean wind each tree feels follows the stand's canopy
//! profile inside the forest, and at its windward edge a mix with the open ground's whose
//! peak wind's load is ForestGALES' edge factor; edge trees sway further than interior ones.

use sylva_forest::canopy::{EdgeFactor, PEAK_FACTOR, Stand, canopy_gust, open_gust, open_speed};
use sylva_forest::{Forest, SceneSpec};

fn stand_scene(canopy: bool, trees: usize) -> SceneSpec {
    SceneSpec::from_toml(
        "edge.toml",
        &format!(
            "name = \"edge\"\nseed = 5\ntrees = {trees}\nspacing = 6.0\nterrain_amplitude = 0.0\n\
             wind = \"strong\"\nwind_direction_deg = 0.0\nscale_variation = 0.0\n\
             canopy_wind = {canopy}\nspecies = [{{ name = \"quaking_aspen\" }}]\n\
             [lod]\nwind = false\n"
        ),
    )
    .expect("scene")
}

/// Trees `a` and `b` of `forest` by fetch, equal fetches by distance from the forest's
/// centre (as its layout lists them): the order does not depend on how trees are numbered.
fn by_fetch(forest: &Forest, a: usize, b: usize) -> std::cmp::Ordering {
    let fetch = |t: usize| forest.fetch_of(t).expect("canopy wind on");
    let centre = |t: usize| {
        let p = forest.placement(t).expect("tree").position;
        p[0] * p[0] + p[1] * p[1]
    };
    fetch(a).total_cmp(&fetch(b)).then(centre(a).total_cmp(&centre(b)))
}

/// The trees of least and of most fetch.
fn edge_and_interior(forest: &Forest) -> (usize, usize) {
    let by = |a: &usize, b: &usize| by_fetch(forest, *a, *b);
    let edge = (0..forest.trees()).min_by(by).expect("trees");
    let interior = (0..forest.trees()).max_by(by).expect("trees");
    (edge, interior)
}

#[test]
fn the_mean_wind_a_tree_feels_is_the_canopy_profile_inside_and_the_edge_factor_at_the_edge() {
    let forest = Forest::new(&stand_scene(true, 900)).expect("forest");
    let stand: Stand = forest.stand().expect("canopy wind on by default");
    let params = sylva_wind::WindParams { profile: stand.profile(), ..Default::default() };
    let (edge, interior) = edge_and_interior(&forest);
    let shelter = |t: usize| forest.shelter_of(t).expect("canopy wind on");
    let (se, si) = (shelter(edge), shelter(interior));
    assert_eq!(forest.fetch_of(edge), Some(0.0));
    assert!(se < 0.95 && si > 0.999, "shelter at the edge {se}, inside {si}");
    // The field's gusts average out over its loop (512 frames of 0.1 s): the mean of what
    // a tree feels there is its mean wind.
    let mean_of = |t: usize, z: f64, f: &dyn Fn([f32; 3]) -> f64| {
        let s: f64 =
            (0..512).map(|k| f(forest.tree_wind(t, z, 0.1 * k as f64).expect("tree"))).sum();
        s / 512.0
    };
    let along = |w: [f32; 3]| w[0] as f64;
    let h = stand.height;
    let mix = |s: f32, z: f64| {
        (1.0 - s as f64) * open_speed(&params, h, z) + s as f64 * params.mean_speed(z)
    };
    for f in [0.25, 0.5, 1.0, 2.0] {
        let z = f * h;
        // U* is the preset's: compare as ratios to the canopy top's speed. Deep inside, the
        // canopy's own profile.
        let got = mean_of(interior, z, &along) / mean_of(interior, h, &along);
        let canopy = params.mean_speed(z) / params.mean_speed(h);
        assert!((got - canopy).abs() < 0.03 * canopy, "inside at {f} h: {got} against {canopy}");
        // At the edge, the mix of the open ground's and the canopy's at its shelter.
        let got = mean_of(edge, z, &along) / mean_of(edge, 2.0 * h, &along);
        let want = mix(se, z) / mix(se, 2.0 * h);
        assert!((got - want).abs() < 0.03 * want, "edge at {f} h: {got} against {want}");
    }
    // The load of the peak wind (mean + PEAK_FACTOR σ_u) on the edge tree's crown (0.7 h),
    // against the interior's: ForestGALES' edge factor for the stand's spacing, which is on
    // the maximum bending moment. The means are measured; the gusts' sizes are the model's
    // (the open ground's and the canopy's, mixed by the shelter) on the field's σ_u = 2.5 U*,
    // U* the preset's, read off the mean at 2 h inside (the profile is linear in U*): the
    // gusts of one realisation at two points differ by their local variance.
    let u_star = params.u_star * mean_of(interior, 2.0 * h, &along) / params.mean_speed(2.0 * h);
    let field_sigma = sylva_wind::spectrum::SIGMA_PER_U_STAR[0] * u_star;
    let crown = 0.7 * h;
    let inside = canopy_gust(crown, h, |z| params.mean_speed(z));
    let edge_gust = (1.0 - se as f64) * open_gust(&params, h) + se as f64 * inside;
    let peak = |t: usize, gust: f64| mean_of(t, crown, &along) + PEAK_FACTOR * gust * field_sigma;
    let load = (peak(edge, edge_gust) / peak(interior, inside)).powi(2);
    let spacing = (std::f64::consts::PI * (forest.radius as f64).powi(2) / 900.0).sqrt();
    let gales = EdgeFactor::new(spacing, h).at(0.0);
    assert!(gales > 1.2 && (load / gales - 1.0).abs() < 0.05, "load ×{load}, ForestGALES ×{gales}");
    // The mean wind alone loads the edge more than that: its gusts are the open ground's,
    // smaller than the canopy's.
    let mean_load = (mean_of(edge, crown, &along) / mean_of(interior, crown, &along)).powi(2);
    assert!(mean_load > load, "mean wind's load ×{mean_load}, peak's ×{load}");
}

#[test]
fn an_edge_tree_sways_further_downwind_than_an_interior_one_of_the_same_size() {
    // The mean trunk-top displacement over 20 s after 4 s, of the edge's least sheltered
    // tenth against the interior's most sheltered tenth, with the canopy wind and without
    // it in the same field (the stand's profile set as the scene's: the same gusts where
    // each tenth stands): the canopy wind raises the edge's share by over a tenth.
    let probe = Forest::new(&stand_scene(true, 300)).expect("forest");
    let mut order: Vec<usize> = (0..probe.trees()).collect();
    order.sort_by(|a, b| by_fetch(&probe, *a, *b));
    let profile = probe.stand().expect("stand").profile();
    let mut ratios = Vec::new();
    for canopy in [true, false] {
        let spec = SceneSpec { wind_profile: Some(profile), ..stand_scene(canopy, 300) };
        let mut forest = Forest::new(&spec).expect("forest");
        let tenth = order.len() / 10;
        let (edge, inner) = (&order[..tenth], &order[order.len() - tenth..]);
        let dt = 1.0 / 30.0;
        let (mut e, mut i) = (0.0f64, 0.0f64);
        for k in 0..720 {
            forest.step(dt);
            if k >= 120 {
                let d = |t: &usize| forest.trunk_top_displacement(*t).expect("tree") as f64;
                e += edge.iter().map(d).sum::<f64>() / tenth as f64;
                i += inner.iter().map(d).sum::<f64>() / tenth as f64;
            }
        }
        ratios.push(e / i);
    }
    let (on, off) = (ratios[0], ratios[1]);
    assert!(on > 1.1 * off, "edge against interior {on}, without the canopy wind {off}");
}

#[test]
fn with_the_canopy_wind_off_or_a_steady_wind_there_is_no_stand() {
    assert!(Forest::new(&stand_scene(false, 50)).expect("forest").stand().is_none());
    let steady = SceneSpec { wind: "6".into(), ..stand_scene(true, 50) };
    let forest = Forest::new(&steady).expect("forest");
    assert!(forest.stand().is_none() && forest.shelter_of(0).is_none());
}

#[test]
fn gusts_at_the_canopy_top_are_the_measured_size_and_below_it_keep_its_intensity() {
    // Deep inside the stand: σ_u at the canopy top is 1.8 U* (Raupach, Finnigan & Brunet
    // 1996) where the field's, at 2h and above, is 2.5 U*: 0.72 of the gusts felt at 2h;
    // below the top the gusts shrink with the mean (a constant turbulence intensity).
    let forest = Forest::new(&stand_scene(true, 900)).expect("forest");
    let h = forest.stand().expect("canopy wind on").height;
    let (_, interior) = edge_and_interior(&forest);
    let moments = |z: f64| {
        let xs: Vec<f64> = (0..512)
            .map(|k| forest.tree_wind(interior, z, 0.1 * k as f64).expect("tree")[0] as f64)
            .collect();
        let mean = xs.iter().sum::<f64>() / 512.0;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 512.0;
        (mean, var.sqrt())
    };
    let (top, above) = (moments(h), moments(2.0 * h));
    let ratio = top.1 / above.1;
    assert!((ratio - 1.8 / 2.5).abs() < 0.01, "σ at h over σ at 2h: {ratio}");
    for f in [0.25, 0.5, 0.8] {
        let (mean, sigma) = moments(f * h);
        let (ti, ti_top) = (sigma / mean, top.1 / top.0);
        assert!((ti / ti_top - 1.0).abs() < 0.01, "intensity at {f} h {ti} against {ti_top} at h");
    }
}
