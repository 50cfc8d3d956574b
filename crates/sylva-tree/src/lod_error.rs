//! How far each mesh level of a tree's LOD chain lies from full detail, in metres of the
//! unscaled tree: what a level's screen-space error is made of (the geometry LOD picks the
//! coarsest level whose error, in pixels at the tree's distance, is within a budget).
//!
//! A level departs from full detail in three ways, and its error is the largest:
//! - the stems it drops: each thinner than the level's `min_radius`, so the widest gap it
//!   leaves is a stem's diameter, `2 · min_radius`;
//! - the stems it keeps with fewer ring sides ([`sides`]): a ring of `n` sides about a
//!   stem of radius `r` lies up to `r (1 − cos(π / n))` inside the true circle, so each
//!   kept stem moves by the difference of that from full detail's;
//! - the leaf clusters it merges: each full-detail card is stood for by the nearest card of
//!   the level, whose centre lies at most the level's leaf error away.

use crate::mesh::{LeafCluster, TreeModel, sides, stem_levels};
use std::f32::consts::PI;

use sylva_core::v3::{length, sub};

impl TreeModel {
    /// Each level's geometric error against full detail, m (unscaled): 0 for level 0, then
    /// non-decreasing (a level is never reported closer to full detail than a finer one).
    pub fn level_errors(&self) -> Vec<f32> {
        let full = self.lods.first().map(|l| &l.clusters[..]).unwrap_or(&[]);
        let joints = self.tree.skeleton.joints();
        let levels = stem_levels(&self.tree.skeleton);
        let sagitta = |r: f32, n: u32| r * (1.0 - (PI / n as f32).cos());
        let mut worst = 0.0f32;
        self.lods
            .iter()
            .map(|l| {
                let leaves = if l.clusters.len() == full.len() {
                    0.0
                } else {
                    leaf_displacement(full, &l.clusters)
                };
                let rings = joints
                    .iter()
                    .zip(&levels)
                    .filter(|(j, _)| j.radius >= l.min_radius)
                    .map(|(j, &s)| {
                        sagitta(j.radius, sides(s, l.level)) - sagitta(j.radius, sides(s, 0))
                    })
                    .fold(0.0f32, f32::max);
                worst = worst.max(2.0 * l.min_radius).max(leaves).max(rings);
                worst
            })
            .collect()
    }
}

/// The largest distance from a card of `full` to the nearest card of `merged`, m, through a
/// grid of cells as wide as that distance's first guess.
fn leaf_displacement(full: &[LeafCluster], merged: &[LeafCluster]) -> f32 {
    if full.is_empty() {
        return 0.0;
    }
    if merged.is_empty() {
        return f32::INFINITY;
    }
    // Cells a tenth of the crown's extent wide; the search widens ring by ring until the
    // nearest card found cannot be beaten by one in a ring further out.
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for c in merged.iter().chain(full) {
        for k in 0..3 {
            lo[k] = lo[k].min(c.center[k]);
            hi[k] = hi[k].max(c.center[k]);
        }
    }
    let extent = (0..3).map(|k| hi[k] - lo[k]).fold(1e-3f32, f32::max);
    let cell = extent / 10.0;
    let n = 11usize;
    let index = |p: [f32; 3]| -> [usize; 3] {
        std::array::from_fn(|k| (((p[k] - lo[k]) / cell) as usize).min(n - 1))
    };
    let mut cells: Vec<Vec<u32>> = vec![Vec::new(); n * n * n];
    for (i, c) in merged.iter().enumerate() {
        let [x, y, z] = index(c.center);
        cells[(z * n + y) * n + x].push(i as u32);
    }
    let mut worst = 0.0f32;
    for c in full {
        let [x, y, z] = index(c.center);
        let mut best = f32::MAX;
        for ring in 0..n {
            // Everything in rings beyond this one is at least `ring · cell` away.
            if best <= ring as f32 * cell {
                break;
            }
            let r = ring as isize;
            for dz in -r..=r {
                for dy in -r..=r {
                    for dx in -r..=r {
                        if dx.abs().max(dy.abs()).max(dz.abs()) != r {
                            continue;
                        }
                        let (cx, cy, cz) = (x as isize + dx, y as isize + dy, z as isize + dz);
                        if [cx, cy, cz].iter().any(|&v| v < 0 || v >= n as isize) {
                            continue;
                        }
                        for &m in &cells[((cz as usize) * n + cy as usize) * n + cx as usize] {
                            best = best.min(length(sub(merged[m as usize].center, c.center)));
                        }
                    }
                }
            }
        }
        worst = worst.max(best);
    }
    worst
}

#[cfg(test)]
mod tests {
    use crate::Species;

    #[test]
    fn errors_start_at_zero_grow_with_the_level_and_bound_the_dropped_stems() {
        for (name, _) in crate::species::PRESETS {
            let m = Species::load(name)
                .expect("preset")
                .model(1, crate::mesh::LOD_LEVELS)
                .expect("model");
            let e = m.level_errors();
            assert_eq!(e.len(), m.lods.len());
            assert_eq!(e[0], 0.0, "{name}: full detail is its own reference");
            for (k, l) in m.lods.iter().enumerate().skip(1) {
                assert!(e[k] >= e[k - 1], "{name}: level {k} {e:?}");
                assert!(
                    e[k] >= 2.0 * l.min_radius,
                    "{name}: level {k} drops stems of {}",
                    l.min_radius
                );
            }
            // Merged clusters move leaves: the coarsest level's error is centimetres at least.
            assert!(e[e.len() - 1] > 0.05, "{name}: {e:?}");
            println!("{name}: {:?}", e);
        }
    }
}
