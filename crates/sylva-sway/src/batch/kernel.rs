//! The step: loads from the tips inwards, the springs' exact step, palettes composed from
//! the root out, for a lane group at a time (vectorised across its lanes) or a lane alone.

use rayon::prelude::*;
use sylva_core::simd_kernel;
use sylva_core::v3::{cross, dot};

use super::*;
use crate::species::{SwaySpecies, Transition};

impl SwayBatch {
    /// Advance every instance by `dt` seconds (> 0) in the wind `wind[i]` (m/s, tree space,
    /// one velocity per instance; missing entries mean still air), then recompose the
    /// palettes. Cannot fail; a non-finite or non-positive `dt` leaves the state unchanged.
    pub fn step(&mut self, dt: f32, wind: &[[f32; 3]]) {
        if !(dt > 0.0 && dt.is_finite()) {
            return;
        }
        for i in 0..self.instances {
            self.refresh(i);
        }
        // Joints a group stores anew start at rest, shown as such before the first step.
        let rest = self.rest_weight();
        let sp = &self.species;
        if dt != self.dt {
            self.transitions.clear();
            let z = sp.params.damping_ratio;
            self.transitions.extend(sp.springs.iter().map(|s| Transition::new(s, z, dt)));
            self.aero_dt.clear();
            self.aero_dt.extend(sp.aero.iter().map(|a| a * dt));
            self.dt = dt;
        }
        let blend = dt / sp.params.blend_time;
        self.plan();
        match self.width {
            1 => self.step_lanes::<1>(blend, rest, wind),
            4 => self.step_lanes::<4>(blend, rest, wind),
            8 => self.step_lanes::<8>(blend, rest, wind),
            _ => self.step_lanes::<LANES>(blend, rest, wind),
        }
        self.updates = self.lane_computed.iter().map(|&s| s as usize).sum();
    }

