//! The geometry and animation LODs in the frame driver: level choice, hysteresis and
//! cross-fade weights; what is uploaded and what is stepped; determinism.

use sylva_forest::driver::SIM_MARGIN;
use sylva_forest::{
    Camera, Forest, FrameData, LodSettings, SceneSpec, ShadowBox, blend_levels, hysteresis,
    lod_cap, lod_coordinate, next_lod_state, past_cap_fraction, shadow_level,
};
use sylva_sway::{LANES, STATE_BYTES, SwayBatch};

#[test]
fn level_is_monotone_in_projected_size_with_hysteresis_and_fades_sum_to_one() {
    let h0 = 1.0;
    let sizes: Vec<f32> = (0..400).map(|k| 2.0 * 0.985f32.powi(k)).collect();
    let xs: Vec<f32> = sizes.iter().map(|&h| lod_coordinate(h, h0)).collect();
    assert!(xs.windows(2).all(|w| w[1] >= w[0]), "smaller trees never get finer levels");
    assert_eq!(
        blend_levels(lod_coordinate(1.5 * h0, h0), 6, 0.3).0,
        0,
        "taller than h0: full detail"
    );
    assert_eq!(blend_levels(lod_coordinate(0.5 * h0, h0), 6, 0.0).0, 1);
    assert_eq!(blend_levels(lod_coordinate(0.2 * h0, h0), 6, 0.0).0, 2);
    // A size wavering about a threshold: without hysteresis the level flips every frame,
    // with it the level holds.
    let threshold = h0 / 3.0; // level 1 | level 2
    let wobble: Vec<f32> =
        (0..20).map(|k| threshold * if k % 2 == 0 { 1.03 } else { 0.97 }).collect();
    let levels = |hw: f32| {
        let mut state = f32::NAN;
        wobble
            .iter()
            .map(|&h| {
                state = hysteresis(state, lod_coordinate(h, h0), hw);
                blend_levels(state, 6, 0.0).0
            })
            .collect::<Vec<u32>>()
    };
    let flips = |v: &[u32]| v.windows(2).filter(|w| w[0] != w[1]).count();
    assert!(flips(&levels(0.0)) >= 10);
    assert_eq!(flips(&levels(0.1)), 0);
    // Cross-fade weights: the band's draws keep complementary dither ranges.
    for &x in &[0.5, 0.75, 0.9, 0.99, 1.2, 2.85, 3.7] {
        let (a, b, w) = blend_levels(x, 4, 0.3);
        assert!((0.0..=1.0).contains(&w));
        if a != b {
            assert_eq!(b, a + 1);
            // [0, 1 − w) and [1 − w, 1): lengths sum to one, no overlap.
            let (ra, rb) = ((0.0, 1.0 - w), (1.0 - w, 1.0));
            assert!(((ra.1 - ra.0) + (rb.1 - rb.0) - 1.0f32).abs() < 1e-6 && ra.1 <= rb.0);
        } else {
            assert_eq!(w, 0.0);
        }
    }
    // Continuity: the weight of the next level rises smoothly across the band.
    let mut last = 0.0;
    for k in 0..=100 {
        let x = 1.7 + 0.3 * k as f32 / 100.0 - 1e-4;
        let w = blend_levels(x, 4, 0.3).2;
        assert!(w >= last - 1e-6 && w - last < 0.05, "weight jumps to {w} at {x}");
        last = w;
    }
}

#[test]
fn a_tree_past_its_lod_cap_is_drawn_and_simulated_as_without_the_cap() {
    // A coordinate wandering in and out past the cap, in small steps and jumps: the capped
    // state is the uncapped one's minimum with the cap, bit for bit, so the levels drawn,
    // their fade and the level simulated are the same; past the cap by the hysteresis'
    // width, a tree goes to the cap without its coordinate being computed.
    for far in [1, 2, 4] {
        for hw in [0.0, 0.1, 0.5] {
            let cap = lod_cap(far);
            let (mut free, mut capped) = (f32::NAN, f32::NAN);
            let mut skipped = 0;
            for k in 0..4000 {
                let t = k as f32;
                let jump = if k % 97 == 0 { 2.0 * (0.1 * t).sin() } else { 0.0 };
                let x = ((cap + 1.0) * (1.0 + (0.013 * t).sin()) + 0.3 * (0.731 * t).sin() + jump)
                    .max(0.0);
                free = hysteresis(free, x, hw);
                let mut computed = false;
                let past = x >= cap + hw;
                capped = next_lod_state(
                    capped,
                    || {
                        computed = true;
                        x
                    },
                    past,
                    hw,
                    cap,
                );
                skipped += !computed as usize;
                assert_eq!(capped.to_bits(), free.min(cap).to_bits(), "step {k}");
                assert_eq!(blend_levels(capped, far, 0.3), blend_levels(free, far, 0.3));
                let sim = |s: f32| blend_levels((s - SIM_MARGIN).max(0.0), far, 0.0).0;
                assert_eq!(sim(capped), sim(free), "step {k}: simulated level");
            }
            assert!(skipped > 400, "far {far}, hw {hw}: {skipped} coordinates skipped");
        }
    }
    // Below `past_cap_fraction` (to within rounding of the fraction), the coordinate is
    // past the cap by the hysteresis' width, so any state goes to the cap; and the
    // bound gives away no more than a hundredth of a level.
    for h0 in [0.01, 0.2, 1.0, 7.0, 100.0] {
        for far in 1..=5 {
            for hw in [0.0, 0.1, 0.5] {
                let cap = lod_cap(far);
                let bound = past_cap_fraction(h0, cap, hw);
                for frac in [bound * (1.0 + 1e-5), bound, 0.5 * bound, 1e-3 * bound, 0.0] {
                    let x = lod_coordinate(frac, h0);
                    assert!(x >= cap + hw, "h0 {h0}, far {far}, hw {hw}: {x} at {frac}");
                    for prev in [f32::NAN, 0.0, cap - 0.5 * hw, cap, cap + 9.0] {
                        assert_eq!(hysteresis(prev, x, hw).min(cap), cap);
                    }
                }
                assert!(lod_coordinate(bound * 1.02, h0) < cap + hw);
            }
        }
    }
}

