//! Per-species precomputation: each joint as a damped angular spring (paper §4.2).
//!
//! Joint i bends about the two axes x_i, y_i of its local frame (z along its segment):
//! I θ'' + c θ' + k θ = τ per axis.
//!
//! * Inertia about the joint: the segment as a uniform rod, m L²/3, plus everything it
//!   carries downstream lumped at the segment tip, (M_carried − m) L².
//! * Stiffness from the natural frequency a cantilever of the segment's size would have,
//!   f_bare = 0.14 √(E/ρ_w) d/L² (first mode of a uniform circular cantilever:
//!   (1.875²/2π)·√(E I_A/(ρ_w A))/L², radius of gyration d/4), lowered by the carried mass
//!   as a tip mass on the rod's effective mass 33/140 m (Rayleigh):
//!   f = f_bare √(0.2357 m / (0.2357 m + M_tip)); then k = I (2πf)².
//! * Damping c = 2ζ√(kI) with one damping ratio ζ (structural + aerodynamic).
//! * Drag area: the segment's projected area d·L (C_d of a cylinder) plus its leaves
//!   (C_d per one-sided leaf area), at the segment's mid point.
//!
//! The model is quasi-physical, as in the paper: torques use rest-pose lever arms (small
//! deflections), and each joint's spring is independent of its parent's motion except
//! through the composed transforms.

use std::f32::consts::PI;

use sylva_tree::Skeleton;

use crate::params::{SwayParamError, SwayParams};

/// Effective mass fraction of a uniform cantilever at its tip (Rayleigh, 33/140).
pub const CANTILEVER_TIP_MASS_FRACTION: f32 = 33.0 / 140.0;

/// Spring constants of one joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointSpring {
    /// Moment of inertia about the joint, kg·m².
    pub inertia: f32,
    /// Angular stiffness, N·m/rad.
    pub stiffness: f32,
    /// Angular damping, N·m·s/rad.
    pub damping: f32,
    /// Undamped natural frequency, Hz.
    pub frequency: f32,
}

/// A species' skeleton prepared for animation.
#[derive(Debug, Clone)]
pub struct SwaySpecies {
    pub(crate) params: SwayParams,
    pub(crate) parent: Vec<u32>,
    pub(crate) origin: Vec<[f32; 3]>,
    /// Bending axes x_i, y_i (tree space).
    pub(crate) axes: Vec<[[f32; 3]; 2]>,
    /// Lever arm from the joint to the centre of pressure (mid segment), tree space.
    pub(crate) arm: Vec<[f32; 3]>,
    /// ½ ρ C_d A of the segment and its leaves, kg/m.
    pub(crate) drag: Vec<f32>,
    pub(crate) springs: Vec<JointSpring>,
    /// Joints ordered by priority (carried mass, descending); a prefix of any length is
    /// closed under taking parents.
    pub(crate) priority: Vec<u32>,
    /// Rank of each joint in `priority`.
    pub(crate) rank: Vec<u32>,
}

impl SwaySpecies {
    /// Prepare `skeleton` for animation with `params`.
    pub fn new(skeleton: &Skeleton, params: SwayParams) -> Result<SwaySpecies, SwayParamError> {
        params.validate()?;
        let joints = skeleton.joints();
        let n = joints.len();
        let mut sp = SwaySpecies {
            params,
            parent: joints.iter().map(|j| j.parent).collect(),
            origin: joints.iter().map(|j| j.origin).collect(),
            axes: Vec::with_capacity(n),
            arm: Vec::with_capacity(n),
            drag: Vec::with_capacity(n),
            springs: Vec::with_capacity(n),
            priority: Vec::new(),
            rank: vec![0; n],
        };
        let cbar = (params.youngs_modulus / params.wood_density).sqrt();
        for (i, j) in joints.iter().enumerate() {
            let [x, y, _] = j.frame();
            sp.axes.push([x, y]);
            let h = 0.5 * j.length;
            sp.arm.push([j.axis[0] * h, j.axis[1] * h, j.axis[2] * h]);
            let d = 2.0 * j.radius;
            let area = params.wood_drag * d * j.length + params.leaf_drag * j.leaf_area;
            sp.drag.push(0.5 * params.air_density * area);
            let m = j.own_mass.max(1e-6);
            let tip = (skeleton.carried_mass(i) - j.own_mass).max(0.0);
            let l2 = j.length * j.length;
            let inertia = m * l2 / 3.0 + tip * l2;
            let f_bare = 0.14 * cbar * d / l2;
            let meff = CANTILEVER_TIP_MASS_FRACTION * m;
            let frequency = f_bare * (meff / (meff + tip)).sqrt();
            let w = 2.0 * PI * frequency;
            let stiffness = inertia * w * w;
            let damping = 2.0 * params.damping_ratio * (stiffness * inertia).sqrt();
            sp.springs.push(JointSpring { inertia, stiffness, damping, frequency });
        }
        let mut order: Vec<u32> = (0..n as u32).collect();
        // Carried mass strictly exceeds every descendant's (own mass > 0), so sorting by
        // it (ties by index, parents first) keeps every prefix closed under parents.
        order.sort_by(|&a, &b| {
            skeleton
                .carried_mass(b as usize)
                .total_cmp(&skeleton.carried_mass(a as usize))
                .then(a.cmp(&b))
        });
        for (r, &j) in order.iter().enumerate() {
            sp.rank[j as usize] = r as u32;
        }
        sp.priority = order;
        Ok(sp)
    }

    /// Number of joints.
    pub fn len(&self) -> usize {
        self.parent.len()
    }

    /// Whether the species has no joints (never true: skeletons are non-empty).
    pub fn is_empty(&self) -> bool {
        self.parent.is_empty()
    }

    /// Spring constants of joint `i`.
    pub fn spring(&self, i: usize) -> JointSpring {
        self.springs[i]
    }

    /// Joints in priority order (the mass each controls, heaviest first).
    pub fn priority(&self) -> &[u32] {
        &self.priority
    }

    /// The parameters in use.
    pub fn params(&self) -> &SwayParams {
        &self.params
    }
}

/// Exact discretisation over a step `dt` of the linear oscillator θ'' + 2ζω θ' + ω² θ = τ/I
/// with τ held constant through the step (zero-order hold): for x = θ − τ/k,
/// [x, θ']ₙ₊₁ = A [x, θ']ₙ. Stable for every dt; without input the energy only decays.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Transition {
    pub a11: f32,
    pub a12: f32,
    pub a21: f32,
    pub a22: f32,
    pub inv_k: f32,
}

impl Transition {
    pub(crate) fn new(s: &JointSpring, zeta: f32, dt: f32) -> Transition {
        // In f64: the terms cancel for stiff joints at long steps.
        let w = 2.0 * std::f64::consts::PI * s.frequency as f64;
        let z = zeta as f64;
        let wd = w * (1.0 - z * z).sqrt();
        let t = dt as f64;
        let e = (-z * w * t).exp();
        let (sn, cs) = (wd * t).sin_cos();
        let a11 = e * (cs + z * w / wd * sn);
        let a12 = e * sn / wd;
        let a21 = -w * w * a12;
        let a22 = e * (cs - z * w / wd * sn);
        Transition {
            a11: a11 as f32,
            a12: a12 as f32,
            a21: a21 as f32,
            a22: a22 as f32,
            inv_k: 1.0 / s.stiffness,
        }
    }
}
