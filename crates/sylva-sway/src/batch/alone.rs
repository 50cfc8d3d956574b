//! One lane stepped on its own: a batch of one instance, or a lane a group steps alone.
//!
//! The same IEEE operations, in the same order for every value, as [`step_group`] at width
//! 1 — an instance moves bit for bit as it does in any group — with the passes split by
//! what depends on what. Across lanes there is nothing to vectorise at width 1, but across
//! joints most of the step is independent: a joint's own drag, its spring and its local
//! rotation need nothing from any other joint. Only two short sweeps are chained along the
//! skeleton: the loads passed from tips inwards, and the palettes composed root outwards.
//! Kept apart from the rest, those independent parts run as plain loops over the joints,
//! which the processor overlaps (the spring pass in chunks of 16 joints gathered into lane
//! arrays, which the compiler vectorises), where the fused sweep made each joint wait for
//! the one before it. On a large skeleton (a near crown of thousands of joints) those two
//! passes run in runs of joints on several threads, and the two sweeps bin by bin of the
//! species' [`Cut`] (whole subtrees, each bin swept on a thread of its own, the few joints
//! above them swept alone): each joint's arithmetic, and the order of every sum, is the
//! same wherever it runs, so the result is the same bits for any number of threads.
//!
//! [`Cut`]: crate::species::Cut
//!
//! [`step_group`]: super::step_group

use std::marker::PhantomData;

use rayon::prelude::*;
use sylva_core::simd_kernel;
use sylva_core::v3::dot;

use super::{
    Group, JointWind, LANES, Lanes, Lump, MAX_BEND, add_held, any_angle, compose, held_wind,
    lever_factors, local_palette, own_drag, pass_on, pass_to_parent, small_angle,
};
use crate::species::{SwaySpecies, Transition};

/// Joints per chunk of the spring pass.
const CHUNK: usize = 16;

/// A skeleton of at least twice this many joints has its independent passes split into
/// runs of joints, stepped in parallel (runs of 1 024 were no faster on scene D), and its
/// sweeps stepped bin by bin.
const RUN: usize = 2048;

/// A run of joints, from joint `first`: their state and what the passes write.
struct Part<'s, const W: usize> {
    first: usize,
    theta: &'s mut [[[f32; W]; 2]],
    rate: &'s mut [[[f32; W]; 2]],
    weight: &'s mut [[f32; W]],
    loads: &'s mut [[[f32; W]; 6]],
    lanes: &'s mut [[[f32; W]; 12]],
}

impl<'s, const W: usize> Part<'s, W> {
    /// The first `n` joints of `st`.
    fn of(st: &'s mut Group<'_, W>, n: usize) -> Self {
        Part {
            first: 0,
            theta: &mut st.theta[..n],
            rate: &mut st.rate[..n],
            weight: &mut st.weight[..n],
            loads: &mut st.loads[..n],
            lanes: &mut st.lanes[..n],
        }
    }

    fn len(&self) -> usize {
        self.theta.len()
    }

    /// The first `m` joints, and the rest.
    fn split(self, m: usize) -> (Self, Self) {
        let (theta, theta_b) = self.theta.split_at_mut(m);
        let (rate, rate_b) = self.rate.split_at_mut(m);
        let (weight, weight_b) = self.weight.split_at_mut(m);
        let (loads, loads_b) = self.loads.split_at_mut(m);
        let (lanes, lanes_b) = self.lanes.split_at_mut(m);
        let first = self.first;
        (
            Part { first, theta, rate, weight, loads, lanes },
            Part {
                first: first + m,
                theta: theta_b,
                rate: rate_b,
                weight: weight_b,
                loads: loads_b,
                lanes: lanes_b,
            },
        )
    }
}

/// `f` on `part`, halved into parallel halves while they hold two runs.
fn in_runs<const W: usize>(part: Part<'_, W>, f: &(impl Fn(Part<'_, W>) + Sync)) {
    let n = part.len();
    if n >= 2 * RUN {
        let (a, b) = part.split(n / 2);
        rayon::join(|| in_runs(a, f), || in_runs(b, f));
    } else {
        f(part);
    }
}