/// Three steps of `forest` seen from [`far_camera`], after a frame before the first step
/// (so that the first step follows the animation LOD: a forest never drawn simulates every
/// joint): the camera and the last frame.
fn far_frames(forest: &mut Forest) -> (Camera, FrameData) {
    let cam = far_camera(forest);
    let mut f = FrameData::default();
    forest.frame(&cam, 4.0 / 3.0, &mut f);
    for _ in 0..3 {
        forest.step(1.0 / 30.0);
        forest.frame(&cam, 4.0 / 3.0, &mut f);
    }
    (cam, f)
}

fn far_camera(forest: &Forest) -> Camera {
    let mut c = forest.default_camera();
    // Far enough that every tree is a few pixels tall: all impostors.
    for i in 0..3 {
        c.eye[i] = c.target[i] + (c.eye[i] - c.target[i]) * 40.0;
    }
    c.far = 1e5;
    c
}

#[test]
fn joints_not_drawn_are_neither_uploaded_nor_stepped() {
    let spec = SceneSpec::builtin("small").expect("small");
    let mut forest = Forest::new(&spec).expect("forest");
    let (cam, mut f) = far_frames(&mut forest);
    assert_eq!(f.stats.impostors, f.stats.drawn, "all trees far away");
    assert!(f.stats.drawn > 0);
    // Uploaded: the trunk joints of each drawn instance, nothing else.
    let trunks: usize = f
        .buckets
        .iter()
        .map(|b| forest.species[b.species as usize].order.trunk * 12 * b.count as usize)
        .sum();
    assert_eq!(f.palettes.len(), trunks, "only the trunks the impostors sway with");
    // Stepped: the trunk joints of every simulated instance.
    let stepped: usize = forest.species.iter().map(|s| s.order.trunk * s.simulated()).sum();
    assert_eq!(f.stats.joints, stepped, "joint updates of the last step");
    // Wind-field LOD: every simulation drives impostors only, so all read the coarse wind.
    assert_eq!(f.stats.coarse_wind, f.stats.simulated);
    let all: usize =
        forest.species.iter().map(|s| s.model.tree.skeleton.len() * s.simulated()).sum();
    assert!(f.stats.joints * 20 < all);
    // Held: the trunks' animation state and nothing else (17 values per joint and lane
    // stored; a lane group stores the joints it simulates).
    let held = |forest: &Forest, joints: fn(&sylva_forest::SpeciesRuntime) -> usize| {
        let lanes = |n: usize| n.div_ceil(LANES) * SwayBatch::width_for(n);
        forest.species.iter().map(|s| joints(s) * lanes(s.simulated()) * STATE_BYTES).sum::<usize>()
    };
    assert_eq!(f.stats.state_bytes, held(&forest, |s| s.order.trunk), "the trunks' state alone");
    // The animation LOD off: every joint stepped and held again.
    forest.set_lod(LodSettings { animation: false, ..forest.lod() });
    forest.step(1.0 / 30.0);
    forest.frame(&cam, 4.0 / 3.0, &mut f);
    assert_eq!(f.stats.joints, all);
    assert_eq!(
        f.stats.state_bytes,
        held(&forest, |s| s.model.tree.skeleton.len()),
        "every joint's"
    );
    assert_eq!(f.stats.state_capped, 0, "under the default cap");
    // The geometry LOD off: full detail, every joint of every drawn tree uploaded.
    forest.set_lod(LodSettings { geometry: false, ..forest.lod() });
    forest.frame(&cam, 4.0 / 3.0, &mut f);
    assert_eq!(f.stats.impostors, 0);
    assert!(f.buckets.iter().all(|b| b.lod == 0));
    let level0: usize = f
        .buckets
        .iter()
        .map(|b| forest.species[b.species as usize].joints_drawn(0) * b.count as usize)
        .sum();
    assert_eq!(f.palettes.len(), 12 * level0);
}

#[test]
fn moving_closer_switches_levels_through_a_cross_fade_and_the_crown_blends_in() {
    // The mesh levels in use (the default goes from the impostor straight to full detail).
    let mut spec = SceneSpec::builtin("small").expect("small");
    spec.lod.fraction = 1.0;
    spec.lod.far_level = 3;
    let mut forest = Forest::new(&spec).expect("forest");
    let near = forest.default_camera();
    let far = far_camera(&forest);
    let mut f = FrameData::default();
    let mut fading = 0;
    let mut levels_seen = std::collections::BTreeSet::new();
    for k in 0..=120 {
        // Fly in from far to near over 4 s.
        let t = k as f32 / 120.0;
        let mut c = far;
        for i in 0..3 {
            c.eye[i] = far.eye[i] + (near.eye[i] - far.eye[i]) * t.powf(0.3);
        }
        forest.step(1.0 / 30.0);
        // The same frame written over a buffer of other values (NaN, and longer than it
        // needs): the palettes are written over the last frame's, and nothing of what the
        // buffer held may show through.
        let mut poisoned = f.clone();
        poisoned.palettes.fill(f32::NAN);
        poisoned.palettes.resize(f.palettes.len() + 4096, f32::NAN);
        forest.frame(&c, 4.0 / 3.0, &mut f);
        forest.frame(&c, 4.0 / 3.0, &mut poisoned);
        let bits = |f: &FrameData| f.palettes.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert!(bits(&poisoned) == bits(&f), "frame {k}: palettes depend on the buffer's past");
        fading += f.stats.fading;
        levels_seen.extend(f.buckets.iter().map(|b| b.lod));
        assert!(f.palettes.iter().all(|v| v.is_finite()));
        // Every instance's palette reads stay inside what was uploaded.
        for b in &f.buckets {
            let joints = forest.species[b.species as usize].joints_drawn(b.lod);
            for i in &f.instances[b.first as usize..(b.first + b.count) as usize] {
                assert!(i.palette.end(joints) <= f.palettes.len());
            }
        }
    }
    // The impostor (bucket level = chain length) and at least two mesh levels on the way in.
    let chain = forest.species[0].model.lods.len() as u32;
    assert!(levels_seen.contains(&chain), "no impostors on the way: {levels_seen:?}");
    assert!(levels_seen.range(..chain).count() >= 2, "levels drawn on the way: {levels_seen:?}");
    assert!(fading > 0, "no tree ever cross-faded");
}