    /// The step's groups, `W` (= [`SwayBatch::width`]) lanes each. (About 130 lines: the
    /// borrow of every group's storage, plan and rows at once for the parallel loop is what
    /// takes the room; the arithmetic is in `step_group` and `alone`.)
    fn step_lanes<const W: usize>(&mut self, blend: f32, rest: f32, wind: &[[f32; 3]]) {
        let sp = &self.species;
        let (tr, aero, budget, ni) =
            (&self.transitions, &self.aero_dt, &self.lane_budget, self.instances);
        let (keep, lumped, plans) = (&self.fading_to, &self.lumped, &self.plans);
        let (lane_shelter, lane_mean) = (&self.lane_shelter, &self.lane_mean);
        let held = |p: usize| lumped.iter().find(|(q, _)| *q == p).map(|(_, v)| v.as_slice());
        let n = sp.len();
        let lanes_of =
            self.lane_moving.par_chunks_mut(LANES).zip(self.lane_computed.par_chunks_mut(LANES));
        self.blocks
            .par_iter_mut()
            .zip(self.group_prefix.par_iter_mut())
            .zip(lanes_of)
            .enumerate()
            .for_each(|(g, ((block, active), (live, stepped)))| {
                let p = *active as usize;
                let Plan { on, need, head, solo } = plans[g];
                let (need, head) = (need.map(|x| x as usize), head as usize);
                // The group stores, for every lane, the joints it steps them all to: what its
                // lanes stepped together need (a lane alone holds its own in its row; joints
                // beyond a lane's need are at rest in it). Joints it now needs are stored (at
                // rest where new) before the rows give back what they held; joints it no
                // longer needs are dropped after the rows have taken theirs, and their memory
                // is given back after TRIM_STEPS steps (nothing reads them: a joint switched
                // back on restarts).
                let stores = head;
                if stores > block.joints {
                    block.store(stores, W, rest);
                }
                let stored = block.joints;
                let Block { theta, rate, weight, pal, alone, rows, .. } = block;
                let mut u = [ZERO; 3];
                let mut bud = [0u32; LANES];
                let mut shelter = [1.0f32; LANES];
                let mut mean = [ZERO; 3];
                let used = W.min(ni - g * LANES);
                for l in 0..used {
                    shelter[l] = lane_shelter[g * LANES + l];
                    for c in 0..3 {
                        mean[c][l] = lane_mean[g * LANES + l][c];
                    }
                    let w = wind.get(g * LANES + l).copied().unwrap_or([0.0; 3]);
                    for c in 0..3 {
                        u[c][l] = w[c];
                    }
                    bud[l] = budget[g * LANES + l];
                }
                let k = (keep[g] as usize).min(p);
                hold_rows(
                    rows,
                    solo,
                    &need,
                    [&mut *theta, &mut *rate, &mut *weight],
                    W,
                    (stored, rest),
                );
                *alone = solo;
                // The scratch is taken out of the thread's slot for the step, not borrowed in
                // it: a crown stepped alone splits its work across threads, and while this
                // thread waits on that split it may step another group, which then finds the
                // slot empty and grows a scratch of its own.
                let mut loads = SCRATCH.take();
                {
                    // Lanes stepped alone, each as a group of one on its row (the kernel at
                    // width 1, the same operations as a batch of that instance alone).
                    for l in (0..used).filter(|&l| solo >> l & 1 == 1) {
                        let r = need[l];
                        if loads.len() < 6 * r {
                            loads.resize(6 * r, 0.0);
                        }
                        let row = &mut rows[l];
                        let mut one = Group::<1> {
                            theta: row.theta.as_chunks_mut::<1>().0.as_chunks_mut::<2>().0,
                            rate: row.rate.as_chunks_mut::<1>().0.as_chunks_mut::<2>().0,
                            weight: row.weight.as_chunks_mut::<1>().0,
                            loads: loads[..6 * r].as_chunks_mut::<1>().0.as_chunks_mut::<6>().0,
                            lanes: row.pal.as_chunks_mut::<1>().0.as_chunks_mut::<12>().0,
                            active: r,
                            on: [on[l]; LANES],
                            held: held(r),
                            ignored: [false; LANES],
                            shelter: [shelter[l]; LANES],
                            mean: std::array::from_fn(|c| {
                                let mut m = ZERO;
                                m[0] = mean[c][l];
                                m
                            }),
                        };
                        let mut u1 = [ZERO; 3];
                        for c in 0..3 {
                            u1[c][0] = u[c][l];
                        }
                        let mut b1 = [0u32; LANES];
                        b1[0] = bud[l];
                        step_one::<1>(sp, tr, aero, blend, &b1, &u1, &mut one);
                    }
                    // The rest of the group, every lane to `head` (the lanes stepped alone
                    // too, on values their rows stand for: nothing reads them).
                    if head > 0 {
                        if loads.len() < 6 * head * W {
                            loads.resize(6 * head * W, 0.0);
                        }
                        let mut st = Group::<W> {
                            theta: theta.as_chunks_mut::<W>().0.as_chunks_mut::<2>().0,
                            rate: rate.as_chunks_mut::<W>().0.as_chunks_mut::<2>().0,
                            weight: weight.as_chunks_mut::<W>().0,
                            loads: loads[..6 * head * W]
                                .as_chunks_mut::<W>()
                                .0
                                .as_chunks_mut::<6>()
                                .0,
                            lanes: pal.as_chunks_mut::<W>().0.as_chunks_mut::<12>().0,
                            active: head,
                            on,
                            held: held(head),
                            ignored: std::array::from_fn(|l| l >= used || solo >> l & 1 == 1),
                            shelter,
                            mean,
                        };
                        if W == 1 {
                            step_one::<W>(sp, tr, aero, blend, &bud, &u, &mut st);
                        } else {
                            step_group::<W>(sp, tr, aero, blend, &bud, &u, &mut st);
                        }
                    }
                }
                SCRATCH.set(loads);
                let lane = LaneShown { rows, weight, width: W };
                mark_live(&lane, (stepped, live), (&on, &need), (head, solo, used), (lumped, n));
                // Joints fading out are dropped once every lane shows them at rest.
                if k < p && live.iter().all(|&x| x as usize <= k) {
                    *active = k as u32;
                }
                block.store(stores, W, rest);
                block.trim(W);
            });
    }
}

