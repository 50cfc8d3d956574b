//! Many instances of one species stepped together (structure of arrays, rayon).
//!
//! Per instance and step: (1) loads — eq.-8 drag on every segment and its leaves (leaves
//! reconfigured: their drag divided by 1 + |u|/U_r, see `SwayParams`), with the
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
//! Animation LOD by prefix: a group may simulate only its first joints (see
//! [`SwayBatch::set_active`]; with a skeleton in LOD order — `sylva_tree::lod_order` — those
//! are the joints a coarse level draws). The joints beyond are not touched at all: no
//! loads, springs or palettes. Held at rest, their drag is still felt by the simulated
//! joints as a lumped static load — with one wind velocity `u` per instance, the drag of a
//! rigid segment k is `c_k |u| u` (its leaves' `l_k |u| u / (1 + |u|/U_r)`), so everything
//! hanging from simulated joint i adds force `D_i |u| u` and moment `(P_i − D_i o_i) × |u| u`
//! about its origin, `D_i = Σ c_k`, `P_i = Σ c_k (o_k + arm_k)` — wood and leaves lumped
//! apart, the leaves' with their reconfigured `|u| u` — precomputed per prefix. Joints switched back on restart at
//! their static equilibrium and blend in over `blend_time`; joints switched off fade out
//! first (computed, frozen, their displayed rotation going to rest over `blend_time`) and
//! are dropped once at rest. A dropped joint rests on its parent, so it shows its nearest
//! simulated ancestor's palette ([`SwayBatch::anchors`]).
//!
//! Each instance may also ask for its own prefix within its group's
//! ([`SwayBatch::set_lane_active`]): one tree near the camera among far ones in a group. Its
//! lane-mates fade out the joints beyond their own and are then left at rest there, and the
//! step picks, per group, which lanes to step alone (at width 1, on a copy of the lane's
//! angles, rates and weights, its palettes kept in a row of their own,
//! [`SwayBatch::lane_palettes`]) and which together to the longest prefix among them —
//! within what [`SwayBatch::set_alone_limit`] lets those rows hold: the cheapest split by the
//! measured cost of a joint at each width (a joint of a 16-lane group costs about 4.4 of
//! one lane alone on AVX-512). A group of 16 far trunks and one near crown then costs one
//! crown and 16 trunks, not 16 crowns.
//!
//! Layout: instances are gathered in groups of [`LANES`]; within a group every array is
//! (joint, …, lane), so each joint is computed for all lanes of a group at once and the
//! compiler vectorises across instances (AVX-512, AVX2 or the baseline, picked at run
//! time; the same IEEE operations either way). A batch of fewer than [`LANES`] instances
//! stores and computes only 1, 4 or 8 lanes ([`SwayBatch::width`]): the step costs per
//! lane stored, so a species with a single simulation (a hero tree, or a heavy species'
//! share of a scene's budget) does not pay for fifteen empty lanes. Each lane gets the
//! same operations at any width, so an instance moves bit for bit as it would in a full
//! group (the one choice made per group, series or full formula for the joint rotations,
//! follows the largest angle among the lanes it steps together; lanes stepped alone, whose
//! values in the group nothing reads, take no part). A single lane (a batch of one, or a lane
//! stepped alone) has nothing to vectorise across and takes a kernel of its own with the
//! same operations, ordered so that the joints' independent work is not chained along the
//! skeleton (`batch/alone.rs`; about 30 % less time a joint). A lane stepped alone keeps its
//! state and palettes in a row of its own for as long as it stays alone, rather than
//! strided across its group's lanes. Groups are independent and each is computed
//! by the same sequence of operations whatever thread runs it, so results are bit-identical
//! for any thread count.
//!
//! Storage follows the animation LOD: each group stores, for every lane, the state of the
//! joints it steps its lanes together to (their prefix, with those still fading out) and no
//! others; a lane stepped alone holds its own, however many, in its row. Memory is
//! allocated when a prefix grows and given back [`TRIM_STEPS`] steps after it shrinks.
//! Joints not stored are at rest; a joint switched back on restarts at its equilibrium, so
//! nothing that was dropped is ever read. A forest of far trees that simulate their trunks
//! holds the trunks' state, not the crowns' ([`SwayBatch::stored_bytes`]), and a group of
//! far trunks with one near crown holds the trunks for every lane and the crown once. Once
//! prefixes have stayed put for [`TRIM_STEPS`] steps, a step allocates nothing.

use std::f32::consts::PI;

use rayon::prelude::*;
use sylva_core::simd_kernel;
use sylva_core::v3::{cross, dot};

use crate::species::{SwaySpecies, Transition};

#[cfg(not(feature = "glam"))]
mod alone;

/// A 3×4 affine matrix, row-major: rotation | translation. Maps a rest-pose tree-space point
/// to its animated position.
pub type Palette = [f32; 12];

/// The rest pose's palette (the identity): a joint not yet simulated.
pub const IDENTITY: Palette = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];

/// Instances per group: the vector width the joint loops run across.
pub const LANES: usize = 16;
/// A value per lane of a group.
pub type Lanes = [f32; LANES];

const ZERO: Lanes = [0.0; LANES];

/// Bytes of animation state per joint and lane stored: 17 `f32` (two angles, two rates, the
/// blend weight, the 3×4 palette).
pub const STATE_BYTES: usize = 17 * 4;

/// Largest bend of any joint from its parent, rad (1.2 rad, about 70°).
pub const MAX_BEND: f32 = 1.2;

/// Where one instance's joint palettes lie in a lane-interleaved buffer of `f32`: element `e`
/// (row-major 3×4) of joint `j` is at `base + (12 j + e) · stride`.
///
/// This is the palette lane layout, the one contract between the sway step, the forest's
/// frame and the shaders: [`SwayBatch::group_palettes`] is such a buffer for each lane
/// group, with `stride` = its [`width`](SwayBatch::width); sylva-forest copies each lane
/// group's block keeping the layout with `stride` = the lanes it simulates (or one
/// simulation's palettes in a row, `stride` 1), and gives every drawn tree its slot
/// (`Instance::palette`); the vertex shaders read it with `palette()` in sylva-render's
/// `common.wgsl`. Tested on the simulation side (against [`SwayBatch::palette`]) and on the
/// GPU side (the WGSL reader against [`PaletteSlot::read`]).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PaletteSlot {
    /// Index of element 0 of joint 0.
    pub base: u32,
    /// Distance between consecutive elements: the instances whose palettes are interleaved
    /// with this one's (1 … [`LANES`]).
    pub stride: u32,
}

impl PaletteSlot {
    /// Index of element `e` (0 … 11) of joint `j`'s palette.
    #[inline]
    pub fn index(self, j: usize, e: usize) -> usize {
        self.base as usize + (12 * j + e) * self.stride as usize
    }

    /// Joint `j`'s palette from `buffer`, or `None` where the buffer ends before it.
    pub fn read(self, buffer: &[f32], j: usize) -> Option<Palette> {
        buffer.get(self.index(j, 11))?;
        Some(std::array::from_fn(|e| buffer[self.index(j, e)]))
    }

    /// One past the last index the first `joints` palettes use (0 for none).
    pub fn end(self, joints: usize) -> usize {
        if joints == 0 { 0 } else { self.index(joints - 1, 11) + 1 }
    }
}

/// Lumped static drag of held joints: [D, c] of their wood, then of their leaves.
type Lump = [[f32; 4]; 2];

/// How a step splits one group's lanes.
#[derive(Debug, Clone, Copy, Default)]
struct Plan {
    /// Per lane: the prefix it keeps switched on, and the one it is stepped to at least
    /// (its joints beyond are at rest).
    on: [u32; LANES],
    need: [u32; LANES],
    /// The prefix the group steps its lanes to together, and the lanes stepped alone (a
    /// bit each).
    head: u32,
    solo: u32,
}