/// Same frames for 1, 2 and 8 threads: the small scene, and one of 9 000 trees whose pass over
/// the trees goes in several runs at once (4 096 trees a run), merged in order: impostors
/// keep tree order within their bucket.
#[test]
fn frames_are_deterministic_for_any_thread_count() {
    let run = |threads: usize, trees: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
        pool.install(|| {
            let mut spec = SceneSpec::builtin("small").expect("small");
            spec.trees = trees;
            let mut forest = Forest::new(&spec).expect("forest");
            let mut cam = forest.default_camera();
            if trees > 5 {
                // From above the forest's edge, most of it in view, near and far.
                cam = far_camera(&forest);
                for i in 0..3 {
                    cam.eye[i] = cam.target[i] + (cam.eye[i] - cam.target[i]) / 12.0;
                }
            }
            let mut f = FrameData::default();
            for _ in 0..(if trees > 5 { 6 } else { 20 }) {
                forest.step(1.0 / 25.0);
                forest.frame(&cam, 1.5, &mut f);
            }
            if trees > 5 {
                // Impostors are drawn in tree order within their bucket, whichever run each
                // tree was visited in.
                let index: std::collections::HashMap<[u32; 3], usize> = (0..trees)
                    .filter_map(|t| forest.placement(t).map(|p| (p.position.map(f32::to_bits), t)))
                    .collect();
                for b in &f.buckets {
                    if b.lod < forest.species[b.species as usize].model.lods.len() as u32 {
                        continue;
                    }
                    let draws = &f.instances[b.first as usize..][..b.count as usize];
                    let order: Vec<usize> =
                        draws.iter().map(|i| index[&i.position.map(f32::to_bits)]).collect();
                    assert!(order.is_sorted(), "impostors out of tree order");
                }
                // Every draw reads its own simulation's palettes through its slot, wherever
                // the copy put its lane group's: the frame's palettes are long enough to be
                // copied in parts, in parallel.
                assert!(f.palettes.len() > 1 << 17, "{} palette values", f.palettes.len());
                for b in &f.buckets {
                    // A tree cast only into the shadow map: the joints of the level it casts.
                    let chain = forest.species[b.species as usize].model.lods.len() as u32;
                    let lod = if b.shadow_only && b.lod < chain {
                        shadow_level(b.lod, chain)
                    } else {
                        b.lod
                    };
                    let drawn = forest.species[b.species as usize].joints_drawn(lod);
                    let joints: Vec<usize> = (0..drawn).collect();
                    let draws = &f.instances[b.first as usize..][..b.count as usize];
                    for inst in draws.iter().step_by(29) {
                        let t = index[&inst.position.map(f32::to_bits)];
                        for (j, want) in forest.tree_palettes(t, &joints).iter().enumerate() {
                            let got = inst.palette.read(&f.palettes, j);
                            assert_eq!(got.as_ref(), Some(want), "tree {t} joint {j}");
                        }
                    }
                }
            }
            let s = &f.stats;
            // Trees seen among the first run's and among the others.
            let seen = |r: std::ops::Range<usize>| r.filter(|&t| f.level(t).is_some()).count();
            let counts = [
                s.drawn,
                s.impostors,
                s.fading,
                s.level_changes,
                s.triangles,
                s.joints,
                seen(0..4096),
                seen(4096..trees),
            ];
            (
                f.palettes.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                f.instances.clone(),
                counts,
            )
        })
    };
    for trees in [5, 9000] {
        let (a, ia, ca) = run(1, trees);
        let (b, ib, cb) = run(2, trees);
        assert!(ia == ib, "{trees} trees: instances differ between 1 and 2 threads");
        assert!(a == b, "{trees} trees: palettes differ between 1 and 2 threads");
        assert_eq!(ca, cb, "{trees} trees");
        // As on a many-core machine: more threads than most species have lane groups.
        let (c, ic, cc) = run(8, trees);
        assert!(ia == ic && a == c, "{trees} trees: frames differ between 1 and 8 threads");
        assert_eq!(ca, cc, "{trees} trees");
        if trees > 5 {
            assert!(ca[6] > 0 && ca[7] > 0, "trees seen in the first run and after: {ca:?}");
            assert!(ca[1] > 0 && ca[1] < ca[0], "near and far trees: {ca:?}");
        }
    }
}

