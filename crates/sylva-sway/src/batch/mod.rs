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

use crate::SwayParamError;
use crate::species::{SwaySpecies, Transition};

#[cfg(not(feature = "glam"))]
mod alone;

mod kernel;
mod plan;
mod rotation;
mod storage;
#[cfg(test)]
mod tests;

#[cfg(not(feature = "glam"))]
use kernel::*;
use plan::*;
use rotation::*;
pub(crate) use rotation::{compose, joint_palette, lever_bend};
pub use rotation::{rotation_of, transform};
pub use storage::TRIM_STEPS;
use storage::*;

/// A 3×4 affine matrix, row-major: rotation | translation. Maps a rest-pose tree-space point
/// to its animated position.
pub type Palette = [f32; 12];

/// The rest pose's palette (the identity): a joint not yet simulated.
pub const IDENTITY: Palette = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];

/// Instances per group: the vector width the joint loops run across.
pub const LANES: usize = 16;
/// A value per lane of a group.
pub type Lanes = [f32; LANES];

/// Per lane, a joint's factors on its instance's mean wind and on the gusts
/// ([`SwaySpecies::set_gust_heights`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct JointWind<const W: usize> {
    pub(crate) mean: [f32; W],
    pub(crate) gust: [f32; W],
}

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

/// Instances of one species and their animation state.
#[derive(Debug, Clone)]
pub struct SwayBatch {
    species: SwaySpecies,
    instances: usize,
    /// Lanes stored per group: [`LANES`], or 1, 4 or 8 for a batch of fewer instances.
    width: usize,
    /// Per group: the state of the joints it stores (see [`Block`]).
    blocks: Vec<Block>,
    /// Per instance: the most joints it may simulate ([`SwayBatch::set_budget`]).
    lane_budget: Vec<u32>,
    /// Per group: joints simulated (a prefix).
    group_prefix: Vec<u32>,
    /// Per instance: joints whose state is current (the prefix its group simulated when
    /// last set; an instance moved by [`SwayBatch::swap_instances`] takes its own along).
    lane_current: Vec<u32>,
    /// Per group: the prefix it is fading down to (= `group_prefix` when not fading).
    /// Joints from `fading_to` to `group_prefix` are still computed, frozen, their displayed
    /// rotation blending to rest; once every one is at rest the group drops them.
    fading_to: Vec<u32>,
    /// Per instance: the prefix it asks for itself ([`SwayBatch::set_lane_active`]; every
    /// joint unless set). Within its group's prefix, an instance's joints beyond it fade out.
    lane_request: Vec<u32>,
    /// Per instance: joints beyond this are at rest in its lane (blend weight 0), so a step
    /// may leave them out for this lane.
    lane_moving: Vec<u32>,
    /// Per instance: its shelter from the wind, 0 … 1 ([`SwayBatch::set_shelter`]).
    lane_shelter: Vec<f32>,
    /// Per instance: its mean wind ([`SwayBatch::set_mean_wind`]).
    lane_mean: Vec<[f32; 3]>,
    /// Per instance: the joints the last step computed for it (its palettes beyond are not
    /// current; it shows them at their anchors).
    lane_computed: Vec<u32>,
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
            lane_budget: vec![n as u32; instances],
            group_prefix: vec![n as u32; groups],
            lane_current: vec![n as u32; instances],
            fading_to: vec![n as u32; groups],
            lane_request: vec![n as u32; instances],
            lane_moving: vec![n as u32; instances],
            lane_computed: vec![n as u32; instances],
            lane_shelter: vec![1.0; instances],
            lane_mean: vec![[0.0; 3]; instances],
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
        self.lane_budget[i] = budget.min(self.species.len()) as u32;
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
        if group >= self.group_prefix.len() {
            return;
        }
        let p = self.prefix_for(joints) as u32;
        self.fading_to[group] = p;
        // Before the first step every joint is at rest: nothing to fade.
        if p >= self.group_prefix[group] || self.dt.is_nan() {
            self.group_prefix[group] = p;
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
        if let Some(&k) = self.fading_to.get(group) {
            self.group_prefix[group] = self.group_prefix[group].min(k);
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
        if let Some(w) = self.lane_request.get_mut(i) {
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
        self.lane_computed.get(i).map_or(0, |&s| (s as usize).min(a))
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
        let (f, p) = (self.lane_current[i] as usize, self.group_prefix[g] as usize);
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
        self.lane_current[i] = p as u32;
        // Joints not current are at rest (reset to weight 0 when simulated again).
        self.lane_moving[i] = self.lane_moving[i].min(p as u32);
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
        let m = self.lane_current[a].max(self.lane_current[b]) as usize;
        let (w, rest) = (self.width, self.rest_weight());
        let from_a = self.blocks[ga].take_lane(la, m, w);
        let from_b = self.blocks[gb].take_lane(lb, m, w);
        self.blocks[gb].put_lane(lb, from_a, w, rest);
        self.blocks[ga].put_lane(la, from_b, w, rest);
        self.lane_current.swap(a, b);
        self.lane_moving.swap(a, b);
        self.lane_request.swap(a, b);
        self.lane_budget.swap(a, b);
        self.lane_shelter.swap(a, b);
        self.lane_mean.swap(a, b);
    }

    /// Let the wind differ with height, per joint ([`SwaySpecies::set_wind_heights`]).
    pub fn set_wind_heights(&mut self, open: &[f32], inside: &[f32]) -> Result<(), SwayParamError> {
        self.species.set_wind_heights(open, inside)
    }

    /// Give the gusts their own height factors ([`SwaySpecies::set_gust_heights`]).
    pub fn set_gust_heights(&mut self, open: &[f32], inside: &[f32]) -> Result<(), SwayParamError> {
        self.species.set_gust_heights(open, inside)
    }

    /// Instance `i`'s mean wind (m/s, tree space, as its wind in [`SwayBatch::step`]): what
    /// of its wind the mean factors scale, the rest being gusts
    /// ([`SwaySpecies::set_gust_heights`]; default still air, every bit of the wind a gust,
    /// which changes nothing while the gusts share the mean's factors). Not finite, or `i`
    /// out of range: ignored.
    pub fn set_mean_wind(&mut self, i: usize, mean: [f32; 3]) {
        if let (Some(m), true) = (self.lane_mean.get_mut(i), mean.iter().all(|c| c.is_finite())) {
            *m = mean;
        }
    }

    /// Instance `i`'s shelter: 0 where its wind is the open ground's (a forest's windward
    /// edge), 1 inside a canopy (the default), between for the mix of the two height
    /// factors ([`SwaySpecies::set_wind_heights`]; without them it changes nothing).
    /// Clamped to 0 … 1; not finite, or `i` out of range: ignored.
    pub fn set_shelter(&mut self, i: usize, shelter: f32) {
        if let (Some(s), true) = (self.lane_shelter.get_mut(i), shelter.is_finite()) {
            *s = shelter.clamp(0.0, 1.0);
        }
    }

    /// Joints simulated in group `group`.
    pub fn active(&self, group: usize) -> usize {
        self.group_prefix.get(group).copied().unwrap_or(0) as usize
    }

    /// Joint updates of the last step: per instance the joints computed for it (its group's
    /// prefix, or its own where it was stepped alone), summed.
    pub fn joint_updates(&self) -> usize {
        self.updates
    }

    /// Active-joint budget of instance `i`.
    pub fn budget(&self, i: usize) -> usize {
        self.lane_budget[i] as usize
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
}
