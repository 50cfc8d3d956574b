//! Many instances of one species stepped together (structure of arrays, rayon).
//!
//! Per instance and step: (1) loads — eq.-8 drag on every segment and its leaves, with the
//! wind relative to the segment's own motion, accumulated from the tips inwards into the
//! moment about each joint; (2) springs — the exact zero-order-hold step of each active
//! joint's two bending angles; joints beyond the instance's budget are frozen and their
//! displayed rotation blends to the rest pose over `blend_time` (a joint switched back on
//! restarts at its static equilibrium under the present load and blends in over the same
//! time), so a switch moves a point per frame by at most its deflection × dt/blend_time
//! beyond the springs' own motion; (3) palette — each joint's
//! rotation about its rest position composed with its parent's into one 3×4 matrix per
//! joint (rest pose → animated pose, tree space).
//!
//! Instances are independent and each is computed by the same sequence of operations
//! whatever the thread that runs it, so results are bit-identical for any thread count.
//! After the first step at a given dt nothing is allocated.

use rayon::prelude::*;

use crate::species::{SwaySpecies, Transition};

/// A 3×4 affine matrix, row-major: rotation | translation. Maps a rest-pose tree-space point
/// to its animated position.
pub type Palette = [f32; 12];

const IDENTITY: Palette = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];

/// Instances of one species and their animation state.
#[derive(Debug, Clone)]
pub struct SwayBatch {
    species: SwaySpecies,
    instances: usize,
    /// Bending angles (rad) and rates (rad/s) per (instance, joint).
    theta: Vec<[f32; 2]>,
    rate: Vec<[f32; 2]>,
    /// Displayed fraction of each joint's rotation (animation-LOD blend), 0 … 1.
    weight: Vec<f32>,
    /// Load scratch per (instance, joint): force and moment accumulators.
    loads: Vec<[f32; 6]>,
    palettes: Vec<Palette>,
    budget: Vec<u32>,
    transitions: Vec<Transition>,
    dt: f32,
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Rotation matrix of the rotation vector φ (axis × angle), Rodrigues' formula. Small
/// angles use Taylor series of sin a/a and (1 − cos a)/a² (error < 1e-9 below 0.5 rad).
fn rotation(phi: [f32; 3]) -> [[f32; 3]; 3] {
    let a2 = dot(phi, phi);
    let (s, c) = if a2 < 0.25 {
        // sin a / a and (1 − cos a) / a²
        (
            1.0 - a2 / 6.0 * (1.0 - a2 / 20.0 * (1.0 - a2 / 42.0 * (1.0 - a2 / 72.0))),
            0.5 * (1.0 - a2 / 12.0 * (1.0 - a2 / 30.0 * (1.0 - a2 / 56.0 * (1.0 - a2 / 90.0)))),
        )
    } else {
        let a = a2.sqrt();
        (a.sin() / a, (1.0 - a.cos()) / a2)
    };
    let [x, y, z] = phi;
    [
        [1.0 - c * (y * y + z * z), c * x * y - s * z, c * x * z + s * y],
        [c * x * y + s * z, 1.0 - c * (x * x + z * z), c * y * z - s * x],
        [c * x * z - s * y, c * y * z + s * x, 1.0 - c * (x * x + y * y)],
    ]
}

impl SwayBatch {
    /// `instances` trees of `species`, at rest, every joint active.
    pub fn new(species: SwaySpecies, instances: usize) -> SwayBatch {
        let n = species.len();
        let total = n * instances;
        SwayBatch {
            instances,
            theta: vec![[0.0; 2]; total],
            rate: vec![[0.0; 2]; total],
            weight: vec![1.0; total],
            loads: vec![[0.0; 6]; total],
            palettes: vec![IDENTITY; total],
            budget: vec![n as u32; instances],
            transitions: Vec::with_capacity(n),
            dt: f32::NAN,
            species,
        }
    }

    /// The species.
    pub fn species(&self) -> &SwaySpecies {
        &self.species
    }

    /// Number of instances.
    pub fn instances(&self) -> usize {
        self.instances
    }

    /// Set how many joints of instance `i` are simulated (the heaviest `budget`, by carried
    /// mass). Clamped to the joint count.
    pub fn set_budget(&mut self, i: usize, budget: usize) {
        self.budget[i] = budget.min(self.species.len()) as u32;
    }

