//! Property: every species with every Weber–Penn parameter inside its documented range
//! (`PARAMS`) either grows a well-formed tree whose model exports a well-formed `.glb`, or is
//! refused up front by the `MaxJoints` guard. Nothing else may happen: no other error, no
//! panic, no unbounded allocation.
//!
//! proptest draws the parameters (a fixed seed, so the same cases every run) and, on a
//! failure, shrinks every parameter toward the bottom of its range to report a minimal
//! species. `PROPTEST_CASES` sets the number of cases (default 24).

use std::cell::Cell;

use proptest::prelude::*;
use sylva_testkit::runner;
use sylva_tree::species::Scope;
use sylva_tree::{PARAMS, SkeletonError, Species};

/// Values drawn per species: one per global parameter, four per per-level one.
fn slots() -> usize {
    PARAMS.iter().map(|p| if p.scope == Scope::Global { 1 } else { 4 }).sum()
}

/// The species whose parameters sit at fractions `u` (0 = minimum, 1 = maximum) of their
/// ranges, integers rounded down.
fn species_at(u: &[f64]) -> Species {
    let mut sp = Species::defaults("drawn");
    let mut u = u.iter();
    for p in PARAMS {
        let levels: &[Option<usize>] = match p.scope {
            Scope::Global => &[None],
            Scope::Level => &[Some(0), Some(1), Some(2), Some(3)],
        };
        for &level in levels {
            let f = *u.next().expect("one fraction per slot");
            let v = p.min as f64 + f * (p.max - p.min) as f64;
            sp.set(level, p.name, (if p.integer { v.floor() } else { v }) as f32);
        }
    }
    // A small guard keeps each case quick; the property is the same at any bound.
    sp.max_joints = 20_000;
    sp
}

#[test]
fn any_species_inside_the_ranges_grows_a_valid_tree_or_is_refused() {
    let mut runner = runner(24, 0x5eed_0001);
    let (grown, refused) = (Cell::new(0u32), Cell::new(0u32));
    let outcome = runner.run(
        // Each case also draws an exponent p and uses uᵖ: p = 1 spreads the parameters
        // evenly over their ranges (most such trees exceed any joint bound), larger p crowds
        // them toward the bottom of their ranges, where trees stay small enough to grow.
        &(proptest::collection::vec(0.0f64..=1.0, slots()), 1.0f64..6.0, 0u64..1000),
        |(u, p, seed)| {
            let u: Vec<f64> = u.iter().map(|v| v.powf(p)).collect();
            let sp = species_at(&u);
            match sp.generate(seed) {
                Ok(tree) => {
                    grown.set(grown.get() + 1);
                    let joints = tree.skeleton.joints();
                    prop_assert!(!joints.is_empty() && joints.len() <= 20_000);
                    for (i, j) in joints.iter().enumerate() {
                        prop_assert!(i == 0 || (j.parent as usize) < i, "joint {} parent", i);
                        prop_assert!(j.origin.iter().all(|v| v.is_finite()), "joint {} origin", i);
                        prop_assert!(j.length >= 0.0 && j.radius >= 0.0, "joint {} size", i);
                        let n = j.axis.iter().map(|a| a * a).sum::<f32>().sqrt();
                        prop_assert!((n - 1.0).abs() < 1e-3, "joint {} axis |{}|", i, n);
                    }
                    prop_assert!(tree.stats.height.is_finite() && tree.stats.height > 0.0);
                    let model = sp
                        .model(seed, sylva_tree::mesh::LOD_LEVELS)
                        .map_err(|e| TestCaseError::fail(format!("model: {e}")))?;
                    let glb = model.to_glb(&Default::default());
                    prop_assert_eq!(&glb[..4], b"glTF");
                    let len = u32::from_le_bytes([glb[8], glb[9], glb[10], glb[11]]) as usize;
                    prop_assert_eq!(len, glb.len(), "GLB length field");
                }
                Err(SkeletonError::TooManyJoints { .. }) => refused.set(refused.get() + 1),
                Err(e) => return Err(TestCaseError::fail(format!("in-range species failed: {e}"))),
            }
            Ok(())
        },
    );
    if let Err(e) = outcome {
        panic!("{e}");
    }
    // With ranges this wide both outcomes occur; if one never did, the draw is degenerate.
    let (grown, refused) = (grown.get(), refused.get());
    eprintln!("species drawn: {grown} grown, {refused} refused by the guard");
    assert!(grown > 0 && refused > 0, "grown {grown}, refused {refused}");
}
