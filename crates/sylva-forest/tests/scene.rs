//! Layout and frame-driver behaviour.

use sylva_forest::{Forest, FrameData, SceneSpec, Terrain, layout};

#[test]
fn layout_is_deterministic_poisson_spaced_and_follows_the_mix() {
    let spec = SceneSpec::builtin("A").expect("scene A");
    let terrain = Terrain::new(&spec);
    let a = layout(&spec, &terrain);
    assert_eq!(a, layout(&spec, &terrain), "same seed, same layout");
    assert_eq!(a.len(), 1000);
    // No two trunks closer than the Poisson-disk distance.
    for (i, p) in a.iter().enumerate() {
        for q in &a[i + 1..] {
            let d = ((p.position[0] - q.position[0]).powi(2)
                + (p.position[1] - q.position[1]).powi(2))
            .sqrt();
            assert!(d >= spec.spacing * 0.999, "trunks {d} m apart");
        }
        assert!(
            (p.position[2] - terrain.height(p.position[0], p.position[1])).abs() < 1e-6,
            "on the ground"
        );
        assert!((p.scale - 1.0).abs() <= spec.scale_variation + 1e-6);
    }
    // Species shares within a few percent of the weights (3:2:3:1:0.3 of 9.3).
    let share = |s: u32| a.iter().filter(|p| p.species == s).count() as f32 / 1000.0;
    assert!((share(0) - 3.0 / 9.3).abs() < 0.05 && (share(4) - 0.3 / 9.3).abs() < 0.03);
    let mut other = spec.clone();
    other.seed += 1;
    assert_ne!(layout(&other, &Terrain::new(&other)), a, "another seed, another layout");
}

#[test]
fn bad_scene_files_name_the_field() {
    let e = SceneSpec::from_toml(
        "x.toml",
        "name = \"x\"\ntrees = 0\nspecies = [{ name = \"quaking_aspen\" }]\n",
    )
    .expect_err("zero trees");
    assert!(e.to_string().contains("`trees`"), "{e}");
    let e = SceneSpec::from_toml(
        "x.toml",
        "name = \"x\"\ntrees = 3\nspecies = []\nwind = \"hurricane\"\n",
    )
    .expect_err("bad");
    assert!(e.to_string().contains("species") || e.to_string().contains("wind"), "{e}");
    let e = SceneSpec::from_toml(
        "x.toml",
        "name = \"x\"\ntrees = 3\nspecies = [{ name = \"a\" }]\nsprecies = 1\n",
    )
    .expect_err("unknown key");
    assert!(e.to_string().contains("sprecies") && e.to_string().contains("line 4"), "{e}");
}