#[test]
fn switching_one_lod_off_changes_only_its_own_figures() {
    let run = |lod: (bool, bool, bool)| {
        let mut spec = SceneSpec::builtin("small").expect("small");
        (spec.lod.geometry, spec.lod.animation, spec.lod.wind) = lod;
        // A budget that makes the three aspens share simulations (instance groups).
        spec.trees = 12;
        spec.sim_joint_budget = 30_000;
        let mut forest = Forest::new(&spec).expect("forest");
        let cam = far_camera(&forest);
        let mut f = FrameData::default();
        for _ in 0..3 {
            forest.step(0.05);
            forest.frame(&cam, 4.0 / 3.0, &mut f);
        }
        f.stats
    };
    let all = run((true, true, true));
    // Animation off: the same drawing, more joints stepped.
    let anim = run((true, false, true));
    assert_eq!(
        (anim.triangles, anim.draw_calls, anim.uploaded_bytes, anim.impostors, anim.simulated),
        (all.triangles, all.draw_calls, all.uploaded_bytes, all.impostors, all.simulated)
    );
    assert!(anim.joints > all.joints);
    // Wind-field LOD off: every tree its own simulation; the same levels drawn.
    let wind = run((true, true, false));
    assert_eq!(
        (wind.triangles, wind.draw_calls, wind.impostors),
        (all.triangles, all.draw_calls, all.impostors)
    );
    assert!(wind.simulated > all.simulated && wind.simulated == 12);
    assert!(
        all.coarse_wind > 0 && wind.coarse_wind == 0,
        "only the wind-field LOD reads coarse wind"
    );
    // Geometry off: full detail drawn (and, as the animation LOD follows what is drawn,
    // every drawn joint stepped).
    let geo = run((false, true, true));
    assert!(geo.triangles > 10 * all.triangles && geo.impostors == 0);
    assert_eq!(geo.simulated, all.simulated);
}

#[test]
fn each_draw_is_tagged_with_its_level_species_and_instance_group() {
    let spec = SceneSpec::builtin("A").expect("scene A");
    let mut forest = Forest::new(&spec).expect("forest");
    let mut frame = FrameData::default();
    forest.frame(&forest.default_camera(), 4.0 / 3.0, &mut frame);
    let mut levels = std::collections::BTreeSet::new();
    for b in &frame.buckets {
        for inst in &frame.instances[b.first as usize..(b.first + b.count) as usize] {
            let level = inst.tag & 15;
            // Impostors sit in the bucket one past the mesh levels and are tagged 15.
            let chain = forest.species[b.species as usize].model.lods.len() as u32;
            assert_eq!(level, if b.lod < chain { b.lod } else { 15 });
            assert_eq!((inst.tag >> 4) & 15, b.species);
            levels.insert(level);
        }
    }
    assert!(levels.len() >= 2, "scene A's default view draws several levels: {levels:?}");
    // Instance groups: many in view, each tag naming one of its species' groups.
    let groups: std::collections::BTreeSet<u32> =
        frame.instances.iter().map(|i| i.tag >> 4).collect();
    assert!(groups.len() > 10, "many (species, group) pairs in view: {}", groups.len());
    let most = (0..forest.trees()).filter_map(|t| forest.tree_info(t)).map(|i| i.group).max();
    assert!(frame.instances.iter().all(|i| Some(i.tag >> 8) <= most));
}

/// Per drawn tree (keyed by trunk position): the dither ranges of its draws.
fn fade_ranges(f: &FrameData) -> std::collections::BTreeMap<[u32; 3], Vec<(f32, f32, u32)>> {
    let mut by_tree = std::collections::BTreeMap::<[u32; 3], Vec<(f32, f32, u32)>>::new();
    for i in &f.instances {
        by_tree.entry(i.position.map(f32::to_bits)).or_default().push((
            i.fade[0],
            i.fade[1],
            i.tag >> 8,
        ));
    }
    by_tree
}

