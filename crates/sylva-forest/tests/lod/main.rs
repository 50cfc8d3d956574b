//! The geometry and animation LODs in the frame driver: level choice, hysteresis and
//! cross-fade weights; what is uploaded and what is stepped; determinism.

use sylva_forest::driver::SIM_MARGIN;
use sylva_forest::driver::{
    blend_levels, hysteresis, lod_cap, lod_coordinate, next_lod_state, past_cap_fraction,
    shadow_level,
};
use sylva_forest::{Camera, Forest, FrameData, LodSettings, SceneSpec, ShadowBox};
use sylva_sway::{LANES, STATE_BYTES, SwayBatch};

mod cells;
mod error;
mod groups;
mod joints;
mod thinning;

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
            // The large forest with occlusion culling on: its occluders go in by depth,
            // whichever run found them.
            spec.lod.occlusion = trees > 5;
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
                s.occluded,
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
            assert!(ca[8] > 0, "trees hidden by nearer ones: {ca:?}");
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
