//! The crown's static lean in a steady wind, for a stand-in that bends at the trunk only (an
//! impostor): how far the leaves move, on average, from the bending of every joint off the
//! trunk line.
//!
//! A tree drawn far away as one picture (sylva-render's impostors) sways by its trunk-top
//! joint alone: the picture shears with the trunk top's displacement. Its limbs and twigs
//! bend too, and in a strong wind they carry the crown downwind further than the trunk
//! does — a weeping willow, whose hanging twigs stream out while its thick trunk hardly
//! moves, most of all. [`CrownLean`] is that part as the springs of [`crate::SwayBatch`]
//! settle in a steady wind. The step sums the drag on the rest pose, so each joint's
//! equilibrium follows from its own load: the moment M_j about joint `j` of the eq.-8 drag
//! on all it carries (wood in |u| u, leaves in the reconfigured |u| u / (1 + |u| / U_r)),
//! projected on its two bending axes and divided by its stiffness, is the linear bend e_j;
//! the joint settles at the step's lever-corrected bend of it, θ_j (never past
//! [`crate::batch::MAX_BEND`]), and turns the leaves it carries by R(θ_j) − I about its
//! origin. Composed root outwards as the step's palettes are (the trunk line held at rest),
//! and averaged over the leaves (weighted by leaf area, each at its segment's middle), the
//! leaves' displacement is the lean.
//!
//! The same rotations turn the leaves: [`CrownLean::tilt`] is the leaf-weighted mean of
//! where they take the vertical, R ẑ. A crown bent in the wind turns its leaves away from
//! the sky on average (the mean's vertical part falls below one: 0.87 for the quaking aspen
//! at 12 m/s, 0.42 for the weeping willow), which is why full detail darkens in a strong
//! wind; an impostor turns its baked normals by it to follow.
//!
//! It depends on the wind's horizontal direction and speed (the vertical component, a
//! tenth of the speed or so, is left out); it is tabulated once per species over
//! [`DIRECTIONS`] directions and the speeds of [`SPEEDS`] (held beyond the last) and read
//! bilinearly. What it leaves out: the dynamic sway about that mean (the joints' own
//! oscillation). `tests/lean.rs` checks it against the step's equilibrium.

use rayon::prelude::*;
use sylva_core::v3::{add, cross, dot, scale, sub};
use sylva_tree::{NO_PARENT, Skeleton};

use crate::SwaySpecies;
use crate::batch::{IDENTITY, MAX_BEND, Palette, compose, joint_palette, lever_bend, transform};

/// Wind directions tabulated over the whole turn, 30° apart. Not half a turn and its
/// negative: the bends are odd in the wind, but their composition is not (a crown that
/// leans a little across a wind from the east does not lean the other way across a wind
/// from the west), which read as a crosswind lean of the wrong sign.
pub const DIRECTIONS: usize = 12;

/// Horizontal wind speeds tabulated, m/s (calm to a violent storm).
pub const SPEEDS: [f32; 12] = [0.0, 2.0, 4.0, 6.0, 8.0, 10.0, 12.0, 15.0, 18.0, 22.0, 27.0, 32.0];

/// A species' static crown lean: see the module documentation.
#[derive(Debug, Clone, PartialEq)]
pub struct CrownLean {
    /// Horizontal lean (m, tree space) and the leaves' mean turned vertical (x, y, z; see
    /// [`CrownLean::tilt`]), direction-major: `table[d · SPEEDS.len() + s]` for the wind
    /// blowing towards azimuth d · 2π / DIRECTIONS (from the x axis) at `SPEEDS[s]`.
    table: Vec<[f32; 5]>,
    /// Leaf-weighted mean of the impostor's shear profile (see [`CrownLean::shear`]): the
    /// shear at the trunk top that moves the leaves by the lean on average.
    profile: f32,
}

/// One joint off the trunk line, as the lean needs it.
struct Bend {
    /// Moment arms about the joint of its subtree's wood and leaf drag (Σ d (x − o)).
    wood: [f32; 3],
    leaves: [f32; 3],
    axes: [[f32; 3]; 2],
    inv_k: f32,
}