/// The ground and the spacing at the ends of their ranges still give a forest: every tree
/// placed, on finite ground, the trunks at least the spacing apart. Past the ends the file
/// is refused naming the field: a spacing of 1e30 m squared in f32 is infinite, so no
/// second tree ever fitted and the layout grew its square without end; a wavelength of
/// 1e-38 m made the terrain's wavenumber infinite, its heights NaN, and the wind sampled
/// at NaN read outside its grid.
#[test]
fn the_ground_and_spacing_at_their_limits_lay_out_and_past_them_are_refused() {
    use sylva_forest::scene::{
        MAX_SPACING, MAX_TERRAIN_AMPLITUDE, MAX_TERRAIN_WAVELENGTH, MIN_SPACING,
        MIN_TERRAIN_WAVELENGTH,
    };
    let file = |spacing: f32, amplitude: f32, wavelength: f32| {
        format!(
            "name = \"x\"\ntrees = 40\nspacing = {spacing:e}\nterrain_amplitude = {amplitude:e}\n\
             terrain_wavelength = {wavelength:e}\nspecies = [{{ name = \"quaking_aspen\" }}]\n"
        )
    };
    for (spacing, amplitude, wavelength) in [
        (MAX_SPACING, MAX_TERRAIN_AMPLITUDE, MIN_TERRAIN_WAVELENGTH),
        (MAX_SPACING, MAX_TERRAIN_AMPLITUDE, MAX_TERRAIN_WAVELENGTH),
        (MIN_SPACING, 0.0, MIN_TERRAIN_WAVELENGTH),
    ] {
        let spec = SceneSpec::from_toml("x.toml", &file(spacing, amplitude, wavelength))
            .expect("inside the ranges");
        let trees = layout(&spec, &Terrain::new(&spec));
        assert_eq!(trees.len(), 40, "spacing {spacing}, wavelength {wavelength}");
        for (i, a) in trees.iter().enumerate() {
            assert!(a.position.iter().all(|v| v.is_finite()), "tree {i} at {:?}", a.position);
            assert!(a.position[2].abs() <= amplitude * 1.01 + 1e-3, "tree {i} at {:?}", a.position);
            for b in &trees[..i] {
                let d = (a.position[0] - b.position[0]).hypot(a.position[1] - b.position[1]);
                assert!(d >= spacing * 0.999, "trunks {d} m apart, spacing {spacing}");
            }
        }
    }
    for (spacing, amplitude, wavelength, field) in [
        (1e30, 2.0, 150.0, "`spacing`"),
        (1e-3, 2.0, 150.0, "`spacing`"),
        (MIN_SPACING * 0.99, 2.0, 150.0, "`spacing`"),
        (MAX_SPACING * 1.01, 2.0, 150.0, "`spacing`"),
        (7.0, 1e30, 150.0, "`terrain_amplitude`"),
        (7.0, 2.0, 1e-38, "`terrain_wavelength`"),
        (7.0, 2.0, 1e38, "`terrain_wavelength`"),
    ] {
        let e = SceneSpec::from_toml("x.toml", &file(spacing, amplitude, wavelength))
            .expect_err("past a range");
        assert!(e.to_string().contains(field), "{field}: {e}");
    }
}

#[test]
fn frames_draw_every_visible_tree_once_with_valid_palettes_and_trees_move() {
    let spec = SceneSpec::builtin("small").expect("small");
    let mut forest = Forest::new(&spec).expect("forest");
    let cam = forest.default_camera();
    let mut f = FrameData::default();
    forest.step(1.0 / 30.0);
    forest.frame(&cam, 4.0 / 3.0, &mut f);
    assert_eq!(f.stats.drawn, 5, "the small scene is all in view");
    assert_eq!(f.buckets.iter().map(|b| b.count).sum::<u32>() as usize, f.instances.len());
    // The palette values (12 per joint) every drawn tree uses: the joints of its level.
    let drawn: Vec<Vec<usize>> = forest
        .species
        .iter()
        .map(|s| (0..=s.model.lods.len() as u32).map(|l| s.joints_drawn(l)).collect())
        .collect();
    let used = |f: &FrameData| -> Vec<usize> {
        let mut out = Vec::new();
        for b in &f.buckets {
            let joints = drawn[b.species as usize][b.lod as usize];
            for inst in &f.instances[b.first as usize..(b.first + b.count) as usize] {
                out.extend(
                    (0..joints).flat_map(|j| (0..12).map(move |e| inst.palette.index(j, e))),
                );
            }
        }
        out
    };
    // Each tree's palettes form one kinematic chain: a joint turns about its own origin,
    // which its parent carries, so M_j · o_j = M_parent · o_j. Palettes gathered from the
    // wrong instance or joint break this.
    for b in &f.buckets {
        let sk = &forest.species[b.species as usize].model.tree.skeleton;
        for inst in &f.instances[b.first as usize..(b.first + b.count) as usize] {
            let pal = |j: usize| inst.palette.read(&f.palettes, j).expect("palette in the frame");
            let drawn = forest.species[b.species as usize].joints_drawn(b.lod);
            for (j, joint) in sk.joints().iter().enumerate().take(drawn).skip(1) {
                let a = sylva_sway::transform(&pal(j), joint.origin);
                let p = sylva_sway::transform(&pal(joint.parent as usize), joint.origin);
                let d = (0..3).map(|c| (a[c] - p[c]).abs()).fold(0.0, f32::max);
                assert!(d < 1e-3, "joint {j}: chain broken by {d} m");
            }
        }
    }
    let idx = used(&f);
    assert!(idx.iter().all(|&i| i < f.palettes.len()), "palette index out of range");
    let before: Vec<_> = idx.iter().map(|&i| f.palettes[i]).collect();
    for _ in 0..30 {
        forest.step(1.0 / 30.0);
    }
    forest.frame(&cam, 4.0 / 3.0, &mut f);
    assert_eq!(used(&f), idx, "same trees, same palettes");
    let moved = idx.iter().zip(&before).filter(|(i, b)| f.palettes[**i] != **b).count();
    assert!(
        moved > idx.len() / 2,
        "only {moved} of {} palette values moved in 1 s of wind",
        idx.len()
    );
    assert!(f.palettes.iter().all(|v| v.is_finite()));
}