    /// Active-joint budget of instance `i`.
    pub fn budget(&self, i: usize) -> usize {
        self.budget[i] as usize
    }

    /// Bending angles (rad) of joint `j` of instance `i`.
    pub fn angles(&self, i: usize, j: usize) -> [f32; 2] {
        self.theta[i * self.species.len() + j]
    }

    /// Displayed fraction of joint `j`'s rotation in instance `i` (animation-LOD blend).
    pub fn weight(&self, i: usize, j: usize) -> f32 {
        self.weight[i * self.species.len() + j]
    }

    /// Set the state of joint `j` of instance `i` (for probes and tests: a release test
    /// starts from a bent joint at rest).
    pub fn set_state(&mut self, i: usize, j: usize, angles: [f32; 2], rates: [f32; 2]) {
        let k = i * self.species.len() + j;
        self.theta[k] = angles;
        self.rate[k] = rates;
    }

    /// The palettes of instance `i`, one per joint.
    pub fn palettes(&self, i: usize) -> &[Palette] {
        let n = self.species.len();
        &self.palettes[i * n..(i + 1) * n]
    }

    /// All palettes, instance-major.
    pub fn all_palettes(&self) -> &[Palette] {
        &self.palettes
    }

    /// Advance every instance by `dt` seconds (> 0) in the wind `wind[i]` (m/s, tree space,
    /// one velocity per instance), then recompose the palettes. Cannot fail; a non-finite
    /// or non-positive `dt` leaves the state unchanged.
    pub fn step(&mut self, dt: f32, wind: &[[f32; 3]]) {
        if !(dt > 0.0 && dt.is_finite()) {
            return;
        }
        let sp = &self.species;
        if dt != self.dt {
            self.transitions.clear();
            let z = sp.params.damping_ratio;
            self.transitions.extend(sp.springs.iter().map(|s| Transition::new(s, z, dt)));
            self.dt = dt;
        }
        let n = sp.len();
        let blend = dt / sp.params.blend_time;
        let tr = &self.transitions;
        self.theta
            .par_chunks_mut(n)
            .zip(self.rate.par_chunks_mut(n))
            .zip(self.weight.par_chunks_mut(n))
            .zip(self.loads.par_chunks_mut(n))
            .zip(self.palettes.par_chunks_mut(n))
            .zip(self.budget.par_iter())
            .enumerate()
            .for_each(|(i, (((((theta, rate), weight), loads), pal), &budget))| {
                let u = wind.get(i).copied().unwrap_or([0.0; 3]);
                step_instance(sp, tr, blend, budget, u, theta, rate, weight, loads, pal);
            });
    }
}

fn step_instance(
    sp: &SwaySpecies,
    tr: &[Transition],
    blend: f32,
    budget: u32,
    u: [f32; 3],
    theta: &mut [[f32; 2]],
    rate: &mut [[f32; 2]],
    weight: &mut [f32],
    loads: &mut [[f32; 6]],
    pal: &mut [Palette],
) {
    let n = theta.len();
    // (1) Loads, tips inwards: loads[i] = (force on the subtree, moment about joint i).
    for l in loads.iter_mut() {
        *l = [0.0; 6];
    }
    for i in (0..n).rev() {
        let [ax, ay] = sp.axes[i];
        let w = weight[i];
        let om = [
            w * (rate[i][0] * ax[0] + rate[i][1] * ay[0]),
            w * (rate[i][0] * ax[1] + rate[i][1] * ay[1]),
            w * (rate[i][0] * ax[2] + rate[i][1] * ay[2]),
        ];
        let arm = sp.arm[i];
        let v = cross(om, arm);
        let rel = [u[0] - v[0], u[1] - v[1], u[2] - v[2]];
        let k = sp.drag[i] * dot(rel, rel).sqrt();
        let f = [k * rel[0], k * rel[1], k * rel[2]];
        let m = cross(arm, f);
        let l = &mut loads[i];
        for c in 0..3 {
            l[c] += f[c];
            l[3 + c] += m[c];
        }
        let p = sp.parent[i];
        if p != sylva_tree::NO_PARENT {
            let p = p as usize;
            let fi = [loads[i][0], loads[i][1], loads[i][2]];
            let mi = [loads[i][3], loads[i][4], loads[i][5]];
            let o = sp.origin[i];
            let op = sp.origin[p];
            let r = [o[0] - op[0], o[1] - op[1], o[2] - op[2]];
            let rf = cross(r, fi);
            let lp = &mut loads[p];
            for c in 0..3 {
                lp[c] += fi[c];
                lp[3 + c] += mi[c] + rf[c];
            }
        }
    }
    // (2) Springs of the active joints; blend weights.
    for i in 0..n {
        let active = sp.rank[i] < budget;
        if active {
            let t = &tr[i];
            let mom = [loads[i][3], loads[i][4], loads[i][5]];
            let restart = weight[i] == 0.0;
            for (a, axis) in sp.axes[i].iter().enumerate() {
                let eq = dot(mom, *axis) * t.inv_k;
                if restart {
                    // Back from fully off: start at rest under the present load, so the
                    // joint fades in without a step response.
                    theta[i][a] = eq;
                    rate[i][a] = 0.0;
                }
                let x = theta[i][a] - eq;
                let v = rate[i][a];
                theta[i][a] = t.a11 * x + t.a12 * v + eq;
                rate[i][a] = t.a21 * x + t.a22 * v;
            }
            weight[i] = (weight[i] + blend).min(1.0);
        } else {
            weight[i] = (weight[i] - blend).max(0.0);
        }
    }
    // (3) Palettes, root outwards: M_i = M_parent · (T(o) R_i T(−o)).
    for i in 0..n {
        let [ax, ay] = sp.axes[i];
        let w = weight[i];
        let (t0, t1) = (w * theta[i][0], w * theta[i][1]);
        let r =
            rotation([t0 * ax[0] + t1 * ay[0], t0 * ax[1] + t1 * ay[1], t0 * ax[2] + t1 * ay[2]]);
        let o = sp.origin[i];
        let t = [
            o[0] - (r[0][0] * o[0] + r[0][1] * o[1] + r[0][2] * o[2]),
            o[1] - (r[1][0] * o[0] + r[1][1] * o[1] + r[1][2] * o[2]),
            o[2] - (r[2][0] * o[0] + r[2][1] * o[1] + r[2][2] * o[2]),
        ];
        let local = [
            r[0][0], r[0][1], r[0][2], t[0], r[1][0], r[1][1], r[1][2], t[1], r[2][0], r[2][1],
            r[2][2], t[2],
        ];
        let p = sp.parent[i];
        pal[i] = if p == sylva_tree::NO_PARENT { local } else { compose(&pal[p as usize], &local) };
    }
}

/// a · b for 3×4 affine matrices.
fn compose(a: &Palette, b: &Palette) -> Palette {
    let mut o = [0.0; 12];
    for r in 0..3 {
        for c in 0..4 {
            let mut v = a[r * 4] * b[c] + a[r * 4 + 1] * b[4 + c] + a[r * 4 + 2] * b[8 + c];
            if c == 3 {
                v += a[r * 4 + 3];
            }
            o[r * 4 + c] = v;
        }
    }
    o
}

/// Apply a palette to a rest-pose point.
pub fn transform(p: &Palette, x: [f32; 3]) -> [f32; 3] {
    [
        p[0] * x[0] + p[1] * x[1] + p[2] * x[2] + p[3],
        p[4] * x[0] + p[5] * x[1] + p[6] * x[2] + p[7],
        p[8] * x[0] + p[9] * x[1] + p[10] * x[2] + p[11],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_matches_rodrigues_across_the_series_switch() {
        for a in [1e-4f32, 0.1, 0.49, 0.51, 1.0] {
            let r = rotation([0.0, 0.0, a]);
            assert!(
                (r[0][0] - a.cos()).abs() < 1e-6 && (r[1][0] - a.sin()).abs() < 1e-6,
                "{a}: {r:?}"
            );
        }
    }

    #[test]
    fn compose_is_matrix_product() {
        let a = [0.0, -1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 2.0, 0.0, 0.0, 1.0, 3.0];
        let b = [1.0, 0.0, 0.0, 5.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let x = [0.3, 0.7, -0.2];
        let ab = transform(&compose(&a, &b), x);
        let want = transform(&a, transform(&b, x));
        for c in 0..3 {
            assert!((ab[c] - want[c]).abs() < 1e-6);
        }
    }
}