impl CrownLean {
    /// The lean of species `sp`, prepared from `skeleton` (the one `sp` was made from).
    pub fn new(sp: &SwaySpecies, skeleton: &Skeleton) -> CrownLean {
        let n = sp.len();
        // The trunk line: the root's stem up to the trunk top.
        let mut trunk = vec![false; n];
        let mut a = skeleton.trunk_top() as u32;
        while a != NO_PARENT && (a as usize) < n {
            trunk[a as usize] = true;
            a = sp.parent[a as usize];
        }
        // The impostor's shear at height z, per unit of shear at the trunk top (z_top): in
        // proportion to the height, z / z_top, but at most 1.5 at the tree's top (h).
        let joints = skeleton.joints();
        let top = joints.get(skeleton.trunk_top()).map_or(1.0, |j| j.tip()[2]).max(0.1);
        let h = joints.iter().map(|j| j.tip()[2].max(j.origin[2])).fold(top, f32::max);
        let corner = (h / top).min(1.5) as f64;
        // Subtree sums, tips inwards: Σ d and Σ d x for wood and leaves, the drag and the
        // leaves sitting mid segment; the leaves' weight is their still-air drag,
        // proportional to their area.
        let mut sums = vec![[0.0f64; 8]; n];
        let (mut total, mut profile) = (0.0f64, 0.0f64);
        for i in (0..n).rev() {
            let (dw, dl) = (sp.drag[i] as f64, sp.leaf_drag[i] as f64);
            let x = add(sp.origin[i], sp.arm[i]).map(|v| v as f64);
            let s = &mut sums[i];
            s[0] += dw;
            s[4] += dl;
            for c in 0..3 {
                s[1 + c] += dw * x[c];
                s[5 + c] += dl * x[c];
            }
            total += dl;
            profile += dl * corner * (x[2] / h as f64).clamp(0.0, 1.0);
            let p = sp.parent[i];
            if p != NO_PARENT {
                let s = sums[i];
                for (q, v) in sums[p as usize].iter_mut().zip(s) {
                    *q += v;
                }
            }
        }
        // Per joint off the trunk line: the moment arms about it of its subtree's wood and
        // leaf drag, Σ d (x − o).
        let bends: Vec<Option<Bend>> = (0..n)
            .map(|j| {
                let (s, o) = (&sums[j], sp.origin[j].map(|v| v as f64));
                let arm = |k: usize| std::array::from_fn(|c| (s[k + 1 + c] - s[k] * o[c]) as f32);
                (!trunk[j]).then(|| Bend {
                    wood: arm(0),
                    leaves: arm(4),
                    axes: sp.axes[j],
                    inv_k: 1.0 / sp.springs[j].stiffness,
                })
            })
            .collect();
        // Joints with leaves in their subtree: the others move no leaf.
        let leafy: Vec<bool> = sums.iter().map(|s| s[4] > 0.0).collect();
        let leaf_at: Vec<[f32; 3]> = (0..n).map(|i| add(sp.origin[i], sp.arm[i])).collect();
        let inv_ur = 1.0 / sp.params.leaf_reconfiguration_speed;
        let table = (0..DIRECTIONS * SPEEDS.len())
            .into_par_iter()
            .map(|k| {
                let (d, s) = (k / SPEEDS.len(), SPEEDS[k % SPEEDS.len()]);
                if total <= 0.0 || s == 0.0 {
                    return REST;
                }
                let a = d as f32 * std::f32::consts::TAU / DIRECTIONS as f32;
                let qw = [s * s * a.cos(), s * s * a.sin(), 0.0];
                let ql = scale(qw, 1.0 / (1.0 + s * inv_ur));
                // Each joint's settled bend, then the palettes composed root outwards (the
                // trunk line at rest) and the leaves moved by them.
                let mut pose = vec![IDENTITY; n];
                let mut sum = [0.0f64; 5];
                for j in (0..n).filter(|&j| leafy[j]) {
                    let phi = bends[j].as_ref().map_or([0.0; 3], |b| b.settled(qw, ql));
                    let local = joint_palette(phi, sp.origin[j]);
                    let m: Palette = match sp.parent[j] {
                        NO_PARENT => local,
                        p => compose(&pose[p as usize], &local),
                    };
                    let x = leaf_at[j];
                    let moved = sub(transform(&m, x), x);
                    let w = sp.leaf_drag[j] as f64;
                    // R ẑ: the rotation's third column (the palette is row-major 3 × 4).
                    let turned = [moved[0], moved[1], m[2], m[6], m[10]];
                    for (a, v) in sum.iter_mut().zip(turned) {
                        *a += w * v as f64;
                    }
                    pose[j] = m;
                }
                sum.map(|v| (v / total) as f32)
            })
            .collect();
        let profile = if total > 0.0 { (profile / total).max(1e-3) as f32 } else { 1.0 };
        CrownLean { table, profile }
    }