/// Scene E: a million trees at D's spacing, about 10 km across, on hills with relief, laid
/// out the same for the same seed, its far trees thinned and its near ones levelled by their
/// error; its high flight stays hundreds of metres over the ground and looks across the
/// forest to its far side.
#[test]
fn scene_e_is_a_million_trees_to_the_horizon_with_a_high_flight() {
    let spec = SceneSpec::builtin("E").expect("built-in");
    assert_eq!(spec.trees, 1_000_000);
    assert!(spec.lod.thin_px > 0.0, "its far impostors thinned");
    // Its near trees by screen-space error, over every mesh level (its walk's triangles).
    assert!(spec.lod.error_px > 0.0 && spec.lod.far_level > 1, "{:?}", spec.lod);
    let t = Terrain::new(&spec);
    let a = layout(&spec, &t);
    assert_eq!(a.len(), 1_000_000);
    let radius = a.iter().map(|p| p.position[0].hypot(p.position[1])).fold(0.0, f32::max);
    assert!((4000.0..5500.0).contains(&radius), "forest radius {radius} m");
    let relief = a.iter().map(|p| p.position[2]).fold(f32::MIN, f32::max)
        - a.iter().map(|p| p.position[2]).fold(f32::MAX, f32::min);
    assert!(relief > 40.0, "hills of {relief} m");
    // (Same seed, same layout: `table3_scenes_and_camera_paths_are_deterministic`, whose
    // scenes take the same path through `layout`.)
    let keys = spec.paths.get("high-flight").expect("scene E's high flight");
    for k in keys {
        let over = k.eye[2] - t.height(k.eye[0], k.eye[1]);
        assert!(over > 300.0, "the high flight {over} m over the ground at t = {}", k.t);
        let inside = k.target[0].hypot(k.target[1]) < radius;
        assert!(inside, "at t = {} it looks at {:?}, outside the forest", k.t, k.target);
    }
    let far = keys.iter().map(|k| k.eye[0].hypot(k.eye[1])).fold(0.0, f32::max);
    assert!(far > radius, "it comes in from beyond the edge");
}