/// One group's stored state: its first `joints` joints for every lane (a prefix: those it
/// steps its lanes together to, and none beyond), `width` lanes inner. A lane's joints are
/// in its row where the row holds them, else here where stored, else at rest.
///
/// The memory behind it may hold more joints than are stored: a group whose prefix shrinks
/// keeps its memory for [`TRIM_STEPS`] steps before giving it back, so a prefix that comes
/// and goes (a tree at the edge of a level, lanes repacked) costs no allocation and no
/// page faults each time.
#[derive(Debug, Clone, Default)]
struct Block {
    /// Per joint, per axis: bending angle (rad) and rate (rad/s).
    theta: Vec<f32>,
    rate: Vec<f32>,
    /// Displayed fraction of each joint's rotation (animation-LOD blend), 0 … 1.
    weight: Vec<f32>,
    /// Palettes per (joint, element) (parents are read from here).
    pal: Vec<f32>,
    /// Joints stored (the vectors hold at least these).
    joints: usize,
    /// Steps in a row this block has held memory for more joints than it stores.
    idle: u32,
    /// Lanes the last step stepped alone (a bit each): their palettes are in `rows`, not
    /// in `pal`.
    alone: u32,
    /// Per lane stepped alone: its row (empty for the others).
    rows: Vec<Row>,
}

/// The state of a lane stepped alone, one value per joint in a row rather than strided
/// across its group's lanes: its palettes (12 per joint) for the joints it simulates, and
/// its angles, rates and blend weights for the first `joints` joints, which stand for the
/// group's values of that lane (the group need not store them: it stores what it steps all
/// its lanes to). The state stays in the row while the lane goes alone from step to step
/// (copying it in and out of the group each step, through memory strided by the group's
/// width, cost a third of a near tree's step), moves with the lane when lanes are
/// exchanged, and goes back to the group when the lane rejoins it.
#[derive(Debug, Clone, Default)]
struct Row {
    pal: Vec<f32>,
    theta: Vec<f32>,
    rate: Vec<f32>,
    weight: Vec<f32>,
    /// Joints whose state the row holds (the group's values of the lane for them are not
    /// current).
    joints: usize,
}

impl Row {
    /// Values held (capacity), all four vectors.
    fn capacity(&self) -> usize {
        self.pal.capacity() + self.theta.capacity() + self.rate.capacity() + self.weight.capacity()
    }

    /// Hold the state of joints `..joints` of lane `l` of a group of `width` lanes (angles
    /// `theta`, rates `rate`, weights `weight`) that stores its first `stored` joints for
    /// every lane: joints the row held beyond go back to the group (those it stores; the
    /// others are at rest, as the lane shows them there), joints it lacks come from it (at
    /// rest, with blend weight `rest`, where it does not store them). Grown exactly, so
    /// that the bytes held are the bytes counted.
    fn hold(
        &mut self,
        joints: usize,
        group: [&mut Vec<f32>; 3],
        width: usize,
        l: usize,
        (stored, rest): (usize, f32),
    ) {
        let [theta, rate, weight] = group;
        let had = self.joints;
        for j in joints..stored.min(had) {
            for k in 0..2 {
                theta[(2 * j + k) * width + l] = self.theta[2 * j + k];
                rate[(2 * j + k) * width + l] = self.rate[2 * j + k];
            }
            weight[j * width + l] = self.weight[j];
        }
        self.theta.truncate(2 * joints.min(had));
        self.rate.truncate(2 * joints.min(had));
        self.weight.truncate(joints.min(had));
        if joints > had {
            for v in [&mut self.theta, &mut self.rate] {
                v.reserve_exact(2 * (joints - had));
            }
            self.weight.reserve_exact(joints - had);
            for j in had..joints.min(stored) {
                for k in 0..2 {
                    self.theta.push(theta[(2 * j + k) * width + l]);
                    self.rate.push(rate[(2 * j + k) * width + l]);
                }
                self.weight.push(weight[j * width + l]);
            }
            self.theta.resize(2 * joints, 0.0);
            self.rate.resize(2 * joints, 0.0);
            self.weight.resize(joints, rest);
        }
        self.joints = joints;
    }
}

impl Block {
    /// Lane `l`'s row, if it holds the state of joint `j`.
    fn row_holding(&self, l: usize, j: usize) -> Option<&Row> {
        self.rows.get(l).filter(|r| j < r.joints)
    }

    /// Take lane `l`'s state (of a group of `width` lanes) for its first `m` joints at
    /// least, as a row: its row, extended with what the group stores for it beyond, and
    /// whether the row's palettes are current (the lane was stepped alone). The lane's
    /// values in the group are left for [`Block::put_lane`] to overwrite.
    fn take_lane(&mut self, l: usize, m: usize, width: usize) -> (Row, bool) {
        let mut row = self.rows.get_mut(l).map(std::mem::take).unwrap_or_default();
        let alone = self.alone >> l & 1 == 1;
        self.alone &= !(1 << l);
        let (had, end) = (row.joints, row.joints.max(self.joints.min(m)));
        if end > had {
            for v in [&mut row.theta, &mut row.rate] {
                v.reserve_exact(2 * (end - had));
            }
            row.weight.reserve_exact(end - had);
            for j in had..end {
                for k in 0..2 {
                    row.theta.push(self.theta[(2 * j + k) * width + l]);
                    row.rate.push(self.rate[(2 * j + k) * width + l]);
                }
                row.weight.push(self.weight[j * width + l]);
            }
            row.joints = end;
        }
        (row, alone)
    }

    /// Give lane `l` the state `taken` by [`Block::take_lane`]: into the group's lane where
    /// the group stores all of it and its palettes are not current, else as the lane's row;
    /// either way at rest (blend weight `rest`) beyond it.
    fn put_lane(&mut self, l: usize, taken: (Row, bool), width: usize, rest: f32) {
        let (row, alone) = taken;
        let (joints, stored) = (row.joints, self.joints);
        let in_group = !alone && joints <= stored;
        if in_group {
            for j in 0..joints {
                for k in 0..2 {
                    self.theta[(2 * j + k) * width + l] = row.theta[2 * j + k];
                    self.rate[(2 * j + k) * width + l] = row.rate[2 * j + k];
                }
                self.weight[j * width + l] = row.weight[j];
            }
        }
        for j in joints..stored {
            for k in 0..2 {
                self.theta[(2 * j + k) * width + l] = 0.0;
                self.rate[(2 * j + k) * width + l] = 0.0;
            }
            self.weight[j * width + l] = rest;
        }
        if in_group {
            if let Some(r) = self.rows.get_mut(l) {
                *r = Row::default();
            }
        } else {
            if self.rows.len() < width {
                self.rows.resize_with(width, Row::default);
            }
            self.rows[l] = row;
            self.alone |= (alone as u32) << l;
        }
    }
}

/// Steps a lane group keeps the memory of joints it no longer stores before giving it
/// back (about two seconds at 30 frames a second).
pub const TRIM_STEPS: u32 = 64;

impl Block {
    /// Joints the memory holds, at `width` lanes.
    fn reserved(&self, width: usize) -> usize {
        self.weight.len() / width
    }

