//! The forest's wind: a field over the whole forest, and where that field is coarser than
//! the trees, a fine tile read near the camera (the wind-field LOD's finest level).

use sylva_forest::{Forest, FrameData, NEAR_REACH, SceneSpec, wind_field, wind_field_over};

#[test]
fn forests_coarser_than_their_trees_get_a_near_tile_at_the_tree_spacing() {
    // Scene D: 50 000 trees 7 m apart under a grid capped at 96 points a side.
    let d = SceneSpec::builtin("D").expect("scene D");
    let wind = wind_field(&d, 0.5 * d.side()).expect("wind");
    let xs = &wind.field.grid.xs;
    assert!(xs[1] - xs[0] > 4.0 * d.spacing as f64, "D's grid is {} m apart", xs[1] - xs[0]);
    let near = wind.near.expect("a near tile for scene D");
    assert_eq!(near.spacing(), d.spacing as f64);
    assert_eq!(near.reach(), NEAR_REACH);
    // Same model, heights and loop as the field it refines; another realisation.
    let (tile, field) = (&near.tile(), &wind.field);
    assert_eq!(tile.params, field.params);
    assert_eq!(
        (&tile.grid.zs, tile.grid.frames, tile.grid.dt),
        (&field.grid.zs, field.grid.frames, field.grid.dt)
    );
    assert_ne!(tile.synth.seed, field.synth.seed);
    // The small scene's grid resolves its five trees: no tile. Nor for a steady wind.
    let small = SceneSpec::builtin("small").expect("small");
    assert!(wind_field(&small, 0.5 * small.side()).expect("wind").near.is_none());
    let steady = SceneSpec { wind: "6".into(), ..d };
    assert!(wind_field(&steady, 0.5 * steady.side()).expect("wind").near.is_none());
}

#[test]
fn trees_near_the_camera_feel_the_near_tile_and_far_ones_the_field() {
    let spec = SceneSpec::builtin("A").expect("scene A");
    let mut forest = Forest::new(&spec).expect("forest");
    let camera = forest.default_camera();
    let mut frame = FrameData::default();
    for _ in 0..3 {
        forest.frame(&camera, 4.0 / 3.0, &mut frame);
        forest.step(0.1);
    }
    forest.frame(&camera, 4.0 / 3.0, &mut frame);
    // The same scene's wind made again: same seed, same bits.
    let wind = wind_field_over(&forest.spec, forest.radius, forest.stand()).expect("wind");
    let near = wind.near.as_ref().expect("scene A's grid is 14 m apart, its trees 7 m");
    let t = forest.time();
    let eye = camera.eye.map(f64::from);
    let at = |d: f64, z: f64| [eye[0] + 0.6 * d, eye[1] + 0.8 * d, z];
    let close = |a: [f32; 3], b: [f64; 3]| (0..3).all(|i| (a[i] as f64 - b[i]).abs() < 1e-4);
    // Within the reach less its fade: the tile alone.
    for d in [0.0, 30.0, 0.7 * NEAR_REACH] {
        let p = at(d, 10.0);
        assert!(close(forest.wind_sample(p), near.sample(p, t)), "{d} m from the camera");
    }
    // Beyond the reach: the field alone.
    for d in [NEAR_REACH + 1.0, 400.0] {
        let p = at(d, 10.0);
        assert!(
            close(forest.wind_sample(p), wind.field.view().sample(p, t)),
            "{d} m from the camera"
        );
    }
    // Some simulated trees were near the camera in the last step, and none are once the
    // camera is far beyond the forest.
    assert!(frame.stats.near_wind > 0 && frame.stats.near_wind <= frame.stats.simulated);
    let mut away = camera;
    for i in 0..2 {
        away.eye[i] += 3.0 * forest.radius + 2.0 * NEAR_REACH as f32;
    }
    forest.frame(&away, 4.0 / 3.0, &mut frame);
    forest.step(0.1);
    forest.frame(&away, 4.0 / 3.0, &mut frame);
    assert_eq!(frame.stats.near_wind, 0);
}