#[test]
fn table3_scenes_and_camera_paths_are_deterministic() {
    for (name, trees) in [("A", 1000), ("B", 3000), ("C", 10_000), ("D", 50_000)] {
        let spec = SceneSpec::builtin(name).expect("built-in");
        assert_eq!(spec.trees, trees);
        let t = Terrain::new(&spec);
        let a = layout(&spec, &t);
        assert_eq!(a.len(), trees, "scene {name}");
        assert_eq!(a, layout(&spec, &Terrain::new(&spec)), "scene {name}: same seed, same layout");
    }
    // A keyframed path: through its keys, smooth between them, held at the ends.
    let text = "name = \"p\"\ntrees = 3\nspecies = [{ name = \"quaking_aspen\" }]\n\
        camera_path = [\n\
          { t = 0.0, eye = [-60.0, -60.0, 20.0], target = [0.0, 0.0, 5.0] },\n\
          { t = 4.0, eye = [-30.0, -40.0, 12.0], target = [0.0, 0.0, 5.0] },\n\
          { t = 8.0, eye = [0.0, -30.0, 8.0], target = [0.0, 0.0, 6.0] },\n\
        ]\n";
    let spec = SceneSpec::from_toml("p.toml", text).expect("path scene");
    let forest = sylva_forest::Forest::new(&spec).expect("forest");
    assert_eq!(forest.camera_at(4.0).eye, [-30.0, -40.0, 12.0]);
    assert_eq!(forest.camera_at(-1.0).eye, [-60.0, -60.0, 20.0]);
    assert_eq!(forest.camera_at(99.0).eye, [0.0, -30.0, 8.0]);
    let mut last = forest.camera_at(0.0).eye;
    for k in 1..=800 {
        let e = forest.camera_at(k as f32 * 0.01).eye;
        let step = (0..3).map(|i| (e[i] - last[i]).abs()).fold(0.0, f32::max);
        assert!(step < 0.25, "the camera jumps {step} m at t = {}", k as f32 * 0.01);
        last = e;
    }
    assert_eq!(forest.camera_at(2.5), forest.camera_at(2.5));
    // Keys out of order are refused, naming the field.
    let bad = text.replace("t = 4.0", "t = 9.0");
    let e = SceneSpec::from_toml("p.toml", &bad).expect_err("decreasing times");
    assert!(e.to_string().contains("camera_path.t"), "{e}");
    let e = SceneSpec::from_toml("p.toml", &format!("{text}[lod]\nfar_level = 9\n"))
        .expect_err("far level");
    assert!(e.to_string().contains("lod.far_level"), "{e}");
}

/// The animation-state cap is the scene's to set: the same scene builds under the default
/// cap and is refused, naming the figure and the cap, under a smaller one; a cap outside
/// 1 … 1 000 000 MB is refused naming the field. Without the animation LOD every joint of
/// every simulation is counted; with it, the trunks (what far trees step).
#[test]
fn the_animation_state_cap_is_the_scenes_and_refuses_before_building() {
    let mut spec = SceneSpec::builtin("small").expect("small");
    spec.lod.wind = false; // every tree simulated on its own: 5 trees, a few MB of state
    spec.lod.animation = false;
    assert!(Forest::new(&spec).is_ok());
    spec.max_state_mb = 1;
    let e = Forest::new(&spec).expect_err("over a 1 MB cap");
    let text = e.to_string();
    assert!(text.contains("over the 1 MB cap") && text.contains("max_state_mb"), "{text}");
    // The figure is the whole forest's, every species counted, wherever the cap falls: just
    // under it the refusal names the same figure.
    let Err(sylva_forest::ForestError::TooLarge { bytes, .. }) = Forest::new(&spec) else {
        panic!("refused for its size");
    };
    assert!(spec.species.len() > 1 && bytes > 2_000_000, "{bytes} bytes");
    spec.max_state_mb = bytes / 1_000_000 - 1;
    match Forest::new(&spec) {
        Err(sylva_forest::ForestError::TooLarge { bytes: again, .. }) => assert_eq!(again, bytes),
        other => panic!("refused for its size just under the total: {:?}", other.err()),
    }
    // With the animation LOD the trunks must fit, and they do.
    spec.lod.animation = true;
    spec.max_state_mb = 1;
    assert!(Forest::new(&spec).is_ok(), "the trunks of five trees fit in 1 MB");
    let e = SceneSpec::from_toml(
        "x.toml",
        "name = \"x\"\ntrees = 3\nspecies = [{ name = \"quaking_aspen\" }]\nmax_state_mb = 0\n",
    )
    .expect_err("zero cap");
    assert!(e.to_string().contains("`max_state_mb`"), "{e}");
}