    /// Store `joints` joints for every lane. Joints it did not store before start at rest
    /// in every lane: angles and rates 0, blend weight `rest` (1 before a batch's first
    /// step, when every joint is shown at rest; 0 after, so that a joint that comes back
    /// blends in). Their palettes are computed by the step that simulates them, and read
    /// only once simulated. Fewer joints than stored: those beyond are no longer stored
    /// (their memory is kept, see [`Block::trim`]).
    fn store(&mut self, joints: usize, width: usize, rest: f32) {
        let had = self.joints;
        if joints > had {
            // Joints the memory still holds from before: reset to rest.
            let kept = joints.min(self.reserved(width));
            if kept > had {
                self.theta[2 * had * width..2 * kept * width].fill(0.0);
                self.rate[2 * had * width..2 * kept * width].fill(0.0);
                self.weight[had * width..kept * width].fill(rest);
            }
        }
        if joints > self.reserved(width) {
            // Exactly what is needed, so that the bytes held are the bytes counted; grown in
            // place where the allocator can (a large block is remapped, not copied).
            let grow = |v: &mut Vec<f32>, len: usize, value: f32| {
                v.reserve_exact(len - v.len());
                v.resize(len, value);
            };
            grow(&mut self.theta, 2 * joints * width, 0.0);
            grow(&mut self.rate, 2 * joints * width, 0.0);
            grow(&mut self.pal, 12 * joints * width, 0.0);
            grow(&mut self.weight, joints * width, rest);
        }
        self.joints = joints;
    }

    /// Count a step: memory held beyond the joints stored for [`TRIM_STEPS`] steps in a row
    /// is given back.
    fn trim(&mut self, width: usize) {
        if self.reserved(width) <= self.joints {
            self.idle = 0;
            return;
        }
        self.idle += 1;
        if self.idle >= TRIM_STEPS {
            let j = self.joints;
            self.theta.truncate(2 * j * width);
            self.rate.truncate(2 * j * width);
            self.weight.truncate(j * width);
            self.pal.truncate(12 * j * width);
            for v in [&mut self.theta, &mut self.rate, &mut self.weight, &mut self.pal] {
                v.shrink_to_fit();
            }
            self.idle = 0;
        }
    }

    /// Bytes held.
    fn bytes(&self) -> usize {
        4 * (self.theta.capacity()
            + self.rate.capacity()
            + self.weight.capacity()
            + self.pal.capacity()
            + self.rows.iter().map(Row::capacity).sum::<usize>())
    }
}

/// Instances of one species and their animation state.
#[derive(Debug, Clone)]
pub struct SwayBatch {
    species: SwaySpecies,
    instances: usize,
    /// Lanes stored per group: [`LANES`], or 1, 4 or 8 for a batch of fewer instances.
    width: usize,
    /// Per group: the state of the joints it stores (see [`Block`]).
    blocks: Vec<Block>,
    budget: Vec<u32>,
    /// Per group: joints simulated (a prefix).
    active: Vec<u32>,
    /// Per instance: joints whose state is current (the prefix its group simulated when
    /// last set; an instance moved by [`SwayBatch::swap_instances`] takes its own along).
    fresh: Vec<u32>,
    /// Per group: the prefix it is fading down to (= `active` when not fading). Joints from
    /// `keep` to `active` are still computed, frozen, their displayed rotation blending to
    /// rest; once every one is at rest the group drops them.
    keep: Vec<u32>,
    /// Per instance: the prefix it asks for itself ([`SwayBatch::set_lane_active`]; every
    /// joint unless set). Within its group's prefix, an instance's joints beyond it fade out.
    want: Vec<u32>,
    /// Per instance: joints beyond this are at rest in its lane (blend weight 0), so a step
    /// may leave them out for this lane.
    live: Vec<u32>,
    /// Per instance: the joints the last step computed for it (its palettes beyond are not
    /// current; it shows them at their anchors).
    stepped: Vec<u32>,
    /// Bytes the rows of lanes stepped alone (their palettes and state) may hold in all
    /// ([`SwayBatch::set_alone_limit`]).
    alone_limit: usize,
    /// Per group, the step's split of its lanes (decided in group order before the step).
    plans: Vec<Plan>,
    /// Registered prefixes and, per joint of each, the lumped static drag [D, c] with
    /// `c = P − D o` (see the module documentation), of the wood and of the leaves.
    lumped: Vec<(usize, Vec<Lump>)>,
    /// Per registered prefix, per joint: the joint whose palette it shows when the prefix is
    /// simulated (itself within the prefix, else its nearest simulated ancestor).
    anchors: Vec<(usize, Vec<u32>)>,
    /// Joint updates (joints computed, summed over instances) of the last step.
    updates: usize,
    transitions: Vec<Transition>,
    /// Per joint, aerodynamic damping rate per unit wind speed × dt (see `loads`).
    aero_dt: Vec<f32>,
    dt: f32,
}

/// Rotation matrix of the rotation vector φ (axis × angle), Rodrigues' formula. Small
/// angles use Taylor series of sin a/a and (1 − cos a)/a² (error < 1e-9 below 0.5 rad).
#[cfg(test)]
fn rotation(phi: [f32; 3]) -> [[f32; 3]; 3] {
    let (s, c) = sin_cos_ratios(dot(phi, phi));
    rodrigues(phi, s, c)
}

/// (sin a / a, (1 − cos a) / a²) from a², by series below a = 0.5 rad.
fn sin_cos_ratios(a2: f32) -> (f32, f32) {
    if a2 < 0.25 { small_angle(a2) } else { large_angle(a2) }
}

/// A joint's palette for the rotation vector `phi` about its rest position `o` (one joint
/// at a time, off the step's lanes: `CrownLean`'s settled crowns).
pub(crate) fn joint_palette(phi: [f32; 3], o: [f32; 3]) -> Palette {
    let (s, c) = sin_cos_ratios(dot(phi, phi));
    local_palette(phi, o, s, c)
}

/// Below this e² (e = 0.1 rad) `lever_bend`'s factor is taken from its series, 1 − e²/2.
const LEVER_SERIES: f32 = 0.01;

/// The bend at which a joint's spring balances the drag's moment on the bent joint, as a
/// factor of the linear equilibrium bend `e` (moment over stiffness), from `e2` = e².
///
/// The loads are summed on the rest pose. As a joint turns by θ into the flow, its load's
/// lever arm shortens as cos θ (a segment across a fixed force), so it settles where
/// θ = e cos θ: θ ≈ e for small loads, 0.74 rad at e = 1, 1.17 at e = 3, and never past a
/// quarter turn however strong the wind — where a linear spring would fold the twig over.
/// Solved by one Newton step from e / √(1 + (2e/π)²) (within 0.6 % of the root for every
/// e), with short polynomials for cos and sin on [0, π/2] so the lane loop vectorises.
#[inline(always)]
pub(crate) fn lever_bend(e2: f32) -> f32 {
    // Floored so that no load divides by zero (the factor tends to 1 there).
    let e = e2.sqrt().max(1e-6);
    let t = e / (1.0 + e2 * (4.0 / (PI * PI))).sqrt();
    let t2 = t * t;
    let c = 1.0 + t2 * (-0.5 + t2 * (1.0 / 24.0 + t2 * (-1.0 / 720.0)));
    let s = t * (1.0 + t2 * (-1.0 / 6.0 + t2 * (1.0 / 120.0 + t2 * (-1.0 / 5040.0))));
    let root = t - (t - e * c) / (1.0 + e * s);
    root / e
}

/// Per lane, [`lever_bend`]'s factor from e², or its series 1 − e²/2 below [`LEVER_SERIES`]:
/// the Newton step is taken only where some lane is above it, and each lane's factor is the
/// same whichever way its neighbours go.
#[inline(always)]
fn lever_factors<const N: usize>(e2: &[f32; N]) -> [f32; N] {
    let heavy = e2.iter().fold(false, |h, &x| h | (x > LEVER_SERIES));
    let mut f = [0.0f32; N];
    for l in 0..N {
        f[l] = 1.0 - 0.5 * e2[l];
    }
    if heavy {
        for l in 0..N {
            let full = lever_bend(e2[l]);
            f[l] = if e2[l] > LEVER_SERIES { full } else { f[l] };
        }
    }
    f
}

