//! Instance groups by distance (the wind-field LOD's grouping): which trees of a species
//! share one simulation, given where the camera is.
//!
//! A species' trees are kept in Morton order of position, so every square of a quadtree over
//! the forest is a contiguous run of them. [`partition`] starts from the whole forest as
//! one group and keeps splitting the square that looks largest from the camera (its
//! diagonal plus a tree height, over its distance from the eye) into its four quarters,
//! while the groups fit the species' simulated instances. Squares near the camera are split
//! down to single trees; far ones stay large, so a group's size grows with its distance.
//! [`assign_slots`] then gives each new group the simulated instance most of its trees
//! already follow, so a regroup moves as few trees as possible.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// Morton code of a point on a square of `side` m centred on the origin: 16 bits per
/// axis, x in the even bits.
pub(crate) fn morton(x: f32, y: f32, side: f32) -> u64 {
    let q = |v: f32| (((v / side + 0.5).clamp(0.0, 1.0)) * 65535.0) as u64;
    let spread = |mut v: u64| {
        v &= 0xffff;
        v = (v | (v << 8)) & 0x00ff_00ff;
        v = (v | (v << 4)) & 0x0f0f_0f0f;
        v = (v | (v << 2)) & 0x3333_3333;
        (v | (v << 1)) & 0x5555_5555
    };
    spread(q(x)) | (spread(q(y)) << 1)
}

fn compact(mut v: u64) -> u64 {
    v &= 0x5555_5555;
    v = (v | (v >> 1)) & 0x3333_3333;
    v = (v | (v >> 2)) & 0x0f0f_0f0f;
    v = (v | (v >> 4)) & 0x00ff_00ff;
    (v | (v >> 8)) & 0xffff
}

/// Levels of the quadtree the 16-bit-per-axis codes resolve.
const DEPTH: u32 = 16;

/// A square of the quadtree: members `lo..hi` (in Morton order) share the top `2 depth`
/// bits of their codes.
#[derive(Debug, Clone, Copy)]
struct Cell {
    priority: f32,
    lo: usize,
    hi: usize,
    depth: u32,
}

