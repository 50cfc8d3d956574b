//! One simulation step: the animation LOD's joints per lane group within the memory cap,
//! the wind sampled per instance group, leaf flutter, and the batched sway step.

use rayon::prelude::*;
use sylva_sway::{LANES, LeafParams, STATE_BYTES};
use sylva_wind::{NearField, OwnedPyramid};

use super::lod::FAR_WIND_LEVEL;
use super::{Forest, SpeciesRuntime};
use crate::lanes;
use crate::wind::{steer, wind_near};

/// What every species' step reads: the time, the wind and its live controls, and what the
/// last frame asked of each lane.
struct StepInputs<'a> {
    t: f64,
    dt: f32,
    leaf: LeafParams,
    pyramid: &'a OwnedPyramid,
    gain: f32,
    turn: f32,
    near: Option<&'a NearField>,
    centre: [f32; 3],
    /// Per lane, all species in a row: joints the last frame asked to simulate, and joints
    /// it drew.
    wanted: &'a [u32],
    drawn: &'a [u32],
    animation: bool,
    coarse_levels: bool,
    /// Each point's shelter (the canopy wind; `None` with it off).
    shelter: Option<&'a crate::canopy::Shelter>,
    /// The field's mean wind of 1 m/s, world axes, live controls applied.
    mean_dir: [f32; 3],
    /// The canopy's mixing-layer eddies (with the canopy wind).
    eddies: Option<&'a crate::canopy::Eddies>,
}

impl Forest {
    /// Advance the simulation by `dt` seconds (> 0; others are ignored).
    pub fn step(&mut self, dt: f32) {
        if !(dt > 0.0 && dt.is_finite()) {
            return;
        }
        let start = clock();
        self.time += dt as f64;
        self.regroup();
        let inputs = StepInputs {
            t: self.time,
            dt,
            leaf: self.leaf_params,
            pyramid: &self.wind,
            gain: self.gain,
            turn: self.turn,
            near: self.near.as_ref(),
            centre: self.near_centre(),
            wanted: &self.want,
            drawn: &self.shown,
            animation: self.lod.animation,
            coarse_levels: self.spec.lod.wind,
            shelter: self.canopy_wind.as_ref().map(|c| &c.1),
            mean_dir: self.mean_wind(1.0),
            eddies: self.eddies.as_ref(),
        };
        // Species in parallel; each samples the shared, read-only field for its groups.
        let work = |s: &mut SpeciesRuntime| step_species(s, &inputs);
        // A species that stepped more than two thirds of the joints last time (a near crown
        // among far trees) starts at once on its own, the others beside it; otherwise the
        // species are shared out as they come. The order changes no result, only when each
        // species is stepped.
        let updates = |s: &SpeciesRuntime| s.batch.joint_updates();
        let total: usize = self.species.iter().map(updates).sum();
        let heaviest = (0..self.species.len()).max_by_key(|&k| updates(&self.species[k]));
        match heaviest {
            Some(m) if 3 * updates(&self.species[m]) > 2 * total => {
                let (before, rest) = self.species.split_at_mut(m);
                if let Some((first, after)) = rest.split_first_mut() {
                    rayon::join(
                        || work(first),
                        || before.par_iter_mut().chain(after.par_iter_mut()).for_each(work),
                    );
                }
            }
            _ => self.species.par_iter_mut().for_each(work),
        }
        self.last_sim_ms = start.map_or(0.0, |s| s.elapsed().as_secs_f64() * 1e3);
    }
}

/// One species' step: its lanes packed by the joints they need, each lane group's joints
/// set within the memory cap, the wind sampled per instance group, and the batch stepped.
fn step_species(s: &mut SpeciesRuntime, k: &StepInputs<'_>) {
    s.coarse_wind = 0;
    s.near_wind = 0;
    pack_lanes(s, k);
    set_joints(s, k.animation);
    sample_wind(s, k);
    s.batch.step(k.dt, &s.winds);
}

/// The joints each lane is asked to step and shows, as the last frame said, and, with the
/// animation LOD, the simulations that need the same joints gathered into the same lane
/// groups.
fn pack_lanes(s: &mut SpeciesRuntime, k: &StepInputs<'_>) {
    let trunk = s.order.trunk;
    let base = s.lane_base * LANES;
    let want = &mut s.want;
    want.clear();
    // A lane group steps the trunk at least: a want below it (nothing drawn) is the
    // trunk's, so out-of-view and impostor simulations are not told apart.
    want.extend((0..s.groups.len()).map(|l| k.wanted[base + l].max(trunk as u32)));
    let shown = &mut s.shown;
    shown.clear();
    shown.extend((0..s.groups.len()).map(|l| k.drawn[base + l]));
    if k.animation {
        let dest = s.packer.pack(want);
        let (batch, lane_of, group_of) = (&mut s.batch, &mut s.lane_of, &mut s.group_of);
        lanes::apply(dest, |a, b| {
            batch.swap_instances(a, b);
            want.swap(a, b);
            shown.swap(a, b);
            group_of.swap(a, b);
            lane_of[group_of[a] as usize] = a as u32;
            lane_of[group_of[b] as usize] = b as u32;
        });
    }
}