/// The rows of a group's lanes for this step: a lane stepped alone (a bit of `solo`) keeps
/// its state and palettes in its row (see [`Row`]), taking from the group's `state`
/// (angles, rates, weights, `width` lanes inner) the joints it lacks and giving back those
/// beyond the `need` it now simulates; a lane that rejoins its group gives its state back
/// and the row up (the step computes every palette it steps afresh, so none is copied
/// back).
fn hold_rows(
    rows: &mut Vec<Row>,
    solo: u32,
    need: &[usize; LANES],
    state: [&mut Vec<f32>; 3],
    width: usize,
    (stored, rest): (usize, f32),
) {
    let [theta, rate, weight] = state;
    if solo != 0 && rows.len() < width {
        rows.resize_with(width, Row::default);
    }
    for (l, row) in rows.iter_mut().enumerate() {
        let r = if solo >> l & 1 == 1 { need[l] } else { 0 };
        row.hold(r, [&mut *theta, &mut *rate, &mut *weight], width, l, (stored, rest));
        if r == 0 {
            if row.capacity() > 0 {
                *row = Row::default();
            }
            continue;
        }
        // Grown exactly (the bytes counted are the bytes held); its values are all written
        // by the step.
        if row.pal.capacity() < 12 * r {
            row.pal = vec![0.0; 12 * r];
        }
        row.pal.resize(12 * r, 0.0);
    }
}

/// Where a group's lanes show their blend weights: a lane's row for the joints it holds,
/// else the group's `weight` (`width` lanes inner).
struct LaneShown<'a> {
    rows: &'a [Row],
    weight: &'a [f32],
    width: usize,
}

/// After a group's step, per lane of the `used`: the joints it computed (`stepped`: its
/// `need` alone, else the group's `head`), and what it has live (`live`): its switched-on
/// prefix (`on`) and the joints beyond it still fading out (the last one not yet at rest),
/// rounded up to a registered prefix of `lumped` (`n` joints in all), as every prefix a
/// step takes is.
fn mark_live(
    shown_in: &LaneShown<'_>,
    (stepped, live): (&mut [u32], &mut [u32]),
    (on, need): (&[u32; LANES], &[usize; LANES]),
    (head, solo, used): (usize, u32, usize),
    (lumped, n): (&[(usize, Vec<Lump>)], usize),
) {
    for l in 0..used {
        stepped[l] = if solo >> l & 1 == 1 { need[l] } else { head } as u32;
        let (kl, was) = (on[l] as usize, live[l] as usize);
        let row = shown_in.rows.get(l).filter(|r| r.joints > 0);
        let shown = |j: usize| match row {
            Some(r) if j < r.joints => r.weight[j],
            _ => shown_in.weight[j * shown_in.width + l],
        };
        let fading = (kl..was.min(need[l])).rev().find(|&j| shown(j) != 0.0);
        live[l] = fading.map_or(kl, |j| round_up(lumped, n, j + 1)).max(kl) as u32;
    }
}

