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

/// A `lo–hi` range of docs/presets.md (an en dash, or a single value for both ends).
fn range(cell: &str) -> (f32, f32) {
    let cell = cell.trim();
    let (lo, hi) = cell.split_once('–').unwrap_or((cell, cell));
    let num = |s: &str| s.trim().parse::<f32>().unwrap_or_else(|e| panic!("{cell:?}: {e}"));
    (num(lo), num(hi))
}

/// The rows of docs/presets.md's "Ranges" table: preset, then its four ranges.
fn documented_ranges() -> Vec<(String, [(f32, f32); 4])> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/presets.md");
    let text = std::fs::read_to_string(path).expect("docs/presets.md");
    let table = text.split("## Ranges").nth(1).expect("a Ranges section");
    table
        .lines()
        .skip_while(|l| !l.starts_with("| preset |"))
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .map(|l| {
            let cells: Vec<&str> = l.trim_matches('|').split('|').collect();
            assert_eq!(cells.len(), 5, "row {l:?}");
            let r = [range(cells[1]), range(cells[2]), range(cells[3]), range(cells[4])];
            (cells[0].trim().to_string(), r)
        })
        .collect()
}

#[test]
fn every_preset_grows_within_its_species_documented_ranges() {
    // docs/presets.md holds each species' height, crown width over height, crown base over
    // height and leaf area index, with their sources; every preset, at four seeds (four
    // tree sizes within its `Scale ± ScaleV`), must grow within them. A preset whose
    // parameters drift, a generator change that moves a species, or a range edited in the
    // docs alone fails here.
    let ranges = documented_ranges();
    let names: Vec<&str> = ranges.iter().map(|(n, _)| n.as_str()).collect();
    for (name, _) in PRESETS {
        assert!(names.contains(name), "docs/presets.md has no row for {name}");
    }
    for (name, [height, width, base, lai]) in &ranges {
        let sp = Species::preset(name).unwrap_or_else(|| panic!("{name}: not a preset"));
        for seed in 1..=4 {
            let s = sp.generate(seed).expect("valid").stats;
            let measured = [
                ("height", s.height, height),
                (
                    "crown width / height",
                    0.5 * (s.crown_width[0] + s.crown_width[1]) / s.height,
                    width,
                ),
                ("crown base / height", s.crown_base / s.height, base),
                ("leaf area index", s.leaf_area_index(), lai),
            ];
            for (what, value, (lo, hi)) in measured {
                // Two decimals, as the table reads.
                let shown = (value * 100.0).round() / 100.0;
                assert!(
                    (*lo..=*hi).contains(&shown),
                    "{name} seed {seed}: {what} {value:.3} outside the documented {lo}–{hi}"
                );
            }
        }
    }
}

#[test]
fn the_crown_base_is_where_the_lowest_leafy_branch_leaves_the_trunk() {
    // The willow's twigs hang to within 0.3 m of the ground, but its crown starts where its
    // limbs leave the trunk, metres up: the crown base is read at the trunk, not at the
    // lowest leaf. And no leafy branch leaves the trunk below it.
    let sp = Species::preset("weeping_willow").expect("preset");
    let tree = sp.generate(1).expect("valid");
    let sk = &tree.skeleton;
    let levels = stem_levels(sk);
    let lowest_leaf = sk
        .joints()
        .iter()
        .filter(|j| j.leaf_area > 0.0)
        .map(|j| j.origin[2])
        .fold(f32::MAX, f32::min);
    let base = tree.stats.crown_base;
    assert!(
        lowest_leaf < 1.0 && base > 1.0,
        "lowest leaf {lowest_leaf:.2} m, crown base {base:.2} m"
    );
    let lowest_branch = sk
        .joints()
        .iter()
        .zip(&levels)
        .filter(|(j, l)| **l == 1 && !j.continues && levels[j.parent as usize] == 0)
        .map(|(j, _)| j.origin[2])
        .fold(f32::MAX, f32::min);
    assert!(
        (lowest_branch - base).abs() < 1e-4,
        "lowest limb {lowest_branch} m, crown base {base} m"
    );
}
