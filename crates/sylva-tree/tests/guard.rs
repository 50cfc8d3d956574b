//! Branch counts inside their documented ranges can ask for billions of stems: the species'
//! `MaxJoints` guard refuses them before memory goes, and stops growth that splits push past
//! it. Peak heap use is measured with a tracking allocator; the tests take turns, since it
//! counts every thread.

use sylva_tree::{SkeletonError, Species};

use sylva_testkit::{CountingAllocator, exclusive, peak_during};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn exploding_branch_counts_are_refused_before_growing() {
    let _one = exclusive();
    // All three inside the documented range [0, 2000]: 8·10⁹ twigs.
    let text = "Levels = 4\n1Branches = 2000\n2Branches = 2000\n3Branches = 2000\n";
    let sp = Species::from_toml("exploding.toml", text).expect("every value is in range");
    let (result, peak) = peak_during(|| sp.generate(1));
    match result {
        Err(e @ SkeletonError::TooManyJoints { joints, max, .. }) => {
            assert!(joints > 8_000_000_000 && max == 1_000_000, "{e}");
            let msg = e.to_string();
            assert!(msg.contains("MaxJoints") && msg.contains("nBranches"), "{msg}");
        }
        other => panic!("expected the guard, got {:?}", other.map(|t| t.stats.stems)),
    }
    assert!(peak < 64 * 1024, "refused after allocating {peak} bytes");
}

#[test]
fn splits_that_pass_the_guard_stop_growth_at_it() {
    let _one = exclusive();
    // Within the branch bound, but every trunk segment splits in three: the clones multiply
    // the stems far past what the bound sees. Growth stops at MaxJoints.
    let text = "Levels = 2\nMaxJoints = 5000\n0CurveRes = 40\n0SegSplits = 2\n1Branches = 20\n";
    let sp = Species::from_toml("splitting.toml", text).expect("every value is in range");
    assert!(sp.joint_bound() <= 5000, "bound {}", sp.joint_bound());
    let (result, peak) = peak_during(|| sp.generate(3));
    match result {
        Err(SkeletonError::TooManyJoints { joints, max: 5000, .. }) => assert_eq!(joints, 5000),
        other => panic!("expected the guard, got {:?}", other.map(|t| t.stats.stems)),
    }
    // 5000 joints of about 60 bytes, with vector doubling: well under 2 MB.
    assert!(peak < 2 << 20, "peak {peak} bytes");
}

#[test]
fn every_preset_grows_within_the_default_guard() {
    let _one = exclusive();
    for (name, _) in sylva_tree::PRESETS {
        let sp = Species::preset(name).expect("preset");
        assert!(sp.joint_bound() < sp.max_joints as u64 / 4, "{name}: {}", sp.joint_bound());
        let tree = sp.generate(1).expect("grows");
        assert!(tree.skeleton.joints().len() < sp.max_joints as usize / 4, "{name}");
    }
}
