//! The hybrid model's invariants at every level of detail, for every preset.

use sylva_tree::mesh::{LOD_LEVELS, TreeModel};
use sylva_tree::{NO_PARENT, PRESETS, Species};

fn model(name: &str, seed: u64) -> TreeModel {
    Species::preset(name).expect("preset").model(seed, LOD_LEVELS).expect("valid tree")
}

/// Axis-aligned box around every segment of the skeleton, widened by the thickest radius
/// (with the trunk's lobes).
fn skeleton_bounds(m: &TreeModel, lobe_depth: f32) -> ([f32; 3], [f32; 3]) {
    let js = m.tree.skeleton.joints();
    let r = js.iter().map(|j| j.radius).fold(0.0, f32::max) * (1.0 + lobe_depth);
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for j in js {
        for p in [j.origin, j.tip()] {
            for c in 0..3 {
                lo[c] = lo[c].min(p[c] - r);
                hi[c] = hi[c].max(p[c] + r);
            }
        }
    }
    (lo, hi)
}

fn inside(p: [f32; 3], (lo, hi): ([f32; 3], [f32; 3]), margin: f32) -> bool {
    (0..3).all(|c| p[c] >= lo[c] - margin && p[c] <= hi[c] + margin)
}

#[test]
fn every_preset_at_every_lod_is_well_formed() {
    for (name, _) in PRESETS {
        let m = model(name, 3);
        let js = m.tree.skeleton.joints();
        assert!(m.lods.len() >= 4, "{name}: {} LOD levels", m.lods.len());
        for (i, j) in js.iter().enumerate() {
            assert!(
                j.parent == NO_PARENT || (j.parent as usize) < i,
                "{name}: joint {i} parent order"
            );
        }
        let lobe_depth = Species::preset(name).expect("preset").lobe_depth;
        let bounds = skeleton_bounds(&m, lobe_depth);
        // Leaf billboards hang outside the wood by at most a branch radius and half their
        // own size (thinned levels' cards are larger).
        let area0 = m.lods[0].leaf_area();
        assert!((area0 / m.tree.stats.leaf_area - 1.0).abs() < 0.01, "{name}: LOD 0 leaf area");
        let mut last_tris = usize::MAX;
        for lod in &m.lods {
            let b = &lod.branches;
            let n = b.positions.len();
            assert!(n > 0, "{name} LOD {}: empty branch mesh", lod.level);
            assert_eq!(b.normals.len(), n);
            assert_eq!(b.uvs.len(), n);
            assert_eq!(b.joints.len(), n);
            assert_eq!(b.weights.len(), n);
            for v in 0..n {
                let p = b.positions[v];
                assert!(
                    p.iter().chain(&b.normals[v]).chain(&b.uvs[v]).all(|x| x.is_finite()),
                    "{name}: NaN"
                );
                assert!(
                    inside(p, bounds, 1e-4),
                    "{name} LOD {}: vertex {v} at {p:?} outside",
                    lod.level
                );
                let w: f32 = b.weights[v].iter().sum();
                assert!((w - 1.0).abs() < 1e-6, "{name}: weights sum to {w}");
                assert!(b.weights[v].iter().all(|&w| (0.0..=1.0).contains(&w)));
                assert!(
                    b.joints[v].iter().all(|&j| (j as usize) < js.len()),
                    "{name}: joint index"
                );
                let len = b.normals[v].iter().map(|x| x * x).sum::<f32>().sqrt();
                assert!((len - 1.0).abs() < 1e-3, "{name}: normal length {len}");
            }
            assert!(b.indices.iter().all(|&i| (i as usize) < n), "{name}: index out of range");
            let leaf_margin = lod.clusters.iter().map(|c| c.size).fold(0.0, f32::max);
            for c in &lod.clusters {
                assert!((c.joint as usize) < js.len());
                assert!(c.size > 0.0 && c.size.is_finite() && c.leaf_area > 0.0);
                assert!(c.center.iter().chain(&c.hang).all(|x| x.is_finite()));
                assert!(inside(c.center, bounds, leaf_margin), "{name}: cluster outside the crown");
            }
            let tris = lod.triangles();
            assert!(tris < last_tris, "{name}: LOD {} has {tris} triangles, not fewer", lod.level);
            if lod.level > 0 {
                // The wood: roughly ×3 per level, between ×1.5 and ×5.
                let prev = &m.lods[lod.level - 1];
                let ratio = prev.branches.triangles() as f32 / b.triangles() as f32;
                assert!(
                    (1.5..5.0).contains(&ratio),
                    "{name}: LOD {} wood ratio {ratio}",
                    lod.level
                );
            }
            // The leaves: level 1 keeps level 0's cards; coarser levels thin them, never
            // adding any.
            if lod.level > 0 {
                let prev = &m.lods[lod.level - 1];
                assert!(
                    lod.clusters.len() <= prev.clusters.len(),
                    "{name}: LOD {} cards",
                    lod.level
                );
            }
            last_tris = tris;
            let area = lod.leaf_area();
            assert!(
                (area / area0 - 1.0).abs() < 0.02,
                "{name} LOD {}: leaf area {area} vs {area0}",
                lod.level
            );
        }
    }
}