/// (sin a / a, (1 − cos a) / a²) from a² by Taylor series, for a² < 0.25.
#[inline(always)]
fn small_angle(a2: f32) -> (f32, f32) {
    (
        1.0 - a2 / 6.0 * (1.0 - a2 / 20.0 * (1.0 - a2 / 42.0 * (1.0 - a2 / 72.0))),
        0.5 * (1.0 - a2 / 12.0 * (1.0 - a2 / 30.0 * (1.0 - a2 / 56.0 * (1.0 - a2 / 90.0)))),
    )
}

fn large_angle(a2: f32) -> (f32, f32) {
    let a = a2.sqrt();
    (a.sin() / a, (1.0 - a.cos()) / a2)
}

/// (sin a / a, (1 − cos a) / a²) from a² for any angle, branch-free so it vectorises: the
/// angle is reduced to r ∈ [−π, π] (same sine and cosine), the Taylor series is taken at
/// r/8 and doubled three times (sin 2h / 2h = (sin h / h) cos h; (1 − cos 2h) / (2h)² =
/// (sin h / h)² / 2; cos h = 1 − h² (1 − cos h)/h²), then rescaled by r/a. Absolute error
/// below 3e-7 (against f64).
#[inline(always)]
fn any_angle(a2: f32) -> (f32, f32) {
    let a = a2.sqrt();
    let r = a - std::f32::consts::TAU * (a / std::f32::consts::TAU).round();
    let ratio = if a > 0.0 { r / a } else { 1.0 };
    let mut h2 = r * r / 64.0;
    let (mut s, mut v) = small_angle(h2);
    for _ in 0..3 {
        let c = 1.0 - h2 * v;
        v = 0.5 * s * s;
        s *= c;
        h2 *= 4.0;
    }
    (s * ratio, v * ratio * ratio)
}

