//! The shipped presets as specimens: every stem level a preset declares grows, and every
//! crown carries a leaf area a forester would recognise.

use sylva_tree::{NO_PARENT, PRESETS, Skeleton, Species};

/// Stem level of every joint: the root's stem is level 0; a joint that starts a new stem on
/// its parent is one level deeper, one that continues its parent's stem keeps its level.
fn stem_levels(sk: &Skeleton) -> Vec<usize> {
    let mut level = vec![0usize; sk.len()];
    for (i, j) in sk.joints().iter().enumerate() {
        if j.parent != NO_PARENT {
            level[i] = level[j.parent as usize] + usize::from(!j.continues);
        }
    }
    level
}

#[test]
fn every_declared_stem_level_grows_stems() {
    // WP95 grows `Levels` levels of stems; a level whose nLength is 0 grows nothing (the
    // generator drops it), so a preset that declares it carries a dead column. The black
    // tupelo's fourth level (3Length = 0.4 in WP95) once grew nothing this way.
    for (name, _) in PRESETS {
        let sp = Species::preset(name).expect("preset");
        let tree = sp.generate(1).expect("valid");
        let levels = stem_levels(&tree.skeleton);
        let declared = sp.levels as usize;
        for want in 0..declared {
            let stems = tree
                .skeleton
                .joints()
                .iter()
                .zip(&levels)
                .filter(|(j, l)| **l == want && (j.parent == NO_PARENT || !j.continues))
                .count();
            assert!(
                stems > 0,
                "{name}: declares Levels = {declared} but grows no level-{want} stem"
            );
        }
        assert!(
            levels.iter().all(|&l| l < declared),
            "{name}: a stem deeper than Levels = {declared}"
        );
    }
}

#[test]
fn every_crown_carries_a_measured_range_of_leaf_area() {
    // Leaf area index (one-sided leaf area over the ground area the crown covers): stands of
    // temperate broadleaf and needleleaf trees measure about 3–6 on average and seldom over
    // 10 (Asner, Scurlock & Hicke 2003, Global Ecology and Biogeography 12, 191–205). A
    // crown is taken as the ellipse spanning its joint tips; the band is wide because a
    // lone crown is not a stand, but a crown at 0.8 (a bare pole with a few leaves) or at 15
    // (leaves enlarged to spare polygons, counted as if true size) is not a tree.
    for (name, _) in PRESETS {
        let sp = Species::preset(name).expect("preset");
        let tree = sp.generate(1).expect("valid");
        // The crown's widths are the extent of the joint tips, and its ground the ellipse
        // they span.
        let (mut lo, mut hi) = ([f32::MAX; 2], [f32::MIN; 2]);
        for t in tree.skeleton.joints().iter().map(|j| j.tip()) {
            for k in 0..2 {
                lo[k] = lo[k].min(t[k]);
                hi[k] = hi[k].max(t[k]);
            }
        }
        let [wx, wy] = tree.stats.crown_width;
        assert!((wx - (hi[0] - lo[0])).abs() < 1e-4 && (wy - (hi[1] - lo[1])).abs() < 1e-4);
        let ground = std::f32::consts::FRAC_PI_4 * wx * wy;
        let lai = tree.stats.leaf_area_index();
        assert!((lai - tree.stats.leaf_area / ground).abs() < 1e-4 * lai);
        assert!(
            (1.5..=10.0).contains(&lai),
            "{name}: {:.0} m² of leaves over a {ground:.0} m² crown, leaf area index {lai:.2}",
            tree.stats.leaf_area
        );
    }
}
