//! The tree skeleton of the paper's hybrid representation (§4.1): every stem is split into
//! rigid segments, and each segment rotates about the joint that links it to its
//! predecessor or parent stem.
//!
//! One index space is shared by the branch mesh (joint indices per vertex), the leaf
//! clusters (a hanging joint each) and the animation (one spring per joint). Joints are
//! stored parents first: `parent < index` for every joint but the root, so one forward pass
//! composes transforms and one backward pass accumulates loads.
//!
//! Units: metres, kilograms, square metres. Tree space: z up, the trunk base at the origin.

use sylva_core::v3::{cross, norm};
use thiserror::Error;

/// Marks the root joint's parent.
pub const NO_PARENT: u32 = u32::MAX;

/// One joint and the rigid segment that hangs from it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Joint {
    /// Parent joint index, or [`NO_PARENT`] for the root. Always smaller than this joint's index.
    pub parent: u32,
    /// Rest position of the joint (the segment's base) in tree space, m.
    pub origin: [f32; 3],
    /// Unit vector along the segment at rest, tree space (the local frame's z axis).
    pub axis: [f32; 3],
    /// Segment length, m.
    pub length: f32,
    /// Segment radius at its base, m.
    pub radius: f32,
    /// Mass of the segment's own wood, kg.
    pub own_mass: f32,
    /// Leaf area attached to this segment (one side), m².
    pub leaf_area: f32,
    /// Mass of the leaves attached to this segment, kg.
    pub leaf_mass: f32,
    /// Whether this segment continues its parent's stem (a later segment of the same stem,
    /// or a clone of a split) rather than starting a new stem on it.
    pub continues: bool,
}

impl Joint {
    /// The local frame (x, y, z) of the joint: z along the segment, x and y the two bending
    /// axes, chosen deterministically (x ⟂ z in the plane of z and world up, or world x for
    /// a vertical segment).
    pub fn frame(&self) -> [[f32; 3]; 3] {
        let z = self.axis;
        let up = if z[2].abs() > 0.999 { [1.0, 0.0, 0.0] } else { [0.0, 0.0, 1.0] };
        let x = norm(cross(up, z));
        let y = cross(z, x);
        [x, y, z]
    }

    /// Rest position of the segment's tip, m.
    pub fn tip(&self) -> [f32; 3] {
        [
            self.origin[0] + self.axis[0] * self.length,
            self.origin[1] + self.axis[1] * self.length,
            self.origin[2] + self.axis[2] * self.length,
        ]
    }
}

/// A skeleton that failed validation.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SkeletonError {
    /// The skeleton has no joint.
    #[error("skeleton has no joints")]
    Empty,
    /// A joint's parent does not come before it.
    #[error("joint {joint}: parent {parent} does not come before it")]
    ParentOrder {
        /// Joint index.
        joint: usize,
        /// Its parent.
        parent: u32,
    },
    /// The species would grow more joints than its `MaxJoints` guard allows.
    #[error(
        "this species would grow {joints} joints ({how}), over MaxJoints = {max}: lower the \
         nBranches, nCurveRes or nSegSplits, or raise MaxJoints in the species file"
    )]
    TooManyJoints {
        /// Joints estimated or grown when the guard stopped it.
        joints: u64,
        /// The species' `MaxJoints`.
        max: u32,
        /// How the figure was found.
        how: &'static str,
    },
    /// Growing and meshing the tree would need more memory than the machine has free.
    #[error(
        "this species would need about {need_gb:.2} GB to grow and mesh ({joints} joints at \
         most), more than the {usable_gb:.2} GB usable of this machine's free memory: lower \
         nBranches, nCurveRes, nSegSplits or Leaves in the species file"
    )]
    TooMuchMemory {
        /// [`Species::memory_estimate`](crate::Species::memory_estimate), GB.
        need_gb: f64,
        /// The share of the free memory one piece of work may use, GB.
        usable_gb: f64,
        /// [`Species::joint_bound`](crate::Species::joint_bound).
        joints: u64,
    },
    /// A joint has a non-finite or out-of-range value.
    #[error("joint {joint}: {field} = {value} is invalid ({expected})")]
    Value {
        /// Joint index.
        joint: usize,
        /// Field name.
        field: &'static str,
        /// Value found.
        value: f32,
        /// Valid range.
        expected: &'static str,
    },
}

