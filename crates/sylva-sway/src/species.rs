//! Per-species precomputation: each joint as a damped angular spring (paper §4.2).
//!
//! Joint i bends about the two axes x_i, y_i of its local frame (z along its segment):
//! I θ'' + c θ' + k θ = τ per axis.
//!
//! * Inertia about the joint: every mass it carries (wood and leaves of each downstream
//!   segment, at the segment's centre), Σ m r².
//! * Stiffness from the natural frequency of the cantilever the joint roots: the rest of
//!   its stem from the joint to the stem's tip (length L, base diameter d),
//!   f_bare = 0.14 √(E/ρ_w) d/L² (first mode of a uniform circular cantilever:
//!   (1.875²/2π)·√(E I_A/(ρ_w A))/L², radius of gyration d/4), lowered by everything else it
//!   carries (side branches, leaves) through the modal mass (Rayleigh): each mass m at
//!   relative height ξ along the stem counts as m φ(ξ)², φ(ξ) = ξ²(3 − ξ)/2 the cantilever's
//!   first-mode shape (a bare uniform stem sums to 33/140 of its mass, the textbook value),
//!   f = f_bare √(0.2357 m_stem / M_modal); then k = I (2πf)².
//!   So a trunk sways at a fraction of a hertz and a twig at several hertz, as measured.
//! * Damping c = 2ζ√(kI) with one damping ratio ζ (structural + aerodynamic).
//! * Drag area: the segment's projected area d·L (C_d of a cylinder) plus its leaves
//!   (C_d per one-sided leaf area), at the segment's mid point; all scaled by one factor
//!   per species where their sum at 20 m/s exceeds the measured whole-crown drag on the
//!   tree's silhouette (`SwayParams::crown_drag`: elements shelter each other).
//!
//! The model is quasi-physical, as in the paper: torques use rest-pose lever arms (small
//! deflections), and each joint's spring is independent of its parent's motion except
//! through the composed transforms.

use std::f32::consts::PI;

use sylva_tree::Skeleton;

use crate::frontal::frontal_area;
use crate::params::{CROWN_DRAG_SPEED, SwayParamError, SwayParams};

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
    /// ½ ρ C_d A of the segment's wood, kg/m.
    pub(crate) drag: Vec<f32>,
    /// ½ ρ C_d A of its leaves in still air, kg/m (reconfigured with speed in the step).
    pub(crate) leaf_drag: Vec<f32>,
    /// Linearised aerodynamic damping rate per unit wind speed, 2·drag·(L/2)²/I, 1/m: the
    /// relative-wind drag damps the joint at about this rate × |U|.
    pub(crate) aero: Vec<f32>,
    pub(crate) springs: Vec<JointSpring>,
    /// Factor on every element's drag from the whole-crown calibration (≤ 1).
    drag_scale: f32,
    /// Joints ordered by priority (carried mass, descending); a prefix of any length is
    /// closed under taking parents.
    pub(crate) priority: Vec<u32>,
    /// Rank of each joint in `priority`.
    pub(crate) rank: Vec<u32>,
    /// The skeleton cut into whole subtrees, for the sweeps along it on several threads.
    pub(crate) cut: Cut,
    /// Per joint, the factor on an instance's wind at the joint's centre of pressure: in the
    /// open (an instance's shelter 0) and deep inside a canopy (shelter 1); an instance
    /// between the two takes the mix. Empty: 1 at every joint, the wind the same at every
    /// height ([`SwaySpecies::set_wind_heights`]).
    pub(crate) wind_open: Vec<f32>,
    pub(crate) wind_inside: Vec<f32>,
    /// Per joint, the factor on the gusts (an instance's wind less its mean,
    /// [`crate::SwayBatch::set_mean_wind`]), in the open and inside; empty: the mean's.
    pub(crate) gust_open: Vec<f32>,
    pub(crate) gust_inside: Vec<f32>,
}