#[test]
fn groups_form_by_distance_and_regrouping_cross_fades_instead_of_jumping() {
    let mut spec = SceneSpec::builtin("small").expect("small");
    // 80 trees, about a dozen simulations per species: groups must be shared.
    spec.trees = 80;
    spec.sim_joint_budget = 150_000;
    let mut forest = Forest::new(&spec).expect("forest");
    let r = forest.radius;
    let corner = |sx: f32, sy: f32| Camera {
        eye: [sx * r, sy * r, 6.0],
        target: [0.0, 0.0, 4.0],
        fov_deg: 60.0,
        near: 0.5,
        far: 1e4,
    };
    let dist = |forest: &Forest, t: usize, c: &Camera| {
        let p = forest.placement(t).expect("tree").position;
        ((p[0] - c.eye[0]).powi(2) + (p[1] - c.eye[1]).powi(2)).sqrt()
    };
    // The tree nearest the camera is simulated alone; the farthest share simulations.
    let check_by_distance = |forest: &Forest, c: &Camera| {
        let mut by: Vec<usize> = (0..forest.trees()).collect();
        by.sort_by(|&a, &b| dist(forest, a, c).total_cmp(&dist(forest, b, c)));
        let size = |t: usize| forest.tree_info(t).expect("tree").group_size;
        assert_eq!(size(by[0]), 1, "the nearest tree has its own simulation");
        let n = by.len();
        let near: usize = by[..n / 4].iter().map(|&t| size(t)).sum();
        let far: usize = by[3 * n / 4..].iter().map(|&t| size(t)).sum();
        assert!(far > 2 * near, "groups grow with distance: {near} near, {far} far");
    };
    let a = corner(-1.0, -1.0);
    let b = corner(1.0, 1.0);
    let mut f = FrameData::default();
    // From the first camera for over a second (the first groups were formed for the
    // scene's own viewpoint; they are formed once more here, then hold still).
    for _ in 0..90 {
        forest.step(1.0 / 30.0);
        forest.frame(&a, 4.0 / 3.0, &mut f);
    }
    assert_eq!(f.stats.regrouping, 0, "a still camera settles: no tree fading between groups");
    check_by_distance(&forest, &a);
    let groups_a: Vec<u32> =
        (0..forest.trees()).map(|t| forest.tree_info(t).expect("tree").group).collect();
    let simulated = f.stats.simulated;
    // Jump to the opposite corner: the next step regroups, and the trees that change group
    // fade from their old simulation to the new one over REGROUP_FADE.
    let mut shares: Vec<f32> = Vec::new();
    let mut watched: Option<[u32; 3]> = None;
    for k in 0..45 {
        forest.step(1.0 / 30.0);
        forest.frame(&b, 4.0 / 3.0, &mut f);
        assert_eq!(f.stats.simulated, simulated, "the budget of simulations holds");
        for (tree, ranges) in fade_ranges(&f) {
            // The draws of one tree tile the dither range [0, 1): no gap, no overlap (a
            // range reaching 1 is written open to 2; an empty one keeps no pixel).
            let mut ranges: Vec<(f32, f32, u32)> = ranges
                .iter()
                .map(|r| (r.0.min(1.0), r.1.min(1.0), r.2))
                .filter(|r| r.1 > r.0)
                .collect();
            ranges.sort_by(|x, y| x.0.total_cmp(&y.0));
            let mut end = 0.0f32;
            for &(lo, hi, _) in &ranges {
                assert!((lo - end).abs() < 1e-6, "tree {tree:?}: draws {ranges:?} leave a gap");
                assert!(hi >= lo);
                end = hi;
            }
            assert!((end - 1.0).abs() < 1e-6, "tree {tree:?}: draws {ranges:?} do not reach 1");
            let groups: std::collections::BTreeSet<u32> = ranges.iter().map(|r| r.2).collect();
            if k == 2 && groups.len() == 2 && watched.is_none() {
                watched = Some(tree);
            }
        }
        if let Some(w) = watched {
            let ranges = &fade_ranges(&f)[&w];
            // The new group's share: the group of the draw that ends the range, [1 − v, 1).
            let last = ranges.iter().max_by(|x, y| x.0.total_cmp(&y.0)).expect("drawn").2;
            let new: f32 = ranges
                .iter()
                .filter(|r| r.2 == last)
                .map(|r| (r.1.min(1.0) - r.0.min(1.0)).max(0.0))
                .sum();
            shares.push(new);
        }
        if k == 1 {
            assert!(f.stats.regrouping > 0, "moving across the forest regroups some trees");
            assert!(f.stats.group_changes > 0);
        } else {
            assert_eq!(f.stats.group_changes, 0, "frame {k}: groups formed once per move");
        }
    }
    assert!(watched.is_some(), "some tree was drawn with two groups");
    assert!(
        shares.windows(2).all(|w| w[1] >= w[0] - 1e-4 && w[1] - w[0] < 0.1),
        "the new group's share rises smoothly: {shares:?}"
    );
    assert!((shares.last().copied().unwrap_or(0.0) - 1.0).abs() < 1e-4, "{shares:?}");
    assert_eq!(f.stats.regrouping, 0, "the fade is over after REGROUP_FADE");
    check_by_distance(&forest, &b);
    let moved =
        (0..forest.trees()).filter(|&t| forest.tree_info(t).expect("tree").group != groups_a[t]);
    assert!(moved.count() < forest.trees(), "groups keep the instance most of their trees had");
    // Without the fade (the comparison popping is measured against) trees switch at once.
    forest.set_regroup_fade(0.0);
    let mut changed = 0;
    for _ in 0..2 {
        forest.step(1.0 / 30.0);
        forest.frame(&a, 4.0 / 3.0, &mut f);
        changed += f.stats.group_changes;
        assert_eq!(f.stats.regrouping, 0, "an instant switch draws no tree twice");
    }
    assert!(changed > 0, "back at the first corner, trees changed group");
}

#[test]
fn draws_go_finest_level_first_and_nearest_tree_first_within_each() {
    // Drawn in this order, the near crowns fill the depth buffer before the trees they
    // hide, whose fragments the depth test then rejects unshaded.
    let spec = SceneSpec::builtin("A").expect("A");
    let mut forest = Forest::new(&spec).expect("forest");
    let mut cam = forest.default_camera();
    let mut f = FrameData::default();
    // Along a walk across the forest, and from every frame's own camera.
    for step in 0..12 {
        cam.eye[0] += 5.0;
        cam.target[0] += 5.0;
        forest.frame(&cam, 4.0 / 3.0, &mut f);
        assert!(f.buckets.len() > 2, "several levels and species");
        // The shadow map's own casters (out of view) come after every tree in view.
        let key = |b: &sylva_forest::Bucket| (b.shadow_only, b.lod, b.species);
        assert!(f.buckets.windows(2).all(|w| key(&w[0]) < key(&w[1])), "(level, species) order");
        let mut meshes = 0;
        for b in &f.buckets {
            let chain = forest.species[b.species as usize].model.lods.len() as u32;
            if b.lod >= chain {
                continue; // impostors: two triangles a tree, in tree order
            }
            let d: Vec<f32> = f.instances[b.first as usize..(b.first + b.count) as usize]
                .iter()
                .map(|i| (0..3).map(|k| (i.position[k] - cam.eye[k]).powi(2)).sum::<f32>())
                .collect();
            assert!(d.windows(2).all(|w| w[0] <= w[1]), "step {step}: nearest first: {d:?}");
            meshes += b.count;
        }
        assert!(meshes > 10, "meshes drawn: {meshes}");
    }
}

