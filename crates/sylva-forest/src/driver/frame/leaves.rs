//! The leaves of the forest's cells in pass 1 ([`Forest::classify`]): each with its own run
//! and slice of the trees' states, in parallel; a far leaf's thinned-out trees decided at
//! once.

use super::{FrameStats, TreeRun, View};
use crate::cells::Cell;
use crate::driver::Forest;
use crate::driver::lod::{THIN_BAND, THIN_MIN_KEEP, lod_cap};

impl Forest {
    /// For a leaf wholly in view whose every tree is surely past its LOD cap and thinned
    /// by the same rule (`View::thin`): how many of its trees in draw order
    /// ([`crate::cells::Cells::by_draw`]) the thinning may keep; the rest it surely leaves
    /// out (their draws are at least the largest keep any of them may have: the one of the
    /// leaf's tallest tree at the leaf's nearest point). `None` where the leaf is to be
    /// classified tree by tree. Margins of a thousandth keep it within the per-tree tests'
    /// rounding.
    pub(super) fn thinned_out(&self, view: &View, cell: &Cell) -> Option<usize> {
        if view.thin <= 0.0 || view.lod.occlusion || !self.leaf_shortcut {
            return None;
        }
        let (dist, depth) = view.cone.holds(cell.centre, 1.001 * cell.radius + 0.01)?;
        let fraction = view.cone.fraction_at(cell.tallest, depth);
        if !(depth > 0.0 && fraction < 0.999 * view.least_past_cap) {
            return None;
        }
        // (At or above the threshold, or not a number, thinning keeps every tree.)
        let s = view.cone.fraction_at(cell.tallest, dist) / view.thin;
        if s.is_nan() || s >= 1.0 {
            return None;
        }
        let keep = 1.001 * (s * s).max(THIN_MIN_KEEP) * (1.0 + THIN_BAND);
        Some(self.cells.draws[cell.trees()].partition_point(|&u| u < keep))
    }

    /// For a far leaf whose thinning keeps at most `kept` of its trees in draw order
    /// ([`Forest::thinned_out`]): the rest are counted thinned and, those not yet at their
    /// cap in this view (`settled`: from where in draw order they are), go there, as a tree
    /// the thinning leaves out does (`classify_tree`); the others go to `run.kept` in tree
    /// order, marked in view, for the caller to classify.
    pub(super) fn settle_far_leaf(
        &self,
        view: &View,
        cell: &Cell,
        kept: usize,
        (states, settled): (&mut [f32], &mut u32),
        run: &mut TreeRun,
    ) {
        let (first, order) = (cell.first as usize, &self.cells.by_draw[cell.trees()]);
        let thinned = order.len() - kept;
        run.stats = FrameStats { thinned, thinned_by_leaf: thinned, ..FrameStats::default() };
        for &t in &order[kept..(*settled as usize).max(kept)] {
            let (k, species) = (t as usize - first, self.trees[t as usize].0.species);
            let x = lod_cap(view.far[species as usize]);
            if !states[k].is_nan() && states[k] as u32 != x as u32 {
                run.stats.level_changes += 1;
            }
            states[k] = x;
        }
        *settled = kept as u32;
        // In tree order, as the trees of a leaf are classified (their draws listed in the same
        // order as tree by tree; memory read in order).
        run.kept.clear();
        run.kept.extend_from_slice(&order[..kept]);
        run.kept.sort_unstable();
        for &t in &run.kept {
            run.seen[t as usize - first] = true;
        }
    }
}

/// `f(run, states, settled, cell)` for each leaf of `leaves` (cell indices into `cells`,
/// ascending) with its own run, its trees' slice of `states` and its entry of `settled`
/// (per leaf), the slices starting at tree and leaf `offset`: the leaves split in halves,
/// the halves in parallel.
pub(super) fn each_leaf<F>(
    (runs, states, settled): (&mut [TreeRun], &mut [f32], &mut [u32]),
    offset: (usize, usize),
    (leaves, cells): (&[u32], &[Cell]),
    f: &F,
) where
    F: Fn(&mut TreeRun, &mut [f32], &mut u32, &Cell) + Sync,
{
    match leaves {
        [] => {}
        [leaf] => {
            let cell = &cells[*leaf as usize];
            let span = cell.trees();
            let states = &mut states[span.start - offset.0..span.end - offset.0];
            f(&mut runs[0], states, &mut settled[cell.leaf as usize - offset.1], cell)
        }
        _ => {
            let mid = leaves.len() / 2;
            let cell = &cells[leaves[mid] as usize];
            let at = (cell.first as usize, cell.leaf as usize);
            let (sa, sb) = states.split_at_mut(at.0 - offset.0);
            let (la, lb) = settled.split_at_mut(at.1 - offset.1);
            let (ra, rb) = runs.split_at_mut(mid);
            rayon::join(
                || each_leaf((ra, sa, la), offset, (&leaves[..mid], cells), f),
                || each_leaf((rb, sb, lb), at, (&leaves[mid..], cells), f),
            );
        }
    }
}