thread_local! {
    /// Per thread: the load accumulators of the group or lane it steps (`6 · joints · W`
    /// values, zero between steps).
    static SCRATCH: std::cell::RefCell<Vec<f32>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Step a group of one lane (`W` = 1): its joints' independent work apart from the sweeps
/// along the skeleton ([`alone`]), the same operations as [`step_group`].
#[inline]
pub(super) fn step_one<const W: usize>(
    sp: &SwaySpecies,
    tr: &[Transition],
    aero: &[f32],
    blend: f32,
    bud: &[u32; LANES],
    u: &[Lanes; 3],
    st: &mut Group<'_, W>,
) {
    #[cfg(not(feature = "glam"))]
    alone::step::<W>(sp, tr, aero, blend, bud, u, st);
    // glam composes the palettes its own way: one kernel for every width.
    #[cfg(feature = "glam")]
    step_group::<W>(sp, tr, aero, blend, bud, u, st);
}

/// One group's state, `W` lanes inner.
pub(super) struct Group<'a, const W: usize> {
    pub(super) theta: &'a mut [[[f32; W]; 2]],
    pub(super) rate: &'a mut [[[f32; W]; 2]],
    pub(super) weight: &'a mut [[f32; W]],
    pub(super) loads: &'a mut [[[f32; W]; 6]],
    pub(super) lanes: &'a mut [[[f32; W]; 12]],
    /// Joints simulated (a prefix).
    pub(super) active: usize,
    /// Per lane: joints switched on (a prefix of the simulated ones; those beyond are
    /// fading out).
    pub(super) on: [u32; LANES],
    /// Lumped static drag of the held joints, per simulated joint (none: all simulated).
    pub(super) held: Option<&'a [Lump]>,
    /// Per lane: whether nothing reads what the step computes in it (a lane stepped alone
    /// on its row, or one past the batch's instances), so that it takes no part in the one
    /// choice made for the whole group (the rotation formula, see `palette_of`).
    pub(super) ignored: [bool; LANES],
    /// Per lane: its shelter, 0 in the open … 1 inside a canopy
    /// ([`SwaySpecies::set_wind_heights`]).
    pub(super) shelter: [f32; LANES],
    /// Per lane: its mean wind, by component ([`SwayBatch::set_mean_wind`]).
    pub(super) mean: [Lanes; 3],
}