/// Joints stored parents first, with the mass each carries downstream.
#[derive(Debug, Clone, PartialEq)]
pub struct Skeleton {
    joints: Vec<Joint>,
    carried: Vec<f32>,
    children: Vec<Vec<u32>>,
}

impl Skeleton {
    /// Validate `joints` (parents first, finite positive sizes, unit axes) and compute the
    /// mass each joint carries: its segment, its leaves and everything downstream.
    pub fn new(joints: Vec<Joint>) -> Result<Skeleton, SkeletonError> {
        if joints.is_empty() {
            return Err(SkeletonError::Empty);
        }
        let bad = |joint, field, value: f32, expected| SkeletonError::Value {
            joint,
            field,
            value,
            expected,
        };
        for (i, j) in joints.iter().enumerate() {
            if (i == 0) != (j.parent == NO_PARENT) || (i > 0 && j.parent as usize >= i) {
                return Err(SkeletonError::ParentOrder { joint: i, parent: j.parent });
            }
            for (field, v) in [("length", j.length), ("radius", j.radius)] {
                if !(v > 0.0 && v.is_finite()) {
                    return Err(bad(i, field, v, "> 0"));
                }
            }
            for (field, v) in
                [("own_mass", j.own_mass), ("leaf_area", j.leaf_area), ("leaf_mass", j.leaf_mass)]
            {
                if !(v >= 0.0 && v.is_finite()) {
                    return Err(bad(i, field, v, "≥ 0"));
                }
            }
            let n = (j.axis[0].powi(2) + j.axis[1].powi(2) + j.axis[2].powi(2)).sqrt();
            if (n - 1.0).abs() > 1e-3 || j.origin.iter().any(|c| !c.is_finite()) {
                return Err(bad(i, "axis", n, "a unit vector and a finite origin"));
            }
        }
        let mut carried: Vec<f32> = joints.iter().map(|j| j.own_mass + j.leaf_mass).collect();
        let mut children = vec![Vec::new(); joints.len()];
        for i in (1..joints.len()).rev() {
            let p = joints[i].parent as usize;
            carried[p] += carried[i];
            children[p].push(i as u32);
        }
        for c in &mut children {
            c.reverse();
        }
        Ok(Skeleton { joints, carried, children })
    }

