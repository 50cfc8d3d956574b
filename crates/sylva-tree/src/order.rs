//! A joint order for level of detail: the joints a coarse level uses come first, so every
//! level's joints are a prefix of the skeleton, and whatever is cut at a level (simulation
//! or upload of palettes) is a tail.
//!
//! Key of a joint: the coarsest LOD level whose branch mesh or leaf clusters use it (or one
//! of its descendants); the trunk (root to [`Skeleton::trunk_top`]) comes before all, so an
//! impostor swaying with the trunk top needs only the trunk's joints. Joints are sorted by
//! key, coarsest first, ties in their original order. A parent is used wherever its child
//! is, so its key is at least the child's and the order stays parents first.

use crate::generate::Tree;
use crate::mesh::TreeModel;
use crate::skeleton::{Joint, NO_PARENT, Skeleton, SkeletonError};

/// A joint order with the length of each level's prefix.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LodOrder {
    /// New index → old index.
    pub order: Vec<u32>,
    /// Per LOD level: the joints it uses are the first `prefix[level]` (non-increasing).
    pub prefix: Vec<usize>,
    /// The trunk, root to top, is the first `trunk` joints; the top is joint `trunk − 1`.
    pub trunk: usize,
}

/// The LOD order of `model`'s skeleton and chain.
pub fn lod_order(model: &TreeModel) -> LodOrder {
    let sk = &model.tree.skeleton;
    let js = sk.joints();
    let n = js.len();
    let levels = model.lods.len();
    // key[j] = coarsest level using j (-1: none).
    let mut key = vec![-1i64; n];
    let mut used = vec![false; n];
    for (k, lod) in model.lods.iter().enumerate() {
        used.iter_mut().for_each(|u| *u = false);
        for (jv, wv) in lod.branches.joints.iter().zip(&lod.branches.weights) {
            for (j, w) in jv.iter().zip(wv) {
                if *w > 0.0 && (*j as usize) < n {
                    used[*j as usize] = true;
                }
            }
        }
        for c in &lod.clusters {
            if (c.joint as usize) < n {
                used[c.joint as usize] = true;
            }
        }
        // Close under ancestors (children after parents: a backward sweep).
        for i in (1..n).rev() {
            if used[i] {
                used[js[i].parent as usize] = true;
            }
        }
        for (i, u) in used.iter().enumerate() {
            if *u {
                key[i] = k as i64;
            }
        }
    }
    let mut top = sk.trunk_top();
    let mut trunk = 0;
    loop {
        key[top] = levels as i64;
        trunk += 1;
        if js[top].parent == NO_PARENT {
            break;
        }
        top = js[top].parent as usize;
    }
    let mut order: Vec<u32> = (0..n as u32).collect();
    order.sort_by_key(|&j| (-key[j as usize], j));
    let prefix = (0..levels).map(|k| key.iter().filter(|&&v| v >= k as i64).count()).collect();
    LodOrder { order, prefix, trunk }
}

impl LodOrder {
    /// Old index → new index.
    pub fn inverse(&self) -> Vec<u32> {
        let mut inv = vec![0u32; self.order.len()];
        for (new, &old) in self.order.iter().enumerate() {
            inv[old as usize] = new as u32;
        }
        inv
    }
}

impl TreeModel {
    /// The same model with its joints in `order` (new → old; parents must stay first):
    /// skeleton, mesh joint indices and cluster joints renumbered, nothing moved.
    pub fn reordered(&self, order: &[u32]) -> Result<TreeModel, SkeletonError> {
        let js = self.tree.skeleton.joints();
        let mut inv = vec![u32::MAX; js.len()];
        for (new, &old) in order.iter().enumerate() {
            if let Some(slot) = inv.get_mut(old as usize) {
                *slot = new as u32;
            }
        }
        let joints: Vec<Joint> = order
            .iter()
            .map(|&old| {
                let j = js[old as usize];
                let parent = if j.parent == NO_PARENT { NO_PARENT } else { inv[j.parent as usize] };
                Joint { parent, ..j }
            })
            .collect();
        let skeleton = Skeleton::new(joints)?;
        let mut out = self.clone();
        out.tree = Tree { skeleton, stats: self.tree.stats };
        for lod in &mut out.lods {
            for jv in &mut lod.branches.joints {
                for j in jv.iter_mut() {
                    *j = inv.get(*j as usize).copied().filter(|&v| v != u32::MAX).unwrap_or(0);
                }
            }
            for c in &mut lod.clusters {
                c.joint = inv.get(c.joint as usize).copied().unwrap_or(0);
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Species;

    #[test]
    fn every_level_uses_only_its_prefix_and_the_trunk_comes_first() {
        let sp = Species::preset("quaking_aspen").expect("preset");
        let model = sp.model(3, 4).expect("model");
        let o = lod_order(&model);
        let m = model.reordered(&o.order).expect("reordered");
        let sk = &m.tree.skeleton;
        // The trunk: joints 0 … trunk−1 form the root-to-top chain.
        assert_eq!(sk.trunk_top(), o.trunk - 1);
        for i in 1..o.trunk {
            assert_eq!(sk.joints()[i].parent as usize, i - 1);
        }
        assert!(o.prefix.windows(2).all(|w| w[0] >= w[1]), "{:?}", o.prefix);
        assert!(o.prefix[3] < o.prefix[0] / 4, "coarse levels use few joints: {:?}", o.prefix);
        for (k, lod) in m.lods.iter().enumerate() {
            let max_branch = lod
                .branches
                .joints
                .iter()
                .zip(&lod.branches.weights)
                .flat_map(|(j, w)| j.iter().zip(w).filter(|(_, w)| **w > 0.0).map(|(j, _)| *j))
                .max()
                .unwrap_or(0);
            let max_cluster = lod.clusters.iter().map(|c| c.joint).max().unwrap_or(0);
            assert!((max_branch.max(max_cluster) as usize) < o.prefix[k], "level {k}");
        }
        // Nothing moved: every joint's rest pose is the old joint's.
        for (new, &old) in o.order.iter().enumerate() {
            let (a, b) = (sk.joints()[new], model.tree.skeleton.joints()[old as usize]);
            assert_eq!((a.origin, a.axis, a.length), (b.origin, b.axis, b.length));
        }
        assert!((sk.carried_mass(0) - model.tree.skeleton.carried_mass(0)).abs() < 1e-3);
    }
}