    /// Leaf-weighted mean horizontal displacement (m, tree space) of the leaves from the
    /// settled bend of the joints off the trunk line in the steady wind `u` (m/s, tree
    /// space; its vertical component is left out; none for a wind that is not finite).
    pub fn mean(&self, u: [f32; 3]) -> [f32; 2] {
        let v = self.lookup(u);
        [v[0], v[1]]
    }

    /// Leaf-weighted mean of where the settled bend of the joints off the trunk line takes
    /// the vertical (tree space, a vector of length at most one): ẑ in still air; in wind
    /// its horizontal part leans with the bend and its vertical part, the mean cosine of
    /// the leaves' tilt, falls.
    pub fn tilt(&self, u: [f32; 3]) -> [f32; 3] {
        let v = self.lookup(u);
        [v[2], v[3], v[4]]
    }

    /// The table read bilinearly in speed and direction (the rest pose for a wind that is
    /// not finite).
    fn lookup(&self, u: [f32; 3]) -> [f32; 5] {
        let speed = (u[0] * u[0] + u[1] * u[1]).sqrt();
        if !speed.is_finite() || speed <= 0.0 || self.table.is_empty() {
            return REST;
        }
        let last = SPEEDS.len() - 1;
        let s = SPEEDS.partition_point(|&v| v <= speed).clamp(1, last);
        let t = ((speed - SPEEDS[s - 1]) / (SPEEDS[s] - SPEEDS[s - 1])).min(1.0);
        // Direction in steps of 2π / DIRECTIONS over the whole turn.
        let turns = u[1].atan2(u[0]) / std::f32::consts::TAU * DIRECTIONS as f32;
        let x = turns.rem_euclid(DIRECTIONS as f32);
        let d0 = (x.floor() as usize).min(DIRECTIONS - 1);
        let w = x - d0 as f32;
        let at = |d: usize| {
            let row = &self.table[d % DIRECTIONS * SPEEDS.len()..][..SPEEDS.len()];
            lerp(row[s - 1], t, row[s])
        };
        lerp(at(d0), w, at(d0 + 1))
    }

    /// The shear at the trunk top's height (m, tree space, horizontal) that moves the leaves
    /// by [`mean`](Self::mean) on average, sheared in with height as an impostor's trunk
    /// sway is: by z · min(1 / z_top, 1.5 / h) of it at height z (z_top the trunk top's
    /// height, h the tree's).
    pub fn shear(&self, u: [f32; 3]) -> [f32; 2] {
        self.shear_and_tilt(u).0
    }

    /// [`shear`](Self::shear) and [`tilt`](Self::tilt) together, from one look-up of the
    /// table (what a simulation's impostors take every step).
    pub fn shear_and_tilt(&self, u: [f32; 3]) -> ([f32; 2], [f32; 3]) {
        let v = self.lookup(u);
        ([v[0] / self.profile, v[1] / self.profile], [v[2], v[3], v[4]])
    }
}

impl Bend {
    /// The rotation vector this joint settles at in the wind (q_w = |u| u on the wood, q_l
    /// the reconfigured one on the leaves), as the step's springs do: the linear bend e
    /// (moment over stiffness on each axis), lever-corrected, never past `MAX_BEND`.
    fn settled(&self, qw: [f32; 3], ql: [f32; 3]) -> [f32; 3] {
        let m = add(cross(self.wood, qw), cross(self.leaves, ql));
        let e = [dot(m, self.axes[0]) * self.inv_k, dot(m, self.axes[1]) * self.inv_k];
        let e2 = e[0] * e[0] + e[1] * e[1];
        let mut f = lever_bend(e2);
        let bend = f * e2.sqrt();
        if bend > MAX_BEND {
            f *= MAX_BEND / bend;
        }
        add(scale(self.axes[0], f * e[0]), scale(self.axes[1], f * e[1]))
    }
}

/// A table entry in still air: no lean, the vertical where it was.
const REST: [f32; 5] = [0.0, 0.0, 0.0, 0.0, 1.0];

/// `a + t (b − a)`.
fn lerp(a: [f32; 5], t: f32, b: [f32; 5]) -> [f32; 5] {
    std::array::from_fn(|i| a[i] + t * (b[i] - a[i]))
}