impl PartialEq for Cell {
    fn eq(&self, other: &Cell) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Cell {}
impl PartialOrd for Cell {
    fn partial_cmp(&self, other: &Cell) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Cell {
    fn cmp(&self, other: &Cell) -> Ordering {
        // Largest-looking first; ties to the earlier run, so the order is total.
        self.priority.total_cmp(&other.priority).then(other.lo.cmp(&self.lo))
    }
}

/// How large the square of `codes[lo]` at `depth` looks from `eye`: its diagonal plus
/// `margin` (a tree's height), over the eye's distance from the square (≥ 1 m).
fn priority(code: u64, depth: u32, side: f32, eye: [f32; 3], margin: f32) -> f32 {
    let cells = (1u64 << depth) as f32;
    let size = side / cells;
    let shift = DEPTH - depth;
    let corner = |bits: u64| ((bits >> shift) as f32 / cells - 0.5) * side;
    let (x0, y0) = (corner(compact(code)), corner(compact(code >> 1)));
    let gap = |e: f32, lo: f32| (lo - e).max(e - (lo + size)).max(0.0);
    let (dx, dy) = (gap(eye[0], x0), gap(eye[1], y0));
    let d = (dx * dx + dy * dy + eye[2] * eye[2]).sqrt().max(1.0);
    (size * std::f32::consts::SQRT_2 + margin) / d
}

/// Cut the members (Morton `codes`, sorted ascending, on a square of `side` m) into at most
/// `slots` runs by distance from `eye`: squares that look largest are split first, and the
/// splitting stops at the first square whose quarters would not fit. Returns the runs
/// `(lo, hi)` in Morton order; they cover every member once.
pub(crate) fn partition(
    codes: &[u64],
    side: f32,
    eye: [f32; 3],
    margin: f32,
    slots: usize,
) -> Vec<(usize, usize)> {
    if codes.is_empty() {
        return Vec::new();
    }
    let cell = |lo: usize, hi: usize, depth: u32| Cell {
        priority: priority(codes[lo], depth, side, eye, margin),
        lo,
        hi,
        depth,
    };
    let mut heap = BinaryHeap::new();
    heap.push(cell(0, codes.len(), 0));
    let mut done = Vec::new();
    let slots = slots.max(1);
    while let Some(c) = heap.pop() {
        if c.hi - c.lo == 1 || c.depth == DEPTH {
            done.push((c.lo, c.hi));
            continue;
        }
        // The quarters: the next two bits below the shared prefix, contiguous in order.
        let shift = 2 * (DEPTH - c.depth - 1);
        let run = &codes[c.lo..c.hi];
        let mut bounds = [c.lo; 5];
        for (k, b) in bounds.iter_mut().enumerate().skip(1) {
            *b = c.lo + run.partition_point(|&v| ((v >> shift) & 3) < k as u64);
        }
        let quarters = bounds.windows(2).filter(|w| w[1] > w[0]).count();
        if done.len() + heap.len() + quarters > slots {
            // The first square that does not fit ends the splitting: what remains keeps
            // its size, so no farther square is split finer than a nearer one.
            done.push((c.lo, c.hi));
            done.extend(heap.drain().map(|c| (c.lo, c.hi)));
            break;
        }
        for w in bounds.windows(2).filter(|w| w[1] > w[0]) {
            heap.push(cell(w[0], w[1], c.depth + 1));
        }
    }
    done.sort_unstable();
    done
}

/// Give each run of `runs` (over `members`, tree indices) a simulated instance out of
/// `slots`: first, greedily, the instance most of its trees follow now (`current[t]`), then
/// the free ones in order. Returns the instance of each run.
pub(crate) fn assign_slots(
    runs: &[(usize, usize)],
    members: &[usize],
    current: impl Fn(usize) -> u32,
    slots: usize,
) -> Vec<u32> {
    // (trees already there, run, instance), most trees first.
    let mut votes: Vec<(usize, usize, u32)> = Vec::new();
    let mut tally: Vec<u32> = Vec::new();
    for (r, &(lo, hi)) in runs.iter().enumerate() {
        tally.clear();
        tally.extend(members[lo..hi].iter().map(|&t| current(t)));
        tally.sort_unstable();
        for same in tally.chunk_by(|a, b| a == b) {
            if (same[0] as usize) < slots {
                votes.push((same.len(), r, same[0]));
            }
        }
    }
    votes.sort_unstable_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut taken = vec![false; slots];
    let mut slot_of = vec![u32::MAX; runs.len()];
    for (_, r, s) in votes {
        if slot_of[r] == u32::MAX && !taken[s as usize] {
            slot_of[r] = s;
            taken[s as usize] = true;
        }
    }
    let mut free = (0..slots as u32).filter(|&s| !taken[s as usize]);
    for s in &mut slot_of {
        if *s == u32::MAX {
            *s = free.next().expect("no more runs than instances");
        }
    }
    slot_of
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Trees on a 40 × 40 grid 5 m apart, in Morton order.
    fn grid() -> (Vec<[f32; 2]>, Vec<u64>, f32) {
        let side = 220.0;
        let mut pts: Vec<([f32; 2], u64)> = (0..1600)
            .map(|k| {
                let p = [5.0 * (k % 40) as f32 - 97.5, 5.0 * (k / 40) as f32 - 97.5];
                (p, morton(p[0], p[1], side))
            })
            .collect();
        pts.sort_by_key(|&(_, c)| c);
        (pts.iter().map(|p| p.0).collect(), pts.iter().map(|p| p.1).collect(), side)
    }

    #[test]
    fn groups_fit_the_budget_cover_every_tree_and_grow_with_distance() {
        let (pts, codes, side) = grid();
        let eye = [-90.0, -90.0, 10.0];
        let runs = partition(&codes, side, eye, 15.0, 120);
        assert!(runs.len() <= 120 && runs.len() > 100, "{} groups", runs.len());
        let mut next = 0;
        for &(lo, hi) in &runs {
            assert_eq!(lo, next, "runs tile the members in order");
            next = hi;
        }
        assert_eq!(next, codes.len());
        // Group size against the distance of the group's first tree from the eye.
        let dist = |p: [f32; 2]| ((p[0] - eye[0]).powi(2) + (p[1] - eye[1]).powi(2)).sqrt();
        let mean_size = |near: f32, far: f32| {
            let s: Vec<usize> = runs
                .iter()
                .filter(|r| (near..far).contains(&dist(pts[r.0])))
                .map(|r| r.1 - r.0)
                .collect();
            s.iter().sum::<usize>() as f32 / s.len().max(1) as f32
        };
        assert_eq!(mean_size(0.0, 12.0), 1.0, "the trees next to the camera are alone");
        let (a, b, c) = (mean_size(0.0, 40.0), mean_size(40.0, 120.0), mean_size(120.0, 400.0));
        assert!(a < b && b < c, "sizes grow with distance: {a} {b} {c}");
    }

    #[test]
    fn a_budget_for_every_tree_gives_every_tree_its_own_simulation() {
        let (_, codes, side) = grid();
        let runs = partition(&codes, side, [0.0, 0.0, 30.0], 15.0, codes.len());
        assert!(runs.iter().all(|r| r.1 - r.0 == 1));
        assert_eq!(runs.len(), codes.len());
    }

    #[test]
    fn instances_follow_the_majority_of_their_trees() {
        // Trees 0..6 followed instance 2, trees 6..10 instance 0; regrouped into 0..4, 4..10.
        let now = [2, 2, 2, 2, 2, 2, 0, 0, 0, 0];
        let members: Vec<usize> = (0..10).collect();
        let slots = assign_slots(&[(0, 4), (4, 10)], &members, |t| now[t], 3);
        // Run 0..4 is all instance 2; run 4..10 has four of instance 0 and two of 2.
        assert_eq!(slots, vec![2, 0]);
        // More runs than the trees' instances: the rest take the free instances in order.
        let slots = assign_slots(&[(0, 2), (2, 4), (4, 10)], &members, |t| now[t], 3);
        assert_eq!(slots, vec![2, 1, 0]);
    }
}