/// A skeleton cut into a small top, closed under taking parents, and whole subtrees below it
/// gathered into bins of similar size: the sweeps along the skeleton (loads tips inwards,
/// palettes root outwards) can then run bin by bin on several threads, each joint's sums
/// taken in the same order as in one sweep over all the joints.
#[derive(Debug, Clone, Default)]
pub(crate) struct Cut {
    /// Joints whose subtree holds more than a bin's share of the skeleton, ascending.
    pub(crate) top: Vec<u32>,
    /// Whether each joint is in `top`.
    pub(crate) in_top: Vec<bool>,
    /// The other joints, ascending in each bin; a subtree is never split between bins.
    pub(crate) bins: Vec<Vec<u32>>,
    /// `top` and the joints whose parent is in it (the roots of the bins' subtrees),
    /// ascending: where the bins' loads meet.
    pub(crate) seam: Vec<u32>,
}

/// Bins a skeleton is cut into, about: enough for the threads of a large machine to share
/// the sweeps, few enough that each is thousands of joints on a near crown.
const BINS: usize = 16;

impl Cut {
    /// Cut the skeleton of `parent` (every parent before its children, as `Skeleton`
    /// validates: the bins' threads write disjoint joints only because of it, so it is
    /// checked here again).
    pub(crate) fn new(parent: &[u32]) -> Cut {
        let n = parent.len();
        assert!(
            parent.iter().enumerate().all(|(i, &p)| p == sylva_tree::NO_PARENT || (p as usize) < i),
            "a joint's parent after it"
        );
        let share = n.div_ceil(BINS).max(1);
        let mut size = vec![1usize; n];
        for i in (0..n).rev() {
            let p = parent[i];
            if p != sylva_tree::NO_PARENT {
                size[p as usize] += size[i];
            }
        }
        let in_top: Vec<bool> = size.iter().map(|&s| s > share).collect();
        // Each joint below the top, the subtree root it hangs from.
        let mut root = vec![0u32; n];
        let mut bin_of_root = vec![u32::MAX; n];
        let (mut bins, mut filled) = (0u32, 0usize);
        for i in 0..n {
            if in_top[i] {
                continue;
            }
            let p = parent[i];
            if p == sylva_tree::NO_PARENT || in_top[p as usize] {
                root[i] = i as u32;
                if filled == 0 || filled >= share {
                    bins += 1;
                    filled = 0;
                }
                bin_of_root[i] = bins - 1;
                filled += size[i];
            } else {
                root[i] = root[p as usize];
            }
        }
        let mut cut = Cut { bins: vec![Vec::new(); bins as usize], ..Cut::default() };
        for i in 0..n {
            let p = parent[i];
            let hangs = p == sylva_tree::NO_PARENT || in_top[p as usize];
            if in_top[i] {
                cut.top.push(i as u32);
            } else {
                cut.bins[bin_of_root[root[i] as usize] as usize].push(i as u32);
            }
            if in_top[i] || hangs {
                cut.seam.push(i as u32);
            }
        }
        cut.in_top = in_top;
        cut
    }
}

/// Wind speed, m/s, under which no joint may bend more than [`DESIGN_BEND`] at rest: a
/// fresh breeze (Beaufort 5, 8–10.7 m/s). Trees grow their twigs stiff enough for the winds
/// they meet (thigmomorphogenesis); Weber–Penn radii are not sized for the load: the
/// cantilever estimate lowered by the carried leaf mass gives the thinnest leafy twigs
/// hundredths of a hertz (a 2 mm twig carrying 0.2 kg of leaves), which turned them through
/// half a circle in a breeze. So a joint's stiffness is raised where its own estimate would
/// let the drag on what it carries fold it; leafy twigs then sway at about 1.5 Hz, and the
/// trunk and limbs keep their frequencies (the design moment binds only on weak joints).
pub const DESIGN_WIND: f32 = 10.0;