simd_kernel! {
    /// Step one group, vectorised with the widest instruction set the CPU has. (About 130
    /// lines: the three sweeps over the joints — loads inwards, springs, palettes outwards —
    /// share the group's borrowed state and must stay in one compiled body for the
    /// instruction set the macro picks.)
    pub(super) fn step_group<const W: usize>(
        sp: &SwaySpecies,
        tr: &[Transition],
        aero: &[f32],
        blend: f32,
        bud: &[u32; LANES],
        u: &[Lanes; 3],
        st: &mut Group<'_, W>,
    ) {
        let n = st.active.min(st.theta.len());
        // Leaves reconfigure: their drag is divided by 1 + |u| / U_r.
        let inv_ur = 1.0 / sp.params.leaf_reconfiguration_speed;
        // |u| u per lane for the held (rigid) joints' wood, and reconfigured for their leaves.
        let q = if st.held.is_some() { held_wind::<W>(u, inv_ur) } else { [[[0.0; W]; 3]; 2] };
        // Narrow groups (4 or 8 lanes) compute each joint's own drag in a loop of its own,
        // and its palette in a sweep of its own after the springs, so that the sweep of
        // loads along the skeleton is short and no joint's independent work waits on the
        // joint before it (a tupelo at 4 / 8 lanes: 3.5 → 3.0 / 4.0 → 3.1 ms a step). At 16
        // lanes the work per joint hides that latency and the extra passes over the state
        // cost memory traffic (19 % slower split): one fused sweep each way.
        let split = W < LANES;
        if split {
            for i in 0..n {
                let own = (&mut st.lanes[i][..6]).try_into().expect("six rows");
                let f = sp.wind_factor::<W>(i, &st.shelter);
                own_drag::<W, false>(sp, aero, inv_ur, u, f.as_ref().map(|f| (f, &st.mean)), i, &st.rate[i], &st.weight[i], own);
            }
        }
        // (1) Loads, tips inwards: loads[i] = (force on the subtree, moment about joint i):
        // what its children passed on, its own drag, and the lumped drag of the joints held
        // beyond it. They start at zero: pass (2) clears each joint's loads once it has used
        // them.
        for i in (0..n).rev() {
            let f = sp.wind_factor::<W>(i, &st.shelter);
            let li = &mut st.loads[i];
            if split {
                for c in 0..6 {
                    for l in 0..W {
                        li[c][l] += st.lanes[i][c][l];
                    }
                }
            } else {
                own_drag::<W, true>(sp, aero, inv_ur, u, f.as_ref().map(|f| (f, &st.mean)), i, &st.rate[i], &st.weight[i], li);
            }
            if let Some(held) = st.held {
                add_held::<W>(li, &held[i], &q, f.as_ref());
            }
            pass_to_parent::<W>(sp, st.loads, i);
        }
        // (2) Springs of the active joints and blend weights, root outwards, and with them:
        for i in 0..n {
            let t = &tr[i];
            let rank = sp.rank[i];
            let [ax, ay] = sp.axes[i];
            let li = &st.loads[i];
            let (th, ra, w) = (&mut st.theta[i], &mut st.rate[i], &mut st.weight[i]);
            // The linear equilibrium bend e (moment over stiffness) per lane and axis, then
            // turned into the bend at which the spring balances the drag's moment as it acts
            // on the bent joint (`lever_bend`). Below e = 0.1 rad the root's series,
            // e (1 − e²/2), is within 6e-5 of it and costs nothing; only a group with a lane above
            // it takes the Newton step, and each lane's factor depends on its own load alone.
            let mut eqs = [[0.0f32; W]; 2];
            let mut e2 = [0.0f32; W];
            for l in 0..W {
                let mom = [li[3][l], li[4][l], li[5][l]];
                eqs[0][l] = dot(mom, ax) * t.inv_k;
                eqs[1][l] = dot(mom, ay) * t.inv_k;
                e2[l] = eqs[0][l] * eqs[0][l] + eqs[1][l] * eqs[1][l];
            }
            let f = lever_factors(&e2);
            for l in 0..W {
                eqs[0][l] *= f[l];
                eqs[1][l] *= f[l];
            }
            for l in 0..W {
                let active = i < st.on[l] as usize && rank < bud[l];
                let restart = active && w[l] == 0.0;
                for a in 0..2 {
                    let eq = eqs[a][l];
                    // Back from fully off: start at rest under the present load, so the joint
                    // fades in without a step response.
                    let x = if restart { 0.0 } else { th[a][l] - eq };
                    let v = if restart { 0.0 } else { ra[a][l] };
                    let (nx, nv) = (t.a11 * x + t.a12 * v + eq, t.a21 * x + t.a22 * v);
                    th[a][l] = if active { nx } else { th[a][l] };
                    ra[a][l] = if active { nv } else { ra[a][l] };
                }
                // A guard beyond the lever's saturation: no joint bends past MAX_BEND.
                let b2 = th[0][l] * th[0][l] + th[1][l] * th[1][l];
                let over = b2 > MAX_BEND * MAX_BEND;
                let k = if over { MAX_BEND / b2.sqrt() } else { 1.0 };
                th[0][l] *= k;
                th[1][l] *= k;
                ra[0][l] = if over { 0.0 } else { ra[0][l] };
                ra[1][l] = if over { 0.0 } else { ra[1][l] };
                w[l] = if active { (w[l] + blend).min(1.0) } else { (w[l] - blend).max(0.0) };
            }
            st.loads[i] = [[0.0f32; W]; 6];
            // (3) Palette: M_i = M_parent · (T(o) R_i T(−o)), in the same sweep (the parent's
            // is done), or from the rotation vector kept in the joint's palette slot for a
            // sweep of its own.
            let (th, w) = (&st.theta[i], &st.weight[i]);
            let mut phi = [[0.0f32; W]; 3];
            for l in 0..W {
                let (t0, t1) = (w[l] * th[0][l], w[l] * th[1][l]);
                for c in 0..3 {
                    phi[c][l] = t0 * ax[c] + t1 * ay[c];
                }
            }
            if split {
                st.lanes[i][..3].copy_from_slice(&phi);
            } else {
                palette_of::<W>(sp, st.lanes, i, &phi, &st.ignored);
            }
        }
        if split {
            for i in 0..n {
                let phi = std::array::from_fn(|c| st.lanes[i][c]);
                palette_of::<W>(sp, st.lanes, i, &phi, &st.ignored);
            }
        }
    }
}