/// Under a cap smaller than every joint's state, the animation LOD keeps lane groups at
/// coarser prefixes instead of going over it: the state held never exceeds the cap, frame
/// after frame, and the frames say how many groups were held back; under the default cap
/// the same frames hold more than that and nothing is held back.
#[test]
fn the_animation_lod_keeps_the_state_under_the_cap() {
    let mut spec = SceneSpec::builtin("small").expect("small");
    spec.lod.wind = false;
    let held = |spec: &SceneSpec| {
        let mut forest = Forest::new(spec).expect("forest");
        let cam = forest.default_camera();
        let mut f = FrameData::default();
        (0..8)
            .map(|_| {
                forest.step(1.0 / 30.0);
                forest.frame(&cam, 4.0 / 3.0, &mut f);
                (f.stats.state_bytes, f.stats.state_capped)
            })
            .collect::<Vec<_>>()
    };
    let free = held(&spec);
    let most = free.iter().map(|h| h.0).max().unwrap_or(0);
    assert!(free.iter().all(|h| h.1 == 0), "nothing held back under 6 GB: {free:?}");
    // Half of what the default camera's trees hold, in whole MB.
    let cap_mb = most / 2_000_000;
    assert!(cap_mb >= 1, "the small scene holds {most} bytes");
    spec.max_state_mb = cap_mb;
    let capped = held(&spec);
    for (k, &(bytes, _)) in capped.iter().enumerate() {
        assert!(bytes <= cap_mb * 1_000_000, "frame {k}: {bytes} bytes over {cap_mb} MB");
    }
    assert!(capped.iter().any(|h| h.1 > 0), "the cap held some group back: {capped:?}");
    // Which groups the cap holds back is decided in a fixed order: the same frames with one
    // thread or two.
    let frames = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
        pool.install(|| {
            let mut forest = Forest::new(&spec).expect("forest");
            let cam = forest.default_camera();
            let mut f = FrameData::default();
            for _ in 0..6 {
                forest.step(1.0 / 30.0);
                forest.frame(&cam, 4.0 / 3.0, &mut f);
            }
            (f.palettes.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), f.stats.state_capped)
        })
    };
    let (one, two) = (frames(1), frames(2));
    assert!(one.1 > 0 && one == two, "capped frames differ between 1 and 2 threads");
    // The animation LOD switched off while running asks for every joint of every tree, more
    // than the cap: the groups stay coarser and the state under the cap.
    let mut forest = Forest::new(&spec).expect("forest");
    let cam = forest.default_camera();
    let mut f = FrameData::default();
    forest.frame(&cam, 4.0 / 3.0, &mut f);
    forest.set_lod(sylva_forest::LodSettings { animation: false, ..forest.lod() });
    for k in 0..4 {
        forest.step(1.0 / 30.0);
        forest.frame(&cam, 4.0 / 3.0, &mut f);
        let bytes = f.stats.state_bytes;
        assert!(bytes <= cap_mb * 1_000_000, "frame {k}: {bytes} bytes over {cap_mb} MB");
        assert!(f.stats.state_capped > 0, "frame {k}: every joint would not fit");
    }
}

