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