/// Joint `i`'s palettes from its rotation vectors `phi`, its parent's being done. One
/// formula for the whole group: the series where every lane's angle is small, else the full
/// one — lanes `ignored` (whose values nothing reads) take no part in the choice, so a lane
/// stepped with its group moves the same whatever the group's other lanes left behind.
#[inline(always)]
pub(super) fn palette_of<const W: usize>(
    sp: &SwaySpecies,
    lanes: &mut [[[f32; W]; 12]],
    i: usize,
    phi: &[[f32; W]; 3],
    ignored: &[bool; LANES],
) {
    let mut small = true;
    for l in 0..W {
        let a2 = phi[0][l] * phi[0][l] + phi[1][l] * phi[1][l] + phi[2][l] * phi[2][l];
        small &= ignored[l] | (a2 < 0.25);
    }
    let p = sp.parent[i];
    let (before, rest) = lanes.split_at_mut(i);
    let parent = (p != sylva_tree::NO_PARENT).then(|| &before[p as usize]);
    // Two copies of the lane loop, both branch-free: the common all-small-angle one, and
    // one for any angle.
    if small {
        palette_lanes::<W>(phi, sp.origin[i], parent, &mut rest[0], small_angle);
    } else {
        palette_lanes::<W>(phi, sp.origin[i], parent, &mut rest[0], any_angle);
    }
}

/// |u| u per lane for held (rigid) joints' wood, and reconfigured for their leaves.
#[inline(always)]
pub(super) fn held_wind<const W: usize>(u: &[Lanes; 3], inv_ur: f32) -> [[[f32; W]; 3]; 2] {
    let mut q = [[[0.0f32; W]; 3]; 2];
    for l in 0..W {
        let speed = (u[0][l] * u[0][l] + u[1][l] * u[1][l] + u[2][l] * u[2][l]).sqrt();
        let leaves = speed / (1.0 + speed * inv_ur);
        for c in 0..3 {
            q[0][c][l] = speed * u[c][l];
            q[1][c][l] = leaves * u[c][l];
        }
    }
    q
}

/// The lanes' wind `u` at a joint of factors `f`: its mean `mean` times the mean's factor,
/// the rest (the gusts) times the gusts' (lanes from `W` on: zero).
#[inline(always)]
fn scale_wind<const W: usize>(u: &[Lanes; 3], f: &JointWind<W>, mean: &[Lanes; 3]) -> [Lanes; 3] {
    let mut out = [ZERO; 3];
    for c in 0..3 {
        for l in 0..W {
            out[c][l] = f.gust[l] * u[c][l] + (f.mean[l] - f.gust[l]) * mean[c][l];
        }
    }
    out
}

/// Add the lumped drag of the joints held beyond a joint (`lump`, in the wind `q` of
/// [`held_wind`]) to its loads `li`; `f`, the joint's height factors, scales the drag by
/// the square of the mean's (the held joints feel the wind at the joint's height).
#[inline(always)]
pub(super) fn add_held<const W: usize>(
    li: &mut [[f32; W]; 6],
    lump: &Lump,
    q: &[[[f32; W]; 3]; 2],
    f: Option<&JointWind<W>>,
) {
    for (part, q) in lump.iter().zip(q) {
        let [d, cx, cy, cz] = *part;
        let mut q = *q;
        if let Some(f) = f {
            for c in 0..3 {
                for l in 0..W {
                    q[c][l] *= f.mean[l] * f.mean[l];
                }
            }
        }
        for l in 0..W {
            li[0][l] += d * q[0][l];
            li[1][l] += d * q[1][l];
            li[2][l] += d * q[2][l];
            li[3][l] += cy * q[2][l] - cz * q[1][l];
            li[4][l] += cz * q[0][l] - cx * q[2][l];
            li[5][l] += cx * q[1][l] - cy * q[0][l];
        }
    }
}

/// Pass joint `i`'s loads (force on its subtree, moment about it) on to its parent's,
/// the moment taken about the parent's origin.
#[inline(always)]
pub(super) fn pass_to_parent<const W: usize>(
    sp: &SwaySpecies,
    loads: &mut [[[f32; W]; 6]],
    i: usize,
) {
    let p = sp.parent[i];
    if p == sylva_tree::NO_PARENT {
        return;
    }
    let p = p as usize;
    let (lp, li) = {
        let (a, b) = loads.split_at_mut(i);
        (&mut a[p], &b[0])
    };
    pass_on::<W>(sp, i, li, p, lp);
}

