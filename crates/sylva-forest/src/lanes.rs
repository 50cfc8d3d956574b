//! Which lane of its species' sway batch each simulation runs in (the animation LOD's
//! packing).
//!
//! The batch steps instances in lane groups of [`LANES`], and a lane group steps the
//! longest joint prefix any of its lanes needs: one tree drawn at full detail among fifteen
//! impostors makes all sixteen simulate the whole crown. [`Packer::pack`] gathers simulations that
//! need the same prefix into the same lane groups — the wants sorted from the longest down
//! and dealt out to lane groups in turn, the groups that already hold the longest wants
//! first — while moving as few simulations as it can: in each lane group, a simulation whose
//! want is among the group's share stays where it is.

use sylva_sway::LANES;

/// Scratch for [`Packer::pack`]: once grown, packing allocates nothing.
#[derive(Debug, Default, Clone)]
pub(crate) struct Packer {
    dest: Vec<u32>,
    sorted: Vec<u32>,
    keys: Vec<([u32; LANES], usize)>,
    order: Vec<usize>,
    leaving: Vec<(u32, u32)>,
    open: Vec<(u32, u32)>,
    here: Vec<(u32, u32)>,
    wanted: Vec<u32>,
    after: Vec<u32>,
}

impl Packer {
    /// New lane of each lane's simulation: `want[l]` is the joint prefix the simulation in
    /// lane `l` needs next; the lanes are cut into groups of `LANES` (the last one possibly
    /// partial). The result is a permutation: lane `l`'s simulation moves to lane
    /// `result[l]`. Every lane group then holds a run of the wants sorted longest first
    /// (a partial group's run where it costs least), so the sum over groups of the longest
    /// want in each, times the group's lanes, is as small as any arrangement makes it.
    pub(crate) fn pack(&mut self, want: &[u32]) -> &mut [u32] {
        let Packer { dest, sorted, keys, order, leaving, open, here, wanted, after } = self;
        let lanes = want.len();
        let groups = lanes.div_ceil(LANES);
        dest.clear();
        dest.extend(0..lanes as u32);
        if groups <= 1 {
            return dest;
        }
        let range = |g: usize| g * LANES..lanes.min(g * LANES + LANES);
        sorted.clear();
        sorted.extend_from_slice(want);
        sorted.sort_unstable_by(|a, b| b.cmp(a));
        // Full lane groups that hold the longest wants now are dealt the longest: ranked by
        // their wants, longest first, compared in turn.
        let full = lanes / LANES;
        keys.clear();
        keys.extend((0..full).map(|g| {
            let mut k = [0u32; LANES];
            k.copy_from_slice(&want[range(g)]);
            k.sort_unstable_by(|a, b| b.cmp(a));
            (k, g)
        }));
        keys.sort_unstable_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
        order.clear();
        order.extend(keys.iter().map(|k| k.1));
        // A partial last group of c lanes goes where it costs least: dealt the run at 16 p,
        // it costs c · sorted[16 p], the full groups before it 16 · sorted[16 k] and those
        // after 16 · sorted[16 (k − 1) + c].
        let c = lanes - full * LANES;
        if c > 0 {
            let before = |k: usize| LANES as u64 * sorted[LANES * k] as u64;
            let after = |k: usize| LANES as u64 * sorted[LANES * (k - 1) + c] as u64;
            let mut tail: u64 = (1..=full).map(after).sum();
            let mut head = 0u64;
            let (mut best, mut at) = (u64::MAX, full);
            for p in 0..=full {
                if p > 0 {
                    head += before(p - 1);
                    tail -= after(p);
                }
                let cost = head + c as u64 * sorted[LANES * p] as u64 + tail;
                // Ties to the later place: a sorted layout stays as it is.
                if cost <= best {
                    (best, at) = (cost, p);
                }
            }
            order.insert(at, full);
        }
        // (want, lane) of the simulations that must move, and (want, lane) of the places
        // they leave, each to take one of the wants its group lacks.
        leaving.clear();
        open.clear();
        let mut start = 0;
        for &g in order.iter() {
            let r = range(g);
            let share = &sorted[start..start + r.len()];
            start += r.len();
            here.clear();
            here.extend(r.map(|l| (want[l], l as u32)));
            here.sort_unstable_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
            // Both lists longest first: what they have in common stays.
            let first = leaving.len();
            wanted.clear();
            let (mut i, mut j) = (0, 0);
            while i < here.len() || j < share.len() {
                match (here.get(i), share.get(j)) {
                    (Some(h), Some(&s)) if h.0 == s => {
                        i += 1;
                        j += 1;
                    }
                    (Some(h), Some(&s)) if h.0 < s => {
                        wanted.push(s);
                        j += 1;
                    }
                    (Some(&h), _) => {
                        leaving.push(h);
                        i += 1;
                    }
                    (None, Some(&s)) => {
                        wanted.push(s);
                        j += 1;
                    }
                    (None, None) => break,
                }
            }
            open.extend(wanted.iter().zip(&leaving[first..]).map(|(&w, &(_, l))| (w, l)));
        }
        // As many leave with each want as there are places for it: pair them up in order.
        leaving.sort_unstable();
        open.sort_unstable();
        for (&(w, from), &(v, to)) in leaving.iter().zip(open.iter()) {
            debug_assert_eq!(w, v);
            dest[from as usize] = to;
        }
        // Moving costs a copy of each moved simulation's state: only for a saving.
        after.clear();
        after.resize(lanes, 0);
        for (l, &d) in dest.iter().enumerate() {
            after[d as usize] = want[l];
        }
        if stepped(after) >= stepped(want) {
            dest.clear();
            dest.extend(0..lanes as u32);
        }
        dest
    }
}