/// One wind type for scenes and commands: a preset, a steady speed or a wind file, each
/// reaching the simulation; U* replaces a preset's; bad text names the field.
#[test]
fn scene_wind_is_a_preset_a_steady_speed_or_a_file() {
    use sylva_forest::WindSource;
    assert_eq!(WindSource::parse("storm"), Ok(WindSource::Preset(sylva_wind::Preset::Storm)));
    assert_eq!(WindSource::parse(" 12.5 "), Ok(WindSource::Steady(12.5)));
    assert!(matches!(WindSource::parse("w.zarr"), Ok(WindSource::File(_))));
    assert!(WindSource::parse("-3").expect_err("negative").contains("0 … 100"));
    assert!(WindSource::parse("NaN").is_err() && WindSource::parse("gale").is_err());
    let mean_wind = |spec: &SceneSpec| {
        let mut forest = Forest::new(spec).expect("forest");
        let mut f = FrameData::default();
        forest.step(1.0 / 30.0);
        forest.frame(&forest.default_camera(), 1.5, &mut f);
        f.wind
    };
    // Steady: the given speed, blowing along the scene's direction.
    let mut spec = SceneSpec::builtin("small").expect("small");
    spec.wind = "12".into();
    spec.wind_direction_deg = 90.0;
    let w = mean_wind(&spec);
    assert!(w[0].abs() < 1e-3 && (w[1] - 12.0).abs() < 1e-3 && w[2] == 0.0, "{w:?}");
    // A preset's U* replaced: the mean speed scales with it (log law: Ū ∝ U*).
    let mut calm = SceneSpec::builtin("small").expect("small");
    calm.wind = "breeze".into();
    let base = mean_wind(&calm);
    calm.u_star = Some(3.0);
    let strong = mean_wind(&calm);
    let speed = |w: [f32; 3]| (w[0] * w[0] + w[1] * w[1]).sqrt();
    assert!(speed(strong) > 2.0 * speed(base), "{strong:?} vs {base:?}");
    // A wind file: a steady-looking field written by the wind crate, read back by the scene.
    let dir = sylva_testkit::TempDir::new("sylva-scene-wind");
    let file = dir.join("w.swf");
    let grid = sylva_wind::Grid::regular(8, 8, 4.0, &[10.0, 20.0], 64, 0.1);
    let sp = sylva_wind::SynthParams { seed: 3, method: sylva_wind::Method::Separable };
    let field =
        sylva_wind::WindField::generate(&sylva_wind::Preset::Strong.params(), &grid, sp, &|_| {})
            .expect("field");
    sylva_wind::io::write_swf(&field, &file).expect("write");
    let mut from_file = SceneSpec::builtin("small").expect("small");
    from_file.wind = file.display().to_string();
    let w = mean_wind(&from_file);
    assert!(speed(w) > 5.0, "a strong field read from the file: {w:?}");
    from_file.wind = dir.join("missing.swf").display().to_string();
    let e = Forest::new(&from_file).expect_err("missing file").to_string();
    assert!(e.contains("missing.swf"), "{e}");
    // U* only with a preset, named in the error.
    let e = SceneSpec::from_toml(
        "x.toml",
        "name = \"x\"\ntrees = 3\nspecies = [{ name = \"quaking_aspen\" }]\nwind = \"8\"\nu_star = 1.0\n",
    )
    .expect_err("u_star with a steady wind");
    assert!(e.to_string().contains("`u_star`"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A scene's `[sway]` and `[leaves]` tables reach the simulation: stiffer wood bends less in
/// the same wind, and a zero flutter amplitude stills the leaves; values out of range are
/// refused naming the table and the key.
#[test]
fn scene_sway_and_leaf_tables_reach_the_simulation() {
    // Mean |palette − identity| over the drawn trees' palette values after 2 s of storm,
    // and the largest leaf amplitude.
    let motion = |spec: &SceneSpec| {
        let mut forest = Forest::new(spec).expect("forest");
        let cam = forest.default_camera();
        let mut f = FrameData::default();
        for _ in 0..60 {
            forest.step(1.0 / 30.0);
            forest.frame(&cam, 1.5, &mut f);
        }
        let identity = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let (mut sum, mut n) = (0.0f64, 0usize);
        for inst in &f.instances {
            for e in 0..12 {
                let v = f.palettes[inst.palette.index(0, e)];
                sum += (v - identity[e]).abs() as f64;
                n += 1;
            }
        }
        let leaf = f.instances.iter().map(|i| i.leaf_amplitude).fold(0.0f32, f32::max);
        (sum / n.max(1) as f64, leaf)
    };
    let mut spec = SceneSpec::builtin("small").expect("small");
    spec.wind = "storm".into();
    let (bend, leaf) = motion(&spec);
    spec.sway.youngs_modulus = Some(9e11); // a hundred times stiffer than green wood
    spec.leaves.amp_max = 0.0;
    let (stiff_bend, still_leaf) = motion(&spec);
    assert!(stiff_bend < 0.5 * bend, "stiff {stiff_bend} vs {bend}");
    assert!(leaf > 0.0 && still_leaf == 0.0, "leaf amplitude {leaf} → {still_leaf}");
    for (table, needle) in [
        ("[sway]\ndamping_ratio = 1.5\n", "damping_ratio"),
        ("[leaves]\nf0 = -1\n", "f0"),
        ("[sway]\nstiffness = 3\n", "stiffness"),
    ] {
        let text =
            format!("name = \"x\"\ntrees = 3\nspecies = [{{ name = \"quaking_aspen\" }}]\n{table}");
        let e = SceneSpec::from_toml("x.toml", &text).expect_err(table).to_string();
        assert!(e.contains(needle), "{table}: {e}");
    }
}

#[test]
fn a_click_on_a_crown_picks_its_tree_and_one_beside_the_trunk_below_does_not() {
    let spec = SceneSpec::builtin("small").expect("small");
    let forest = Forest::new(&spec).expect("forest");
    let crowns = forest.crowns();
    for t in 0..forest.trees() {
        let p = forest.placement(t).expect("tree").position;
        let [_, _, r] = crowns[t];
        let h = forest.tree_info(t).expect("tree").height;
        assert!(
            r > 0.2 * h,
            "tree {t}: a crown of {r} m on a {h} m tree is wider than the trunk's reach"
        );
        // Rays along +y from 60 m before the tree, passing its axis halfway between the
        // trunk's reach (a fifth of the height) and the crown's radius.
        let side = 0.5 * (0.2 * h + r);
        let ray = |z: f32| {
            let o = [p[0] + side, p[1] - 60.0, p[2] + z];
            forest.pick(o, [0.0, 1.0, 0.0])
        };
        let hit = ray(0.6 * h).expect("the crown is hit");
        let q = forest.placement(hit).expect("tree").position;
        assert!(hit == t || q[1] < p[1], "tree {t}: picked {hit}, behind it");
        assert_ne!(ray(0.1 * h), Some(t), "tree {t}: beside the bare trunk is not the tree");
    }
}

/// A scene's tree was grown from the scene's seed plus 1 000 per species, so the tree a
/// user picked with `tree stats --seed 1` was not the one the scene grew. A species entry
/// may pin the seed: the scene's tree is then that tree.
#[test]
fn a_species_entry_with_a_pinned_seed_grows_the_tree_of_that_seed() {
    let text = "name = \"one\"\ntrees = 1\nspecies = [{ name = \"quaking_aspen\", seed = 11 }]\n";
    let spec = SceneSpec::from_toml("one.toml", text).expect("scene");
    let forest = Forest::new(&spec).expect("forest");
    let alone = sylva_tree::Species::load("quaking_aspen")
        .expect("preset")
        .model(11, sylva_tree::mesh::LOD_LEVELS)
        .expect("model");
    let grown = &forest.species[0].model.tree;
    assert_eq!(grown.stats, alone.tree.stats);
    assert_eq!(grown.skeleton.len(), alone.tree.skeleton.len());
    // Without the pin the scene grows another tree.
    let unpinned =
        SceneSpec::from_toml("one.toml", &text.replace(", seed = 11", "")).expect("scene");
    let other = Forest::new(&unpinned).expect("forest");
    assert_ne!(other.species[0].model.tree.stats, alone.tree.stats);
}
