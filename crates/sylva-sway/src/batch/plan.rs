//! How a step splits each lane group's lanes: which to step alone (in a row of their own)
//! and to which prefix the rest go together, by a cost model of a joint at each width.

use super::{LANES, Lump, Row, STATE_BYTES, SwayBatch};

/// How a step splits one group's lanes.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Plan {
    /// Per lane: the prefix it keeps switched on, and the one it is stepped to at least
    /// (its joints beyond are at rest).
    pub(super) on: [u32; LANES],
    pub(super) need: [u32; LANES],
    /// The prefix the group steps its lanes to together, and the lanes stepped alone (a
    /// bit each).
    pub(super) head: u32,
    pub(super) solo: u32,
}

impl SwayBatch {
    /// Decide each group's split for the step: per lane the prefix it keeps on and the one
    /// it must be stepped to, and which lanes go alone — within the rows' byte limit,
    /// served in group order so that the outcome does not depend on threads.
    pub(super) fn plan(&mut self) {
        let (ni, w) = (self.instances, self.width);
        let mut left = self.alone_limit;
        self.plans.resize(self.blocks.len(), Plan::default());
        for (g, plan) in self.plans.iter_mut().enumerate() {
            let p = self.group_prefix[g] as usize;
            let k = (self.fading_to[g] as usize).min(p);
            let used = w.min(ni - g * LANES);
            let mut on = [k as u32; LANES];
            let mut need = [0usize; LANES];
            for l in 0..used {
                let i = g * LANES + l;
                on[l] = on[l].min(self.lane_request[i]);
                need[l] = (self.lane_moving[i].max(on[l]) as usize).min(p);
            }
            let (mut head, mut solo) = plan_lanes(&need[..used], w);
            // Bytes of the rows the lanes alone will hold (a row is kept, not shrunk).
            let rows = &self.blocks[g].rows;
            let bytes: usize = (0..used)
                .filter(|&l| solo >> l & 1 == 1)
                .map(|l| (STATE_BYTES * need[l]).max(4 * rows.get(l).map_or(0, Row::capacity)))
                .sum();
            if bytes > left {
                (head, solo) = (need[..used].iter().copied().max().unwrap_or(0), 0);
            } else {
                left -= bytes;
            }
            *plan = Plan { on, need: need.map(|x| x as u32), head: head as u32, solo };
        }
    }
}

/// The smallest registered prefix holding `joints` joints (every joint, `n`, if none does).
pub(super) fn round_up(lumped: &[(usize, Vec<Lump>)], n: usize, joints: usize) -> usize {
    lumped.iter().map(|(q, _)| *q).filter(|&q| q >= joints).min().unwrap_or(n).min(n)
}

/// Relative cost of one joint of a group step at 4, 8 and 16 lanes, against one lane
/// alone: what a wide group saves is memory traffic more than arithmetic. Defaults
/// measured once with `sylva bench sway --instances N` (a black tupelo at 1, 4, 8 and 16
/// lanes on an AVX-512 Xeon); the plan only compares costs, so they need to hold as
/// ratios, not as times, and a machine where they differ steps the same trees with a
/// slightly different split of lanes — never a different result.
pub(super) const COST_AT_4_LANES: f32 = 3.0;
pub(super) const COST_AT_8_LANES: f32 = 3.2;
pub(super) const COST_AT_16_LANES: f32 = 4.4;

/// Relative cost of one joint of a group step at `width` lanes (see [`COST_AT_4_LANES`]).
pub(super) fn width_cost(width: usize) -> f32 {
    match width {
        0..=1 => 1.0,
        2..=4 => COST_AT_4_LANES,
        5..=8 => COST_AT_8_LANES,
        _ => COST_AT_16_LANES,
    }
}

/// Relative cost of one joint of a lane stepped alone within its group, against a batch
/// of one: one lane's step, and the copies of its state into its row when it goes alone
/// and back when it rejoins (see `Row`). A default measured as [`COST_AT_4_LANES`] (a
/// black tupelo alone in a group of eight against a batch of its own), on the cautious
/// side: a lower figure sends more lanes alone, each with a row of palettes, for no
/// measured gain.
pub(super) const ALONE_COST: f32 = 1.7;

/// Which lanes of a group to step alone: (the prefix the group steps every lane to, a bit
/// per lane stepped alone). From the joints each lane must be stepped to, the cheapest of
/// stepping the `m` longest alone and the rest together, for every `m` (none alone: the
/// longest, as a group always stepped).
pub(super) fn plan_lanes(need: &[usize], width: usize) -> (usize, u32) {
    let mut order: [usize; LANES] = std::array::from_fn(|l| l);
    let order = &mut order[..need.len()];
    order.sort_by_key(|&l| std::cmp::Reverse(need[l]));
    let together = width_cost(width);
    let (mut best, mut best_m, mut alone) = (f32::INFINITY, 0, 0.0);
    for m in 0..=order.len() {
        let head = order.get(m).map_or(0, |&l| need[l]);
        let cost = together * head as f32 + alone;
        if cost < best {
            (best, best_m) = (cost, m);
        }
        if let Some(&l) = order.get(m) {
            alone += ALONE_COST * need[l] as f32;
        }
    }
    let head = order.get(best_m).map_or(0, |&l| need[l]);
    (head, order[..best_m].iter().fold(0, |b, &l| b | 1 << l))
}
