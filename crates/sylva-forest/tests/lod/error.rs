//! Levels by screen-space error: each level's error comes from its geometry, shrinks in
//! pixels with distance, and the level drawn is the coarsest within the budget, held by
//! the hysteresis about each threshold.

use sylva_forest::driver::{blend_levels, error_coordinate, hysteresis, level_thresholds};
use sylva_forest::{Camera, Forest, FrameData, LodSettings, SceneSpec};

/// A species' level errors as shares of its height, from its geometry.
fn errors(name: &str) -> Vec<f32> {
    let mut spec = SceneSpec::builtin("small").expect("small");
    spec.species.retain(|s| s.name == name);
    spec.trees = 1;
    let forest = Forest::new(&spec).expect("forest");
    forest.species[0].level_error.clone()
}

#[test]
fn a_levels_error_in_pixels_falls_with_distance_and_the_coarsest_level_within_budget_is_drawn() {
    let (rows, budget) = (768u32, 2.0f32);
    let e = errors("quaking_aspen");
    // Level 0 is full detail itself; every coarser level departs from it, more or equally.
    assert_eq!(e[0], 0.0);
    assert!(e.windows(2).all(|w| w[1] >= w[0]) && e[1] > 0.0, "{e:?}");
    let mut f = Vec::new();
    level_thresholds(&e, rows, budget, &mut f);
    // A 12 m tree seen from 2 m to 3 km: its image fraction, the pixels each level's error
    // spans there (falling as 1 / distance), and the level chosen.
    let inv_height = 1.0 / (2.0 * 25f32.to_radians().tan());
    let mut last = 0.0f32;
    for k in 0..600 {
        let d = 2.0 * 1.0125f32.powi(k);
        let frac = 12.0 * inv_height / d;
        let px: Vec<f32> = e.iter().map(|&ek| frac * rows as f32 * ek).collect();
        let x = error_coordinate(frac, &f);
        assert!(x >= last, "at {d} m the level coordinate went back: {x} < {last}");
        last = x;
        let level = blend_levels(x, e.len() as u32 - 1, 0.0).0 as usize;
        assert!(px[level] <= budget * 1.0001, "at {d} m level {level} shows {} px", px[level]);
        // The next coarser level (if any) is over the budget: the coarsest within it.
        if level + 1 < e.len() {
            assert!(px[level + 1] > budget * 0.9999, "at {d} m level {} fits too", level + 1);
        }
    }
    assert!(last >= (e.len() - 1) as f32, "the coarsest mesh far away: {last}");
    // About a threshold, a tree wavering 3 % in size keeps its level with the hysteresis.
    let t = f[1];
    let mut state = f32::NAN;
    let levels: Vec<u32> = (0..20)
        .map(|k| {
            let frac = t * if k % 2 == 0 { 1.03 } else { 0.97 };
            state = hysteresis(state, error_coordinate(frac, &f), 0.1);
            blend_levels(state, e.len() as u32 - 1, 0.0).0
        })
        .collect();
    assert!(levels.windows(2).all(|w| w[0] == w[1]), "{levels:?}");
}

#[test]
fn a_larger_budget_draws_coarser_levels_and_fewer_triangles() {
    // Walking into scene A: trees from a few metres away to the impostors.
    let mut spec = SceneSpec::builtin("A").expect("A");
    spec.path = sylva_forest::WALK.into();
    let mut forest = Forest::new(&spec).expect("forest");
    let camera = forest.camera_at(5.0);
    let tris = |forest: &mut Forest, budget: f32| {
        forest.set_lod(LodSettings { error_budget: budget, far_level: 3, ..forest.lod() });
        let mut frame = FrameData::with_rows(768);
        forest.frame(&camera, 4.0 / 3.0, &mut frame);
        frame.stats.triangles
    };
    let (fine, coarse) = (tris(&mut forest, 0.5), tris(&mut forest, 8.0));
    assert!(coarse < fine, "{coarse} ≥ {fine}");
    // The image's size counts: the same budget on a smaller image is coarser.
    forest.set_lod(LodSettings { error_budget: 0.25, far_level: 3, ..forest.lod() });
    let mut big = FrameData::with_rows(1536);
    let mut small = FrameData::with_rows(384);
    forest.frame(&camera, 4.0 / 3.0, &mut big);
    forest.frame(&camera, 4.0 / 3.0, &mut small);
    assert!(small.stats.triangles < big.stats.triangles);
}

#[test]
fn the_leaf_area_drawn_holds_within_two_percent_from_full_detail_to_the_impostor() {
    // One aspen seen from 1 to 40 heights away, its levels by error with every mesh level
    // before the impostor: whatever level, or pair of levels cross-fading, the tree is
    // drawn at, its cards show the crown's whole leaf area (coarser levels thin the cards
    // and grow the ones kept).
    let mut spec = SceneSpec::builtin("small").expect("small");
    spec.species.retain(|s| s.name == "quaking_aspen");
    spec.trees = 1;
    let mut forest = Forest::new(&spec).expect("forest");
    let levels = forest.species[0].model.lods.len() as u32;
    forest.set_lod(LodSettings {
        error_budget: 1.0,
        far_level: levels,
        fraction: 0.01,
        ..forest.lod()
    });
    let p = forest.placement(0).expect("tree").position;
    let tall = forest.tree_info(0).expect("tree").height;
    let mut frame = FrameData::with_rows(768);
    let (mut seen, mut blended, mut compared) = (vec![false; levels as usize], 0, 0);
    for k in 0..400 {
        let d = tall * 1.0095f32.powi(k);
        let mid = [p[0], p[1], p[2] + 0.5 * tall];
        let camera = Camera {
            eye: [mid[0] - d, mid[1], mid[2]],
            target: mid,
            fov_deg: 60.0,
            near: 0.5,
            far: 1e4,
        };
        forest.frame(&camera, 4.0 / 3.0, &mut frame);
        let (mut area, mut full, mut weight, mut impostor, mut drawn) =
            (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0);
        for b in frame.buckets.iter().filter(|b| !b.shadow_only) {
            let lods = &forest.species[b.species as usize].model.lods;
            for i in &frame.instances[b.first as usize..(b.first + b.count) as usize] {
                let w = (i.fade[1].min(1.0) - i.fade[0].max(0.0)).max(0.0) as f64;
                if i.tag & 0xF == 15 {
                    impostor += w;
                    continue;
                }
                let s2 = (i.scale * i.scale) as f64;
                area += w * lods[b.lod as usize].leaf_area() as f64 * s2;
                full += w * lods[0].leaf_area() as f64 * s2;
                weight += w;
                seen[b.lod as usize] = true;
                drawn += usize::from(w > 0.0);
            }
        }
        if impostor > 0.0 {
            break;
        }
        assert!((weight - 1.0).abs() < 1e-4, "at {d} m the tree is drawn with weight {weight}");
        assert!((area / full - 1.0).abs() <= 0.02, "at {d} m {area} of {full} m² of leaves drawn");
        blended += usize::from(drawn > 1);
        compared += 1;
    }
    assert!(seen.iter().filter(|&&s| s).count() >= 4, "levels drawn: {seen:?}");
    assert!(blended > 0 && compared > 100, "{compared} distances, {blended} cross-fading");
}