simd_kernel! {
    /// Step lane 0 of `st` (`W` is 1: the lane layout of a group of one).
    pub(super) fn step<const W: usize>(
        sp: &SwaySpecies,
        tr: &[Transition],
        aero: &[f32],
        blend: f32,
        bud: &[u32; LANES],
        u: &[Lanes; 3],
        st: &mut Group<'_, W>,
    ) {
        debug_assert_eq!(W, 1);
        let n = st.active.min(st.theta.len());
        let inv_ur = 1.0 / sp.params.leaf_reconfiguration_speed;
        let (on, bud) = (st.on[0] as usize, bud[0]);
        // (1a) Each joint's own drag and its moment about the joint, kept in the joint's
        // palette slot (free until pass 2 writes it).
        let (shelter, mean) = (st.shelter, st.mean);
        in_runs(Part::of(st, n), &|part| drags::<W>(sp, aero, inv_ur, u, (&shelter, &mean), part));
        // (1b) Tips inwards: a joint's loads are its subtree's (added by its children, all
        // after it), then its own, then the lumped drag of the joints held beyond it; they
        // pass to its parent.
        let q = held_wind::<W>(u, inv_ur);
        if n >= 2 * RUN {
            loads_in_bins::<W>(sp, n, st.held, &q, &st.shelter, st.lanes, st.loads);
        } else {
            for i in (0..n).rev() {
                let f = sp.wind_factor::<W>(i, &st.shelter);
                gather::<W>(&mut st.loads[i], &st.lanes[i], st.held, i, &q, f.as_ref());
                pass_to_parent::<W>(sp, st.loads, i);
            }
        }
        // (2) Springs and blend weights, then each joint's rotation about its rest position
        // (T(o) R_i T(−o)) into its palette slot; the loads cleared for the next step.
        in_runs(Part::of(st, n), &|part| springs::<W>(sp, tr, blend, on, bud, part));
        // (3) Palettes, root outwards: M_i = M_parent · (T(o) R_i T(−o)).
        // On a large skeleton, the cut's top first, then its bins on their threads.
        let place_at = |lanes: &mut [[[f32; W]; 12]], i: usize| {
            let p = sp.parent[i];
            if p != sylva_tree::NO_PARENT {
                let (before, rest) = lanes.split_at_mut(i);
                place::<W>(&before[p as usize], &mut rest[0]);
            }
        };
        if n >= 2 * RUN {
            let top = &sp.cut.top;
            for &i in &top[..top.partition_point(|&j| (j as usize) < n)] {
                place_at(st.lanes, i as usize);
            }
            let rows = Rows::new(st.lanes);
            sp.cut.bins.par_iter().for_each(|bin| {
                bin_palettes::<W>(sp, &bin[..bin.partition_point(|&j| (j as usize) < n)], &rows);
            });
        } else {
            for i in 0..n {
                place_at(st.lanes, i);
            }
        }
    }
}

/// A joint's loads `li` take its own drag (the first six rows of its palette slot `own`)
/// and the lumped drag of the joints `held` beyond joint `i`, in the wind `q` (times the
/// joint's height factor `f`).
#[inline(always)]
fn gather<const W: usize>(
    li: &mut [[f32; W]; 6],
    own: &[[f32; W]; 12],
    held: Option<&[Lump]>,
    i: usize,
    q: &[[[f32; W]; 3]; 2],
    f: Option<&JointWind<W>>,
) {
    for c in 0..6 {
        li[c][0] += own[c][0];
    }
    if let Some(held) = held {
        add_held::<W>(li, &held[i], q, f);
    }
}

