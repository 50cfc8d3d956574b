//! Instance groups formed again as the camera travels: which trees share a simulation, and
//! the cross-fade of a tree that changed group (see the `driver` module's documentation).

use sylva_tree::WIND_SAMPLE_HEIGHT;

use crate::groups::{assign_slots, partition};
use crate::scene::Placement;

use super::{Forest, Group};

/// Seconds over which a tree that changes instance group cross-fades from its old
/// simulation to its new one; also the shortest time between two regroupings.
pub const REGROUP_FADE: f32 = 1.0;

/// Camera travel, m, after which instance groups are formed again for the new viewpoint.
pub const REGROUP_TRAVEL: f32 = 2.0;

/// A tree's last change of instance group: the group it left (`u32::MAX`: none) and when.
#[derive(Debug, Clone, Copy)]
pub(super) struct Switch {
    pub(super) from: u32,
    pub(super) at: f64,
}

impl Switch {
    pub(super) const NONE: Switch = Switch { from: u32::MAX, at: 0.0 };

    /// Weight of the new group at time `t` and the old group, while fading over `fade` s.
    pub(super) fn fading(&self, t: f64, fade: f32) -> Option<(f32, u32)> {
        // Past the fade (or none), without the division: the quotient of a ≥ b > 0 is ≥ 1.
        if self.from == u32::MAX || !(fade > 0.0 && t - self.at < fade as f64) {
            return None;
        }
        let w = ((t - self.at) / fade as f64) as f32;
        (w < 1.0).then_some((w.max(0.0), self.from))
    }
}

/// Put the trees of `runs` (over `members`) in the instance groups `slots`, move each
/// group's wind sample point to its trees' crowns, and report each tree that changed group
/// to `moved(tree, old group)`. Groups without a run keep their sample point.
pub(super) fn regroup_species(
    trees: &mut [(Placement, u32)],
    groups: &mut [Group],
    members: &[usize],
    runs: &[(usize, usize)],
    slots: &[u32],
    height: f32,
    mut moved: impl FnMut(usize, u32),
) {
    for (&(lo, hi), &g) in runs.iter().zip(slots) {
        let group = &mut groups[g as usize];
        let mut c = [0.0f64; 3];
        for &t in &members[lo..hi] {
            let old = trees[t].1;
            if old != g {
                moved(t, old);
            }
            trees[t].1 = g;
            trees[t].0.yaw = group.yaw;
            let p = trees[t].0;
            c[0] += p.position[0] as f64;
            c[1] += p.position[1] as f64;
            c[2] += (p.position[2] + WIND_SAMPLE_HEIGHT as f32 * height * p.scale) as f64;
        }
        let k = (hi - lo).max(1) as f64;
        group.sample = [c[0] / k, c[1] / k, c[2] / k];
    }
}

impl Forest {
    /// Form the instance groups again if the camera has moved on (see the module
    /// documentation): called by [`Forest::step`].
    pub(super) fn regroup(&mut self) {
        let Some(eye) = self.eye else { return };
        let (at, when) = self.grouped;
        let travel = (0..3).map(|i| (eye[i] - at[i]).powi(2)).sum::<f32>().sqrt();
        if !self.spec.lod.wind || travel < REGROUP_TRAVEL || self.time - when < REGROUP_FADE as f64
        {
            return;
        }
        self.grouped = (eye, self.time);
        let side = self.spec.side();
        let (now, switches) = (self.time, &mut self.switches);
        for s in &mut self.species {
            if s.groups.len() >= s.members.len() {
                continue;
            }
            let height = s.model.tree.stats.height;
            let runs = partition(&s.codes, side, eye, height, s.groups.len());
            let trees = &self.trees;
            let slots = assign_slots(&runs, &s.members, |t| trees[t].1, s.groups.len());
            regroup_species(
                &mut self.trees,
                &mut s.groups,
                &s.members,
                &runs,
                &slots,
                height,
                |t, from| switches[t] = Switch { from, at: now },
            );
        }
    }

    /// Seconds over which a tree that changes instance group cross-fades from its old
    /// simulation to its new one (default [`REGROUP_FADE`]; 0 switches at once, as a
    /// comparison for measuring popping). Clamped to 0 … 10.
    pub fn set_regroup_fade(&mut self, seconds: f32) {
        self.regroup_fade =
            if seconds.is_finite() { seconds.clamp(0.0, 10.0) } else { REGROUP_FADE };
    }
}