/// Largest static bend, rad, of any joint under [`DESIGN_WIND`]: 0.35 rad (20°).
pub const DESIGN_BEND: f32 = 0.35;

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
            leaf_drag: Vec::with_capacity(n),
            aero: Vec::with_capacity(n),
            springs: Vec::with_capacity(n),
            priority: Vec::new(),
            rank: vec![0; n],
            cut: Cut::default(),
            drag_scale: crown_drag_scale(skeleton, &params),
            wind_open: Vec::new(),
            wind_inside: Vec::new(),
            gust_open: Vec::new(),
            gust_inside: Vec::new(),
        };
        let scale = sp.drag_scale;
        let cbar = (params.youngs_modulus / params.wood_density).sqrt();
        // Rest of each joint's stem (tip inwards): length and wood mass along the longest
        // continuation.
        let mut rest_len = vec![0.0f32; n];
        let mut rest_mass = vec![0.0f32; n];
        for i in (0..n).rev() {
            rest_len[i] += joints[i].length;
            rest_mass[i] += joints[i].own_mass;
            let p = joints[i].parent;
            if joints[i].continues && p != sylva_tree::NO_PARENT {
                let p = p as usize;
                // Children come after parents: a parent's own terms are added at its turn.
                if rest_len[i] > rest_len[p] {
                    rest_len[p] = rest_len[i];
                    rest_mass[p] = rest_mass[i];
                }
            }
        }
        // Inertia about each joint, Σ m r², and modal mass of the stem it roots,
        // Σ m φ(ξ)² with the cantilever's first-mode shape φ(ξ) = ξ²(3 − ξ)/2 at the
        // relative height ξ where each mass sits along that stem (a uniform stem alone gives
        // 33/140 of its mass, the textbook value).
        let mut inertia = vec![0.0f32; n];
        let mut modal = vec![0.0f32; n];
        // Σ drag area × lever over what each joint carries, for the design-wind floor.
        let mut lever_area = vec![0.0f32; n];
        let reconfigured = 1.0 / (1.0 + DESIGN_WIND / params.leaf_reconfiguration_speed);
        for (k, jk) in joints.iter().enumerate() {
            let m = jk.own_mass + jk.leaf_mass;
            let c = [
                jk.origin[0] + 0.5 * jk.length * jk.axis[0],
                jk.origin[1] + 0.5 * jk.length * jk.axis[1],
                jk.origin[2] + 0.5 * jk.length * jk.axis[2],
            ];
            let area = scale
                * (params.wood_drag * 2.0 * jk.radius * jk.length
                    + params.leaf_drag * jk.leaf_area * reconfigured);
            let mut a = k as u32;
            while a != sylva_tree::NO_PARENT {
                let ja = &joints[a as usize];
                let d = [c[0] - ja.origin[0], c[1] - ja.origin[1], c[2] - ja.origin[2]];
                let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                inertia[a as usize] += m * r2;
                lever_area[a as usize] += area * r2.sqrt();
                let along = d[0] * ja.axis[0] + d[1] * ja.axis[1] + d[2] * ja.axis[2];
                let xi = (along / rest_len[a as usize]).clamp(0.0, 1.0);
                let phi = 0.5 * xi * xi * (3.0 - xi);
                modal[a as usize] += m * phi * phi;
                a = ja.parent;
            }
        }
        for (i, j) in joints.iter().enumerate() {
            let [x, y, _] = j.frame();
            sp.axes.push([x, y]);
            let h = 0.5 * j.length;
            sp.arm.push([j.axis[0] * h, j.axis[1] * h, j.axis[2] * h]);
            let d = 2.0 * j.radius;
            sp.drag.push(scale * 0.5 * params.air_density * params.wood_drag * d * j.length);
            sp.leaf_drag.push(scale * 0.5 * params.air_density * params.leaf_drag * j.leaf_area);
            let l = rest_len[i];
            let m_stem = rest_mass[i].max(1e-6);
            let inertia = inertia[i].max(1e-9);
            let f_bare = 0.14 * cbar * d / (l * l);
            let meff = CANTILEVER_TIP_MASS_FRACTION * m_stem;
            let mut frequency = f_bare * (meff / modal[i].max(meff)).sqrt();
            // No joint bends more than DESIGN_BEND under the drag of the design wind on all it
            // carries (the moment at rest pose, an upper bound): thin twigs loaded with leaves
            // would otherwise come out at hundredths of a hertz and whirl round in a breeze.
            let design_moment =
                0.5 * params.air_density * DESIGN_WIND * DESIGN_WIND * lever_area[i];
            let w_design = (design_moment / DESIGN_BEND / inertia).sqrt();
            frequency = frequency.max(w_design / (2.0 * PI));
            let w = 2.0 * PI * frequency;
            let stiffness = inertia * w * w;
            let damping = 2.0 * params.damping_ratio * (stiffness * inertia).sqrt();
            sp.aero.push(2.0 * (sp.drag[i] + sp.leaf_drag[i]) * h * h / inertia);
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
        sp.cut = Cut::new(&sp.parent);
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

    /// Factor on every segment's and leaf's drag from the whole-crown calibration
    /// ([`SwayParams::crown_drag`]): 1 where the summed drag is within it.
    pub fn drag_scale(&self) -> f32 {
        self.drag_scale
    }

    /// Each joint's centre of pressure at rest (its segment's middle), tree space, m: the
    /// points whose heights [`SwaySpecies::set_wind_heights`] takes factors for.
    pub fn pressure_centres(&self) -> Vec<[f32; 3]> {
        self.origin
            .iter()
            .zip(&self.arm)
            .map(|(o, a)| [o[0] + a[0], o[1] + a[1], o[2] + a[2]])
            .collect()
    }

    /// Let the wind differ with height: at joint `i` an instance feels its wind times
    /// `open[i]` where its shelter is 0 (a forest's windward edge, open ground upwind),
    /// `inside[i]` where it is 1 (deep in a canopy), and the linear mix between
    /// ([`crate::SwayBatch::set_shelter`]). A mean wind profile divided by the mean speed where
    /// the instance's wind is sampled gives the factors: the mean wind at every joint is then
    /// the profile's at its height. Two empty slices: the same wind at every joint (the
    /// default). Factors must be finite and ≥ 0, one per joint. The gusts take the same
    /// factors until [`SwaySpecies::set_gust_heights`] gives them their own.
    pub fn set_wind_heights(&mut self, open: &[f32], inside: &[f32]) -> Result<(), SwayParamError> {
        if open.is_empty() && inside.is_empty() {
            self.wind_open.clear();
            self.wind_inside.clear();
            self.gust_open.clear();
            self.gust_inside.clear();
            return Ok(());
        }
        self.check_factors(("wind_open", open), ("wind_inside", inside))?;
        self.wind_open = open.to_vec();
        self.wind_inside = inside.to_vec();
        self.gust_open = open.to_vec();
        self.gust_inside = inside.to_vec();
        Ok(())
    }

    /// Give the gusts their own factors per joint (after [`SwaySpecies::set_wind_heights`],
    /// which they otherwise share): an instance's wind u with mean ū
    /// ([`crate::SwayBatch::set_mean_wind`]) is felt at joint `i` as m ū + g (u − ū), m the
    /// mean's factor and g the gusts' (`open[i]` … `inside[i]` by shelter, as the mean's).
    /// Refused without mean factors set; factors finite and ≥ 0, one per joint.
    pub fn set_gust_heights(&mut self, open: &[f32], inside: &[f32]) -> Result<(), SwayParamError> {
        if self.wind_open.is_empty() {
            let expected = "mean factors first (set_wind_heights)";
            return Err(SwayParamError { field: "gust_open", value: open.len() as f32, expected });
        }
        self.check_factors(("gust_open", open), ("gust_inside", inside))?;
        self.gust_open = open.to_vec();
        self.gust_inside = inside.to_vec();
        Ok(())
    }

    fn check_factors(
        &self,
        a: (&'static str, &[f32]),
        b: (&'static str, &[f32]),
    ) -> Result<(), SwayParamError> {
        let n = self.len();
        for (field, f) in [a, b] {
            if f.len() != n {
                let expected = "one factor per joint";
                return Err(SwayParamError { field, value: f.len() as f32, expected });
            }
            if let Some(&value) = f.iter().find(|x| !(x.is_finite() && **x >= 0.0)) {
                return Err(SwayParamError { field, value, expected: "finite, >= 0" });
            }
        }
        Ok(())
    }

    /// Whether the wind differs with height ([`SwaySpecies::set_wind_heights`]).
    pub fn has_wind_heights(&self) -> bool {
        !self.wind_open.is_empty()
    }

    /// Per lane: the factors on the mean wind and on the gusts at joint `i` for lanes of
    /// shelter `shelter`; `None` without height factors (the wind then passes through as it
    /// is).
    #[inline(always)]
    pub(crate) fn wind_factor<const W: usize>(
        &self,
        i: usize,
        shelter: &[f32; crate::batch::LANES],
    ) -> Option<crate::batch::JointWind<W>> {
        if self.wind_open.is_empty() {
            return None;
        }
        let (open, gain) = (self.wind_open[i], self.wind_inside[i] - self.wind_open[i]);
        let (gust, more) = (self.gust_open[i], self.gust_inside[i] - self.gust_open[i]);
        Some(crate::batch::JointWind {
            mean: std::array::from_fn(|l| open + shelter[l] * gain),
            gust: std::array::from_fn(|l| gust + shelter[l] * more),
        })
    }

    /// The tree's drag area C_d·A at rest in a steady wind of `speed` m/s, m²: every
    /// segment's and leaf's (leaves reconfigured), as the step sums them.
    pub fn drag_area(&self, speed: f32) -> f32 {
        let leaves = 1.0 / (1.0 + speed.max(0.0) / self.params.leaf_reconfiguration_speed);
        let wood: f32 = self.drag.iter().sum();
        let leaf: f32 = self.leaf_drag.iter().sum();
        (wood + leaf * leaves) / (0.5 * self.params.air_density)
    }
}

/// The whole-crown calibration's factor for `skeleton` ([`SwayParams::crown_drag`]):
/// min(1, C_crown · silhouette / Σ element C_d A at [`CROWN_DRAG_SPEED`]).
fn crown_drag_scale(skeleton: &Skeleton, params: &SwayParams) -> f32 {
    if params.crown_drag <= 0.0 {
        return 1.0;
    }
    let leaves = 1.0 / (1.0 + CROWN_DRAG_SPEED / params.leaf_reconfiguration_speed);
    let elements: f32 = skeleton
        .joints()
        .iter()
        .map(|j| {
            params.wood_drag * 2.0 * j.radius * j.length + params.leaf_drag * j.leaf_area * leaves
        })
        .sum();
    if elements <= 0.0 {
        return 1.0;
    }
    (params.crown_drag * frontal_area(skeleton).union / elements).min(1.0)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The cut of a near crown (the black tupelo, 19 000 joints): every joint is in the top
    /// or in one bin; the top is closed under taking parents; a bin joint's parent is in the
    /// top or in the same bin (a bin holds whole subtrees, so its sweeps need no other bin);
    /// the seam is the top and the bins' subtree roots; and the bins share the skeleton
    /// (none more than twice its share plus one subtree), so the sweeps do split.
    #[test]
    fn a_cut_holds_whole_subtrees_in_bins_of_similar_size() {
        let model = sylva_tree::Species::preset("black_tupelo").expect("preset").model(5, 4);
        let sp = SwaySpecies::new(&model.expect("model").tree.skeleton, SwayParams::default())
            .expect("species");
        let (n, cut) = (sp.len(), &sp.cut);
        let mut bin_of = vec![usize::MAX; n];
        for (b, bin) in cut.bins.iter().enumerate() {
            assert!(bin.windows(2).all(|w| w[0] < w[1]), "bin {b} ascending");
            for &j in bin {
                assert_eq!(bin_of[j as usize], usize::MAX, "joint {j} in two bins");
                bin_of[j as usize] = b;
            }
        }
        assert!(cut.top.windows(2).all(|w| w[0] < w[1]));
        for j in 0..n {
            let p = sp.parent[j];
            let in_bin = bin_of[j] != usize::MAX;
            assert_eq!(cut.in_top[j], cut.top.binary_search(&(j as u32)).is_ok());
            assert!(cut.in_top[j] != in_bin, "joint {j}: in the top or in a bin, not both");
            let hangs = in_bin && (p == sylva_tree::NO_PARENT || cut.in_top[p as usize]);
            if p != sylva_tree::NO_PARENT {
                let p = p as usize;
                if cut.in_top[j] {
                    assert!(cut.in_top[p], "joint {j} in the top, its parent {p} not");
                } else if !hangs {
                    assert_eq!(bin_of[p], bin_of[j], "joint {j} and its parent {p}");
                }
            }
            assert_eq!(
                cut.seam.binary_search(&(j as u32)).is_ok(),
                cut.in_top[j] || hangs,
                "joint {j} on the seam"
            );
        }
        let share = n.div_ceil(BINS);
        assert!(
            n > 10_000 && cut.top.len() < n / 100,
            "{} of {n} joints in the top",
            cut.top.len()
        );
        assert!(cut.bins.len() >= BINS / 2, "{} bins", cut.bins.len());
        assert!(cut.bins.iter().all(|b| b.len() <= 2 * share + 1), "bins over twice a share");
    }
}