/// A joint's palette slot `local`, holding its rotation about its rest position, becomes its
/// palette: its parent's palette `parent` composed with it.
#[inline(always)]
fn place<const W: usize>(parent: &[[f32; W]; 12], local: &mut [[f32; W]; 12]) {
    let m = compose(&std::array::from_fn(|e| parent[e][0]), &std::array::from_fn(|e| local[e][0]));
    for (e, x) in m.into_iter().enumerate() {
        local[e][0] = x;
    }
}

/// Rows of one slice that the threads stepping the bins of a [`Cut`] reach at once: each
/// thread writes the joints of its own bin only, and reads those and the cut's top, which no
/// thread writes meanwhile.
///
/// [`Cut`]: crate::species::Cut
struct Rows<'s, T> {
    ptr: *mut T,
    len: usize,
    rows: PhantomData<&'s mut [T]>,
}

// SAFETY: a `Rows` is only reached through `row` and `row_mut`, whose callers keep the
// threads on disjoint rows.
unsafe impl<T: Send> Sync for Rows<'_, T> {}

impl<'s, T> Rows<'s, T> {
    fn new(rows: &'s mut [T]) -> Self {
        Rows { ptr: rows.as_mut_ptr(), len: rows.len(), rows: PhantomData }
    }

    /// Row `i`, to read.
    ///
    /// # Safety
    /// No thread writes row `i` while the reference lives.
    unsafe fn row(&self, i: usize) -> &T {
        assert!(i < self.len, "row {i} of {}", self.len);
        // SAFETY: in bounds; the caller keeps writers off row `i`.
        unsafe { &*self.ptr.add(i) }
    }

    /// Row `i`, to write.
    ///
    /// # Safety
    /// No other reference to row `i` lives while this one does.
    #[allow(clippy::mut_from_ref)]
    unsafe fn row_mut(&self, i: usize) -> &mut T {
        assert!(i < self.len, "row {i} of {}", self.len);
        // SAFETY: in bounds; the caller keeps every other reference off row `i`.
        unsafe { &mut *self.ptr.add(i) }
    }
}

/// Pass (1b) of [`step`] on a large skeleton, the first `n` joints: each bin of the
/// species' [`Cut`] tips inwards on its own thread, its subtrees' roots keeping their loads;
/// then the seam, tips inwards, the roots passing theirs on. A joint's loads take its
/// children's in the order one sweep over all the joints takes them (descending index), so
/// the bits are the same.
///
/// [`Cut`]: crate::species::Cut
fn loads_in_bins<const W: usize>(
    sp: &SwaySpecies,
    n: usize,
    held: Option<&[Lump]>,
    q: &[[[f32; W]; 3]; 2],
    shelter: &[f32; LANES],
    lanes: &[[[f32; W]; 12]],
    loads: &mut [[[f32; W]; 6]],
) {
    let cut = &sp.cut;
    {
        let rows = Rows::new(loads);
        cut.bins.par_iter().for_each(|bin| {
            let bin = &bin[..bin.partition_point(|&j| (j as usize) < n)];
            bin_loads::<W>(sp, held, q, shelter, lanes, bin, &rows);
        });
    }
    let seam = &cut.seam[..cut.seam.partition_point(|&j| (j as usize) < n)];
    for &i in seam.iter().rev() {
        let i = i as usize;
        if cut.in_top[i] {
            let f = sp.wind_factor::<W>(i, shelter);
            gather::<W>(&mut loads[i], &lanes[i], held, i, q, f.as_ref());
        }
        pass_to_parent::<W>(sp, loads, i);
    }
}