#[test]
fn same_seed_same_model_and_another_seed_another() {
    let a = model("douglas_fir", 11);
    let b = model("douglas_fir", 11);
    assert_eq!(a.lods, b.lods);
    assert_eq!(a.bark, b.bark);
    assert_eq!(a.leaves, b.leaves);
    let c = model("douglas_fir", 12);
    assert_ne!(a.lods[0].branches.positions, c.lods[0].branches.positions);
    assert_ne!(a.leaves.image, c.leaves.image);
}

#[test]
fn thin_stems_are_dropped_first_and_their_leaves_rehung_on_kept_joints() {
    let m = model("black_tupelo", 5);
    let js = m.tree.skeleton.joints();
    for pair in m.lods.windows(2) {
        assert!(pair[1].min_radius >= pair[0].min_radius, "threshold falls");
    }
    for lod in &m.lods[2..] {
        // Every joint a vertex or a cluster uses is kept: no geometry on dropped joints
        // (level 1 keeps level 0's cards on their own joints, see above).
        let mut used = vec![false; js.len()];
        for v in &lod.branches.joints {
            used[v[0] as usize] = true;
        }
        for c in &lod.clusters {
            assert!(used[c.joint as usize], "LOD {}: cluster on a joint without wood", lod.level);
        }
    }
}

#[test]
fn level_one_keeps_every_leaf_card_of_full_detail_on_less_wood() {
    // A tree drawn at level 1 shows the leaves of level 0, card for card, each on its own
    // joint (so it moves as at full detail), where level 1 drops the thinnest stems: some
    // cards hang from joints whose wood level 1 does not draw.
    for name in ["quaking_aspen", "douglas_fir", "black_tupelo"] {
        let m = model(name, 5);
        let (l0, l1) = (&m.lods[0], &m.lods[1]);
        assert!(l1.min_radius > 0.0, "{name}: level 1 drops no stem");
        assert!(3 * l1.branches.triangles() < 2 * l0.branches.triangles(), "{name}: wood");
        assert_eq!(l1.clusters, l0.clusters, "{name}: level 1's cards are level 0's");
        let mut wood = vec![false; m.tree.skeleton.len()];
        for v in &l1.branches.joints {
            wood[v[0] as usize] = true;
        }
        assert!(
            l1.clusters.iter().any(|c| !wood[c.joint as usize]),
            "{name}: no card on a dropped twig"
        );
    }
}

