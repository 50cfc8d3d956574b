//! The painted woodland around a forest: where it is painted, and its crowns standing up.

use super::*;

/// The small scene bare and with a woodland surround; its woodland; a unit direction from
/// the forest's centre in which the ground 2.5 × the woodland's start out is all woodland;
/// and the ground point at a given distance along that direction.
fn woodland_scenes() -> (
    SceneSpec,
    SceneSpec,
    sylva_render::passes::ground::Woodland,
    [f32; 2],
    impl Fn(f32) -> [f32; 3],
) {
    use sylva_forest::Surround;
    use sylva_render::passes::ground::Woodland;
    let open = SceneSpec::builtin("small").expect("small scene");
    let wooded = SceneSpec { surround: Surround::Woodland, ..open.clone() };
    let forest = Forest::new(&open).expect("forest");
    let woodland = Woodland {
        start: Surround::woodland_start(forest.radius, open.spacing),
        ramp: Surround::woodland_ramp(open.spacing),
        spacing: open.spacing,
        shares: vec![1.0],
    };
    let reach = 2.5 * woodland.start;
    let a = (0..64)
        .map(|k| k as f32 / 64.0 * std::f32::consts::TAU)
        .find(|a| woodland.share(reach * a.cos(), reach * a.sin()) > 0.99)
        .expect("woodland in some direction");
    let (c, s) = (a.cos(), a.sin());
    let terrain = forest.terrain;
    let ground = move |r: f32| [r * c, r * s, terrain.height(r * c, r * s)];
    (open, wooded, woodland, [c, s], ground)
}

#[test]
fn woodland_around_the_forest_is_painted_past_its_meadow_and_nowhere_else() {
    let (open, wooded, woodland, _, ground) = woodland_scenes();
    let reach = 2.5 * woodland.start;
    // From high above the forest (over its tallest crowns), looking out along that direction
    // and down at the woodland, the meadow in the lower part of the view.
    let camera = Camera {
        eye: [0.0, 0.0, 45.0],
        target: ground(reach),
        fov_deg: 70.0,
        near: 0.5,
        far: 8000.0,
    };
    let (img_open, ..) = render_spec(&open, Some(camera));
    let (img_wood, ..) = render_spec(&wooded, Some(camera));
    let wood_px = pixel_of(&camera, ground(reach)).expect("woodland point in view");
    let meadow_px =
        pixel_of(&camera, ground(woodland.start - 0.5 * open.spacing)).expect("meadow in view");
    // The canopy is darker than the grass it replaces.
    let (grass, canopy) = (brightness(&img_open, wood_px), brightness(&img_wood, wood_px));
    assert!(canopy < 0.85 * grass, "woodland {canopy:.1} against grass {grass:.1}");
    // The meadow in front of it, and the sky above, are untouched.
    let (m_open, m_wood) = (brightness(&img_open, meadow_px), brightness(&img_wood, meadow_px));
    assert!((m_open - m_wood).abs() < 1.0, "meadow {m_wood:.1} against {m_open:.1}");
    assert!((brightness(&img_open, (W / 2, 3)) - brightness(&img_wood, (W / 2, 3))).abs() < 1.0);
}

#[test]
fn painted_woodland_crowns_stand_up_in_front_of_the_meadow_behind_them() {
    // A canopy is crowns standing up from the ground. Looked at from outside the woodland,
    // low over it, towards the forest, the crowns at the woodland's edge hide part of the
    // meadow behind them (paint flat on the ground would leave every meadow point as it
    // is), while looked at from above the same meadow points show.
    let (open, wooded, woodland, [c, s], ground) = woodland_scenes();
    let spacing = open.spacing;
    let terrain = Forest::new(&open).expect("forest").terrain;
    // Meadow points one to four spacings inside the woodland's start, across a stretch of
    // eight spacings of it.
    let meadow: Vec<[f32; 3]> = (1..=4)
        .flat_map(|k| (-4..=4).map(move |l| (k, l)))
        .map(|(k, l)| {
            let (r, side) = (woodland.start - k as f32 * spacing, l as f32 * spacing);
            let (x, y) = (r * c - side * s, r * s + side * c);
            [x, y, terrain.height(x, y)]
        })
        .collect();
    let target = ground(woodland.start - 2.5 * spacing);
    // Seen from 75° and 12° above the target, 120 m out beyond the woodland's edge.
    let cameras: Vec<Camera> = [75.0f32, 12.0]
        .iter()
        .map(|elevation_deg| {
            let (e, d) = (elevation_deg.to_radians(), 120.0);
            let eye =
                [target[0] + d * e.cos() * c, target[1] + d * e.cos() * s, target[2] + d * e.sin()];
            Camera { eye, target, fov_deg: 50.0, near: 0.5, far: 8000.0 }
        })
        .collect();
    let (bare, wood) = (render_views(&open, &cameras), render_views(&wooded, &cameras));
    // Share of the meadow points whose pixel the woodland changes, seen from camera `i`.
    let hidden = |i: usize| {
        let changed = meadow
            .iter()
            .map(|&p| pixel_of(&cameras[i], p).expect("meadow point in view"))
            .filter(|&px| (brightness(&bare[i], px) - brightness(&wood[i], px)).abs() > 4.0)
            .count();
        changed as f64 / meadow.len() as f64
    };
    let (above, low) = (hidden(0), hidden(1));
    assert!(above < 0.1, "from above, {:.0} % of the meadow points changed", 100.0 * above);
    assert!(low > 0.3, "low over the woodland, {:.0} % of the meadow points hidden", 100.0 * low);
}