simd_kernel! {
    /// The loads of one bin's joints, tips inwards (see [`loads_in_bins`]).
    fn bin_loads<const W: usize>(
        sp: &SwaySpecies,
        held: Option<&[Lump]>,
        q: &[[[f32; W]; 3]; 2],
        shelter: &[f32; LANES],
        lanes: &[[[f32; W]; 12]],
        bin: &[u32],
        rows: &Rows<'_, [[f32; W]; 6]>,
    ) {
        for &i in bin.iter().rev() {
            let i = i as usize;
            // SAFETY: joint `i` is in this bin alone, and so is its parent unless the parent
            // is in the top (which this pass does not touch); the parent precedes `i`.
            let li = unsafe { rows.row_mut(i) };
            let f = sp.wind_factor::<W>(i, shelter);
            gather::<W>(li, &lanes[i], held, i, q, f.as_ref());
            let p = sp.parent[i];
            if p != sylva_tree::NO_PARENT && !sp.cut.in_top[p as usize] {
                // SAFETY: as above: the parent is in this bin, and is not joint `i`.
                let lp = unsafe { rows.row_mut(p as usize) };
                pass_on::<W>(sp, i, li, p as usize, lp);
            }
        }
    }
}

simd_kernel! {
    /// The palettes of one bin's joints, root outwards, the top's being done.
    fn bin_palettes<const W: usize>(sp: &SwaySpecies, bin: &[u32], rows: &Rows<'_, [[f32; W]; 12]>) {
        for &i in bin {
            let i = i as usize;
            let p = sp.parent[i];
            if p != sylva_tree::NO_PARENT {
                // SAFETY: the parent is in the top, which no thread writes now, or earlier in
                // this bin, which this thread alone writes; joint `i` is in this bin alone.
                let (parent, local) = unsafe { (rows.row(p as usize), rows.row_mut(i)) };
                place::<W>(parent, local);
            }
        }
    }
}

simd_kernel! {
    /// Pass (1a) of [`step`] on a run of joints.
    fn drags<const W: usize>(
        sp: &SwaySpecies,
        aero: &[f32],
        inv_ur: f32,
        u: &[Lanes; 3],
        wind_at: (&[f32; LANES], &[Lanes; 3]),
        part: Part<'_, W>,
    ) {
        let (shelter, mean) = wind_at;
        for (j, lanes) in part.lanes.iter_mut().enumerate() {
            let own = (&mut lanes[..6]).try_into().expect("six rows");
            let i = part.first + j;
            let f = sp.wind_factor::<W>(i, shelter);
            own_drag::<W, false>(sp, aero, inv_ur, u, f.as_ref().map(|f| (f, mean)), i, &part.rate[j], &part.weight[j], own);
        }
    }
}

