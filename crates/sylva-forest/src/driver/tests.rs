//! The driver's own invariants: species without trees, lanes packed by the joints they need.

use super::*;

#[test]
fn a_species_the_layout_gave_no_tree_simulates_nothing() {
    // The small scene's five trees, and a fourth species of so small a share that none
    // of them draws it: every tree is simulated on its own (wind-field LOD off), so each
    // species simulates exactly its own trees, and the one without trees none.
    let mut spec = SceneSpec::builtin("small").expect("small");
    spec.species.push(crate::SpeciesShare {
        name: "black_tupelo".into(),
        weight: 1e-6,
        seed: None,
    });
    for wind in [false, true] {
        spec.lod.wind = wind;
        let mut forest = Forest::new(&spec).expect("forest");
        let mut planted = vec![0; forest.species.len()];
        for (p, _) in &forest.trees {
            planted[p.species as usize] += 1;
        }
        assert_eq!(planted[3], 0, "the fourth species drew no tree");
        assert_eq!(forest.species[3].simulated(), 0, "wind LOD {wind}");
        let simulated: Vec<usize> = forest.species.iter().map(|s| s.simulated()).collect();
        if !wind {
            assert_eq!(simulated, planted, "each tree its own simulation");
        }
        assert!(simulated.iter().zip(&planted).all(|(&s, &p)| s <= p && (s > 0) == (p > 0)));
        // It still steps and builds frames.
        let cam = forest.default_camera();
        let mut f = FrameData::default();
        forest.step(1.0 / 30.0);
        forest.frame(&cam, 4.0 / 3.0, &mut f);
        assert_eq!(f.stats.simulated, simulated.iter().sum::<usize>());
        assert!(f.stats.drawn > 0);
    }
}

#[test]
fn simulations_that_need_the_same_joints_are_stepped_together() {
    // Scene A from its default viewpoint: a few trees at full detail, most impostors.
    let spec = SceneSpec::builtin("A").expect("A");
    let mut forest = Forest::new(&spec).expect("forest");
    let cam = forest.default_camera();
    let mut f = FrameData::default();
    let dt = 1.0 / 30.0;
    // Long enough for the joints switched off to fade out (blend_time, 0.5 s).
    for _ in 0..30 {
        forest.step(dt);
        forest.frame(&cam, 4.0 / 3.0, &mut f);
    }
    forest.step(dt);
    let (mut packed, mut scattered, mut sorted, mut stepped) = (0, 0, 0, 0);
    for s in &forest.species {
        // The step just packed the lanes; `want` is what each lane's simulation asked
        // for (the trunk at least: a lane group steps no less).
        packed += lanes::stepped(&s.want) as usize;
        // Each simulation in the lane of its own number, as if nothing had been moved.
        let own: Vec<u32> = s.lane_of.iter().map(|&l| s.want[l as usize]).collect();
        scattered += lanes::stepped(&own) as usize;
        let mut w = s.want.clone();
        w.sort_unstable_by(|a, b| b.cmp(a));
        sorted += lanes::stepped(&w) as usize;
        stepped += s.batch.joint_updates();
        for (g, &l) in s.lane_of.iter().enumerate() {
            assert_eq!(s.group_of[l as usize] as usize, g, "lanes and groups agree");
        }
    }
    eprintln!(
        "joint updates: packed {packed}, scattered {scattered}, sorted longest first {sorted}"
    );
    assert_eq!(stepped, packed, "the batch steps what the packed lanes want");
    assert!(packed <= sorted, "packed {packed}, sorted {sorted}");
    assert!(packed * 10 < scattered * 9, "packed {packed}, scattered {scattered}");
}

#[test]
fn far_leaves_thin_at_once_exactly_as_tree_by_tree() {
    // Scene C with far impostors thinned under 30 px, along its fly-in: a leaf wholly in
    // view and far decides the trees its thinning surely leaves out at once. The frames
    // draw the same instances in the same order, count the same figures and leave every
    // tree at the same level as a forest that decides tree by tree, bit for bit.
    let mut spec = SceneSpec::builtin("C").expect("C");
    spec.lod.thin_px = 30.0;
    let mut shortcut = Forest::new(&spec).expect("forest");
    let mut tree_by_tree = Forest::new(&spec).expect("forest");
    tree_by_tree.leaf_shortcut = false;
    let (mut a, mut b) = (FrameData::with_rows(768), FrameData::with_rows(768));
    let duration = shortcut.path_duration();
    let mut thinned = 0;
    // Out along the path and back again, so leaves change from tree by tree to at once
    // and back.
    for k in (0..12).chain((0..12).rev()) {
        let camera = shortcut.camera_at(duration * k as f32 / 11.0);
        for forest in [&mut shortcut, &mut tree_by_tree] {
            forest.step(0.1);
        }
        shortcut.frame(&camera, 4.0 / 3.0, &mut a);
        tree_by_tree.frame(&camera, 4.0 / 3.0, &mut b);
        let bytes = |f: &FrameData| bytemuck::cast_slice::<_, u8>(&f.instances).to_vec();
        let (n, m) = (a.instances.len(), b.instances.len());
        assert!(bytes(&a) == bytes(&b), "instances at {k}: {n} against {m} tree by tree");
        assert!(a.palettes == b.palettes, "palettes at {k}");
        assert_eq!(a.buckets, b.buckets, "buckets at {k}");
        let figures = |f: &FrameData| FrameStats { sim_ms: 0.0, thinned_by_leaf: 0, ..f.stats };
        assert_eq!(figures(&a), figures(&b), "figures at {k}");
        assert!((0..shortcut.trees()).all(|t| a.level(t) == b.level(t)), "levels at {k}");
        assert_eq!(b.stats.thinned_by_leaf, 0);
        thinned += a.stats.thinned_by_leaf;
    }
    assert!(thinned > 1000, "leaves thin trees at once: {thinned}");
}