#[inline(always)]
fn rodrigues(phi: [f32; 3], s: f32, c: f32) -> [[f32; 3]; 3] {
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
        let groups = instances.div_ceil(LANES);
        let width = Self::width_for(instances);
        SwayBatch {
            instances,
            width,
            // Stored as the steps need them: nothing until the first step or set_active.
            blocks: vec![Block::default(); groups],
            budget: vec![n as u32; instances],
            active: vec![n as u32; groups],
            fresh: vec![n as u32; instances],
            keep: vec![n as u32; groups],
            want: vec![n as u32; instances],
            live: vec![n as u32; instances],
            stepped: vec![n as u32; instances],
            alone_limit: usize::MAX,
            plans: Vec::new(),
            lumped: Vec::new(),
            anchors: Vec::new(),
            updates: 0,
            transitions: Vec::with_capacity(n),
            aero_dt: Vec::with_capacity(n),
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

    /// Lanes stored and computed per group: [`LANES`], or for a batch of fewer instances
    /// the first of 1, 4 and 8 that holds them all.
    pub fn width(&self) -> usize {
        self.width
    }

    /// The [`width`](Self::width) of a batch of `instances`.
    pub fn width_for(instances: usize) -> usize {
        match instances {
            0..=1 => 1,
            2..=4 => 4,
            5..=8 => 8,
            _ => LANES,
        }
    }

    /// Bytes of animation state and palettes a batch of `instances` instances of a
    /// `joints`-joint species holds when every group stores `joints` joints (17 values per
    /// joint and stored lane: angles, rates, blend weight, palette). The step's load
    /// accumulators are scratch, one group's per thread.
    pub fn state_bytes(instances: usize, joints: usize) -> usize {
        instances.div_ceil(LANES) * Self::width_for(instances) * joints * STATE_BYTES
    }

    /// Bytes of animation state and palettes this batch holds now. A group stores the
    /// joints it simulates and no others (those beyond are at rest), so this follows the
    /// animation LOD, a few seconds behind as a prefix shrinks ([`TRIM_STEPS`]): a forest
    /// of far trees that simulate their trunks holds the trunks'.
    pub fn stored_bytes(&self) -> usize {
        self.blocks.iter().map(Block::bytes).sum()
    }

    /// Number of lane groups ([`LANES`] instances each, the last one partial).
    pub fn groups(&self) -> usize {
        self.blocks.len()
    }

    /// Set how many joints of instance `i` are simulated (the heaviest `budget`, by carried
    /// mass). Clamped to the joint count.
    pub fn set_budget(&mut self, i: usize, budget: usize) {
        self.budget[i] = budget.min(self.species.len()) as u32;
    }

    /// Make `prefixes` (joint counts) available to [`SwayBatch::set_active`]: the lumped
    /// static drag of the joints beyond each is precomputed here. Call once, at set-up.
    pub fn set_prefixes(&mut self, prefixes: &[usize]) {
        let sp = &self.species;
        let n = sp.len();
        self.lumped.clear();
        self.anchors.clear();
        for &p in prefixes {
            let p = p.clamp(1, n);
            if p == n || self.lumped.iter().any(|(q, _)| *q == p) {
                continue;
            }
            let mut sums: Vec<Lump> = vec![[[0.0f32; 4]; 2]; p];
            // The simulated ancestor each held joint hangs from (parents come first).
            let mut anchor: Vec<u32> = (0..n as u32).collect();
            for k in p..n {
                let parent = sp.parent[k] as usize;
                let a = if parent < p { parent } else { anchor[parent] as usize };
                anchor[k] = a as u32;
                let at = [
                    sp.origin[k][0] + sp.arm[k][0],
                    sp.origin[k][1] + sp.arm[k][1],
                    sp.origin[k][2] + sp.arm[k][2],
                ];
                for (part, c) in [sp.drag[k], sp.leaf_drag[k]].into_iter().enumerate() {
                    sums[a][part][0] += c;
                    for d in 0..3 {
                        sums[a][part][1 + d] += c * at[d];
                    }
                }
            }
            for (i, s) in sums.iter_mut().enumerate() {
                for part in s.iter_mut() {
                    for d in 0..3 {
                        part[1 + d] -= part[0] * sp.origin[i][d];
                    }
                }
            }
            self.lumped.push((p, sums));
            self.anchors.push((p, anchor));
        }
    }

    /// For a registered prefix `prefix`, per joint: the joint whose palette it shows while a
    /// group simulates only `prefix` joints — itself within the prefix, else its nearest
    /// simulated ancestor. A held joint rests on its parent, so its palette (rest →
    /// animated) is its anchor's: a renderer drawing joints beyond the prefix reads them
    /// there. `None` for the whole skeleton (every joint shows its own) or a prefix not
    /// registered.
    pub fn anchors(&self, prefix: usize) -> Option<&[u32]> {
        self.anchors.iter().find(|(q, _)| *q == prefix).map(|(_, a)| a.as_slice())
    }

    /// Simulate only the first `joints` joints of group `group` (instances `16 group …
    /// 16 group + 15`): rounded up to the joint count or the nearest prefix registered with
    /// [`SwayBatch::set_prefixes`]. Joints switched back on restart at equilibrium and blend
    /// in; joints switched off fade out first — still computed, frozen, their displayed
    /// rotation blending to rest over `blend_time` — and are dropped once at rest, so
    /// neither way does a displayed joint jump. Joints dropped are left untouched (their
    /// palettes keep old values: draw them with [`SwayBatch::anchors`]). What is switched
    /// on is decided per instance: a joint an instance was already simulating (in this
    /// group or, moved by [`SwayBatch::swap_instances`], in another) carries on as it was.
    pub fn set_active(&mut self, group: usize, joints: usize) {
        if group >= self.active.len() {
            return;
        }
        let p = self.prefix_for(joints) as u32;
        self.keep[group] = p;
        // Before the first step every joint is at rest: nothing to fade.
        if p >= self.active[group] || self.dt.is_nan() {
            self.active[group] = p;
            for i in group * LANES..self.instances.min(group * LANES + LANES) {
                self.refresh(i);
            }
        }
    }

    /// The prefix [`SwayBatch::set_active`] simulates when asked for `joints` joints: the
    /// smallest registered prefix that holds them, or every joint.
    pub fn prefix_for(&self, joints: usize) -> usize {
        round_up(&self.lumped, self.species.len(), joints)
    }

    /// Drop at once the joints group `group` is fading out (see
    /// [`SwayBatch::set_active`]), as a group switched off before any step would.
    pub fn settle(&mut self, group: usize) {
        if let Some(&k) = self.keep.get(group) {
            self.active[group] = self.active[group].min(k);
        }
    }

    /// Simulate only the first `joints` joints of instance `i` (rounded up as
    /// [`SwayBatch::set_active`] rounds), within its group's prefix: its joints beyond fade
    /// out (computed, frozen, blending to rest) and are then left out of its lane. A group
    /// whose lanes want very different prefixes — one tree near the camera among far ones —
    /// then steps the longest of them in that lane alone, and the rest of the group to the
    /// prefix its other lanes need, rather than every lane to the longest (see
    /// [`SwayBatch::step`]). Every joint unless set; out-of-range indices are ignored.
    pub fn set_lane_active(&mut self, i: usize, joints: usize) {
        let p = self.prefix_for(joints) as u32;
        if let Some(w) = self.want.get_mut(i) {
            *w = p;
        }
    }

    /// Let the rows of lanes stepped alone (each its palettes and state, [`STATE_BYTES`] a
    /// joint) hold at most `bytes` in all (they count in
    /// [`stored_bytes`](SwayBatch::stored_bytes)): a caller keeping the state
    /// under a memory cap gives them what the cap leaves. Groups are served in order; one
    /// whose lanes would go past it steps them together. No limit unless set.
    pub fn set_alone_limit(&mut self, bytes: usize) {
        self.alone_limit = bytes;
    }

    /// Joints of instance `i` the last step computed: its group's prefix, or less where its
    /// own prefix ([`SwayBatch::set_lane_active`]) let the step leave the rest out of its
    /// lane. Joints beyond rest on their parents: read them at their
    /// [`anchors`](SwayBatch::anchors), as [`SwayBatch::palette`] does.
    pub fn simulated(&self, i: usize) -> usize {
        let a = self.active(i / LANES);
        self.stepped.get(i).map_or(0, |&s| (s as usize).min(a))
    }

    /// Blend weight of a joint that starts at rest: 1 before the first step (every joint is
    /// shown, at rest), 0 after (it blends in).
    fn rest_weight(&self) -> f32 {
        if self.dt.is_nan() { 1.0 } else { 0.0 }
    }

    /// Bring instance `i`'s record of its current joints in line with its group's prefix:
    /// joints newly simulated for it restart at equilibrium (blend weight 0). Once the batch
    /// has stepped, joints its group does not store for every lane stay unstored here (they
    /// are at rest with weight 0 already): the step stores what the lanes it steps together
    /// need.
    fn refresh(&mut self, i: usize) {
        let w = self.width;
        let (g, l) = (i / LANES, i % LANES);
        let (f, p) = (self.fresh[i] as usize, self.active[g] as usize);
        if f < p {
            let rest = self.rest_weight();
            let block = &mut self.blocks[g];
            if block.joints < p && rest != 0.0 {
                block.store(p, w, rest);
            }
            for j in f..p {
                match block.rows.get_mut(l).filter(|r| j < r.joints) {
                    Some(row) => row.weight[j] = 0.0,
                    None if j < block.joints => block.weight[j * w + l] = 0.0,
                    None => break,
                }
            }
        }
        self.fresh[i] = p as u32;
        // Joints not current are at rest (reset to weight 0 when simulated again).
        self.live[i] = self.live[i].min(p as u32);
    }

    /// Exchange the whole animation state of instances `a` and `b` (angles, rates, blend
    /// weights, budgets): each carries on in the other's lane exactly as it would have in
    /// its own, so a caller can gather instances that need the same joints into one group
    /// (a group steps the longest prefix any of its lanes needs). Joints beyond what either
    /// was simulating are stale and not moved; palettes are recomputed by the next step.
    /// Neither group grows: a lane whose state reaches beyond what its new group stores
    /// takes it along in a row (as a lane stepped alone does), and the next step either
    /// steps it alone there or stores it in the group. Out-of-range indices are ignored.
    pub fn swap_instances(&mut self, a: usize, b: usize) {
        if a == b || a >= self.instances || b >= self.instances {
            return;
        }
        let (ga, gb) = (a / LANES, b / LANES);
        let (la, lb) = (a % LANES, b % LANES);
        let m = self.fresh[a].max(self.fresh[b]) as usize;
        let (w, rest) = (self.width, self.rest_weight());
        let from_a = self.blocks[ga].take_lane(la, m, w);
        let from_b = self.blocks[gb].take_lane(lb, m, w);
        self.blocks[gb].put_lane(lb, from_a, w, rest);
        self.blocks[ga].put_lane(la, from_b, w, rest);
        self.fresh.swap(a, b);
        self.live.swap(a, b);
        self.want.swap(a, b);
        self.budget.swap(a, b);
    }

    /// Joints simulated in group `group`.
    pub fn active(&self, group: usize) -> usize {
        self.active.get(group).copied().unwrap_or(0) as usize
    }

    /// Joint updates of the last step: per instance the joints computed for it (its group's
    /// prefix, or its own where it was stepped alone), summed.
    pub fn joint_updates(&self) -> usize {
        self.updates
    }

    /// Active-joint budget of instance `i`.
    pub fn budget(&self, i: usize) -> usize {
        self.budget[i] as usize
    }

    /// Where joint `j` of instance `i` lies: (its group, the first value of its joint block
    /// in a one-value-per-lane array of the group's [`Block`], its lane), or `None` where the
    /// group does not store the joint. A quantity with `m` values per joint (2 angles, 12
    /// palette elements) has value `k` at `m · block + k · width + lane`.
    fn slot(&self, i: usize, j: usize) -> Option<(usize, usize, usize)> {
        let (g, w) = (i / LANES, self.width);
        (j < self.blocks.get(g)?.joints).then_some((g, j * w, i % LANES))
    }

    /// Joints group `group` stores for every one of its lanes: those its lanes stepped
    /// together simulate (with those fading out), at least — a lane stepped alone holds its
    /// own in a row, however many ([`SwayBatch::lane_palettes`]). The others are at rest.
    pub fn stored(&self, group: usize) -> usize {
        self.blocks.get(group).map_or(0, |b| b.joints)
    }

    /// Whether the batch has stepped (before its first step every joint is at rest and
    /// shows the identity palette).
    pub fn has_stepped(&self) -> bool {
        !self.dt.is_nan()
    }

    /// Joints group `group` holds memory for: those it stores, and for up to
    /// [`TRIM_STEPS`] steps those it stored before.
    pub fn reserved(&self, group: usize) -> usize {
        self.blocks.get(group).map_or(0, |b| b.reserved(self.width))
    }

    /// Bending angles (rad) of joint `j` of instance `i`; 0 for a joint not stored (at rest).
    pub fn angles(&self, i: usize, j: usize) -> [f32; 2] {
        let Some(block) = self.blocks.get(i / LANES) else { return [0.0; 2] };
        if let Some(row) = block.row_holding(i % LANES, j) {
            return [row.theta[2 * j], row.theta[2 * j + 1]];
        }
        let Some((_, b, l)) = self.slot(i, j) else { return [0.0; 2] };
        let (t, w) = (&block.theta, self.width);
        [t[2 * b + l], t[2 * b + w + l]]
    }

    /// Displayed fraction of joint `j`'s rotation in instance `i` (animation-LOD blend); 0
    /// for a joint not stored.
    pub fn weight(&self, i: usize, j: usize) -> f32 {
        let Some(block) = self.blocks.get(i / LANES) else { return 0.0 };
        if let Some(row) = block.row_holding(i % LANES, j) {
            return row.weight[j];
        }
        self.slot(i, j).map_or(0.0, |(_, b, l)| block.weight[b + l])
    }

    /// Set the state of joint `j` of instance `i` (for probes and tests: a release test
    /// starts from a bent joint at rest). Stores the joint (and those before it) if neither
    /// its group nor its row did.
    pub fn set_state(&mut self, i: usize, j: usize, angles: [f32; 2], rates: [f32; 2]) {
        let (g, w, l) = (i / LANES, self.width, i % LANES);
        if i >= self.instances || j >= self.species.len() {
            return;
        }
        if let Some(row) = self.blocks[g].rows.get_mut(l).filter(|r| j < r.joints) {
            row.theta[2 * j..2 * j + 2].copy_from_slice(&angles);
            row.rate[2 * j..2 * j + 2].copy_from_slice(&rates);
            return;
        }
        let rest = self.rest_weight();
        if self.blocks[g].joints <= j {
            self.blocks[g].store(j + 1, w, rest);
        }
        let (block, b) = (&mut self.blocks[g], j * w);
        for a in 0..2 {
            block.theta[2 * b + a * w + l] = angles[a];
            block.rate[2 * b + a * w + l] = rates[a];
        }
    }

    /// Joint `j`'s palette of instance `i`. A joint its group does not simulate rests on its
    /// parent and shows its nearest simulated ancestor's palette (see
    /// [`SwayBatch::anchors`]); before the first step every joint shows the identity.
    pub fn palette(&self, i: usize, j: usize) -> Palette {
        let simulated = self.simulated(i);
        let shown = if j < simulated {
            j
        } else {
            match self.anchors(simulated) {
                Some(a) if j < a.len() => a[j] as usize,
                _ => return IDENTITY,
            }
        };
        if let Some(row) = self.lane_palettes(i) {
            return row.get(12 * shown..12 * shown + 12).map_or(IDENTITY, |p| {
                let mut m = [0.0; 12];
                m.copy_from_slice(p);
                m
            });
        }
        let Some((g, b, l)) = self.slot(i, shown) else { return IDENTITY };
        let w = self.width;
        std::array::from_fn(|e| self.blocks[g].pal[12 * b + e * w + l])
    }

    /// The palettes of instance `i` where the last step stepped it alone (see
    /// [`SwayBatch::set_lane_active`]): 12 per joint (row-major 3×4) in a row, for its
    /// [`simulated`](SwayBatch::simulated) joints; its values in
    /// [`group_palettes`](SwayBatch::group_palettes) are then not current. `None` for an
    /// instance stepped with its group.
    pub fn lane_palettes(&self, i: usize) -> Option<&[f32]> {
        let b = self.blocks.get(i / LANES)?;
        let l = i % LANES;
        (b.alone >> l & 1 == 1).then(|| b.rows[l].pal.as_slice())
    }

    /// Where instance `i`'s palettes lie in its group's
    /// [`group_palettes`](Self::group_palettes).
    pub fn palette_slot(&self, i: usize) -> PaletteSlot {
        PaletteSlot { base: (i % LANES) as u32, stride: self.width as u32 }
    }

    /// The palettes of group `group` (instances `16 group … 16 group + 15`), as the step
    /// computes them: per joint the group stores ([`SwayBatch::stored`]), per matrix element
    /// (row-major 3×4), the group's [`width`](Self::width) lanes side by side — element e
    /// of joint j of instance i is at `palette_slot(i).index(j, e)`, that is `(12 j + e) ·
    /// width + i % LANES`. A last, partial group of a full-width batch is padded. Copied to
    /// the GPU as it is (see `sylva-forest`). A lane the last step stepped alone has its
    /// palettes in [`lane_palettes`](SwayBatch::lane_palettes) instead. Empty for a group
    /// out of range.
    pub fn group_palettes(&self, group: usize) -> &[f32] {
        self.blocks.get(group).map_or(&[], |b| b.pal.as_slice())
    }

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
        self.updates = self.stepped.iter().map(|&s| s as usize).sum();
    }

    /// Decide each group's split for the step: per lane the prefix it keeps on and the one
    /// it must be stepped to, and which lanes go alone — within the rows' byte limit,
    /// served in group order so that the outcome does not depend on threads.
    fn plan(&mut self) {
        let (ni, w) = (self.instances, self.width);
        let mut left = self.alone_limit;
        self.plans.resize(self.blocks.len(), Plan::default());
        for (g, plan) in self.plans.iter_mut().enumerate() {
            let p = self.active[g] as usize;
            let k = (self.keep[g] as usize).min(p);
            let used = w.min(ni - g * LANES);
            let mut on = [k as u32; LANES];
            let mut need = [0usize; LANES];
            for l in 0..used {
                let i = g * LANES + l;
                on[l] = on[l].min(self.want[i]);
                need[l] = (self.live[i].max(on[l]) as usize).min(p);
            }
            let (mut head, mut solo) = plan_lanes(&need[..used], w);
            // Bytes of the rows the lanes alone will hold (a row is kept, not shrunk).
            let rows = &self.blocks[g].rows;
            let bytes: usize = (0..used)
                .filter(|&l| solo >> l & 1 == 1)
                .map(|l| (STATE_BYTES * need[l]).max(4 * rows.get(l).map_or(0, Row::capacity)))
                .sum();
            if bytes > left {
                (head, solo) = (need[..used].iter().copied().max().unwrap_or(0), 0);
            } else {
                left -= bytes;
            }
            *plan = Plan { on, need: need.map(|x| x as u32), head: head as u32, solo };
        }
    }

    /// The step's groups, `W` (= [`SwayBatch::width`]) lanes each.
    fn step_lanes<const W: usize>(&mut self, blend: f32, rest: f32, wind: &[[f32; 3]]) {
        let sp = &self.species;
        let (tr, aero, budget, ni) =
            (&self.transitions, &self.aero_dt, &self.budget, self.instances);
        let (keep, lumped, plans) = (&self.keep, &self.lumped, &self.plans);
        let held = |p: usize| lumped.iter().find(|(q, _)| *q == p).map(|(_, v)| v.as_slice());
        let n = sp.len();
        let lanes_of = self.live.par_chunks_mut(LANES).zip(self.stepped.par_chunks_mut(LANES));
        self.blocks
            .par_iter_mut()
            .zip(self.active.par_iter_mut())
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
                let used = W.min(ni - g * LANES);
                for l in 0..used {
                    let w = wind.get(g * LANES + l).copied().unwrap_or([0.0; 3]);
                    for c in 0..3 {
                        u[c][l] = w[c];
                    }
                    bud[l] = budget[g * LANES + l];
                }
                let k = (keep[g] as usize).min(p);
                // A lane stepped alone keeps its state and palettes in its row (see [`Row`]),
                // taking from the group the joints it lacks and giving back those beyond what
                // it now simulates; a lane that rejoins its group gives its state back and
                // the row up (the step computes every palette it steps afresh, so none is
                // copied back).
                if solo != 0 && rows.len() < W {
                    rows.resize_with(W, Row::default);
                }
                for (l, row) in rows.iter_mut().enumerate() {
                    let r = if solo >> l & 1 == 1 { need[l] } else { 0 };
                    row.hold(r, [&mut *theta, &mut *rate, &mut *weight], W, l, (stored, rest));
                    if r == 0 {
                        if row.capacity() > 0 {
                            *row = Row::default();
                        }
                        continue;
                    }
                    // Grown exactly (the bytes counted are the bytes held); its values are
                    // all written by the step.
                    if row.pal.capacity() < 12 * r {
                        row.pal = vec![0.0; 12 * r];
                    }
                    row.pal.resize(12 * r, 0.0);
                }
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
                        };
                        if W == 1 {
                            step_one::<W>(sp, tr, aero, blend, &bud, &u, &mut st);
                        } else {
                            step_group::<W>(sp, tr, aero, blend, &bud, &u, &mut st);
                        }
                    }
                }
                SCRATCH.set(loads);
                // What each lane now has live: its switched-on prefix, and the joints beyond
                // it still fading out (the last one not yet at rest).
                for l in 0..used {
                    stepped[l] = if solo >> l & 1 == 1 { need[l] } else { head } as u32;
                    let (kl, was) = (on[l] as usize, live[l] as usize);
                    let row = rows.get(l).filter(|r| r.joints > 0);
                    let shown = |j: usize| match row {
                        Some(r) if j < r.joints => r.weight[j],
                        _ => weight[j * W + l],
                    };
                    let fading = (kl..was.min(need[l])).rev().find(|&j| shown(j) != 0.0);
                    // Rounded up to a registered prefix, as every prefix a step takes is.
                    live[l] = fading.map_or(kl, |j| round_up(lumped, n, j + 1)).max(kl) as u32;
                }
                // Joints fading out are dropped once every lane shows them at rest.
                if k < p && live.iter().all(|&x| x as usize <= k) {
                    *active = k as u32;
                }
                block.store(stores, W, rest);
                block.trim(W);
            });
    }
}