simd_kernel! {
    /// Pass (2) of [`step`] on a run of joints (of lane 0 of `W` = 1), in chunks of joints
    /// gathered into lane arrays, so the loops vectorise across joints (a chunk's lanes past
    /// the last joint compute on zeros and are not written back). Joints from `on` and
    /// those ranked from `bud` on are switched off.
    fn springs<const W: usize>(
        sp: &SwaySpecies,
        tr: &[Transition],
        blend: f32,
        on: usize,
        bud: u32,
        part: Part<'_, W>,
    ) {
        let n = part.len();
        let run = part.first..part.first + n;
        let (tr, axes) = (&tr[run.clone()], &sp.axes[run.clone()]);
        let (rank, origin) = (&sp.rank[run.clone()], &sp.origin[run]);
        for first in (0..n).step_by(CHUNK) {
            let m = CHUNK.min(n - first);
            let joints = first..first + m;
            let mut eqs = [[0.0f32; CHUNK]; 2];
            let mut th = [[0.0f32; CHUNK]; 2];
            let mut ra = [[0.0f32; CHUNK]; 2];
            let mut w = [0.0f32; CHUNK];
            let mut a = [[0.0f32; CHUNK]; 4];
            let mut axis = [[[0.0f32; CHUNK]; 3]; 2];
            let mut active = [false; CHUNK];
            for (j, i) in joints.clone().enumerate() {
                let (t, li, [ax, ay]) = (&tr[i], &part.loads[i], axes[i]);
                let mom = [li[3][0], li[4][0], li[5][0]];
                eqs[0][j] = dot(mom, ax) * t.inv_k;
                eqs[1][j] = dot(mom, ay) * t.inv_k;
                for c in 0..2 {
                    th[c][j] = part.theta[i][c][0];
                    ra[c][j] = part.rate[i][c][0];
                }
                w[j] = part.weight[i][0];
                a[0][j] = t.a11;
                a[1][j] = t.a12;
                a[2][j] = t.a21;
                a[3][j] = t.a22;
                for c in 0..3 {
                    axis[0][c][j] = ax[c];
                    axis[1][c][j] = ay[c];
                }
                active[j] = part.first + i < on && rank[i] < bud;
                part.loads[i] = [[0.0; W]; 6];
            }
            // The Newton step only where a joint of the chunk needs it, as a group does.
            let mut e2 = [0.0f32; CHUNK];
            for j in 0..CHUNK {
                e2[j] = eqs[0][j] * eqs[0][j] + eqs[1][j] * eqs[1][j];
            }
            let f = lever_factors(&e2);
            for j in 0..CHUNK {
                eqs[0][j] *= f[j];
                eqs[1][j] *= f[j];
            }
            for j in 0..CHUNK {
                let restart = active[j] && w[j] == 0.0;
                for c in 0..2 {
                    let eq = eqs[c][j];
                    let x = if restart { 0.0 } else { th[c][j] - eq };
                    let v = if restart { 0.0 } else { ra[c][j] };
                    let (nx, nv) = (a[0][j] * x + a[1][j] * v + eq, a[2][j] * x + a[3][j] * v);
                    th[c][j] = if active[j] { nx } else { th[c][j] };
                    ra[c][j] = if active[j] { nv } else { ra[c][j] };
                }
                let b2 = th[0][j] * th[0][j] + th[1][j] * th[1][j];
                let over = b2 > MAX_BEND * MAX_BEND;
                let k = if over { MAX_BEND / b2.sqrt() } else { 1.0 };
                th[0][j] *= k;
                th[1][j] *= k;
                ra[0][j] = if over { 0.0 } else { ra[0][j] };
                ra[1][j] = if over { 0.0 } else { ra[1][j] };
                w[j] = if active[j] { (w[j] + blend).min(1.0) } else { (w[j] - blend).max(0.0) };
            }
            let mut phi = [[0.0f32; CHUNK]; 3];
            let mut a2 = [0.0f32; CHUNK];
            let mut large = false;
            for j in 0..CHUNK {
                let (t0, t1) = (w[j] * th[0][j], w[j] * th[1][j]);
                for c in 0..3 {
                    phi[c][j] = t0 * axis[0][c][j] + t1 * axis[1][c][j];
                }
                a2[j] = phi[0][j] * phi[0][j] + phi[1][j] * phi[1][j] + phi[2][j] * phi[2][j];
                // (As `a2 < 0.25` decides it below: NaN takes the formula for any angle.)
                large |= a2[j] >= 0.25 || a2[j].is_nan();
            }
            // The formula for any angle only where a joint of the chunk turns that far: each
            // joint takes the series below a² = 0.25 whichever way the chunk goes.
            let mut sc = [[0.0f32; CHUNK]; 2];
            for j in 0..CHUNK {
                (sc[0][j], sc[1][j]) = small_angle(a2[j]);
            }
            if large {
                for j in 0..CHUNK {
                    let any = any_angle(a2[j]);
                    (sc[0][j], sc[1][j]) = if a2[j] < 0.25 { (sc[0][j], sc[1][j]) } else { any };
                }
            }
            for (j, i) in joints.enumerate() {
                for c in 0..2 {
                    part.theta[i][c][0] = th[c][j];
                    part.rate[i][c][0] = ra[c][j];
                }
                part.weight[i][0] = w[j];
                let ph = [phi[0][j], phi[1][j], phi[2][j]];
                let local = local_palette(ph, origin[i], sc[0][j], sc[1][j]);
                for (e, x) in local.into_iter().enumerate() {
                    part.lanes[i][e][0] = x;
                }
            }
        }
    }
}
