//! Which joints a `.glb` exports (within `max_joints`: the heaviest, and the twigs that
//! hang; the others folded into their ancestors) and their nodes and skin.

use super::*;

impl TreeModel {
    /// Joints exported for level `lod` with at most `max_joints` of them (as
    /// [`to_glb`](Self::to_glb) picks them), of those its vertices and clusters use: half
    /// the budget for the heaviest (carried mass), then every twig tip that
    /// hangs (points down) with its path to them, the largest hanging runs first, then the
    /// heaviest of the rest. Parents come before children; every exported joint's parent is
    /// exported. A sway clip for `tree animate` records these.
    pub fn exported_joints(&self, lod: usize, max_joints: usize) -> Vec<usize> {
        let order = self.joint_priority();
        let keep = self.exported_mask(lod, max_joints.clamp(1, MAX_GLTF_JOINTS), &order);
        (0..keep.len()).filter(|&j| keep[j]).collect()
    }

    /// Joints by priority: carried mass, heaviest first (a parent carries at least what its
    /// child does; ties go to the lower index, which is the parent).
    pub(super) fn joint_priority(&self) -> Vec<usize> {
        let sk = &self.tree.skeleton;
        let mut order: Vec<usize> = (0..sk.len()).collect();
        order.sort_by(|&a, &b| sk.carried_mass(b).total_cmp(&sk.carried_mass(a)).then(a.cmp(&b)));
        order
    }

    /// Per joint: exported at level `l` (see [`exported_joints`](Self::exported_joints)).
    pub(super) fn exported_mask(&self, l: usize, limit: usize, order: &[usize]) -> Vec<bool> {
        let js = self.tree.skeleton.joints();
        let n = js.len();
        let Some(lod) = self.lods.get(l) else { return vec![false; n] };
        let b = &lod.branches;
        let mut used = vec![false; n];
        for (j, w) in b.joints.iter().zip(&b.weights) {
            for s in 0..4 {
                if w[s] > 0.0 {
                    used[j[s] as usize] = true;
                }
            }
        }
        for c in &lod.clusters {
            used[c.joint as usize] = true;
        }
        used[0] = true;
        for j in (1..n).rev() {
            if used[j] && js[j].parent != NO_PARENT {
                used[js[j].parent as usize] = true;
            }
        }
        let mut keep = vec![false; n];
        let mut left = limit;
        // Adds `j` and its ancestors not yet kept, if they fit in what is left.
        let add_path = |j: usize, keep: &mut Vec<bool>, left: &mut usize| -> bool {
            let mut path = Vec::new();
            let mut k = j;
            while !keep[k] {
                path.push(k);
                if js[k].parent == NO_PARENT {
                    break;
                }
                k = js[k].parent as usize;
            }
            if path.len() > *left {
                return false;
            }
            *left -= path.len();
            for k in path {
                keep[k] = true;
            }
            true
        };
        // 1. The scaffold: the heaviest half of the budget, by carried mass (a parent
        //    carries at least what its child does, so these are whole paths from the root).
        for &j in order.iter().filter(|&&j| used[j]).take(limit.div_ceil(2)) {
            add_path(j, &mut keep, &mut left);
        }
        // 2. What hangs: every twig tip pointing down, with its path to the scaffold, the
        //    largest hanging runs first (the mass carried where the run starts to point
        //    down), so a weeping crown's curtains keep joints of their own to sway on
        //    instead of folding into the limbs they hang from.
        let mut has_child = vec![false; n];
        for j in 0..n {
            if used[j] && js[j].parent != NO_PARENT {
                has_child[js[j].parent as usize] = true;
            }
        }
        let sk = &self.tree.skeleton;
        let mut hanging: Vec<(f32, usize)> = (0..n)
            .filter(|&j| used[j] && !has_child[j] && js[j].axis[2] < 0.0)
            .map(|j| {
                let mut start = j;
                while js[start].parent != NO_PARENT && js[js[start].parent as usize].axis[2] < 0.0 {
                    start = js[start].parent as usize;
                }
                (sk.carried_mass(start), j)
            })
            .collect();
        hanging.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        for &(_, j) in &hanging {
            if left == 0 {
                break;
            }
            add_path(j, &mut keep, &mut left);
        }
        // 3. The rest of the budget by carried mass, as the scaffold.
        for &j in order.iter().filter(|&&j| used[j]) {
            if left == 0 {
                break;
            }
            if !keep[j] {
                add_path(j, &mut keep, &mut left);
            }
        }
        keep
    }

    /// Append the joint nodes of the joints marked in `keep` (parents first) to `nodes`,
    /// their inverse bind matrices and a skin over them. Returns, per skeleton joint, its
    /// exported index (or its nearest exported ancestor's).
    pub(super) fn joint_nodes(
        &self,
        keep: &[bool],
        frames: &[[V3; 3]],
        nodes: &mut Vec<Node>,
        bin: &mut Bin,
        skins: &mut Vec<Skin>,
    ) -> Vec<u16> {
        let base = nodes.len();
        let js = self.tree.skeleton.joints();
        let n = js.len();
        let mut index = vec![0u16; n];
        let mut exported = Vec::new();
        for j in 0..n {
            if keep[j] {
                index[j] = exported.len() as u16;
                exported.push(j);
            } else if js[j].parent != NO_PARENT {
                index[j] = index[js[j].parent as usize];
            }
        }
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); exported.len()];
        for (i, &j) in exported.iter().enumerate().skip(1) {
            children[index[js[j].parent as usize] as usize].push(i);
        }
        let mut ibm = Vec::with_capacity(exported.len());
        for (i, &j) in exported.iter().enumerate() {
            let f = &frames[j];
            let (t, r) = if js[j].parent == NO_PARENT {
                (js[j].origin, quaternion(f))
            } else {
                let p = js[j].parent as usize;
                let pf = &frames[p];
                let local = [to_local(pf, f[0]), to_local(pf, f[1]), to_local(pf, f[2])];
                (to_local(pf, sub(js[j].origin, js[p].origin)), quaternion(&local))
            };
            nodes.push(Node {
                name: format!("joint{j}"),
                translation: Some(t),
                rotation: Some(r),
                scale: None,
                children: children[i].iter().map(|c| base + c).collect(),
                mesh: None,
                skin: None,
            });
            // Inverse bind: [Rᵀ | −Rᵀ o], column-major.
            let o = js[j].origin;
            ibm.push([
                f[0][0],
                f[1][0],
                f[2][0],
                0.0,
                f[0][1],
                f[1][1],
                f[2][1],
                0.0,
                f[0][2],
                f[1][2],
                f[2][2],
                0.0,
                -dot(f[0], o),
                -dot(f[1], o),
                -dot(f[2], o),
                1.0,
            ]);
        }
        let inverse_bind_matrices =
            bin.accessor(&f32_bytes(&ibm), None, FLOAT, ibm.len(), "MAT4", None);
        skins.push(Skin {
            inverse_bind_matrices,
            skeleton: base,
            joints: (base..base + exported.len()).collect(),
        });
        index
    }
}