/// The smallest registered prefix holding `joints` joints (every joint, `n`, if none does).
fn round_up(lumped: &[(usize, Vec<Lump>)], n: usize, joints: usize) -> usize {
    lumped.iter().map(|(q, _)| *q).filter(|&q| q >= joints).min().unwrap_or(n).min(n)
}

/// Relative cost of one joint of a group step at `width` lanes, against one lane alone
/// (the narrow-batch figures of docs/benchmarks.md: a black tupelo steps 1.3, 3.9, 4.2 and
/// 5.7 ms at 1, 4, 8 and 16 lanes on AVX-512) — what a wide group saves is memory traffic
/// more than arithmetic.
fn width_cost(width: usize) -> f32 {
    match width {
        0..=1 => 1.0,
        2..=4 => 3.0,
        5..=8 => 3.2,
        _ => 4.4,
    }
}

/// A lane stepped alone cost one lane's step and the copies of its angles, rates and
/// weights in and out, strided across its group's lanes: in scene D's forest a black
/// tupelo's whole skeleton stepped in about 1.8 ms alone in its group of eight, against
/// 1.1–1.3 ms in a batch of its own (docs/benchmarks.md). A lane alone now keeps its state
/// in its row from step to step (see `Row`), so it pays for the copies only when it goes
/// alone or rejoins.
///
/// These costs predate the single-lane kernel (`alone`), which made a lane alone about 30 %
/// cheaper (a tupelo now steps in 0.77, 3.4, 3.9 and 4.3 ms at 1, 4, 8 and 16 lanes, and
/// alone in a group of 8 or 16 in 1.3 or 1.6 times its batch-of-one time). Refitted to
/// those figures, scenes A and D stepped the same within the noise, and a group of three
/// lanes needing the same few joints went all alone, each with a row of palettes, at a
/// tie in cost: the older, more cautious figures are kept.
const ALONE_COST: f32 = 1.7;

