//! The canopy wind of a forest: the mean wind each tree feels follows the stand's canopy
//! profile inside the forest and the open ground's at its windward edge; edge trees bear
//! more of the wind than interior ones.

use sylva_forest::canopy::{Stand, open_speed};
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

/// The trees of least and of most fetch.
fn edge_and_interior(forest: &Forest) -> (usize, usize) {
    let fetch = |t: &usize| forest.fetch_of(*t).expect("canopy wind on");
    let by = |a: &usize, b: &usize| fetch(a).total_cmp(&fetch(b));
    let edge = (0..forest.trees()).min_by(by).expect("trees");
    let interior = (0..forest.trees()).max_by(by).expect("trees");
    (edge, interior)
}

#[test]
fn the_mean_wind_a_tree_feels_is_the_canopy_profile_inside_and_the_open_one_at_the_edge() {
    let forest = Forest::new(&stand_scene(true, 900)).expect("forest");
    let stand: Stand = forest.stand().expect("canopy wind on by default");
    let params = sylva_wind::WindParams { profile: stand.profile(), ..Default::default() };
    let (edge, interior) = edge_and_interior(&forest);
    let (se, si) = (forest.shelter_of(edge).unwrap(), forest.shelter_of(interior).unwrap());
    assert!(se < 0.25 && si > 0.95, "shelter at the edge {se}, inside {si}");
    // The field's gusts average out over its loop (512 frames of 0.1 s): the mean of what
    // a tree feels there is its mean wind.
    let mean_along = |t: usize, z: f64| {
        let s: f64 =
            (0..512).map(|k| forest.tree_wind(t, z, 0.1 * k as f64).expect("tree")[0] as f64).sum();
        s / 512.0
    };
    let h = stand.height;
    for f in [0.25, 0.5, 1.0, 2.0] {
        let z = f * h;
        // U* is the preset's: compare as ratios to the canopy top's speed.
        let inside = mean_along(interior, z);
        let want = (1.0 - si as f64) * open_speed(&params, h, z) + si as f64 * params.mean_speed(z);
        let top = mean_along(interior, h);
        let want_top =
            (1.0 - si as f64) * open_speed(&params, h, h) + si as f64 * params.mean_speed(h);
        let (got, model) = (inside / top, want / want_top);
        assert!((got - model).abs() < 0.03 * model, "inside at {f} h: {got} against {model}");
        // Deep inside, the canopy's own profile to 3 %.
        let canopy = params.mean_speed(z) / params.mean_speed(h);
        assert!((got - canopy).abs() < 0.03 * canopy.max(0.3), "{f} h: {got} against {canopy}");
        let at_edge = mean_along(edge, z) / mean_along(edge, 2.0 * h);
        let want = ((1.0 - se as f64) * open_speed(&params, h, z)
            + se as f64 * params.mean_speed(z))
            / params.mean_speed(2.0 * h);
        assert!((at_edge - want).abs() < 0.03 * want, "edge at {f} h: {at_edge} against {want}");
    }
}

#[test]
fn an_edge_tree_sways_further_downwind_than_an_interior_one_of_the_same_size() {
    // The mean trunk-top displacement over 12 s after 4 s, of the edge's least sheltered
    // tenth against the interior's most sheltered tenth: with the canopy wind the edge bears
    // more than twice the interior's, and over twice the ratio without it (one wind at
    // every height and place: what differs is the gusts where each tenth stands).
    let mut ratios = Vec::new();
    for canopy in [true, false] {
        let mut forest = Forest::new(&stand_scene(canopy, 300)).expect("forest");
        let mut order: Vec<usize> = (0..forest.trees()).collect();
        let probe = Forest::new(&stand_scene(true, 300)).expect("forest");
        order.sort_by(|a, b| probe.fetch_of(*a).unwrap().total_cmp(&probe.fetch_of(*b).unwrap()));
        let tenth = order.len() / 10;
        let (edge, inner) = (&order[..tenth], &order[order.len() - tenth..]);
        let dt = 1.0 / 30.0;
        let (mut e, mut i) = (0.0f64, 0.0f64);
        for k in 0..480 {
            forest.step(dt);
            if k >= 120 {
                let d = |t: &usize| forest.trunk_top_displacement(*t).unwrap() as f64;
                e += edge.iter().map(d).sum::<f64>() / tenth as f64;
                i += inner.iter().map(d).sum::<f64>() / tenth as f64;
            }
        }
        ratios.push(e / i);
    }
    let (on, off) = (ratios[0], ratios[1]);
    assert!(
        on > 2.0 && on > 2.0 * off,
        "edge against interior {on}, without the canopy wind {off}"
    );
}

#[test]
fn with_the_canopy_wind_off_or_a_steady_wind_there_is_no_stand() {
    assert!(Forest::new(&stand_scene(false, 50)).expect("forest").stand().is_none());
    let steady = SceneSpec { wind: "6".into(), ..stand_scene(true, 50) };
    let forest = Forest::new(&steady).expect("forest");
    assert!(forest.stand().is_none() && forest.shelter_of(0).is_none());
}
