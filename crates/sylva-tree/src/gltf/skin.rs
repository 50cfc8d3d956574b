//! Which joints a `.glb` exports (the heaviest within `max_joints`, lighter ones folded
//! into their ancestors) and their nodes and skin.

use super::*;

impl TreeModel {
    /// Joints exported for level `lod` with at most `max_joints` of them (as
    /// [`to_glb`](Self::to_glb) picks them): those its vertices and clusters use, with
    /// their ancestors, heaviest first (carried mass). Parents come before children; every
    /// exported joint's parent is exported. A sway clip for `tree animate` records these.
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
        for &j in order.iter().filter(|&&j| used[j]).take(limit) {
            keep[j] = true;
        }
        for j in 0..n {
            let p = js[j].parent;
            if keep[j] && p != NO_PARENT && !keep[p as usize] {
                keep[j] = false;
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