/// Which lanes of a group to step alone: (the prefix the group steps every lane to, a bit
/// per lane stepped alone). From the joints each lane must be stepped to, the cheapest of
/// stepping the `m` longest alone and the rest together, for every `m` (none alone: the
/// longest, as a group always stepped).
fn plan_lanes(need: &[usize], width: usize) -> (usize, u32) {
    let mut order: [usize; LANES] = std::array::from_fn(|l| l);
    let order = &mut order[..need.len()];
    order.sort_by_key(|&l| std::cmp::Reverse(need[l]));
    let together = width_cost(width);
    let (mut best, mut best_m, mut alone) = (f32::INFINITY, 0, 0.0);
    for m in 0..=order.len() {
        let head = order.get(m).map_or(0, |&l| need[l]);
        let cost = together * head as f32 + alone;
        if cost < best {
            (best, best_m) = (cost, m);
        }
        if let Some(&l) = order.get(m) {
            alone += ALONE_COST * need[l] as f32;
        }
    }
    let head = order.get(best_m).map_or(0, |&l| need[l]);
    (head, order[..best_m].iter().fold(0, |b, &l| b | 1 << l))
}

thread_local! {
    /// Per thread: the load accumulators of the group or lane it steps (`6 · joints · W`
    /// values, zero between steps).
    static SCRATCH: std::cell::RefCell<Vec<f32>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Step a group of one lane (`W` = 1): its joints' independent work apart from the sweeps
/// along the skeleton ([`alone`]), the same operations as [`step_group`].
#[inline]
fn step_one<const W: usize>(
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
struct Group<'a, const W: usize> {
    theta: &'a mut [[[f32; W]; 2]],
    rate: &'a mut [[[f32; W]; 2]],
    weight: &'a mut [[f32; W]],
    loads: &'a mut [[[f32; W]; 6]],
    lanes: &'a mut [[[f32; W]; 12]],
    /// Joints simulated (a prefix).
    active: usize,
    /// Per lane: joints switched on (a prefix of the simulated ones; those beyond are
    /// fading out).
    on: [u32; LANES],
    /// Lumped static drag of the held joints, per simulated joint (none: all simulated).
    held: Option<&'a [Lump]>,
    /// Per lane: whether nothing reads what the step computes in it (a lane stepped alone
    /// on its row, or one past the batch's instances), so that it takes no part in the one
    /// choice made for the whole group (the rotation formula, see `palette_of`).
    ignored: [bool; LANES],
}

simd_kernel! {
    /// Step one group, vectorised with the widest instruction set the CPU has.
    fn step_group<const W: usize>(
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
                own_drag::<W, false>(sp, aero, inv_ur, u, i, &st.rate[i], &st.weight[i], own);
            }
        }
        // (1) Loads, tips inwards: loads[i] = (force on the subtree, moment about joint i):
        // what its children passed on, its own drag, and the lumped drag of the joints held
        // beyond it. They start at zero: pass (2) clears each joint's loads once it has used
        // them.
        for i in (0..n).rev() {
            let li = &mut st.loads[i];
            if split {
                for c in 0..6 {
                    for l in 0..W {
                        li[c][l] += st.lanes[i][c][l];
                    }
                }
            } else {
                own_drag::<W, true>(sp, aero, inv_ur, u, i, &st.rate[i], &st.weight[i], li);
            }
            if let Some(held) = st.held {
                add_held::<W>(li, &held[i], &q);
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
fn palette_of<const W: usize>(
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
fn held_wind<const W: usize>(u: &[Lanes; 3], inv_ur: f32) -> [[[f32; W]; 3]; 2] {
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

/// Add the lumped drag of the joints held beyond a joint (`lump`, in the wind `q` of
/// [`held_wind`]) to its loads `li`.
#[inline(always)]
fn add_held<const W: usize>(li: &mut [[f32; W]; 6], lump: &Lump, q: &[[[f32; W]; 3]; 2]) {
    for (part, q) in lump.iter().zip(q) {
        let [d, cx, cy, cz] = *part;
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
fn pass_to_parent<const W: usize>(sp: &SwaySpecies, loads: &mut [[[f32; W]; 6]], i: usize) {
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
fn pass_on<const W: usize>(
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
/// segment and leaves, in the wind relative to the segment's motion — added to `out`
/// (`ADD`) or written to it.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn own_drag<const W: usize, const ADD: bool>(
    sp: &SwaySpecies,
    aero: &[f32],
    inv_ur: f32,
    u: &[Lanes; 3],
    i: usize,
    ra: &[[f32; W]; 2],
    w: &[f32; W],
    out: &mut [[f32; W]; 6],
) {
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

/// Joint palettes of all lanes from their rotation vectors φ, the rest position `o` of the
/// joint and the parent's palettes.
#[cfg(not(feature = "glam"))]
#[inline(always)]
fn palette_lanes<const W: usize>(
    phi: &[[f32; W]; 3],
    o: [f32; 3],
    parent: Option<&[[f32; W]; 12]>,
    out: &mut [[f32; W]; 12],
    sc: impl Fn(f32) -> (f32, f32),
) {
    for l in 0..W {
        let ph = [phi[0][l], phi[1][l], phi[2][l]];
        let (s, c) = sc(dot(ph, ph));
        let local = local_palette(ph, o, s, c);
        let m = match parent {
            None => local,
            Some(pm) => compose(&std::array::from_fn(|e| pm[e][l]), &local),
        };
        for e in 0..12 {
            out[e][l] = m[e];
        }
    }
}

/// A joint's rotation about its rest position `o`, T(o) R T(−o), for the rotation vector
/// `ph` with (sin a / a, (1 − cos a) / a²) = (`s`, `c`).
#[inline(always)]
fn local_palette(ph: [f32; 3], o: [f32; 3], s: f32, c: f32) -> Palette {
    let r = rodrigues(ph, s, c);
    let t = [
        o[0] - (r[0][0] * o[0] + r[0][1] * o[1] + r[0][2] * o[2]),
        o[1] - (r[1][0] * o[0] + r[1][1] * o[1] + r[1][2] * o[2]),
        o[2] - (r[2][0] * o[0] + r[2][1] * o[1] + r[2][2] * o[2]),
    ];
    [
        r[0][0], r[0][1], r[0][2], t[0], r[1][0], r[1][1], r[1][2], t[1], r[2][0], r[2][1],
        r[2][2], t[2],
    ]
}

/// The same palettes through glam's `Affine3A` (the comparison behind the choice of a small
/// math module over glam: `cargo run --release -p sylva --features sylva-sway/glam -- bench
/// sway`, figures in docs/benchmarks.md). Same rotation formula; glam builds, composes and
/// stores the matrices, one lane at a time as its types require.
#[cfg(feature = "glam")]
#[inline(always)]
fn palette_lanes<const W: usize>(
    phi: &[[f32; W]; 3],
    o: [f32; 3],
    parent: Option<&[[f32; W]; 12]>,
    out: &mut [[f32; W]; 12],
    sc: impl Fn(f32) -> (f32, f32),
) {
    use glam::{Affine3A, Mat3A, Vec3A};
    let origin = Vec3A::from(o);
    let affine = |m: [f32; 12]| Affine3A {
        matrix3: Mat3A::from_cols_array(&[m[0], m[4], m[8], m[1], m[5], m[9], m[2], m[6], m[10]]),
        translation: Vec3A::new(m[3], m[7], m[11]),
    };
    for l in 0..W {
        let ph = Vec3A::new(phi[0][l], phi[1][l], phi[2][l]);
        let (s, c) = sc(ph.length_squared());
        let r = rodrigues(ph.to_array(), s, c);
        let rot = Mat3A::from_cols_array_2d(&r).transpose();
        let local = Affine3A { matrix3: rot, translation: origin - rot * origin };
        let m = match parent {
            None => local,
            Some(pm) => affine(std::array::from_fn(|e| pm[e][l])) * local,
        };
        let (x, y, z, w) = (m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis, m.translation);
        let rows = [x.x, y.x, z.x, w.x, x.y, y.y, z.y, w.y, x.z, y.z, z.z, w.z];
        for e in 0..12 {
            out[e][l] = rows[e];
        }
    }
}

/// a · b for 3×4 affine matrices.
pub(crate) fn compose(a: &Palette, b: &Palette) -> Palette {
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

/// The rotation part of a palette, row-major 3×3.
pub fn rotation_of(p: &Palette) -> [f32; 9] {
    [p[0], p[1], p[2], p[4], p[5], p[6], p[8], p[9], p[10]]
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
    #[test]
    fn the_lever_bend_balances_spring_and_shortened_arm() {
        // θ = e cos θ, solved in f64 by Newton to convergence, against lever_bend's one step.
        let mut last = 0.0;
        for k in 0..=400 {
            let e = 0.001 * 1.03f64.powi(k); // 0.001 … 1.4e2
            let mut t = e.min(1.0);
            for _ in 0..60 {
                t -= (t - e * t.cos()) / (1.0 + e * t.sin());
            }
            // The step's rule: the series below LEVER_SERIES, the Newton step above.
            let e2 = (e * e) as f32;
            let factor =
                if e2 > super::LEVER_SERIES { super::lever_bend(e2) } else { 1.0 - 0.5 * e2 };
            let got = factor as f64 * e;
            assert!((got / t - 1.0).abs() < 0.007, "e {e}: {got} against {t}");
            assert!(got < std::f64::consts::FRAC_PI_2, "e {e}: past a quarter turn");
            assert!(got > last, "the bend grows with the load (e {e})");
            last = got;
        }
    }

    /// The group's one choice of rotation formula is made by the lanes whose values are
    /// read: a lane nothing reads (stepped alone on its row), however far it is bent, leaves
    /// the others' palettes exactly as they are with it at rest; taking part, it would
    /// switch the whole group to the full formula.
    #[test]
    fn lanes_nothing_reads_take_no_part_in_the_group_formula() {
        use crate::SwayParams;
        let model = sylva_tree::Species::preset("quaking_aspen").expect("preset").model(5, 6);
        let sp =
            crate::SwaySpecies::new(&model.expect("model").tree.skeleton, SwayParams::default())
                .expect("species");
        // Joint 0 (the root, no parent) bent by a small angle in lanes 0–2; lane 3 far bent.
        let palettes = |bent: f32, ignored: bool| {
            let mut lanes = vec![[[0.0f32; 4]; 12]; 1];
            let mut phi = [[0.0f32; 4]; 3];
            for l in 0..3 {
                phi[0][l] = 0.013 * (l + 1) as f32;
                phi[1][l] = -0.007 * (l + 1) as f32;
            }
            phi[0][3] = bent;
            let mut skip = [false; LANES];
            skip[3] = ignored;
            palette_of::<4>(&sp, &mut lanes, 0, &phi, &skip);
            (0..3)
                .map(|l| (0..12).map(|e| lanes[0][e][l].to_bits()).collect())
                .collect::<Vec<Vec<u32>>>()
        };
        let at_rest = palettes(0.0, false);
        assert_eq!(palettes(1.1, true), at_rest, "ignored: as if at rest");
        assert_ne!(palettes(1.1, false), at_rest, "taking part, it switches the formula");
    }

    #[test]
    fn any_angle_matches_f64_within_3e_7() {
        for k in 0..=40000 {
            let a = k as f32 * 1e-3;
            let (s, v) = any_angle(a * a);
            // Reference in f64 (f32's 1 − cos a cancels at small a).
            let x = a as f64;
            let (ls, lv) = if k > 0 {
                ((x.sin() / x) as f32, ((1.0 - x.cos()) / (x * x)) as f32)
            } else {
                (1.0, 0.5)
            };
            assert!((s - ls).abs() <= 3e-7, "sin a / a at {a}: {s} vs {ls}");
            assert!((v - lv).abs() <= 3e-7, "(1 − cos a)/a² at {a}: {v} vs {lv}");
        }
    }

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