#[test]
fn a_near_tree_among_far_ones_sends_its_fine_joints_alone() {
    // Twelve aspens, each simulated on its own: one lane group of twelve lanes (of 16
    // stored); eight: a batch that stores eight lanes.
    for trees in [12, 8] {
        near_tree_among_far_ones(trees);
    }
}

fn near_tree_among_far_ones(count: usize) {
    let text = format!(
        "name = \"mixed\"\ntrees = {count}\nspacing = 25.0\nspecies = [{{ name = \"quaking_aspen\" }}]\n"
    );
    let mut spec = SceneSpec::from_toml("mixed.toml", &text).expect("scene");
    spec.lod.wind = false;
    spec.lod.fraction = 0.6;
    let mut forest = Forest::new(&spec).expect("forest");
    let trees: Vec<_> = (0..).map_while(|t| forest.placement(t)).collect();
    assert_eq!(trees.len(), count);
    // Seen from just outside tree 0, looking across the stand: tree 0 fills the image at
    // full detail, the others stand 25 m and more behind it, impostors.
    let n = trees.len() as f32;
    let centre: Vec<f32> =
        (0..2).map(|k| trees.iter().map(|p| p.position[k]).sum::<f32>() / n).collect();
    let p0 = trees[0].position;
    let (dx, dy) = (p0[0] - centre[0], p0[1] - centre[1]);
    let len = dx.hypot(dy).max(1e-3);
    let mut cam = forest.default_camera();
    cam.eye = [p0[0] + 12.0 * dx / len, p0[1] + 12.0 * dy / len, p0[2] + 5.0];
    cam.target = [centre[0], centre[1], p0[2] + 5.0];
    let mut f = FrameData::default();
    // A frame first (what to simulate), then a second of steps: the far trees' crowns,
    // simulated before any frame, fade out in their lanes (half a second).
    forest.frame(&cam, 4.0 / 3.0, &mut f);
    for _ in 0..30 {
        forest.step(1.0 / 30.0);
        forest.frame(&cam, 4.0 / 3.0, &mut f);
    }
    // Stepped, in the group of 16 lanes: the whole skeleton in the lanes of the trees at
    // full detail (tree 0 and the next nearest) alone, the trunk in the others' — not every
    // lane to tree 0's prefix, `count` whole skeletons. (Eight lanes with three trees at
    // full detail cost less stepped together: `SwayBatch::step`.)
    let all = forest.species[0].joints_drawn(0);
    let stepped = f.stats.joints;
    if count > 8 {
        assert!(stepped < 3 * all, "{stepped} joint updates ({all} a tree)");
    } else {
        assert_eq!(stepped, count * all);
    }
    // Finest level each drawn tree reads, by its instance's trunk position.
    let sp = &forest.species[0];
    let chain = sp.model.lods.len() as u32;
    let mut finest = vec![u32::MAX; trees.len()];
    let mut draws = Vec::new();
    for b in &f.buckets {
        for inst in &f.instances[b.first as usize..(b.first + b.count) as usize] {
            let t = trees.iter().position(|p| p.position == inst.position).expect("a scene tree");
            finest[t] = finest[t].min(b.lod);
            draws.push((t, b.lod, inst.palette));
        }
    }
    assert_eq!(finest[0], 0, "tree 0 at full detail");
    let far = finest.iter().filter(|&&l| l == chain).count();
    assert!(far >= (count - 2) / 2, "only {far} trees drawn as impostors: {finest:?}");
    // Uploaded: full detail's joints for tree 0, the trunk for each impostor — not full
    // detail's for every lane of the group.
    let expected: usize =
        finest.iter().filter(|&&l| l != u32::MAX).map(|&l| 12 * sp.joints_drawn(l)).sum();
    assert_eq!(f.palettes.len(), expected);
    // Every draw reads its own simulation's palettes, joint by joint.
    for (t, lod, slot) in draws {
        let joints: Vec<usize> = (0..sp.joints_drawn(lod)).collect();
        for (j, want) in forest.tree_palettes(t, &joints).iter().enumerate() {
            assert_eq!(slot.read(&f.palettes, j).as_ref(), Some(want), "tree {t} joint {j}");
        }
    }
}

