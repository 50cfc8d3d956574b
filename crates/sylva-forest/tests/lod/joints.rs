//! What is simulated and drawn where: near trees among far ones, small trees, shadow casters out of view, impostors leaning.

use super::*;

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
    // The twigs beyond level 2's prefix.
    let bends = |forest: &Forest| twig_bends(forest, &sk, level2);
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

#[test]
fn a_tree_that_comes_into_view_after_ten_seconds_out_of_it_blends_its_crown_in() {
    // One tree in a strong wind, the camera turned away from it for 10 s (it steps its
    // trunk alone; its crown rests on it), then turned to it at 80 % of the image height
    // (every joint simulated again); beside it the same forest with the tree in view all
    // along. The crown's joints blend in from rest: over the first second in view no frame
    // changes a twig's bend by more than twice what the tree seen all along shows in the
    // same second, nor by half of how far its twigs are bent (a snap would be all of it).
    let mut spec = SceneSpec::builtin("small").expect("small");
    spec.trees = 1;
    // The field's wind as sampled, the same at every height: a lone tree under the canopy
    // wind stands in the open ground's gusts, less than half the field's, and the frame-to-
    // frame changes this compares with would shrink with them.
    spec.canopy_wind = Some(false);
    let (mut returning, mut watched) =
        (Forest::new(&spec).expect("forest"), Forest::new(&spec).expect("forest"));
    let (p, si) = {
        let pl = returning.placement(0).expect("tree");
        (pl.position, pl.species as usize)
    };
    let tall = returning.tree_info(0).expect("tree").height;
    let mid = [p[0], p[1], p[2] + 0.5 * tall];
    let d = tall / (2.0 * 30f32.to_radians().tan() * 0.8);
    let toward = Camera {
        eye: [mid[0] - d, mid[1], mid[2]],
        target: mid,
        fov_deg: 60.0,
        near: 0.5,
        far: 1e4,
    };
    let away = Camera { target: [mid[0] - 2.0 * d, mid[1], mid[2]], ..toward };
    let sk = returning.species[si].model.tree.skeleton.clone();
    let (n, trunk) = (sk.len(), returning.species[si].order.trunk);
    // The crown's joints, beyond the trunk.
    let bends = |forest: &Forest| twig_bends(forest, &sk, trunk);
    let dt = 1.0 / 30.0;
    let (mut f, mut g) = (FrameData::default(), FrameData::default());
    for _ in 0..300 {
        returning.step(dt);
        returning.frame(&away, 4.0 / 3.0, &mut f);
        watched.step(dt);
        watched.frame(&toward, 4.0 / 3.0, &mut g);
    }
    assert_eq!((f.stats.drawn, g.stats.drawn), (0, 1), "out of view, and in view");
    let rest = vec![[0.0; 3]; n - trunk];
    let mut last = bends(&returning);
    assert!(farthest(&last, &rest) < 1e-4, "out of view its crown rests on its trunk");
    let snap = farthest(&bends(&watched), &rest);
    let mut last_watched = bends(&watched);
    let (mut entering, mut ordinary) = (0.0f32, 0.0f32);
    for _ in 0..30 {
        for (forest, frame) in [(&mut returning, &mut f), (&mut watched, &mut g)] {
            forest.step(dt);
            forest.frame(&toward, 4.0 / 3.0, frame);
        }
        let (now, now_watched) = (bends(&returning), bends(&watched));
        entering = entering.max(farthest(&last, &now));
        ordinary = ordinary.max(farthest(&last_watched, &now_watched));
        (last, last_watched) = (now, now_watched);
    }
    eprintln!(
        "largest change of a twig's bend in a frame over the first second in view: {entering:.4} m \
         (the tree seen all along: {ordinary:.4} m; its twigs bent up to {snap:.4} m)"
    );
    assert!(
        entering < 2.0 * ordinary,
        "{entering} m in a frame coming into view against {ordinary} m"
    );
    assert!(entering < 0.5 * snap, "{entering} m in a frame coming into view, bent {snap} m");
}

/// Tree 0's joints from `first` on: where each one's tip is, relative to where its
/// parent's motion alone would carry it (its own bend), m.
fn twig_bends(forest: &Forest, sk: &sylva_tree::skeleton::Skeleton, first: usize) -> Vec<[f32; 3]> {
    let joints: Vec<usize> = (0..sk.len()).collect();
    let all = forest.tree_palettes(0, &joints);
    (first..sk.len())
        .map(|j| {
            let tip = sk.joints()[j].tip();
            let parent = sk.joints()[j].parent as usize;
            let (a, b) =
                (sylva_sway::transform(&all[j], tip), sylva_sway::transform(&all[parent], tip));
            [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
        })
        .collect()
}

/// The largest distance between matching points of `a` and `b`, m.
fn farthest(a: &[[f32; 3]], b: &[[f32; 3]]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (0..3).map(|k| (x[k] - y[k]).powi(2)).sum::<f32>().sqrt())
        .fold(0.0f32, f32::max)
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
