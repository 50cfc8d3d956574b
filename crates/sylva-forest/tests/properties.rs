//! Property: any scene with every field inside its documented range builds a forest (or is
//! refused with the documented animation-state cap), and its frames are well formed: every
//! drawn instance lies in a bucket, every palette value a drawn tree reads is finite, no
//! more trees are drawn than exist, and the animation state held stays under the cap
//! (drawn between 1 MB and 1 GB). The scene goes through its TOML text, as a user's
//! file would.
//!
//! proptest draws the scenes from a fixed seed and shrinks a failure. Scenes stay small (up
//! to 300 trees) to keep each case short; the layout of large scenes is covered by the
//! built-in A–D tests. `PROPTEST_CASES` sets the number of cases (default 6).

use proptest::prelude::*;
use sylva_forest::{Forest, ForestError, FrameData, SceneSpec};
use sylva_testkit::runner;

fn scene() -> impl Strategy<Value = SceneSpec> {
    let species = proptest::sample::subsequence(
        sylva_tree::PRESETS.iter().map(|(name, _)| name.to_string()).collect::<Vec<_>>(),
        1..=3,
    );
    (
        (0..=i64::MAX as u64, 1usize..=300, (0.0f32..=1.7).prop_map(|e| 10f32.powf(e))),
        (species, proptest::collection::vec(0.05f32..=10.0, 3)),
        (0.0f32..=0.9, 0.0f32..=30.0, (0.5f32..=3.5).prop_map(|e| 10f32.powf(e))),
        (0usize..4, -720.0f32..=720.0, (0.0f32..=6.3).prop_map(|e| 10f32.powf(e) as usize + 1)),
        (any::<[bool; 3]>(), (-1.0f32..=2.0).prop_map(|e| 10f32.powf(e)), 1u32..=6),
        (0.0f32..=3.0).prop_map(|e| 10f32.powf(e) as usize),
    )
        .prop_map(|(basic, mix, ground, wind, lod, cap_mb)| {
            let mut s = SceneSpec::builtin("small").expect("small scene");
            (s.seed, s.trees, s.spacing) = basic;
            s.species = mix
                .0
                .into_iter()
                .zip(mix.1)
                .map(|(name, weight)| sylva_forest::scene::SpeciesShare {
                    name,
                    weight,
                    seed: None,
                })
                .collect();
            (s.scale_variation, s.terrain_amplitude, s.terrain_wavelength) = ground;
            s.wind = ["calm", "breeze", "strong", "storm"][wind.0].to_string();
            (s.wind_direction_deg, s.sim_joint_budget) = (wind.1, wind.2);
            [s.lod.geometry, s.lod.animation, s.lod.wind] = lod.0;
            (s.lod.fraction, s.lod.far_level) = (lod.1, lod.2);
            s.max_state_mb = cap_mb;
            s.camera = None;
            s.camera_path.clear();
            s
        })
}

#[test]
fn any_scene_inside_the_ranges_builds_and_draws_well_formed_frames() {
    let mut runner = runner(6, 0x5eed_0003);
    let outcome = runner.run(&scene(), |drawn| {
        let text = toml::to_string(&drawn).map_err(|e| TestCaseError::fail(e.to_string()))?;
        let spec = SceneSpec::from_toml("drawn.toml", &text)
            .map_err(|e| TestCaseError::fail(format!("drawn inside the ranges, refused: {e}")))?;
        let mut forest = match Forest::new(&spec) {
            Ok(f) => f,
            Err(ForestError::TooLarge { .. }) => return Ok(()),
            Err(e) => return Err(TestCaseError::fail(format!("did not build: {e}"))),
        };
        let camera = forest.default_camera();
        let mut frame = FrameData::default();
        for _ in 0..3 {
            forest.step(1.0 / 30.0);
            forest.frame(&camera, 16.0 / 9.0, &mut frame);
        }
        prop_assert!(frame.stats.drawn <= spec.trees);
        // The animation state never goes past the cap, however small.
        prop_assert!(
            frame.stats.state_bytes <= spec.max_state_mb * 1_000_000,
            "{} bytes of state over {} MB",
            frame.stats.state_bytes,
            spec.max_state_mb
        );
        prop_assert_eq!(
            frame.buckets.iter().map(|b| b.count as usize).sum::<usize>(),
            frame.instances.len()
        );
        for b in &frame.buckets {
            let joints = forest.species[b.species as usize].joints_drawn(b.lod);
            for inst in &frame.instances[b.first as usize..(b.first + b.count) as usize] {
                for at in (0..joints).flat_map(|j| (0..12).map(move |e| inst.palette.index(j, e))) {
                    prop_assert!(
                        frame.palettes.get(at).is_some_and(|v| v.is_finite()),
                        "palette value {} of a species-{} tree at level {}",
                        at,
                        b.species,
                        b.lod
                    );
                }
            }
        }
        Ok(())
    });
    if let Err(e) = outcome {
        panic!("{e}");
    }
}