#[test]
fn a_small_tree_at_full_detail_simulates_a_coarser_prefix_and_holds_its_twigs_without_a_jump() {
    // One tree drawn at full detail (the geometry LOD off), seen first at 80 % of the image
    // height (every joint simulated), then at 2.5 %, where its size calls for level 2:
    // level 2's prefix simulated, the rest held on their parents after fading out. (Level
    // 1 keeps every leaf card of level 0 on its own joint, so its prefix holds nearly every
    // joint.)
    let mut spec = SceneSpec::builtin("small").expect("small");
    spec.trees = 1;
    spec.lod.geometry = false;
    let mut forest = Forest::new(&spec).expect("forest");
    let (p, si) = {
        let pl = forest.placement(0).expect("tree");
        (pl.position, pl.species as usize)
    };
    let tall = forest.tree_info(0).expect("tree").height;
    let cam = |h: f32| {
        let d = tall / (2.0 * 30f32.to_radians().tan() * h);
        let mid = [p[0], p[1], p[2] + 0.5 * tall];
        Camera {
            eye: [mid[0] - d, mid[1], mid[2]],
            target: mid,
            fov_deg: 60.0,
            near: 0.5,
            far: 1e4,
        }
    };
    let sp = &forest.species[si];
    let (n, level2) = (sp.model.tree.skeleton.len(), sp.order.prefix[2]);
    // The other species (no tree here) step their trunks.
    let others: usize = (forest.species.iter().enumerate())
        .filter(|&(k, _)| k != si)
        .map(|(_, s)| s.order.trunk * s.simulated())
        .sum();
    let joints: Vec<usize> = (0..n).collect();
    let sk = forest.species[si].model.tree.skeleton.clone();
    let parent_of = |j: usize| sk.joints()[j].parent as usize;
    // Where each twig beyond level 2's prefix has its tip, relative to where its parent's
    // motion alone would carry it (its own bend).
    let bends = |forest: &Forest| -> Vec<[f32; 3]> {
        let all = forest.tree_palettes(0, &joints);
        (level2..n)
            .map(|j| {
                let tip = sk.joints()[j].tip();
                let (a, b) = (
                    sylva_sway::transform(&all[j], tip),
                    sylva_sway::transform(&all[parent_of(j)], tip),
                );
                [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
            })
            .collect()
    };
    let farthest = |a: &[[f32; 3]], b: &[[f32; 3]]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (0..3).map(|k| (x[k] - y[k]).powi(2)).sum::<f32>().sqrt())
            .fold(0.0f32, f32::max)
    };
    let dt = 1.0 / 30.0;
    let mut f = FrameData::default();
    let mut last = bends(&forest);
    let mut ordinary = 0.0f32;
    for k in 0..60 {
        forest.step(dt);
        forest.frame(&cam(0.8), 4.0 / 3.0, &mut f);
        let now = bends(&forest);
        if k >= 30 {
            ordinary = ordinary.max(farthest(&last, &now));
        }
        last = now;
    }
    assert_eq!(
        f.stats.joints - others,
        n,
        "a tree at 80 % of the image height simulates every joint"
    );
    // How far the held twigs would jump if they went to rest at once: their bend now.
    let snap = farthest(&bends(&forest), &vec![[0.0; 3]; n - level2]);
    let mut switch = 0.0f32;
    for _ in 0..30 {
        forest.step(dt);
        forest.frame(&cam(0.025), 4.0 / 3.0, &mut f);
        assert!(f.buckets.iter().all(|b| b.lod == 0), "still drawn at full detail");
        let now = bends(&forest);
        switch = switch.max(farthest(&last, &now));
        last = now;
    }
    eprintln!(
        "largest change of a twig's bend in a frame: {ordinary:.4} m in ordinary frames, \
         {switch:.4} m across the switch; the held twigs were bent up to {snap:.4} m"
    );
    assert_eq!(f.stats.joints - others, level2, "at 2.5 % only level 2's prefix is simulated");
    assert!(switch < 0.5 * snap, "held twigs jumped: {switch} m in a frame, bent {snap} m");
    assert!(switch < 2.0 * ordinary, "{switch} m in a frame against {ordinary} m");
    // Uploaded as shown: every drawn joint's palette, the held ones their ancestors'.
    let inst = f.instances[0];
    let pal = forest.tree_palettes(0, &joints);
    for j in 0..n {
        assert_eq!(inst.palette.read(&f.palettes, j), Some(pal[j]), "joint {j}");
        if j >= level2 {
            assert_eq!(pal[j], pal[parent_of(j)], "held joint {j} rests on its parent");
        }
    }
}

/// One aspen on flat ground, lit by a sun in direction `sun` (with or without shadows),
/// and a camera that `place` puts from the tree's foot and height. Returns the forest,
/// the camera and its frame.
fn lone_tree(
    sun: [f32; 3],
    shadows: bool,
    place: impl Fn([f32; 3], f32) -> Camera,
) -> (Forest, Camera, FrameData) {
    let text = format!(
        r#"
        name = "beside"
        seed = 5
        trees = 1
        terrain_amplitude = 0.0
        wind = "calm"
        species = [ {{ name = "quaking_aspen" }} ]
        [lighting]
        sun_direction = [{}, {}, {}]
        shadows = {shadows}
        "#,
        sun[0], sun[1], sun[2]
    );
    let spec = SceneSpec::from_toml("beside.toml", &text).expect("scene");
    let mut forest = Forest::new(&spec).expect("forest");
    let foot = forest.crowns()[0];
    let h = forest.tree_info(0).expect("tree").height;
    let camera = place(foot, h);
    forest.step(1.0 / 30.0);
    let mut f = FrameData::default();
    forest.frame(&camera, 4.0 / 3.0, &mut f);
    (forest, camera, f)
}

/// [`lone_tree`] with a camera looking straight down at the ground beside the tree: the
/// tree is out of view, the shadow of its crown in it when the sun stands 20° up on the
/// far side of the tree.
fn lone_tree_beside_the_view(sun: [f32; 3], shadows: bool) -> FrameData {
    // 2.2 heights along +x from the trunk, 1.2 heights up: the crown's sphere lies 53° off
    // the view axis, the image's corners 31°.
    let (_, _, f) = lone_tree(sun, shadows, |[x, y, _], h| Camera {
        eye: [x + 2.2 * h, y, 1.2 * h],
        target: [x + 2.2 * h, y + 0.01, 0.0],
        fov_deg: 40.0,
        near: 0.5,
        far: 2000.0,
    });
    f
}