/// Per lane group, the joints to step: the longest prefix any of its lanes wants (every
/// joint without the animation LOD), kept within the species' share of the memory cap.
fn set_joints(s: &mut SpeciesRuntime, animation: bool) {
    let all = s.batch.species().len();
    let trunk = s.order.trunk;
    let (want, shown) = (&s.want, &s.shown);
    let longest = &mut s.longest;
    longest.clear();
    longest.extend(want.chunks(LANES).map(|c| c.iter().copied().max().unwrap_or(0)));
    // Bytes per joint stored of a lane group, and what the species holds now.
    let per_joint = s.batch.width() * STATE_BYTES;
    let mut held: usize = (0..longest.len()).map(|k| s.batch.reserved(k) * per_joint).sum();
    s.capped = 0;
    for (k, &w) in longest.iter().enumerate() {
        let mut w = if animation { (w as usize).min(all) } else { all };
        let reserved = s.batch.reserved(k);
        if s.batch.prefix_for(w) > reserved {
            // Counted as if every lane of the group stored the prefix (a lane the step sends
            // alone holds its own in a row, for less): within the cap whatever the step
            // decides. Growing past the species' share of the memory cap: the group keeps
            // the finest registered prefix it already holds memory for, the trunk at least.
            let more = (s.batch.prefix_for(w) - reserved) * per_joint;
            if held + more > s.state_cap {
                w = s
                    .order
                    .prefix
                    .iter()
                    .copied()
                    .filter(|&p| p <= reserved)
                    .max()
                    .unwrap_or(0)
                    .max(trunk);
                s.capped += 1;
            }
            held += s.batch.prefix_for(w).saturating_sub(reserved) * per_joint;
        }
        s.batch.set_active(k, w);
        // Each lane its own prefix within the group's: a lane group holding one near tree
        // among far ones steps the near tree's crown in its lane alone.
        for i in k * LANES..want.len().min(k * LANES + LANES) {
            s.batch.set_lane_active(i, if animation { want[i] as usize } else { all });
        }
        // Joints switched off fade out where a tree shows them; where none does, they go
        // at once.
        let end = shown.len().min(k * LANES + LANES);
        if shown[k * LANES..end].iter().all(|&d| d as usize <= w) {
            s.batch.settle(k);
        }
    }
    // What the cap leaves to the rows of simulations stepped alone.
    s.batch.set_alone_limit(s.state_cap.saturating_sub(held));
}

/// Per instance group: the wind at its sample point (the pyramid's coarse level where all
/// its trees are impostors or out of view: the wind-field LOD), turned into the group's
/// frame, its crown's lean and its leaves' flutter.
fn sample_wind(s: &mut SpeciesRuntime, k: &StepInputs<'_>) {
    let trunk = s.order.trunk;
    for (i, g) in s.groups.iter_mut().enumerate() {
        let lane = s.lane_of[i] as usize;
        let far = k.coarse_levels && s.longest[lane / LANES] as usize <= trunk;
        s.coarse_wind += far as usize;
        let w = if far {
            k.pyramid.level(FAR_WIND_LEVEL).sample(g.sample, k.t)
        } else {
            let (w, is_near) = wind_near(k.pyramid.level(0), k.near, k.centre, g.sample, k.t);
            s.near_wind += is_near as usize;
            w
        };
        let shelter = k.shelter.map(|sh| sh.at(g.sample[0], g.sample[1]));
        let w = match (k.eddies, shelter) {
            (Some(e), Some(x)) => e.mix(w, g.sample, k.t, s.mean_speed as f64, x as f64),
            _ => w,
        };
        let w = steer(w, k.gain, k.turn);
        let (sn, cs) = g.yaw.sin_cos();
        s.winds[lane] = [cs * w[0] + sn * w[1], -sn * w[0] + cs * w[1], w[2]];
        if let Some(shelter) = shelter {
            s.batch.set_shelter(lane, shelter);
            let m = k.mean_dir.map(|c| c * s.mean_speed);
            s.batch.set_mean_wind(lane, [cs * m[0] + sn * m[1], -sn * m[0] + cs * m[1], m[2]]);
        }
        let (shear, tilt) = s.lean.shear_and_tilt(s.winds[lane]);
        g.lean = shear.map(|v| half::f16::from_f32(v).to_bits());
        g.tilt = tilt_along(shear, tilt).map(|v| half::f16::from_f32(v).to_bits());
        let speed = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
        k.leaf.step(&mut g.leaf, speed, k.dt);
    }
}

/// [`Instance::tilt`] from the crown's shear and its turned vertical `t` (tree space): the
/// horizontal part along the shear, and one minus the vertical part.
fn tilt_along(shear: [f32; 2], t: [f32; 3]) -> [f32; 2] {
    let len = (shear[0] * shear[0] + shear[1] * shear[1]).sqrt();
    let along = if len > 1e-6 { (t[0] * shear[0] + t[1] * shear[1]) / len } else { 0.0 };
    [along, 1.0 - t[2]]
}

/// Now, for timing a step; `None` on WebAssembly without an operating system
/// (`wasm32-unknown-unknown`), whose standard library has no clock (a step there reports
/// 0 ms).
fn clock() -> Option<std::time::Instant> {
    if cfg!(all(target_family = "wasm", target_os = "unknown")) {
        None
    } else {
        Some(std::time::Instant::now())
    }
}