#[test]
fn thinned_levels_keep_a_subset_of_the_cards_grown_to_the_whole_leaf_area() {
    // Stochastic simplification (Cook et al. 2007): a coarser level keeps some of full
    // detail's cards where they were, each grown by one factor so that the crown shows its
    // whole leaf area (its brightness and coverage) at every level, and the cards a level
    // keeps are kept by every finer one, so a change of level only adds or drops cards.
    for (name, _) in PRESETS {
        let m = model(name, 4);
        let base = &m.lods[0].clusters;
        let area0 = m.lods[0].leaf_area();
        let side0 = base[0].size;
        assert!(base.iter().all(|c| c.size == side0), "{name}: level 0's cards differ in size");
        let mut finer: Vec<([u32; 3], u32)> = Vec::new();
        let key = |c: &sylva_tree::mesh::LeafCluster| (c.hang.map(f32::to_bits), c.atlas);
        for lod in &m.lods {
            let area = lod.leaf_area();
            assert!(
                (area / area0 - 1.0).abs() <= 0.02,
                "{name} LOD {}: {area} of {area0} m²",
                lod.level
            );
            let grown = lod.clusters[0].size / side0;
            let kept_area: f32 =
                lod.clusters.iter().map(|c| c.leaf_area).sum::<f32>() / (grown * grown);
            assert!(
                ((grown * grown) * kept_area / area0 - 1.0).abs() < 1e-3,
                "{name} LOD {}: cards grown ×{grown} for {kept_area} of {area0} m²",
                lod.level
            );
            for c in &lod.clusters {
                assert!(
                    (c.size / side0 - grown).abs() < 1e-4 * grown,
                    "{name}: one growth per level"
                );
                assert!(base.iter().any(|b| key(b) == key(c)), "{name}: a card full detail lacks");
            }
            // Each kept card grows by at most what the level's dropped stems leave open.
            let reach = (grown - 1.0) * side0 * sylva_tree::mesh::CARD_GROWTH_REACH;
            assert!(
                reach <= 2.0 * lod.min_radius * 1.001 + 1e-6,
                "{name} LOD {}: grows {reach} m",
                lod.level
            );
            let keys: Vec<_> = lod.clusters.iter().map(key).collect();
            if lod.level > 0 {
                assert!(
                    keys.iter().all(|k| finer.contains(k)),
                    "{name} LOD {}: not nested",
                    lod.level
                );
            }
            finer = keys;
        }
        // The coarsest level thins: fewer cards than full detail.
        assert!(finer.len() < base.len(), "{name}: {} of {} cards", finer.len(), base.len());
    }
}

#[test]
fn textures_are_opaque_bark_and_alpha_masked_leaves() {
    let m = model("quaking_aspen", 1);
    assert!(m.bark.rgba.chunks(4).all(|p| p[3] == 255), "bark is opaque");
    let distinct: std::collections::HashSet<_> = m.bark.rgba.chunks(4).map(|p| p[0]).collect();
    assert!(distinct.len() > 20, "bark has texture, not a flat colour");
    for &c in &m.leaves.coverage {
        assert!((0.15..0.9).contains(&c), "leaf cell coverage {c}");
    }
    let opaque_green =
        m.leaves.image.rgba.chunks(4).filter(|p| p[3] == 255 && p[1] > p[0] && p[1] > p[2]).count();
    let clear = m.leaves.image.rgba.chunks(4).filter(|p| p[3] == 0).count();
    assert!(opaque_green > 1000 && clear > 1000, "leaves green on a transparent ground");
}

#[test]
fn trunk_cross_section_carries_the_lobes() {
    // WP95: r(θ) = r (1 + LobeDepth sin(Lobes θ)) on the trunk. The first ring of the mesh
    // is the trunk's base ring, centred on the origin.
    let mut sp = Species::preset("sugar_maple").expect("preset");
    sp.lobes = 4;
    sp.lobe_depth = 0.2;
    sp.flare = 0.0; // the flare's own test is below
    let m = sp.model(1, 1).expect("tree");
    let r0 = m.tree.skeleton.joints()[0].radius;
    let b = &m.lods[0].branches;
    let sides = sylva_tree::mesh::SIDES[0] as usize;
    let radii: Vec<f32> =
        b.positions[..sides].iter().map(|p| (p[0] * p[0] + p[1] * p[1]).sqrt() / r0).collect();
    let (lo, hi) = radii.iter().fold((f32::MAX, 0.0f32), |(l, h), &r| (l.min(r), h.max(r)));
    assert!(hi > 1.15 && lo < 0.85 && hi <= 1.2 + 1e-4 && lo >= 0.8 - 1e-4, "radii {lo} … {hi}");
    sp.lobe_depth = 0.0;
    let round = sp.model(1, 1).expect("tree");
    let p = &round.lods[0].branches.positions[..sides];
    assert!(p.iter().all(|p| ((p[0] * p[0] + p[1] * p[1]).sqrt() / r0 - 1.0).abs() < 1e-4));
}

