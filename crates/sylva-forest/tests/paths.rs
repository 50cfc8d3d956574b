//! The camera paths every scene has: the fly-in, a walk at eye height through the forest and
//! a low flight across the canopy, as a user would take them.

use sylva_forest::{Forest, SceneSpec, Terrain, low_flight_path, walk_path};

/// Speed between two keys, m/s, and the change of viewing direction, rad.
fn pace(a: &sylva_forest::CameraKey, b: &sylva_forest::CameraKey) -> (f32, f32) {
    let d: Vec<f32> = (0..2).map(|i| b.eye[i] - a.eye[i]).collect();
    let speed = d.iter().map(|v| v * v).sum::<f32>().sqrt() / (b.t - a.t);
    let look = |k: &sylva_forest::CameraKey| (k.target[1] - k.eye[1]).atan2(k.target[0] - k.eye[0]);
    (speed, (look(b) - look(a)).abs())
}

#[test]
fn the_walk_keeps_eye_height_and_walking_pace_for_a_minute_and_turns() {
    let spec = SceneSpec::builtin("D").expect("D");
    let terrain = Terrain::new(&spec);
    let keys = walk_path(&terrain);
    assert!(keys.last().expect("keys").t >= 60.0, "at least a minute");
    let mut heading: Vec<f32> = Vec::new();
    for w in keys.windows(2) {
        let (speed, _) = pace(&w[0], &w[1]);
        // Walking pace, a leisurely 1.4 m/s (the chord of a turning step is a little less).
        assert!((1.3..=1.41).contains(&speed), "speed {speed} m/s at t = {}", w[1].t);
    }
    for k in &keys {
        let ground = terrain.height(k.eye[0], k.eye[1]);
        assert!(
            (k.eye[2] - ground - 1.7).abs() < 1e-3,
            "eye {} m over the ground",
            k.eye[2] - ground
        );
        heading.push((k.target[1] - k.eye[1]).atan2(k.target[0] - k.eye[0]));
    }
    let (lo, hi) = heading.iter().fold((f32::MAX, f32::MIN), |(a, b), &h| (a.min(h), b.max(h)));
    assert!(hi - lo > 1.5, "the walk turns: its heading spans {} rad", hi - lo);
    // It stays inside scene D's forest (trees within about 1 km of the centre).
    let far = keys.iter().map(|k| k.eye[0].hypot(k.eye[1])).fold(0.0, f32::max);
    assert!(far < 100.0, "{far} m from the centre");
}

#[test]
fn the_low_flight_crosses_the_canopy_at_its_height_and_speed_to_the_far_edge() {
    let spec = SceneSpec::builtin("D").expect("D");
    let terrain = Terrain::new(&spec);
    let (radius, canopy) = (1000.0, 23.0);
    let keys = low_flight_path(&terrain, radius, canopy);
    let (first, last) = (keys[0], keys[keys.len() - 1]);
    assert!(first.eye[0] <= -radius + 1.0, "from the near edge");
    assert!(last.target[0] >= radius - 1.0, "until it looks at the far edge");
    assert!(last.eye[0] >= radius - 200.0, "reaching the far edge: {}", last.eye[0]);
    for w in keys.windows(2) {
        let (speed, _) = pace(&w[0], &w[1]);
        assert!((speed - 15.0).abs() < 0.01, "{speed} m/s");
    }
    for k in &keys {
        let over = k.eye[2] - terrain.height(k.eye[0], k.eye[1]) - canopy;
        assert!((30.0..=60.0).contains(&over), "{over} m over the canopy");
        assert!(k.target[2] < k.eye[2], "it looks down at the canopy ahead");
    }
}

#[test]
fn a_forest_follows_the_path_it_is_set_to_and_refuses_one_it_lacks() {
    let spec = SceneSpec::builtin("small").expect("small");
    let mut forest = Forest::new(&spec).expect("forest");
    let fly_in = forest.camera_at(0.0);
    forest.set_path("walk").expect("walk");
    assert!(forest.path_duration() >= 60.0);
    let walk = forest.camera_at(10.0);
    let ground = forest.terrain.height(walk.eye[0], walk.eye[1]);
    assert!((walk.eye[2] - ground - 1.7).abs() < 0.05, "the camera walks at eye height");
    assert_ne!(walk.eye, fly_in.eye);
    forest.set_path("low-flight").expect("low flight");
    let up = forest.camera_at(1.0);
    let over = up.eye[2] - forest.terrain.height(up.eye[0], up.eye[1]) - forest.canopy_height();
    assert!((30.0..=60.0).contains(&over), "{over} m over the tallest tree");
    let err = forest.set_path("sideways").expect_err("no such path").to_string();
    assert!(err.contains("sideways") && err.contains("walk"), "{err}");
    // A scene file names its own paths and the one to follow; an unknown one is refused.
    let text = "name = \"p\"\ntrees = 3\nspecies = [{ name = \"quaking_aspen\" }]\npath = \"orbit\"\n\
                [[paths.orbit]]\nt = 0.0\neye = [30.0, 0.0, 10.0]\ntarget = [0.0, 0.0, 5.0]\n\
                [[paths.orbit]]\nt = 4.0\neye = [0.0, 30.0, 10.0]\ntarget = [0.0, 0.0, 5.0]\n";
    let own = SceneSpec::from_toml("p.toml", text).expect("a scene with its own path");
    let forest = Forest::new(&own).expect("forest");
    assert_eq!(forest.path_duration(), 4.0);
    assert_eq!(forest.camera_at(0.0).eye, [30.0, 0.0, 10.0]);
    let bad = SceneSpec::from_toml("p.toml", &text.replace("path = \"orbit\"", "path = \"loop\""));
    let msg = bad.expect_err("unknown path").to_string();
    assert!(msg.contains("`path`") && msg.contains("loop"), "{msg}");
    // A key time that is not a number was reported as a bad `camera_path.eye`: the error
    // names the time, the path and the key.
    let nan = SceneSpec::from_toml("p.toml", &text.replace("t = 4.0", "t = nan"));
    let msg = nan.expect_err("NaN time").to_string();
    assert!(msg.contains("`paths.t`") && msg.contains("orbit, key 1"), "{msg}");
}