#[test]
fn a_tree_out_of_view_whose_shadow_falls_in_it_is_drawn_into_the_shadow_map_only() {
    // The sun 20° up towards −x: shadows fall towards +x, 2.7 times as long as what casts
    // them is high, so the crown's shadow lies 0.8 to 2.5 heights from the trunk, across
    // the view.
    let (e, z) = (20f32.to_radians().cos(), 20f32.to_radians().sin());
    let f = lone_tree_beside_the_view([-e, 0.0, z], true);
    assert_eq!(f.stats.drawn, 0, "the tree itself is out of view");
    assert_eq!(f.stats.shadow_only, 1, "its shadow falls in view");
    assert!(!f.instances.is_empty() && f.buckets.iter().all(|b| b.shadow_only));
    assert_eq!((f.stats.triangles, f.stats.draw_calls), (0, 0), "nothing drawn in the image");
    assert!(!f.palettes.is_empty(), "the shadow bends with the trunk: its palettes are sent");
    // The sun on the near side (shadows falling away from the view), or no shadows at all:
    // the tree is culled as before.
    for (sun, shadows) in [([e, 0.0, z], true), ([-e, 0.0, z], false)] {
        let f = lone_tree_beside_the_view(sun, shadows);
        assert_eq!((f.stats.drawn, f.stats.shadow_only), (0, 0), "sun {sun:?}, {shadows}");
        assert!(f.instances.is_empty() && f.buckets.is_empty());
    }
}

/// Nothing outside the shadow map's far cascade takes a shadow, so a tree out of view
/// whose shadow falls in view only there is not drawn into the map either. A camera 2 m up
/// looking along the ground towards a point 20 m ahead: the far cascade covers the first
/// 160 m of the view. The aspen stands 800 m ahead and 510 m to the left, just outside the
/// image's corners; with the sun 20° up on its left, its crown's shadow reaches into the
/// view, 800 m out, far beyond the cascade.
#[test]
fn a_tree_whose_shadow_falls_in_view_beyond_the_shadow_map_is_not_drawn_into_it() {
    let (e, z) = (20f32.to_radians().cos(), 20f32.to_radians().sin());
    let sun = [-e, 0.0, z];
    // The camera with the tree `ahead` m ahead and `left` m to the left.
    let along_the_ground = |ahead: f32, left: f32| {
        move |[x, y, _]: [f32; 3], _| Camera {
            eye: [x + left, y - ahead, 2.0],
            target: [x + left, y - ahead + 20.0, 1.0],
            fov_deg: 40.0,
            near: 0.5,
            far: 2000.0,
        }
    };
    let (forest, camera, f) = lone_tree(sun, true, along_the_ground(800.0, 510.0));
    // What the frame is tested against holds: the crown is out of view, its shadow in it,
    // and it casts outside the far cascade.
    let [x, y, ground] = forest.crowns()[0];
    let h = forest.tree_info(0).expect("tree").height;
    let (c, r) = ([x, y, ground + 0.5 * h], 0.75 * h);
    let cone = camera.cone(4.0 / 3.0);
    let sweep = 1.5 * h / z;
    assert!(!cone.may_see(c, r), "the crown is out of view");
    assert!(cone.may_see_shadow(c, r, [e, 0.0, -z], sweep), "its shadow falls in view");
    let far = ShadowBox::new(&camera, 4.0 / 3.0, camera.shadow_reach().1, sun);
    assert!(!far.may_take(c, r, sweep, 0.0), "it casts outside the far cascade");
    assert_eq!((f.stats.drawn, f.stats.shadow_only), (0, 0));
    assert!(f.instances.is_empty() && f.buckets.is_empty());
    // Nearer, 100 m ahead and 80 m to the left (still out of view), its shadow falls
    // within the cascade, and it is drawn into the map.
    let (_, _, f) = lone_tree(sun, true, along_the_ground(100.0, 80.0));
    assert_eq!((f.stats.drawn, f.stats.shadow_only), (0, 1));
}

/// An instance's crown lean, decoded (tree space, m).
fn lean_of(i: &sylva_forest::Instance) -> [f32; 2] {
    i.lean.map(|b| half::f16::from_bits(b).to_f32())
}

#[test]
fn impostors_lean_downwind_and_turn_their_leaves_with_their_limbs_not_in_still_air() {
    for speed in ["10", "0"] {
        let spec = SceneSpec {
            wind: speed.into(),
            wind_direction_deg: 30.0,
            ..SceneSpec::builtin("small").expect("small")
        };
        let mut forest = Forest::new(&spec).expect("forest");
        let (_, f) = far_frames(&mut forest);
        assert!(f.stats.impostors > 0 && f.stats.impostors == f.stats.drawn);
        let mut by_group = std::collections::BTreeMap::new();
        for inst in &f.instances {
            let l = lean_of(inst);
            // Instances sharing a simulation share its lean, as they share its palettes.
            let key = (inst.tag >> 4 & 15, inst.tag >> 8);
            assert_eq!(*by_group.entry(key).or_insert(l), l, "group {key:?}");
            let size = l[0].hypot(l[1]);
            let t = inst.tilt.map(|b| half::f16::from_bits(b).to_f32());
            if speed == "0" {
                assert_eq!(size, 0.0, "a lean in still air");
                assert_eq!(t, [0.0; 2], "leaves turned in still air");
                continue;
            }
            // The leaves turned from the sky: the mean cosine of their tilt below one
            // (`Instance::tilt` holds one minus it), and at most a right angle.
            assert!(t[1] > 0.005 && t[1] < 1.0, "leaves' tilt {t:?} in 10 m/s");
            // In world space, downwind: the tree-space lean turned by the instance's yaw,
            // against the wind at its crown.
            let (s, c) = inst.yaw.sin_cos();
            let world = [c * l[0] - s * l[1], s * l[0] + c * l[1]];
            let p = inst.position;
            let w = forest.wind_sample([p[0] as f64, p[1] as f64, p[2] as f64 + 10.0]);
            let along = (world[0] * w[0] + world[1] * w[1]) / w[0].hypot(w[1]);
            assert!(size > 0.01, "a crown in 10 m/s leans {size} m");
            assert!(along > 0.95 * size, "lean {world:?} against the wind {w:?}");
        }
    }
}