#[test]
fn the_trunk_base_flares_as_wp95_says_and_narrows_upward() {
    // WP95: the trunk radius × (1 + Flare (100^y − 1) / 100), y = 1 − 8 z, over the lowest
    // eighth of the trunk. The aspen's Flare 0.6 makes its foot 1.59 times the trunk above.
    let mut sp = Species::preset("quaking_aspen").expect("preset");
    sp.lobe_depth = 0.0;
    let m = sp.model(1, 1).expect("tree");
    let j0 = m.tree.skeleton.joints()[0];
    let trunk: f32 = m.tree.stats.height;
    let core = j0.radius / sylva_tree::mesh::flare_factor(sp.flare, 0.5 * j0.length / trunk);
    let sides = sylva_tree::mesh::SIDES[0] as usize + 1;
    let b = &m.lods[0].branches;
    // The first rings, bottom up: their mean radius and height.
    let rings: Vec<(f32, f32)> = b.positions[..4 * sides]
        .chunks(sides)
        .map(|ring| {
            let r = ring.iter().map(|p| (p[0] * p[0] + p[1] * p[1]).sqrt()).sum::<f32>();
            (r / sides as f32, ring[0][2])
        })
        .collect();
    let foot = rings[0].0 / core;
    assert!((foot - 1.594).abs() < 0.03, "foot {foot} × the trunk radius, WP95 says 1.594");
    assert!(
        rings.windows(2).all(|w| w[1].1 > w[0].1 && w[1].0 < w[0].0),
        "rings rise and narrow: {rings:?}"
    );
    // Without Flare the trunk starts at its own radius.
    sp.flare = 0.0;
    let plain = sp.model(1, 1).expect("tree");
    let r: f32 = plain.lods[0].branches.positions[..sides - 1]
        .iter()
        .map(|p| (p[0] * p[0] + p[1] * p[1]).sqrt())
        .sum::<f32>()
        / (sides - 1) as f32;
    let r0 = plain.tree.skeleton.joints()[0].radius;
    assert!((r / r0 - 1.0).abs() < 1e-3, "{r} vs {r0}");
}

#[test]
fn leaves_are_drawn_at_their_species_size() {
    // Every preset's leaf cards show leaves of its LeafScale: a card at full detail spans
    // the atlas cell's span, and each leaf in a cell is LeafScale long (± 20 %) on it, its
    // outline reaching from near its base to near its tip.
    for (name, _) in PRESETS {
        let sp = Species::preset(name).expect("preset");
        let m = sp.model(2, 1).expect("tree");
        let atlas = &m.leaves;
        for c in &m.lods[0].clusters {
            assert!(
                (c.size / atlas.span - 1.0).abs() < 1e-4,
                "{name}: card {} m vs span {}",
                c.size,
                atlas.span
            );
        }
        for cell in 0..atlas.cells * atlas.cells {
            let (_, leaves) = sylva_tree::texture::cluster_layout(&sp, 2, cell);
            assert_eq!(leaves.len() as u32, atlas.leaves[cell as usize]);
            for l in &leaves {
                let metres = l.length * atlas.span;
                assert!(
                    (metres / sp.leaf_scale - 1.0).abs() <= 0.2,
                    "{name}: a leaf {metres:.3} m long, LeafScale {}",
                    sp.leaf_scale
                );
            }
        }
        // The outline along the midrib covers most of the blade's length.
        let w = sp.leaf_scale_x;
        let inside: Vec<f32> = (0..200)
            .map(|k| (k as f32 + 0.5) / 200.0)
            .filter(|&t| sylva_tree::texture::blade_contains(sp.leaf_shape, t, 0.0, w))
            .collect();
        let extent = inside.last().copied().unwrap_or(0.0) - inside.first().copied().unwrap_or(1.0);
        assert!(
            extent > 0.75,
            "{name}: outline {LeafShape} spans {extent:.2} of the blade",
            LeafShape = sp.leaf_shape
        );
    }
}
