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
//! passes run in runs of joints on several threads: each joint's arithmetic is the same
//! wherever it runs, so the result is the same bits for any number of threads.
//!
//! [`step_group`]: super::step_group

use sylva_core::simd_kernel;
use sylva_core::v3::dot;

use super::{
    Group, LANES, LEVER_SERIES, Lanes, MAX_BEND, add_held, any_angle, compose, held_wind,
    lever_bend, local_palette, own_drag, pass_to_parent, small_angle,
};
use crate::species::{SwaySpecies, Transition};

/// Joints per chunk of the spring pass.
const CHUNK: usize = 16;

/// A skeleton of at least twice this many joints has its independent passes split into
/// runs of joints, stepped in parallel (runs of 1 024 were no faster on scene D).
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
        in_runs(Part::of(st, n), &|part| drags::<W>(sp, aero, inv_ur, u, part));
        // (1b) Tips inwards: a joint's loads are its subtree's (added by its children, all
        // after it), then its own, then the lumped drag of the joints held beyond it; they
        // pass to its parent.
        let q = held_wind::<W>(u, inv_ur);
        for i in (0..n).rev() {
            let own = &st.lanes[i];
            let li = &mut st.loads[i];
            for c in 0..6 {
                li[c][0] += own[c][0];
            }
            if let Some(held) = st.held {
                add_held::<W>(li, &held[i], &q);
            }
            pass_to_parent::<W>(sp, st.loads, i);
        }
        // (2) Springs and blend weights, then each joint's rotation about its rest position
        // (T(o) R_i T(−o)) into its palette slot; the loads cleared for the next step.
        in_runs(Part::of(st, n), &|part| springs::<W>(sp, tr, blend, on, bud, part));
        // (3) Palettes, root outwards: M_i = M_parent · (T(o) R_i T(−o)).
        for i in 0..n {
            let p = sp.parent[i];
            if p != sylva_tree::NO_PARENT {
                let (before, rest) = st.lanes.split_at_mut(i);
                let parent = std::array::from_fn(|e| before[p as usize][e][0]);
                let local = std::array::from_fn(|e| rest[0][e][0]);
                let m = compose(&parent, &local);
                for (e, x) in m.into_iter().enumerate() {
                    rest[0][e][0] = x;
                }
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
        part: Part<'_, W>,
    ) {
        for (j, lanes) in part.lanes.iter_mut().enumerate() {
            let own = (&mut lanes[..6]).try_into().expect("six rows");
            let i = part.first + j;
            own_drag::<W, false>(sp, aero, inv_ur, u, i, &part.rate[j], &part.weight[j], own);
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
            for j in 0..CHUNK {
                let e2 = eqs[0][j] * eqs[0][j] + eqs[1][j] * eqs[1][j];
                let full = lever_bend(e2);
                let f = if e2 > LEVER_SERIES { full } else { 1.0 - 0.5 * e2 };
                eqs[0][j] *= f;
                eqs[1][j] *= f;
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
            let mut sc = [[0.0f32; CHUNK]; 2];
            for j in 0..CHUNK {
                let (t0, t1) = (w[j] * th[0][j], w[j] * th[1][j]);
                for c in 0..3 {
                    phi[c][j] = t0 * axis[0][c][j] + t1 * axis[1][c][j];
                }
                let a2 = phi[0][j] * phi[0][j] + phi[1][j] * phi[1][j] + phi[2][j] * phi[2][j];
                let (small, any) = (small_angle(a2), any_angle(a2));
                let (s, c) = if a2 < 0.25 { small } else { any };
                sc[0][j] = s;
                sc[1][j] = c;
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