    /// The joints, parents first.
    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }

    /// Number of joints.
    pub fn len(&self) -> usize {
        self.joints.len()
    }

    /// Whether there are no joints (never true for a validated skeleton).
    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }

    /// Mass carried by joint `i`, kg: its segment, its leaves and everything downstream.
    pub fn carried_mass(&self, i: usize) -> f32 {
        self.carried[i]
    }

    /// Children of joint `i`, in index order.
    pub fn children(&self, i: usize) -> &[u32] {
        &self.children[i]
    }

    /// The heaviest child of `i` that continues its stem, if any.
    fn continuation(&self, i: usize) -> Option<usize> {
        self.children[i]
            .iter()
            .map(|&c| c as usize)
            .filter(|&c| self.joints[c].continues)
            .max_by(|&a, &b| self.carried[a].total_cmp(&self.carried[b]))
    }

    /// Trunk diameter at breast height (1.3 m above the trunk's base, along the trunk), m:
    /// the segments' base radii interpolated linearly; a trunk shorter than that gives its
    /// top's.
    pub fn dbh(&self) -> f32 {
        const BREAST: f32 = 1.3;
        if self.joints.is_empty() {
            return 0.0;
        }
        let mut i = 0;
        let mut climbed = 0.0;
        loop {
            let j = &self.joints[i];
            let next = self.continuation(i);
            let r_end = next.map_or(0.0, |n| self.joints[n].radius);
            if climbed + j.length >= BREAST || next.is_none() {
                let f = ((BREAST - climbed) / j.length.max(1e-6)).clamp(0.0, 1.0);
                return 2.0 * (j.radius + f * (r_end - j.radius));
            }
            climbed += j.length;
            i = next.unwrap_or(i);
        }
    }

    /// The last segment of the stem that starts at (or passes through) joint `i`,
    /// following the heaviest continuation at splits.
    pub fn stem_end(&self, mut i: usize) -> usize {
        while let Some(c) = self.continuation(i) {
            i = c;
        }
        i
    }

    /// Length of the stem from joint `i` to [`Skeleton::stem_end`], m.
    pub fn stem_length(&self, mut i: usize) -> f32 {
        let mut len = self.joints[i].length;
        while let Some(c) = self.continuation(i) {
            len += self.joints[c].length;
            i = c;
        }
        len
    }

    /// Radius of the trunk at height `z` above its base, m: the radius of the trunk segment
    /// spanning that height (the top segment's above the trunk). `radius_at_height(1.3)` is
    /// half the diameter at breast height (DBH).
    pub fn radius_at_height(&self, z: f32) -> f32 {
        let mut i = 0;
        loop {
            let j = &self.joints[i];
            let next =
                self.children[i].iter().copied().rev().find(|&c| self.joints[c as usize].continues);
            match next {
                Some(c) if j.tip()[2] < z => i = c as usize,
                _ => return j.radius,
            }
        }
    }

    /// The trunk's top segment: the end of the root's stem.
    pub fn trunk_top(&self) -> usize {
        self.stem_end(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn joint(parent: u32, z: f32, len: f32, mass: f32) -> Joint {
        Joint {
            parent,
            origin: [0.0, 0.0, z],
            axis: [0.0, 0.0, 1.0],
            length: len,
            radius: 0.1,
            own_mass: mass,
            leaf_area: 0.0,
            leaf_mass: 0.5,
            continues: parent != NO_PARENT,
        }
    }

    #[test]
    fn dbh_is_the_trunk_diameter_interpolated_at_one_point_three_metres() {
        // A trunk of 1 m segments tapering 0.30 → 0.20 → 0.10 m in radius: at 1.3 m, 30 %
        // of the way up the second segment, the radius is 0.20 − 0.3 × 0.10 = 0.17 m.
        let mut js =
            vec![joint(NO_PARENT, 0.0, 1.0, 1.0), joint(0, 1.0, 1.0, 1.0), joint(1, 2.0, 1.0, 1.0)];
        for (j, r) in js.iter_mut().zip([0.3, 0.2, 0.1]) {
            j.radius = r;
        }
        let s = Skeleton::new(js).expect("valid");
        assert!((s.dbh() - 0.34).abs() < 1e-6, "{}", s.dbh());
        // A trunk shorter than breast height: the diameter near its top.
        let short = Skeleton::new(vec![joint(NO_PARENT, 0.0, 1.0, 1.0)]).expect("valid");
        assert!((short.dbh() - 0.0).abs() < 1e-6, "tapers to nothing at its tip");
    }

    #[test]
    fn carried_mass_sums_everything_downstream() {
        let s = Skeleton::new(vec![
            joint(NO_PARENT, 0.0, 2.0, 10.0),
            joint(0, 2.0, 2.0, 5.0),
            joint(1, 4.0, 1.0, 1.0),
        ])
        .expect("valid");
        assert_eq!(s.carried_mass(2), 1.5);
        assert_eq!(s.carried_mass(1), 7.0);
        assert_eq!(s.carried_mass(0), 17.5);
        assert_eq!(s.children(0), &[1]);
    }

    #[test]
    fn bad_skeletons_are_refused_with_the_joint_named() {
        let e = Skeleton::new(vec![joint(NO_PARENT, 0.0, 1.0, 1.0), joint(1, 1.0, 1.0, 1.0)])
            .expect_err("self parent");
        assert_eq!(e, SkeletonError::ParentOrder { joint: 1, parent: 1 });
        let e = Skeleton::new(vec![joint(NO_PARENT, 0.0, -1.0, 1.0)]).expect_err("negative length");
        assert!(e.to_string().contains("length"));
        assert_eq!(Skeleton::new(vec![]), Err(SkeletonError::Empty));
    }

    #[test]
    fn frame_is_orthonormal_with_z_along_the_segment() {
        let mut j = joint(NO_PARENT, 0.0, 1.0, 1.0);
        for axis in [[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.0, -1.0, 0.0]] {
            j.axis = axis;
            let [x, y, z] = j.frame();
            let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
            assert!((dot(x, x) - 1.0).abs() < 1e-6 && (dot(y, y) - 1.0).abs() < 1e-6);
            assert!(dot(x, y).abs() < 1e-6 && dot(x, z).abs() < 1e-6 && dot(y, z).abs() < 1e-6);
            assert_eq!(z, axis);
        }
    }
}