/// Pass joint `i`'s loads `li` on to its parent `p`'s, `lp` (see [`pass_to_parent`]).
#[inline(always)]
pub(super) fn pass_on<const W: usize>(
    sp: &SwaySpecies,
    i: usize,
    li: &[[f32; W]; 6],
    p: usize,
    lp: &mut [[f32; W]; 6],
) {
    let (o, op) = (sp.origin[i], sp.origin[p]);
    let r = [o[0] - op[0], o[1] - op[1], o[2] - op[2]];
    for l in 0..W {
        let fi = [li[0][l], li[1][l], li[2][l]];
        lp[0][l] += fi[0];
        lp[1][l] += fi[1];
        lp[2][l] += fi[2];
        lp[3][l] += li[3][l] + (r[1] * fi[2] - r[2] * fi[1]);
        lp[4][l] += li[4][l] + (r[2] * fi[0] - r[0] * fi[2]);
        lp[5][l] += li[5][l] + (r[0] * fi[1] - r[1] * fi[0]);
    }
}

/// A joint's own drag, per lane: (force, moment about the joint) of eq.-8 drag on its
/// segment and leaves, in the wind (the lane's wind `u` at the joint's height factors `f`
/// with the lanes' mean wind, [`SwaySpecies::set_gust_heights`]) relative to the segment's
/// motion — added to `out`
/// (`ADD`) or written to it.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn own_drag<const W: usize, const ADD: bool>(
    sp: &SwaySpecies,
    aero: &[f32],
    inv_ur: f32,
    u: &[Lanes; 3],
    f: Option<(&JointWind<W>, &[Lanes; 3])>,
    i: usize,
    ra: &[[f32; W]; 2],
    w: &[f32; W],
    out: &mut [[f32; W]; 6],
) {
    let scaled;
    let u = match f {
        None => u,
        Some((f, mean)) => {
            scaled = scale_wind::<W>(u, f, mean);
            &scaled
        }
    };
    let [ax, ay] = sp.axes[i];
    let arm = sp.arm[i];
    let (drag, leaf) = (sp.drag[i], sp.leaf_drag[i]);
    // Simple lane loops, one quantity each, so they vectorise.
    let mut rel = [[0.0f32; W]; 3];
    let g = aero[i];
    for l in 0..W {
        // The segment's own motion enters the relative wind implicitly (backward Euler on
        // the linearised drag damping): stable however light the segment and long the
        // step; explicit use of the rate blows up for leafy twigs at 25 fps.
        let speed = (u[0][l] * u[0][l] + u[1][l] * u[1][l] + u[2][l] * u[2][l]).sqrt();
        let implicit = w[l] / (1.0 + g * speed);
        let (r0, r1) = (implicit * ra[0][l], implicit * ra[1][l]);
        let om = [r0 * ax[0] + r1 * ay[0], r0 * ax[1] + r1 * ay[1], r0 * ax[2] + r1 * ay[2]];
        let v = cross(om, arm);
        rel[0][l] = u[0][l] - v[0];
        rel[1][l] = u[1][l] - v[1];
        rel[2][l] = u[2][l] - v[2];
    }
    let mut f = [[0.0f32; W]; 3];
    for l in 0..W {
        let s = (rel[0][l] * rel[0][l] + rel[1][l] * rel[1][l] + rel[2][l] * rel[2][l]).sqrt();
        let k = s * (drag + leaf / (1.0 + s * inv_ur));
        f[0][l] = k * rel[0][l];
        f[1][l] = k * rel[1][l];
        f[2][l] = k * rel[2][l];
    }
    for l in 0..W {
        let own = [
            f[0][l],
            f[1][l],
            f[2][l],
            arm[1] * f[2][l] - arm[2] * f[1][l],
            arm[2] * f[0][l] - arm[0] * f[2][l],
            arm[0] * f[1][l] - arm[1] * f[0][l],
        ];
        for (o, x) in out.iter_mut().zip(own) {
            o[l] = if ADD { o[l] + x } else { x };
        }
    }
}
