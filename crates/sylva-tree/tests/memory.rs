//! A tree's growth is sized before it starts: a species whose tree would not fit in memory
//! is refused with the figure, not grown until the allocator aborts.

use sylva_tree::{SkeletonError, Species};

/// The aspen with two crowded branch levels and the documented largest `MaxJoints`:
/// 2 000 branches on 2 000 branches, 12 million joints.
fn crowded() -> Species {
    let text = Species::load("quaking_aspen").expect("preset").to_toml();
    let text = text
        .replacen("1Branches = 50", "1Branches = 2000", 1)
        .replacen("2Branches = 30", "2Branches = 2000", 1)
        .replacen("MaxJoints = 1000000", "MaxJoints = 16000000", 1);
    Species::from_toml("crowded.toml", &text).expect("within every field's range")
}

#[test]
fn a_species_too_large_for_memory_is_refused_before_it_grows() {
    let sp = crowded();
    assert!(sp.joint_bound() > 10_000_000, "{}", sp.joint_bound());
    // 12 million joints at over 2 kB each: more than 8 GB.
    match sp.check_memory(8e9) {
        Err(SkeletonError::TooMuchMemory { need_gb, usable_gb, .. }) => {
            assert!(need_gb > 24.0 && usable_gb == 8.0, "{need_gb} {usable_gb}");
        }
        other => panic!("{other:?}"),
    }
    let e = sp.check_memory(8e9).expect_err("refused").to_string();
    assert!(e.contains("GB") && e.contains("nBranches"), "{e}");
}

#[test]
fn the_memory_estimate_grows_with_branches_and_leaves_and_passes_the_presets() {
    let aspen = Species::load("quaking_aspen").expect("preset");
    assert!(crowded().memory_estimate() > 100.0 * aspen.memory_estimate());
    let text = aspen.to_toml().replacen("Leaves = 25", "Leaves = 2000", 1);
    let leafy = Species::from_toml("leafy.toml", &text).expect("leafy");
    assert!(leafy.memory_estimate() > 2.0 * aspen.memory_estimate());
    // Every preset fits well within a gigabyte, and is grown.
    for (name, _) in sylva_tree::species::PRESETS {
        let sp = Species::load(name).expect("preset");
        assert!(sp.memory_estimate() < 1e9, "{name}: {}", sp.memory_estimate());
        sp.check_memory(1e9).expect("a preset fits");
    }
}