/// Joint updates of lanes wanting `want`, 16 to a lane group, each group stepping its longest.
pub(crate) fn stepped(want: &[u32]) -> u64 {
    want.chunks(LANES).map(|c| c.iter().copied().max().unwrap_or(0) as u64 * c.len() as u64).sum()
}

/// Carry out the permutation `dest` (lane `l`'s simulation to lane `dest[l]`) as a sequence
/// of exchanges of two lanes, calling `swap(a, b)` for each; `dest` is left the identity.
/// Each exchange puts at least one simulation in its place.
pub(crate) fn apply(dest: &mut [u32], mut swap: impl FnMut(usize, usize)) {
    for l in 0..dest.len() {
        while dest[l] as usize != l {
            let to = dest[l] as usize;
            swap(l, to);
            dest.swap(l, to);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sylva_core::rng::SplitMix64;

    fn pack(want: &[u32]) -> Vec<u32> {
        Packer::default().pack(want).to_vec()
    }

    fn moved(want: &[u32]) -> Vec<u32> {
        let mut dest = pack(want);
        let mut w = want.to_vec();
        apply(&mut dest, |a, b| w.swap(a, b));
        w
    }

    #[test]
    fn packing_gathers_equal_wants_and_steps_no_more_than_sorting_would() {
        let mut rng = SplitMix64::new(7);
        // 100 simulations: a few near trees (full crown, 900 joints), some at a middle level,
        // most impostors (trunk, 12 joints) or out of view (0).
        let levels = [900u32, 300, 12, 0];
        let want: Vec<u32> = (0..100)
            .map(|_| {
                let u = rng.unit();
                levels[(u > 0.08) as usize + (u > 0.2) as usize + (u > 0.7) as usize]
            })
            .collect();
        let after = moved(&want);
        let mut a = after.clone();
        let mut b = want.clone();
        a.sort_unstable();
        b.sort_unstable();
        assert_eq!(a, b, "packing moves simulations, it does not change them");
        let mut best = want.clone();
        best.sort_unstable_by(|x, y| y.cmp(x));
        assert!(stepped(&after) <= stepped(&best), "no dearer than the wants sorted longest first");
        assert!(
            stepped(&after) * 2 < stepped(&want),
            "packed {} joint updates, scattered {}",
            stepped(&after),
            stepped(&want)
        );
    }

    #[test]
    fn simulations_already_packed_stay_and_a_change_moves_few() {
        // Sorted wants in full lane groups are packed already: nothing moves.
        let mut want: Vec<u32> = (0..64).map(|i| if i < 20 { 500 } else { 10 }).collect();
        assert!(pack(&want).iter().enumerate().all(|(l, &d)| d as usize == l));
        // One impostor in a far lane group comes near: it trades places with one simulation
        // of the partly full group, and nothing else moves.
        want[50] = 500;
        let dest = pack(&want);
        let moving: Vec<usize> = (0..64).filter(|&l| dest[l] as usize != l).collect();
        assert_eq!(moving.len(), 2, "moved: {moving:?}");
        assert_eq!(dest[50] / LANES as u32, 1, "the near tree joins the group of near trees");
        let after = moved(&want);
        assert_eq!(stepped(&after), 16 * 500 + 16 * 500 + 16 * 10 + 16 * 10);
    }

    #[test]
    fn nothing_moves_for_no_saving() {
        // Seventeen near trees in two lane groups: both groups step the whole crown however
        // they are spread, so gathering sixteen of them in one saves nothing; nothing moves.
        let want: Vec<u32> = (0..32).map(|i| if i % 2 == 0 || i == 1 { 500 } else { 10 }).collect();
        assert_eq!(want.iter().filter(|&&w| w == 500).count(), 17);
        assert!(pack(&want).iter().enumerate().all(|(l, &d)| d as usize == l));
        // With one near tree fewer, sixteen fit one lane group: they are gathered.
        let mut fewer = want.clone();
        fewer[0] = 10;
        assert_eq!(stepped(&moved(&fewer)), 16 * 500 + 16 * 10);
    }

    #[test]
    fn a_partial_last_group_and_a_single_group_are_handled() {
        assert_eq!(pack(&[3, 1, 2]), vec![0, 1, 2], "one lane group: nothing to gain");
        assert!(pack(&[]).is_empty());
        // 17 lanes: the lone lane of the partial group is the one near tree, the cheapest
        // place for it (16 + 100 joint updates); it stays.
        let mut want = vec![1u32; 17];
        want[16] = 100;
        assert!(pack(&want).iter().enumerate().all(|(l, &d)| d as usize == l));
        // The near tree elsewhere: it moves to the lone lane, and one far tree to its place.
        want.swap(3, 16);
        let after = moved(&want);
        assert_eq!(stepped(&after), 16 + 100, "{after:?}");
    }
}
