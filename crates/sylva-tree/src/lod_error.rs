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
//! - the leaf cards it thins ([`crate::mesh::leaf_growth`]): each card kept grows by a factor
//!   `s` in side so the level shows full detail's leaf area, and its corners move out by
//!   `(s − 1) · side · (√2/2 + 0.45)` ([`CARD_GROWTH_REACH`]); the thinning keeps this within
//!   the dropped stems' diameter. The cards dropped are not bounded geometrically:
//!   they are accounted for statistically, the crown keeping its leaf area, and with it its
//!   coverage and brightness once cards are small in the image (Cook et al. 2007).

use crate::mesh::{CARD_GROWTH_REACH, TreeModel, sides, stem_levels};
use std::f32::consts::PI;

impl TreeModel {
    /// Each level's geometric error against full detail, m (unscaled): 0 for level 0, then
    /// non-decreasing (a level is never reported closer to full detail than a finer one).
    pub fn level_errors(&self) -> Vec<f32> {
        // Level 0's cards all have one side; a thinned level's are grown uniformly.
        let side0 = self.lods.first().and_then(|l| l.clusters.first()).map(|c| c.size);
        let joints = self.tree.skeleton.joints();
        let levels = stem_levels(&self.tree.skeleton);
        let sagitta = |r: f32, n: u32| r * (1.0 - (PI / n as f32).cos());
        let mut worst = 0.0f32;
        self.lods
            .iter()
            .map(|l| {
                let grown = l.clusters.iter().map(|c| c.size).fold(0.0f32, f32::max);
                let leaves = match side0 {
                    Some(side) if grown > side => (grown - side) * CARD_GROWTH_REACH,
                    _ => 0.0,
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
            // Thinned cards grow: the coarsest level's error is centimetres at least.
            assert!(e[e.len() - 1] > 0.05, "{name}: {e:?}");
            println!("{name}: {:?}", e);
        }
    }
}
