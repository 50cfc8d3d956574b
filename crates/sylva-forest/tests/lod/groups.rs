//! Instance groups and draw order: groups by distance, cross-faded regrouping, near trees first.

use super::*;

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
