//! The per-frame driver: time step → wind sample per simulated tree → sway step →
//! palettes → [`FrameData`].
//!
//! **Instance groups.** Each species runs one [`SwayBatch`]; a scene's
//! `sim_joint_budget` (joint updates per frame) is shared among species in proportion to
//! their tree counts, and a species whose trees do not all fit shares simulations: its
//! trees are cut into as many groups as fit, each one simulated instance driven by the wind
//! at the group's centre. Groups are formed by distance from the camera (squares of a
//! quadtree split while they fit, those that look largest first: see `groups.rs`), so
//! trees near the camera are simulated one by one and groups grow with distance. Trees
//! that share a simulation share its yaw, so the wind bends them all downwind.
//!
//! **Regrouping.** [`Forest::frame`] records where the camera is; once it has travelled
//! [`REGROUP_TRAVEL`] from where the groups were last formed, the next [`Forest::step`]
//! forms them again (at most once per [`REGROUP_FADE`]). Each new group keeps the simulated
//! instance most of its trees already follow, so most trees do not change; a tree that does
//! is drawn with both its old and its new simulation for [`REGROUP_FADE`] seconds
//! ([`Forest::set_regroup_fade`]),
//! cross-faded per pixel like a level change, so no tree jumps to its new group's pose.
//!
//! **Wind-field LOD.** Besides the instance groups, the wind has three resolutions. Within
//! [`NEAR_REACH`] of the camera, a forest whose field is coarser than its tree spacing reads a
//! fine tile at the tree spacing ([`SceneWind::near`], a [`NearField`]), faded into the
//! field over the reach's outer quarter; the other simulations read the field itself, and
//! those whose trees are all impostors (or out of view) its mip pyramid's level
//! [`FAR_WIND_LEVEL`] (4 × 4 grid points averaged). The tile follows the camera by where it
//! is read, not by being made again: it is periodic and fixed in the world.
//!
//! **Geometry LOD** ([`LodSettings`]). A tree's continuous level is
//! `x = 1 + log₃(h₀ / h)` (≥ 0; level ⌊x⌋), where `h` is the fraction of the image height its
//! crown covers and `h₀` the fraction from which it is drawn at full detail. A backlash of half-width
//! [`LodSettings::hysteresis`] (per view, kept in the [`FrameData`]) keeps a tree whose size
//! wavers about a threshold from flickering. Levels `0 … far_level − 1` are meshes of the
//! tree's LOD chain; from `far_level` on the tree is an impostor (two triangles showing
//! the tree rendered from sixteen sides). In the last [`LodSettings::band`] of each level the
//! tree is drawn at both that level and the next, cross-faded per pixel by a screen-space
//! dither: the two draws keep complementary pixel sets ([`Instance::fade`]), so no frame
//! shows a tree jump from one level to the next. Trees outside the view cone are culled,
//! except, with shadows on, those whose shadow may fall in view: their crown swept away
//! from the sun ([`ShadowSweep`]) may reach the cone, and it may cast into the shadow
//! map's far cascade ([`ShadowBox`]; outside it nothing takes a shadow). They are drawn
//! into the shadow map only ([`Bucket::shadow_only`]), at the level their size gives, so
//! a long shadow neither appears when its tree comes into view nor changes level then
//! (its crown's sway blends in, as for any tree entering the view).
//! The per-tree state stops at [`lod_cap`], half a level past the far level, where nothing
//! drawn or simulated changes any more; a tree whose image fraction is surely below
//! [`past_cap_fraction`] (one multiplication, no division or logarithm) goes there without
//! its coordinate being computed, which is most trees of a large forest.
//!
//! **Joint order, uploads and animation LOD.** Each species' skeleton is put in LOD order
//! (`sylva_tree::lod_order`): the trunk first, then the joints of the coarsest level, and
//! so on, so the joints a level draws are a prefix (an impostor needs only the trunk). Per
//! simulation, [`Forest::frame`] uploads the prefix the finest level its trees are drawn
//! at needs (nothing for one with no tree in view; see [`FrameData::palettes`] for the
//! layout), and records per simulation the prefix the next [`Forest::step`] simulates:
//! that of the level half a level finer ([`SIM_MARGIN`]), so a tree about to move closer is
//! already simulated when drawn. The joints beyond are not stepped at all (their drag is
//! felt as a lumped static load by the simulated ones, see `sylva_sway::batch`), and blend
//! in from rest when switched back on. The batch steps 16 simulations (lanes) at a time, and
//! a lane group steps the longest prefix any of its lanes needs, so before each step the
//! simulations are packed (`lanes.rs`): those that need the same prefix are gathered into
//! the same lane groups, moving as few as possible. A simulation changes lane with its whole
//! state ([`SwayBatch::swap_instances`]) and carries on exactly as it would have; an
//! instance group keeps its number.

use std::sync::Mutex;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Instant;

use bytemuck::{Pod, Zeroable};
use rayon::prelude::*;
use sylva_sway::{
    CrownLean, IDENTITY, LANES, LeafParams, LeafSway, PaletteSlot, STATE_BYTES, SwayBatch,
    SwayParams, SwaySpecies,
};

use sylva_tree::mesh::{LOD_LEVELS, TreeModel};
use sylva_tree::{LodOrder, Species, lod_order};
use sylva_wind::{NearField, OwnedPyramid};
use thiserror::Error;

use crate::camera::{Camera, ShadowBox, ShadowSweep, may_see_trees, may_shade_trees};
use crate::groups::{assign_slots, morton, partition};
use crate::lanes;
use crate::scene::{
    Placement, SceneSpec, Terrain, camera_on_path, default_camera, default_camera_path, layout,
};
pub use crate::wind::{
    MAX_NEAR_POINTS, MAX_WIND_POINTS, NEAR_BAND, NEAR_REACH, SceneWind, wind_field, wind_points,
};
use crate::wind::{steer, wind_near};

mod palettes;
use palettes::{Layout, PaletteCopy, copy_palettes, lay_out};

/// A forest that could not be built.
#[derive(Debug, Error)]
pub enum ForestError {
    /// A species could not be loaded or generated.
    #[error("species `{name}`: {message}")]
    Species {
        /// Preset name or file.
        name: String,
        /// What went wrong.
        message: String,
    },
    /// The wind field could not be made.
    #[error("wind: {0}")]
    Wind(String),
    /// The simulation state would not fit the documented memory cap.
    #[error(
        "the simulation would need {} MB of animation state (every joint of every \
         simulation without the animation LOD, the trunks with it), over the {} MB cap: lower \
         `sim_joint_budget`, keep the wind-field LOD on (instance groups), use fewer trees, or \
         raise the cap deliberately (scene `max_state_mb`, or --max-memory)",
        bytes / 1_000_000, limit / 1_000_000
    )]
    TooLarge {
        /// Bytes needed.
        bytes: usize,
        /// The cap.
        limit: usize,
    },
}

/// Default cap on the animation state of a forest (angles, rates, blend weights, loads and
/// palettes of every simulated joint), bytes: 6 GB. A scene sets its own with
/// `max_state_mb`.
pub const MAX_STATE_BYTES: usize = 6_000_000_000;

/// One tree drawn this frame, as the vertex shaders read it (56 bytes; sylva-render maps
/// each field to a vertex attribute by its offset).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct Instance {
    /// Trunk base, world m.
    pub position: [f32; 3],
    /// Rotation about z, rad.
    pub yaw: f32,
    /// Uniform scale.
    pub scale: f32,
    /// Where the instance's joint palettes lie in [`FrameData::palettes`]: element e of
    /// joint j at `palette.base + (12 j + e) · palette.stride`, the stride being the
    /// instances of its lane group (the lane layout) or 1 (one simulation's palettes in a
    /// row, see [`FrameData::palettes`]).
    pub palette: PaletteSlot,
    /// Leaf flutter phase, rad.
    pub leaf_phase: f32,
    /// Leaf flutter amplitude, rad.
    pub leaf_amplitude: f32,
    /// Cross-fade: the draw keeps the pixels whose dither value d ∈ [0, 1) lies in
    /// `[fade[0], fade[1])`. A tree between two levels is drawn twice with complementary
    /// ranges `[0, 1 − w)` and `[1 − w, 1)`; a tree at one level has `[0, 2)`. A tree that
    /// changed instance group is also drawn with its old group over `[0, 1 − v)` and its new
    /// one over `[1 − v, 1)`, each range split between two levels the same way.
    pub fade: [f32; 2],
    /// What the renderer's colour overlay shows: bits 0–3 the geometry level of this draw
    /// (15: an impostor), bits 4–7 the species, bits 8–31 the instance group within the
    /// species.
    pub tag: u32,
    /// An impostor's crown lean: the horizontal shear at the trunk top's height (tree space,
    /// m, as IEEE half-precision bits) that its limbs and twigs add in the wind to the
    /// trunk's own sway, which alone moves its picture ([`sylva_sway::CrownLean`]: the
    /// static bend of every joint off the trunk line in the instance's wind). Mesh levels
    /// simulate those joints and do not read it.
    pub lean: [u16; 2],
    /// How the same bend turns an impostor's leaves (as half-precision bits): the
    /// leaf-weighted mean of where it takes the vertical ([`sylva_sway::CrownLean::tilt`]),
    /// as its horizontal part along the lean's direction and one minus its vertical part
    /// (the mean cosine of the leaves' tilt); zero in still air. The impostor turns its
    /// baked leaf normals by it, so a crown bent in the wind darkens as full detail does.
    pub tilt: [u16; 2],
}

/// The geometry-LOD switch and thresholds (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LodSettings {
    /// Geometry LOD on. Off: every tree at full detail (level 0), no impostors.
    pub geometry: bool,
    /// `h₀`: image-height fraction from which a tree is drawn at full detail (0.01 … 100;
    /// larger is coarser). Default [`DEFAULT_LOD_FRACTION`].
    pub fraction: f32,
    /// First level drawn as an impostor (1 … the chain's length). Default
    /// [`DEFAULT_FAR_LEVEL`].
    pub far_level: u32,
    /// Cross-fade band, in levels (0 … 1): over the last `band` of each level the tree
    /// blends into the next. Default 0.3.
    pub band: f32,
    /// Hysteresis half-width, in levels (0 … 0.5). Default 0.1.
    pub hysteresis: f32,
    /// Animation LOD on: each lane group simulates only the joints its drawn levels use.
    /// Off: every joint of every simulated tree, every step.
    pub animation: bool,
}

/// Seconds over which a tree that changes instance group cross-fades from its old
/// simulation to its new one; also the shortest time between two regroupings.
pub const REGROUP_FADE: f32 = 1.0;

/// Camera travel, m, after which instance groups are formed again for the new viewpoint.
pub const REGROUP_TRAVEL: f32 = 2.0;

/// Pyramid level the wind of far groups is read from: averages of 4 × 4 grid points.
pub const FAR_WIND_LEVEL: usize = 2;

/// Mesh levels coarser than drawn that trees cast their shadows with (the renderer's
/// shadow pass; a tree past the last mesh level casts its last one). Two levels: scene A's
/// image differs from one level's by 1.7 grey levels on average, for about 6 % less
/// rendering time on lavapipe. A tree drawn into the shadow map only
/// ([`Bucket::shadow_only`]) needs just the joints of the level it casts, and
/// simulates only its trunk.
pub const SHADOW_COARSER: u32 = 2;

/// The mesh level a tree drawn at mesh level `level` of a chain of `chain` meshes casts its
/// shadow with: [`SHADOW_COARSER`] levels coarser, the last mesh at most.
pub fn shadow_level(level: u32, chain: u32) -> u32 {
    (level + SHADOW_COARSER).min(chain.saturating_sub(1))
}

/// How much finer (in levels) than it is drawn a tree is simulated, so the simulation
/// leads the camera by a frame. A quarter level was measured and not kept: a quarter to
/// three fifths fewer joint updates, but scene B's image error in motion rose from FLIP
/// 0.057 to 0.069, its nearest crowns drawn before their sway had built up
/// (docs/benchmarks.md).
pub const SIM_MARGIN: f32 = 0.5;

/// Animation LOD by projected size: a tree simulates the joints of the mesh level its size
/// calls for by the default geometry rule — [`lod_coordinate`] with this h₀, half a level
/// ahead ([`SIM_MARGIN`]), every level a mesh — and never finer than the geometry LOD
/// would simulate it; the joints it draws beyond are held at rest on their parents. With
/// the geometry LOD at its defaults this is what it draws (every joint for a tree at full
/// detail); it saves work where trees are drawn finer than their size calls for (the
/// geometry LOD off, or a smaller h₀). A larger value was measured and not kept: at 1.5
/// (every joint only above half the image height) scene A's simulation took 13 ms instead
/// of 27, but its image error rose from FLIP 0.037 to 0.098 — twigs held at rest lack the
/// bend the wind gives them (docs/benchmarks.md).
pub const ANIMATION_FRACTION: f32 = 0.2;

impl Default for LodSettings {
    fn default() -> LodSettings {
        LodSettings {
            geometry: true,
            fraction: DEFAULT_LOD_FRACTION,
            far_level: DEFAULT_FAR_LEVEL,
            band: 0.3,
            hysteresis: 0.1,
            animation: true,
        }
    }
}

/// The continuous LOD coordinate of a tree covering `frac` of the image height:
/// `1 + log₃(h₀ / frac)`, clamped to ≥ 0, so level 0 (x < 1) is for trees taller than `h₀`
/// and level k for `h₀ / 3^k ≤ frac < h₀ / 3^(k−1)`. Monotone: smaller trees get larger
/// values.
pub fn lod_coordinate(frac: f32, h0: f32) -> f32 {
    (1.0 + (h0 / frac.max(1e-9)).ln() / 3f32.ln()).max(0.0)
}

/// Where a tree's LOD state stops: `far + SIM_MARGIN`. From this coordinate on a tree at
/// far level `far` is drawn at that level alone (its impostor, or its last mesh level) and
/// simulates only its trunk, whatever the coordinate's value, and the hysteresis commutes
/// with the cap (`min(hysteresis(p, x, w), cap) = min(hysteresis(min(p, cap), x, w), cap)`,
/// the clamp being monotone in `p`), so a frame built from the capped state is the frame
/// built from the uncapped one. A tree whose image fraction is surely below
/// [`past_cap_fraction`] goes to the cap without its logarithm: most of a large forest.
pub fn lod_cap(far: u32) -> f32 {
    far as f32 + SIM_MARGIN
}

/// The image-height fraction below which [`lod_coordinate`] with this `h0` is at least
/// `cap + half_width` (so that the hysteresis takes a tree to the cap at least), made smaller
/// by 10⁻³ of itself (about 10⁻³ of a level), far more than the rounding of the
/// coordinate, the fraction and this bound.
pub fn past_cap_fraction(h0: f32, cap: f32, half_width: f32) -> f32 {
    h0 * 3f32.powf(1.0 - cap - half_width) * (1.0 - 1e-3)
}

/// A tree's LOD state after a frame: the coordinate `x()` through the hysteresis of
/// `half_width`, capped at `cap` ([`lod_cap`]). `past` says the coordinate is surely at
/// least `cap + half_width`: whatever the state before, the hysteresis then gives at least
/// `cap`, so the state is the cap and `x` is not called.
pub fn next_lod_state(
    prev: f32,
    x: impl FnOnce() -> f32,
    past: bool,
    half_width: f32,
    cap: f32,
) -> f32 {
    if past { cap } else { hysteresis(prev, x(), half_width).min(cap) }
}

/// The first `n` values of `buf`, for the caller to write every one of: a frame's palettes
/// and instances written over the last frame's, so that only growth is filled (cleared and
/// refilled each frame, zeroing scene A's 15 MB of palettes cost about 0.4 ms of its 4 ms
/// of frame building). The caller truncates the buffer to `n` after.
fn overwrite<T: Copy + Default>(buf: &mut Vec<T>, n: usize) -> &mut [T] {
    if buf.len() < n {
        buf.resize(n, T::default());
    }
    &mut buf[..n]
}

/// Backlash hysteresis: the previous value `prev` is kept while within `half_width` of the
/// new `x`, else dragged along with it (NaN `prev`: no history, `x` itself).
pub fn hysteresis(prev: f32, x: f32, half_width: f32) -> f32 {
    if prev.is_nan() { x } else { prev.clamp(x - half_width, x + half_width) }
}

/// Levels of a tree at continuous level `x` (levels ≥ `last` are `last`): the level, the
/// next one and the weight of the next (0 outside the band).
pub fn blend_levels(x: f32, last: u32, band: f32) -> (u32, u32, f32) {
    if x >= last as f32 {
        return (last, last, 0.0);
    }
    // The float-to-integer cast truncates and saturates (negative and NaN give 0): the
    // floor of x, clamped to 0, without a call to `floorf` where the target lacks SSE4.1.
    let level = x as u32;
    let t = x - level as f32;
    let band = band.clamp(0.0, 1.0);
    if band > 0.0 && t > 1.0 - band {
        (level, level + 1, ((t - (1.0 - band)) / band).clamp(0.0, 1.0))
    } else {
        (level, level, 0.0)
    }
}

/// A run of instances of one species at one LOD: one instanced draw.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Bucket {
    /// Species index.
    pub species: u32,
    /// LOD level.
    pub lod: u32,
    /// First instance in [`FrameData::instances`].
    pub first: u32,
    /// Instances.
    pub count: u32,
    /// Drawn into the sun's shadow map only: trees outside the view whose shadow may fall
    /// in it. These buckets come after every bucket in view.
    pub shadow_only: bool,
}

/// Figures of one frame.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameStats {
    /// Trees in the scene.
    pub trees: usize,
    /// Trees drawn (not culled).
    pub drawn: usize,
    /// Trees outside the view drawn into the shadow map only, as their shadow may fall in
    /// view (not counted in `drawn`, `triangles` or `draw_calls`).
    pub shadow_only: usize,
    /// Triangles drawn (branches and leaf billboards).
    pub triangles: usize,
    /// Simulated instances (instance groups).
    pub simulated: usize,
    /// Joint updates of the last simulation step: per simulated instance the joints
    /// computed for it, summed (`SwayBatch::joint_updates`).
    pub joints: usize,
    /// Bytes of animation state held (angles, rates, blend weights and palettes of the
    /// joints each lane group simulates: the animation LOD sets it).
    pub state_bytes: usize,
    /// Lane groups that the memory cap (`max_state_mb`) kept at fewer joints than the
    /// animation LOD asked for, in the last step.
    pub state_capped: usize,
    /// Trees drawn as impostors (fully or fading in).
    pub impostors: usize,
    /// Trees drawn at two levels (cross-fading).
    pub fading: usize,
    /// Trees drawn with two instance groups (cross-fading after a regroup).
    pub regrouping: usize,
    /// Trees in view that changed instance group since the previous frame of this view.
    pub group_changes: usize,
    /// Trees whose level changed since the previous frame of this view (levels past the
    /// far level count as the far level: an impostor stays one as it recedes).
    pub level_changes: usize,
    /// Simulated instances that read the wind pyramid's coarse level in the last step.
    pub coarse_wind: usize,
    /// Simulated instances that read the near field (fully or fading) in the last step.
    pub near_wind: usize,
    /// Bytes of palettes and instances this frame sends to the GPU.
    pub uploaded_bytes: usize,
    /// Instanced draws (per bucket: branches and leaves, or one impostor draw).
    pub draw_calls: usize,
    /// Wall time of the last simulation step, ms.
    pub sim_ms: f64,
}

/// What the renderer reads each frame: plain arrays, no simulation types.
#[derive(Debug, Clone, Default)]
pub struct FrameData {
    /// Simulation time, s.
    pub time: f64,
    /// Instances, grouped by bucket.
    pub instances: Vec<Instance>,
    /// Buckets in (LOD, species) order, and within each bucket of meshes the trees nearest
    /// the camera first: drawn in this order, near crowns fill the depth buffer before the
    /// ones they hide, whose fragments the depth test then rejects before shading.
    pub buckets: Vec<Bucket>,
    /// Joint palettes the drawn trees use (3×4 row-major, rest → animated, tree space).
    /// Each simulation's palettes are the prefix of joints the finest level any of its
    /// trees is drawn at reads (an impostor: the trunk). A lane group (up to 16 simulated
    /// instances) whose simulations all need the same prefix has it as the simulation
    /// computes it: per joint, per matrix element, the group's values side by side. One
    /// whose simulations need different prefixes (a near tree among far ones) has each
    /// simulation's prefix in a row instead, so a fine level's joints are sent only for
    /// the simulations drawn at it. [`Instance::palette`] says which. Simulations with no
    /// drawn tree are left out. No padding.
    pub palettes: Vec<f32>,
    /// Mean wind at the scene centre, 20 m up, world m/s.
    pub wind: [f32; 3],
    /// Figures.
    pub stats: FrameStats,
    /// (bucket key, tagged tree: see `TREE_BITS`) of each draw.
    keys: Vec<(u32, u32)>,
    /// Distance-sort scratch.
    sorted: Vec<(u32, u32)>,
    /// Per tree: continuous level after hysteresis, capped at [`lod_cap`] (NaN: not seen
    /// yet).
    lod_state: Vec<f32>,
    /// Per simulation (lane group · 16 + lane, all species in a row): joints its drawn
    /// trees read (a prefix; 0: not drawn).
    need: Vec<u32>,
    /// Per simulation: where its palettes lie in `palettes`.
    slots: Vec<PaletteSlot>,
    /// Per simulation (as `need`): joints the next step is to simulate for it.
    want: Vec<u32>,
    /// The pass over the trees, a run of them at a time.
    runs: Vec<TreeRun>,
    /// Per species, the image fraction below which a tree goes to its LOD cap
    /// ([`past_cap_fraction`]).
    past_cap: Vec<f32>,
    /// Per lane group drawn: where its palettes go.
    copies: Vec<PaletteCopy>,
    /// `need` and `want` as the runs raise them, and `need` of the trees in view alone.
    need_max: Maxima,
    want_max: Maxima,
    seen_max: Maxima,
}

/// Trees a frame's pass takes at a time (the runs go in parallel).
const TREE_RUN: usize = 4096;

/// A draw's tree, tagged: the tree's index in the low bits (a scene holds at most a million
/// trees), whether the tree is cross-fading between two instance groups, and whether the
/// draw is its old group's.
const TREE_BITS: u32 = (1 << 30) - 1;
const REGROUPING: u32 = 1 << 30;
const OLD_GROUP: u32 = 1 << 31;

/// What a bucket key says of its draws: species, level, the species' runtime and last
/// level, whether drawn as an impostor.
#[derive(Clone, Copy)]
struct KeyOf<'a> {
    key: u32,
    species: u32,
    level: u32,
    sp: &'a SpeciesRuntime,
    last: u32,
    far: bool,
}

/// Instances a frame writes at a time (the runs go in parallel).
const INSTANCE_RUN: usize = 2048;

/// What a run of trees adds to a frame: per bucket key, its draws' tagged trees in tree
/// order; and its counts.
#[derive(Debug, Clone, Default)]
struct TreeRun {
    by_key: Vec<Vec<u32>>,
    stats: FrameStats,
    /// Per tree of the run: whether it may be in view.
    seen: Vec<bool>,
    /// Per tree of the run: whether its shadow may fall in view (first cut).
    shade: Vec<bool>,
}

/// The trees' feet and heights as separate arrays (what culling reads, in the layout that
/// lets [`may_see_trees`] test many trees at a time).
#[derive(Debug, Clone, Default)]
struct Crowns {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    h: Vec<f32>,
}

impl Crowns {
    /// From the trees' placements and each species' height.
    fn new(trees: &[(Placement, u32)], height: impl Fn(u32) -> f32) -> Crowns {
        let mut c = Crowns::default();
        for (p, _) in trees {
            c.x.push(p.position[0]);
            c.y.push(p.position[1]);
            c.z.push(p.position[2]);
            c.h.push(height(p.species) * p.scale);
        }
        c
    }
}

/// Per-simulation maxima that the runs of trees raise together.
#[derive(Debug, Default)]
struct Maxima(Vec<AtomicU32>);

impl Clone for Maxima {
    fn clone(&self) -> Maxima {
        Maxima(self.0.iter().map(|m| AtomicU32::new(m.load(Ordering::Relaxed))).collect())
    }
}

impl Maxima {
    /// `n` zeros (no allocation once grown).
    fn reset(&mut self, n: usize) {
        self.0.clear();
        self.0.resize_with(n, || AtomicU32::new(0));
    }

    /// Raise entry `i` to `v` at least (a plain load where it is already there, as it is for
    /// most trees of a group).
    fn raise(&self, i: usize, v: u32) {
        let m = &self.0[i];
        if m.load(Ordering::Relaxed) < v {
            m.fetch_max(v, Ordering::Relaxed);
        }
    }
}

impl FrameData {
    /// The geometry level tree `t` was drawn at in the last frame built into this
    /// `FrameData` (the finer of two while cross-fading); `None` if it has not been in view
    /// or the geometry LOD is off.
    pub fn level(&self, t: usize) -> Option<u32> {
        self.lod_state.get(t).filter(|x| !x.is_nan()).map(|x| x.floor().max(0.0) as u32)
    }
}

/// What a viewer shows of one tree ([`Forest::tree_info`]).
#[derive(Debug, Clone, PartialEq)]
pub struct TreeInfo {
    /// Species name.
    pub species: String,
    /// Height, m.
    pub height: f32,
    /// Trunk diameter at breast height (1.3 m up the trunk of the unscaled tree, then
    /// scaled with it), m.
    pub dbh: f32,
    /// Undamped natural frequency of the trunk's base joint, Hz.
    pub trunk_frequency: f32,
    /// Its instance group (trees of a species sharing one simulation).
    pub group: u32,
    /// Trees in that group.
    pub group_size: usize,
}

/// One species of a forest: its model, simulation and instance groups.
#[derive(Debug)]
pub struct SpeciesRuntime {
    /// Name as given in the scene.
    pub name: String,
    /// Geometry, LOD chain and textures.
    pub model: TreeModel,
    batch: SwayBatch,
    /// The crown's static lean in wind, for its impostors.
    lean: CrownLean,
    /// Per group: wind sample point (world), yaw, leaf flutter, crown lean.
    groups: Vec<Group>,
    winds: Vec<[f32; 3]>,
    /// Its trees, in Morton order of position, and their Morton codes.
    members: Vec<usize>,
    codes: Vec<u64>,
    /// Index of this species' first lane group in the forest's list of lane groups.
    lane_base: usize,
    /// Bytes of animation state this species may hold (its share of `max_state_mb`).
    state_cap: usize,
    /// Lane groups the cap kept at fewer joints than they were asked for, last step.
    capped: usize,
    /// Per group: the batch instance (lane) that simulates it. The animation LOD moves
    /// simulations between lanes (see `lanes.rs`); a group keeps its number.
    lane_of: Vec<u32>,
    /// Per lane: the group it simulates.
    group_of: Vec<u32>,
    /// Scratch: per lane the joints its simulation is to step, per lane group the longest,
    /// and the packing's.
    want: Vec<u32>,
    longest: Vec<u32>,
    shown: Vec<u32>,
    packer: lanes::Packer,
    /// The skeleton's LOD order: joints each level uses, joints of the trunk.
    pub order: LodOrder,
    /// Simulated instances that read the coarse wind in the last step.
    coarse_wind: usize,
    /// Simulated instances that read the near field in the last step.
    near_wind: usize,
}

impl SpeciesRuntime {
    /// The crown's static lean in wind that its impostors are sheared with.
    pub fn lean(&self) -> &CrownLean {
        &self.lean
    }

    /// Simulated instances (instance groups) of this species.
    pub fn simulated(&self) -> usize {
        self.groups.len()
    }

    /// Joints (a prefix in LOD order) a tree drawn in bucket level `lod` reads palettes of:
    /// its mesh level's, or the trunk's for the impostor (`lod` = the chain's length).
    pub fn joints_drawn(&self, lod: u32) -> usize {
        match self.order.prefix.get(lod as usize) {
            Some(&p) if (lod as usize) < self.model.lods.len() => p,
            _ => self.order.trunk,
        }
    }
}

#[derive(Debug, Clone, Copy)]
struct Group {
    sample: [f64; 3],
    yaw: f32,
    leaf: LeafSway,
    /// The crown's static lean in the group's wind, as an impostor's shear at the trunk
    /// top (tree space, m; see [`Instance::lean`]), and how it turns the leaves (see
    /// [`Instance::tilt`]).
    lean: [f32; 2],
    tilt: [f32; 2],
}

/// A forest in wind.
#[derive(Debug)]
pub struct Forest {
    /// The scene it was built from.
    pub spec: SceneSpec,
    /// The terrain.
    pub terrain: Terrain,
    /// Species runtimes, in the scene's order.
    pub species: Vec<SpeciesRuntime>,
    /// Trees: placement and the (species-local) group each one follows.
    trees: Vec<(Placement, u32)>,
    /// The trees' feet and heights, one array each, for culling many at a time.
    crowns: Crowns,
    /// The wind field and its mip pyramid (the wind-field LOD).
    wind: OwnedPyramid,
    /// The fine tile read near the camera, where the field is coarser than the trees.
    near: Option<NearField>,
    leaf_params: LeafParams,
    /// Radius of the forest (trunks), m.
    pub radius: f32,
    time: f64,
    gain: f32,
    turn: f32,
    last_sim_ms: f64,
    lod: LodSettings,
    lane_groups: usize,
    /// Per lane (lane group · 16 + lane, all species in a row): joints to simulate for its
    /// simulation, as the last frame asked (animation LOD).
    want: Vec<AtomicU32>,
    /// Per lane (as `want`): joints the last frame drew of its simulation.
    shown: Vec<AtomicU32>,
    /// Per tree: the instance group it is fading out of, if it changed group lately.
    switches: Vec<Switch>,
    /// Where the last frame's camera was.
    eye: Mutex<Option<[f32; 3]>>,
    /// Where the camera was, and when, the last time groups were formed.
    grouped: ([f32; 3], f64),
    /// Seconds a tree that changed group cross-fades (0: it switches at once).
    regroup_fade: f32,
}

/// A tree's last change of instance group: the group it left (`u32::MAX`: none) and when.
#[derive(Debug, Clone, Copy)]
struct Switch {
    from: u32,
    at: f64,
}

impl Switch {
    const NONE: Switch = Switch { from: u32::MAX, at: 0.0 };

    /// Weight of the new group at time `t` and the old group, while fading over `fade` s.
    fn fading(&self, t: f64, fade: f32) -> Option<(f32, u32)> {
        // Past the fade (or none), without the division: the quotient of a ≥ b > 0 is ≥ 1.
        if self.from == u32::MAX || !(fade > 0.0 && t - self.at < fade as f64) {
            return None;
        }
        let w = ((t - self.at) / fade as f64) as f32;
        (w < 1.0).then_some((w.max(0.0), self.from))
    }
}

/// Put the trees of `runs` (over `members`) in the instance groups `slots`, move each
/// group's wind sample point to its trees' crowns, and report each tree that changed group
/// to `moved(tree, old group)`. Groups without a run keep their sample point.
fn regroup_species(
    trees: &mut [(Placement, u32)],
    groups: &mut [Group],
    members: &[usize],
    runs: &[(usize, usize)],
    slots: &[u32],
    height: f32,
    mut moved: impl FnMut(usize, u32),
) {
    for (&(lo, hi), &g) in runs.iter().zip(slots) {
        let group = &mut groups[g as usize];
        let mut c = [0.0f64; 3];
        for &t in &members[lo..hi] {
            let old = trees[t].1;
            if old != g {
                moved(t, old);
            }
            trees[t].1 = g;
            trees[t].0.yaw = group.yaw;
            let p = trees[t].0;
            c[0] += p.position[0] as f64;
            c[1] += p.position[1] as f64;
            c[2] += (p.position[2] + 0.7 * height * p.scale) as f64;
        }
        let k = (hi - lo).max(1) as f64;
        group.sample = [c[0] / k, c[1] / k, c[2] / k];
    }
}

/// Default image-height fraction above which a tree is drawn at full detail (with
/// [`DEFAULT_FAR_LEVEL`], below which it is an impostor). Chosen by measurement
/// (`sylva bench table3`, docs/benchmarks.md): against full detail, scene A's image error
/// falls from mean FLIP 0.19 at h₀ = 1 (mesh levels 1 and 2 down to a ninth of the image)
/// to 0.04 here, while scene D draws fewer triangles than before.
pub const DEFAULT_LOD_FRACTION: f32 = 0.2;

/// Default first level drawn as an impostor: 1, so a tree is either at full detail or an
/// impostor, cross-faded between. A scene or `--far-level` can use the mesh levels in
/// between. Level 1 shows full detail's leaf cards on a third of its wood, so at 2 the trees
/// between h₀ and h₀/3 of the image look nearly as at full detail (scene B: mean FLIP
/// against full detail 0.062 → 0.031) for about six times the triangles (8.6 → 49.7 M a
/// frame along B's path); from level 2 on, merged cards look further from full detail than
/// the impostor does (docs/benchmarks.md).
pub const DEFAULT_FAR_LEVEL: u32 = 1;

impl Forest {
    /// Build the forest of `spec`: layout, tree models, simulations and wind field.
    pub fn new(spec: &SceneSpec) -> Result<Forest, ForestError> {
        let terrain = Terrain::new(spec);
        let placements = layout(spec, &terrain);
        let radius = placements
            .iter()
            .map(|p| (p.position[0].powi(2) + p.position[1].powi(2)).sqrt())
            .fold(0.0, f32::max);
        // Models, one per species, in parallel (deterministic: each from its own seed).
        let models: Vec<Result<TreeModel, ForestError>> = spec
            .species
            .par_iter()
            .enumerate()
            .map(|(i, s)| {
                let sp = Species::load(&s.name).map_err(|e| ForestError::Species {
                    name: s.name.clone(),
                    message: e.to_string(),
                })?;
                sp.model(spec.seed.wrapping_add(1000 * i as u64 + 1), LOD_LEVELS).map_err(|e| {
                    ForestError::Species { name: s.name.clone(), message: e.to_string() }
                })
            })
            .collect();
        let models: Vec<TreeModel> = models.into_iter().collect::<Result<_, _>>()?;
        let mut species = Vec::with_capacity(models.len());
        let mut trees: Vec<(Placement, u32)> = placements.iter().map(|&p| (p, 0)).collect();
        let total = trees.len().max(1);
        // Groups are first formed for where the camera starts.
        let eye = start_camera(spec, radius).eye;
        let side = spec.side();
        let mut lane_base = 0;
        // Simulations per species: its share of `sim_joint_budget` in whole trees, or every
        // tree its own without the wind-field LOD.
        let members_of = |si: usize| trees.iter().filter(|t| t.0.species == si as u32).count();
        let simulations = |trees_here: usize, joints: usize| {
            let share = spec.sim_joint_budget as f64 * trees_here as f64 / total as f64;
            // A species the layout gave no tree simulates nothing.
            if spec.lod.wind {
                ((share / joints as f64) as usize).clamp(trees_here.min(1), trees_here)
            } else {
                trees_here
            }
        };
        // The whole forest's animation state (68 bytes per joint and lane stored), per
        // species: every joint of every simulation, and the trunks alone. A batch stores
        // what it simulates, so with the animation LOD the trunks are what must fit (far
        // trees step them and nothing else); without it, every joint. Refused before any is
        // allocated. Joints go in LOD order: each level's joints a prefix, the trunk first.
        let orders: Vec<LodOrder> = models.iter().map(lod_order).collect();
        let (full, floor): (Vec<usize>, Vec<usize>) = models
            .iter()
            .zip(&orders)
            .enumerate()
            .map(|(si, (m, order))| {
                let (joints, trunk) = (m.tree.skeleton.len(), order.trunk);
                let sims = simulations(members_of(si), joints);
                (SwayBatch::state_bytes(sims, joints), SwayBatch::state_bytes(sims, trunk))
            })
            .unzip();
        let limit = spec.max_state_mb.saturating_mul(1_000_000);
        let (all_full, all_floor) = (full.iter().sum::<usize>(), floor.iter().sum::<usize>());
        let needed = if spec.lod.animation { all_floor } else { all_full };
        if needed > limit {
            return Err(ForestError::TooLarge { bytes: needed, limit });
        }
        // Each species may hold its trunks and a share of the rest of the cap in proportion
        // to its crowns (all of them where the whole forest fits): the animation LOD keeps a
        // lane group at a coarser prefix rather than go over it (`FrameStats::state_capped`).
        // Where the forest fits, a quarter more: the rows of simulations stepped alone
        // (`SwayBatch::set_alone_limit`; a row holds a lane's palettes and state, 68 bytes a
        // joint as the group does per joint and lane), at most two lanes' of a group of 16
        // or one of 8 or 4 (≤ 25 %).
        let spare = (all_full - all_floor).max(1) as f64;
        let allowance = |si: usize| {
            let share = (full[si] - floor[si]) as f64 / spare;
            let most = (full[si] - floor[si]) as f64 + full[si] as f64 / 4.0;
            floor[si] + ((limit - all_floor) as f64 * share).min(most) as usize
        };
        for (si, (original, order)) in models.into_iter().zip(orders).enumerate() {
            let model = original.reordered(&order.order).map_err(|e| ForestError::Species {
                name: spec.species[si].name.clone(),
                message: e.to_string(),
            })?;
            let joints = model.tree.skeleton.len();
            let mut members: Vec<usize> =
                (0..trees.len()).filter(|&t| trees[t].0.species == si as u32).collect();
            members.sort_by_key(|&t| {
                (morton(trees[t].0.position[0], trees[t].0.position[1], side), t)
            });
            let codes: Vec<u64> = members
                .iter()
                .map(|&t| morton(trees[t].0.position[0], trees[t].0.position[1], side))
                .collect();
            let n_groups = simulations(members.len(), joints);
            let height = model.tree.stats.height;
            // The first groups, by distance from where the camera starts; each simulated
            // instance keeps the yaw of its first group's first tree.
            let runs = partition(&codes, side, eye, height, n_groups);
            let mut groups = Vec::with_capacity(n_groups);
            for g in 0..n_groups {
                let yaw = runs
                    .get(g)
                    .map(|r| trees[members[r.0]].0.yaw)
                    .or(members.get(g).map(|&t| trees[t].0.yaw))
                    .unwrap_or(0.0);
                groups.push(Group {
                    sample: [0.0; 3],
                    yaw,
                    leaf: LeafSway::default(),
                    lean: [0.0; 2],
                    tilt: [0.0; 2],
                });
            }
            let slots: Vec<u32> = (0..runs.len() as u32).collect();
            regroup_species(&mut trees, &mut groups, &members, &runs, &slots, height, |_, _| {});
            let sway = SwaySpecies::new(
                &model.tree.skeleton,
                spec.sway.apply(SwayParams::for_leaves(model.leaves.needles)),
            )
            .map_err(|e| ForestError::Species {
                name: spec.species[si].name.clone(),
                message: e.to_string(),
            })?;
            let lean = CrownLean::new(&sway, &model.tree.skeleton);
            let mut batch = SwayBatch::new(sway, n_groups);
            let mut prefixes = order.prefix.clone();
            prefixes.push(order.trunk);
            batch.set_prefixes(&prefixes);
            species.push(SpeciesRuntime {
                name: spec.species[si].name.clone(),
                model,
                batch,
                lean,
                winds: vec![[0.0; 3]; n_groups],
                groups,
                members,
                codes,
                lane_base,
                state_cap: allowance(si),
                capped: 0,
                lane_of: (0..n_groups as u32).collect(),
                group_of: (0..n_groups as u32).collect(),
                want: Vec::with_capacity(n_groups),
                longest: Vec::with_capacity(n_groups.div_ceil(LANES)),
                shown: Vec::with_capacity(n_groups),
                packer: lanes::Packer::default(),
                order,
                coarse_wind: 0,
                near_wind: 0,
            });
            lane_base += n_groups.div_ceil(LANES);
        }
        let SceneWind { field, near } = wind_field(spec, radius)?;
        let wind = OwnedPyramid::new(field);
        let n_trees = trees.len();
        let crowns = Crowns::new(&trees, |s| species[s as usize].model.tree.stats.height);
        Ok(Forest {
            spec: spec.clone(),
            terrain,
            species,
            trees,
            crowns,
            wind,
            near,
            leaf_params: spec.leaves,
            radius,
            time: 0.0,
            gain: 1.0,
            turn: 0.0,
            last_sim_ms: 0.0,
            lod: LodSettings {
                geometry: spec.lod.geometry,
                animation: spec.lod.animation,
                fraction: spec.lod.fraction,
                far_level: spec.lod.far_level,
                ..LodSettings::default()
            },
            lane_groups: lane_base,
            // Before any frame every joint is simulated: a forest stepped and then drawn (or
            // read through `tree_palettes`) shows every joint's motion. A caller that draws
            // builds a frame first, so that the first step already follows the animation LOD
            // (and holds only the state it needs).
            want: (0..lane_base * LANES).map(|_| AtomicU32::new(u32::MAX)).collect(),
            shown: (0..lane_base * LANES).map(|_| AtomicU32::new(u32::MAX)).collect(),
            switches: vec![Switch::NONE; n_trees],
            eye: Mutex::new(None),
            grouped: (eye, 0.0),
            regroup_fade: REGROUP_FADE,
        })
    }

    /// The scene's default viewpoint.
    pub fn default_camera(&self) -> Camera {
        default_camera(&self.spec, self.radius)
    }

    /// Form the instance groups again if the camera has moved on (see the module
    /// documentation): called by [`Forest::step`].
    fn regroup(&mut self) {
        let Some(eye) = *self.eye.lock().unwrap_or_else(|e| e.into_inner()) else { return };
        let (at, when) = self.grouped;
        let travel = (0..3).map(|i| (eye[i] - at[i]).powi(2)).sum::<f32>().sqrt();
        if !self.spec.lod.wind || travel < REGROUP_TRAVEL || self.time - when < REGROUP_FADE as f64
        {
            return;
        }
        self.grouped = (eye, self.time);
        let side = self.spec.side();
        let (now, switches) = (self.time, &mut self.switches);
        for s in &mut self.species {
            if s.groups.len() >= s.members.len() {
                continue;
            }
            let height = s.model.tree.stats.height;
            let runs = partition(&s.codes, side, eye, height, s.groups.len());
            let trees = &self.trees;
            let slots = assign_slots(&runs, &s.members, |t| trees[t].1, s.groups.len());
            regroup_species(
                &mut self.trees,
                &mut s.groups,
                &s.members,
                &runs,
                &slots,
                height,
                |t, from| switches[t] = Switch { from, at: now },
            );
        }
    }

    /// Seconds over which a tree that changes instance group cross-fades from its old
    /// simulation to its new one (default [`REGROUP_FADE`]; 0 switches at once, as a
    /// comparison for measuring popping). Clamped to 0 … 10.
    pub fn set_regroup_fade(&mut self, seconds: f32) {
        self.regroup_fade =
            if seconds.is_finite() { seconds.clamp(0.0, 10.0) } else { REGROUP_FADE };
    }

    /// How long the scene's camera path lasts, s: its last key's time, or the default
    /// fly-in's ([`crate::scene::default_camera_path`]) when the scene has none (12 s if
    /// that has no keys either), the span [`Forest::camera_at`] follows.
    pub fn path_duration(&self) -> f32 {
        if self.spec.camera_path.is_empty() {
            default_camera_path(&self.spec, self.radius).last().map_or(12.0, |k| k.t)
        } else {
            self.spec.camera_path.last().map_or(0.0, |k| k.t)
        }
    }

    /// The camera at time `t` on the scene's camera path, or on the default fly-in
    /// ([`crate::scene::default_camera_path`]) when the scene has none.
    pub fn camera_at(&self, t: f32) -> Camera {
        let base = self.default_camera();
        if self.spec.camera_path.is_empty() {
            camera_on_path(&default_camera_path(&self.spec, self.radius), t, &base)
        } else {
            camera_on_path(&self.spec.camera_path, t, &base)
        }
    }

    /// Geometry-LOD threshold: the image-height fraction `h₀` above which a tree is drawn at
    /// full detail (larger: coarser everywhere). Clamped to 0.01 … 100.
    pub fn set_lod_fraction(&mut self, h0: f32) {
        self.lod.fraction =
            if h0.is_finite() { h0.clamp(0.01, 100.0) } else { DEFAULT_LOD_FRACTION };
    }

    /// Geometry-LOD settings; values out of range are clamped.
    pub fn set_lod(&mut self, lod: LodSettings) {
        let chain = self.species.iter().map(|s| s.model.lods.len()).min().unwrap_or(1) as u32;
        let finite = |v: f32, d: f32| if v.is_finite() { v } else { d };
        let d = LodSettings::default();
        self.lod = LodSettings {
            geometry: lod.geometry,
            fraction: finite(lod.fraction, d.fraction).clamp(0.01, 100.0),
            far_level: lod.far_level.clamp(1, chain.max(1)),
            band: finite(lod.band, d.band).clamp(0.0, 1.0),
            hysteresis: finite(lod.hysteresis, d.hysteresis).clamp(0.0, 0.5),
            animation: lod.animation,
        };
    }

    /// The geometry-LOD settings in use.
    pub fn lod(&self) -> LodSettings {
        self.lod
    }

    /// Simulation time, s.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Live wind controls: speed multiplier (≥ 0) and extra turn of the direction, degrees.
    pub fn set_wind_control(&mut self, gain: f32, turn_deg: f32) {
        self.gain = gain.max(0.0);
        self.turn = turn_deg.to_radians();
    }

    /// Current wind controls (gain, turn in degrees).
    pub fn wind_control(&self) -> (f32, f32) {
        (self.gain, self.turn.to_degrees())
    }

    /// The wind grid: points per side and their spacing, m.
    pub fn wind_grid(&self) -> (usize, f64) {
        let xs = &self.wind.field().grid.xs;
        let spacing = if xs.len() > 1 { xs[1] - xs[0] } else { 0.0 };
        (xs.len(), spacing)
    }

    /// The near field read around the camera, if the scene's field is coarser than its
    /// trees (see [`wind_field`]).
    pub fn near_field(&self) -> Option<&NearField> {
        self.near.as_ref()
    }

    /// One line on the wind's resolution: the grid, and the near tile if there is one.
    pub fn wind_summary(&self) -> String {
        let (n, dx) = self.wind_grid();
        let mut line = format!("wind grid {n}×{n} at {dx:.1} m");
        if let Some(near) = &self.near {
            line += &format!(
                ", near tile {m}×{m} at {:.1} m within {:.0} m of the camera",
                near.spacing(),
                near.reach(),
                m = near.points()
            );
        }
        line
    }

    /// Number of trees.
    pub fn trees(&self) -> usize {
        self.trees.len()
    }

    /// Each tree's crown as seen from above: trunk position x, y and the crown's radius, m
    /// (the species' leaf clusters at full detail: the distance from the trunk within which
    /// 90 % of them hang, plus half a card, times the tree's scale).
    pub fn crowns(&self) -> Vec<[f32; 3]> {
        let radii = self.crown_radii();
        self.trees
            .iter()
            .map(|(p, _)| [p.position[0], p.position[1], radii[p.species as usize] * p.scale])
            .collect()
    }

    /// Per species: the crown radius of the unscaled tree (see [`Forest::crowns`]), m.
    fn crown_radii(&self) -> Vec<f32> {
        self.species
            .iter()
            .map(|s| {
                let clusters = s.model.lods.first().map(|l| &l.clusters[..]).unwrap_or(&[]);
                let mut d: Vec<f32> = clusters
                    .iter()
                    .map(|c| (c.center[0] * c.center[0] + c.center[1] * c.center[1]).sqrt())
                    .collect();
                d.sort_by(f32::total_cmp);
                let card = clusters.first().map(|c| 0.5 * c.size).unwrap_or(0.0);
                d.get(d.len() * 9 / 10).copied().unwrap_or(0.0) + card
            })
            .collect()
    }

    /// Placement of tree `t` (species, trunk base, yaw, scale), if there is such a tree.
    pub fn placement(&self, t: usize) -> Option<Placement> {
        self.trees.get(t).map(|&(p, _)| p)
    }

    /// Palettes (rest → animated, tree space) of joints `joints` of tree `t`'s simulation
    /// — its instance group's — in its species' joint numbering ([`SpeciesRuntime::model`],
    /// in LOD order). Empty for an unknown tree; a joint past the skeleton reads identity.
    pub fn tree_palettes(&self, t: usize, joints: &[usize]) -> Vec<sylva_sway::Palette> {
        let Some(&(p, g)) = self.trees.get(t) else { return Vec::new() };
        let s = &self.species[p.species as usize];
        let n = s.batch.species().len();
        // Joints beyond what the lane simulates show their anchors' palettes.
        let lane = s.lane_of[g as usize] as usize;
        joints.iter().map(|&j| if j < n { s.batch.palette(lane, j) } else { IDENTITY }).collect()
    }

    /// Replace the wind (e.g. one [`wind_field`] synthesised in the background for a changed
    /// scene wind); time, sway state and live controls carry on.
    pub fn set_wind_field(&mut self, wind: SceneWind) {
        self.wind = OwnedPyramid::new(wind.field);
        self.near = wind.near;
    }

    /// The wind at world point `p` (m) now, as the trees feel it (live controls applied).
    pub fn wind_sample(&self, p: [f64; 3]) -> [f32; 3] {
        self.wind_at(p, self.time)
    }

    /// How far tree `t`'s trunk top has moved from rest, m (its instance group's sway).
    pub fn trunk_top_displacement(&self, t: usize) -> Option<f32> {
        let &(p, _) = self.trees.get(t)?;
        let sk = &self.species[p.species as usize].model.tree.skeleton;
        let top = sk.trunk_top();
        let rest = sk.joints()[top].tip();
        let m = self.tree_palettes(t, &[top]);
        let moved = sylva_sway::transform(m.first()?, rest);
        let d: f32 = (0..3).map(|i| (moved[i] - rest[i]).powi(2)).sum::<f32>().sqrt();
        Some(d * p.scale)
    }

    /// What a viewer shows of tree `t`.
    pub fn tree_info(&self, t: usize) -> Option<TreeInfo> {
        let &(p, g) = self.trees.get(t)?;
        let s = &self.species[p.species as usize];
        let stats = &s.model.tree.stats;
        Some(TreeInfo {
            species: s.name.clone(),
            height: stats.height * p.scale,
            dbh: s.model.tree.skeleton.dbh() * p.scale,
            trunk_frequency: s.batch.species().spring(0).frequency,
            group: g,
            group_size: self
                .trees
                .iter()
                .filter(|&&(q, h)| q.species == p.species && h == g)
                .count(),
        })
    }

    /// The tree the ray from `origin` along `dir` (world) hits first: one whose axis it
    /// passes within its crown's radius ([`Forest::crowns`]) above a third of its height,
    /// or within a fifth of its height lower down (the trunk), in front of the origin; the
    /// closest such along the ray. The crown stands as a cylinder about the trunk.
    pub fn pick(&self, origin: [f32; 3], dir: [f32; 3]) -> Option<usize> {
        let n = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
        if n.is_nan() || n <= 0.0 {
            return None;
        }
        let d = [dir[0] / n, dir[1] / n, dir[2] / n];
        let radii = self.crown_radii();
        let mut best: Option<(f32, usize)> = None;
        for (i, (p, _)) in self.trees.iter().enumerate() {
            let h = self.species[p.species as usize].model.tree.stats.height * p.scale;
            // Closest approach of the ray and the trunk segment (base to base + h ẑ).
            let w =
                [origin[0] - p.position[0], origin[1] - p.position[1], origin[2] - p.position[2]];
            let b = d[2];
            let (dd, e) = (d[0] * w[0] + d[1] * w[1] + d[2] * w[2], w[2]);
            let den = 1.0 - b * b;
            let (s, z) = if den > 1e-6 {
                let s = (b * e - dd) / den;
                (s, (e + s * b).clamp(0.0, h))
            } else {
                (-dd, 0.5 * h)
            };
            let s = s.max(0.0);
            let q = [origin[0] + s * d[0], origin[1] + s * d[1], origin[2] + s * d[2]];
            let gap = ((q[0] - p.position[0]).powi(2)
                + (q[1] - p.position[1]).powi(2)
                + (q[2] - p.position[2] - z).powi(2))
            .sqrt();
            let reach = if z >= h / 3.0 {
                (radii[p.species as usize] * p.scale).max(0.2 * h)
            } else {
                0.2 * h
            };
            if gap <= reach && s > 0.0 && best.is_none_or(|(bs, _)| s < bs) {
                best = Some((s, i));
            }
        }
        best.map(|(_, i)| i)
    }

    /// Leaf flutter of tree `t` (its instance group's), as the renderer draws it; `None`
    /// for an unknown tree.
    pub fn tree_leaves(&self, t: usize) -> Option<sylva_sway::LeafSway> {
        let &(p, g) = self.trees.get(t)?;
        self.species[p.species as usize].groups.get(g as usize).map(|g| g.leaf)
    }

    fn wind_at(&self, p: [f64; 3], t: f64) -> [f32; 3] {
        let w = wind_near(self.wind.level(0), self.near.as_ref(), self.near_centre(), p, t).0;
        steer(w, self.gain, self.turn)
    }

    /// Where the near field is centred: the last frame's camera (before any frame, the
    /// camera the groups were formed for).
    fn near_centre(&self) -> [f32; 3] {
        self.eye.lock().unwrap_or_else(|e| e.into_inner()).unwrap_or(self.grouped.0)
    }

    /// Advance the simulation by `dt` seconds (> 0; others are ignored).
    pub fn step(&mut self, dt: f32) {
        if !(dt > 0.0 && dt.is_finite()) {
            return;
        }
        let start = Instant::now();
        self.time += dt as f64;
        self.regroup();
        let t = self.time;
        let leaf = self.leaf_params;
        let (pyramid, gain, turn) = (&self.wind, self.gain, self.turn);
        let (near, centre) = (self.near.as_ref(), self.near_centre());
        let (wanted, drawn, animation) = (&self.want, &self.shown, self.lod.animation);
        let coarse_levels = self.spec.lod.wind;
        // Species in parallel; each samples the shared, read-only field for its groups.
        let work = |s: &mut SpeciesRuntime| {
            let all = s.batch.species().len();
            let trunk = s.order.trunk;
            s.coarse_wind = 0;
            s.near_wind = 0;
            let base = s.lane_base * LANES;
            let want = &mut s.want;
            want.clear();
            // A lane group steps the trunk at least: a want below it (nothing drawn) is the
            // trunk's, so out-of-view and impostor simulations are not told apart.
            want.extend(
                (0..s.groups.len())
                    .map(|l| wanted[base + l].load(Ordering::Relaxed).max(trunk as u32)),
            );
            let shown = &mut s.shown;
            shown.clear();
            shown.extend((0..s.groups.len()).map(|l| drawn[base + l].load(Ordering::Relaxed)));
            if animation {
                // Gather the simulations that need the same joints into the same lane groups.
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
            // Per lane group: the longest prefix any of its lanes wants.
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
                    // Counted as if every lane of the group stored the prefix (a lane the step
                    // sends alone holds its own in a row, for less): within the cap whatever
                    // the step decides. Growing past the species' share of the memory cap:
                    // the group keeps the finest registered prefix it already holds memory
                    // for, the trunk at least.
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
                // Each lane its own prefix within the group's: a lane group holding one near
                // tree among far ones steps the near tree's crown in its lane alone.
                for i in k * LANES..want.len().min(k * LANES + LANES) {
                    s.batch.set_lane_active(i, if animation { want[i] as usize } else { all });
                }
                // Joints switched off fade out where a tree shows them; where none does, they
                // go at once.
                let end = shown.len().min(k * LANES + LANES);
                if shown[k * LANES..end].iter().all(|&d| d as usize <= w) {
                    s.batch.settle(k);
                }
            }
            // What the cap leaves to the rows of simulations stepped alone.
            s.batch.set_alone_limit(s.state_cap.saturating_sub(held));
            for (i, g) in s.groups.iter_mut().enumerate() {
                let lane = s.lane_of[i] as usize;
                // Wind-field LOD: groups whose trees are all impostors (or out of view) read
                // the pyramid's coarse level.
                let far = coarse_levels && longest[lane / LANES] as usize <= trunk;
                s.coarse_wind += far as usize;
                let w = if far {
                    pyramid.level(FAR_WIND_LEVEL).sample(g.sample, t)
                } else {
                    let (w, is_near) = wind_near(pyramid.level(0), near, centre, g.sample, t);
                    s.near_wind += is_near as usize;
                    w
                };
                let w = steer(w, gain, turn);
                let (sn, cs) = g.yaw.sin_cos();
                s.winds[lane] = [cs * w[0] + sn * w[1], -sn * w[0] + cs * w[1], w[2]];
                let (shear, tilt) = s.lean.shear_and_tilt(s.winds[lane]);
                g.lean = shear;
                g.tilt = tilt_along(shear, tilt);
                let speed = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
                leaf.step(&mut g.leaf, speed, dt);
            }
            s.batch.step(dt, &s.winds);
        };
        // A species that stepped more than two thirds of the joints last time (a near crown
        // among far trees) starts at once on its own, the others beside it; otherwise the
        // species are shared out as they come (with the threshold at half, B's step without
        // the wind-field LOD, where one species' share hovers about half, was 8 % slower;
        // docs/benchmarks.md). The order changes no result, only when each species is
        // stepped.
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
        self.last_sim_ms = start.elapsed().as_secs_f64() * 1e3;
    }

    /// Fill `out` for `camera` and an image of `aspect` = width / height. Allocates only
    /// while `out`'s arrays grow. `out` keeps the per-tree LOD history (hysteresis) of this
    /// view: use one `FrameData` per view.
    pub fn frame(&self, camera: &Camera, aspect: f32, out: &mut FrameData) {
        *self.eye.lock().unwrap_or_else(|e| e.into_inner()) = Some(camera.eye);
        let previous = out.time;
        out.time = self.time;
        out.keys.clear();
        if out.lod_state.len() != self.trees.len() {
            out.lod_state.clear();
            out.lod_state.resize(self.trees.len(), f32::NAN);
        }
        // A scene holds at most a million trees (`SceneSpec` refuses more).
        debug_assert!(self.trees.len() <= TREE_BITS as usize, "too many trees to tag");
        let sims = self.lane_groups * LANES;
        out.need_max.reset(sims);
        out.want_max.reset(sims);
        out.seen_max.reset(sims);
        let lod = self.lod;
        let mut stats = FrameStats { trees: self.trees.len(), ..FrameStats::default() };
        let cone = camera.cone(aspect);
        // Bucket keys: level-major, so the finest levels are drawn first.
        let n_species = self.species.len().max(1) as u32;
        // Keys: levels 0 to the longest chain (its impostor) for each species.
        let longest = self.species.iter().map(|s| s.model.lods.len()).max().unwrap_or(0);
        let n_keys = (longest + 1) * n_species as usize;
        // Trees out of view whose shadow may fall in it: with shadows on, culled by their
        // crown swept away from the sun, and keyed after every tree in view.
        let lighting = &self.spec.lighting;
        let sweep = if lighting.shadows { ShadowSweep::new(lighting.sun_unit()) } else { None };
        // Nothing outside the shadow map's far cascade takes a shadow: a tree out of view is
        // kept only where it may also cast into that cascade (a margin of two of its texels
        // for the renderer's snapping).
        let far_box = ShadowBox::new(camera, aspect, camera.shadow_reach().1, lighting.sun_unit());
        let box_margin = 4.0 * far_box.radius / ShadowBox::TEXELS as f32;
        let all_keys = if sweep.is_some() { 2 * n_keys } else { n_keys };
        let split = |key: u32| {
            let key = key % n_keys as u32;
            (key % n_species, key / n_species)
        };
        // Whether a tree of `species` at `level` is drawn as its impostor.
        let impostor = |species: u32, level: u32| {
            let chain = self.species[species as usize].model.lods.len() as u32;
            lod.geometry && level >= lod.far_level.min(chain)
        };
        // The trees in runs of TREE_RUN, the runs in parallel: each fills its own keys,
        // merged below in run order, and raises the per-simulation maxima (which do not
        // depend on order), so the frame is the same for any number of threads.
        let runs = self.trees.len().div_ceil(TREE_RUN);
        if out.runs.len() < runs {
            out.runs.resize_with(runs, TreeRun::default);
        }
        let (need_max, want_max, seen_max) = (&out.need_max, &out.want_max, &out.seen_max);
        // The animation LOD's coordinate less the geometry LOD's: the same for every tree.
        let ahead = (ANIMATION_FRACTION / lod.fraction).ln() / 3f32.ln();
        // Per species, the fraction below which a tree goes to its LOD cap.
        let mut past_cap = std::mem::take(&mut out.past_cap);
        past_cap.clear();
        past_cap.extend(self.species.iter().map(|sp| {
            let far = lod.far_level.min(sp.model.lods.len() as u32);
            past_cap_fraction(lod.fraction, lod_cap(far), lod.hysteresis)
        }));
        out.runs[..runs]
            .par_iter_mut()
            .zip(out.lod_state.par_chunks_mut(TREE_RUN))
            .zip(self.trees.par_chunks(TREE_RUN))
            .enumerate()
            .for_each(|(r, ((run, states), trees))| {
                if run.by_key.len() < all_keys {
                    run.by_key.resize_with(all_keys, Vec::new);
                }
                run.by_key.iter_mut().for_each(Vec::clear);
                let (first, n) = (r * TREE_RUN, trees.len());
                run.seen.resize(n, false);
                let (cr, span) = (&self.crowns, first..first + n);
                let (cx, cy) = (&cr.x[span.clone()], &cr.y[span.clone()]);
                let (cz, ch) = (&cr.z[span.clone()], &cr.h[span]);
                may_see_trees(&cone, cx, cy, cz, ch, &mut run.seen[..n]);
                run.shade.resize(n, false);
                match &sweep {
                    Some(sw) => may_shade_trees(
                        &cone,
                        sw,
                        cx,
                        cy,
                        cz,
                        ch,
                        &run.seen[..n],
                        &mut run.shade[..n],
                    ),
                    None => run.shade[..n].fill(false),
                }
                run.stats = FrameStats::default();
                for (k, ((p, g), state)) in trees.iter().zip(states).enumerate() {
                    let i = r * TREE_RUN + k;
                    let sp = &self.species[p.species as usize];
                    // The crown's height and centre, as the culling took them.
                    let h = ch[k];
                    let c = [cx[k], cy[k], cz[k] + 0.5 * h];
                    // Out of view: kept for the shadow map only where its swept crown may
                    // reach the view.
                    let shadow_only = !run.seen[k];
                    if shadow_only {
                        let Some(sw) = sweep.filter(|_| run.shade[k]) else { continue };
                        let (r, len) = (0.75 * h, sw.length(h));
                        if !(far_box.may_take(c, r, len, box_margin)
                            && cone.may_see_shadow(c, r, sw.away, len))
                        {
                            continue;
                        }
                    }
                    let key_base = if shadow_only { n_keys as u32 } else { 0 };
                    let chain = sp.model.lods.len() as u32;
                    let far = lod.far_level.min(chain);
                    // Joints level `l` draws (a prefix in LOD order).
                    let joints = |l: u32| {
                        if lod.geometry && l >= far {
                            sp.order.trunk
                        } else {
                            sp.order.prefix[l as usize]
                        }
                    };
                    // Joints a tree out of view casts its shadow at level `l` with.
                    let casts = |l: u32| {
                        if lod.geometry && l >= far {
                            sp.order.trunk
                        } else {
                            sp.order.prefix[shadow_level(l, chain) as usize]
                        }
                    };
                    let frac = || cone.screen_fraction(c, h);
                    let (a, b, sim, x) = if lod.geometry {
                        let before = *state;
                        let x = next_lod_state(
                            before,
                            || lod_coordinate(frac(), lod.fraction),
                            cone.fraction_below(c, h, past_cap[p.species as usize]),
                            lod.hysteresis,
                            lod_cap(far),
                        );
                        // Levels as `blend_levels` takes them (both are ≥ 0).
                        if !before.is_nan() && before as u32 != x as u32 {
                            run.stats.level_changes += 1;
                        }
                        *state = x;
                        let (a, b, _) = blend_levels(x, far, lod.band);
                        (a, b, blend_levels((x - SIM_MARGIN).max(0.0), far, 0.0).0, x)
                    } else {
                        (0, 0, 0, f32::NAN)
                    };
                    // Joints to simulate: the geometry's choice half a level ahead, or coarser by
                    // projected size (the joints it draws beyond are held, shown at rest on their
                    // parents).
                    let moving = if lod.geometry && sim >= far {
                        sp.order.trunk
                    } else {
                        // With the geometry LOD on, from its coordinate (and so its hysteresis), so
                        // the two agree wherever their thresholds do.
                        let by_size = if x.is_nan() {
                            lod_coordinate(frac(), ANIMATION_FRACTION)
                        } else {
                            x + ahead
                        } - SIM_MARGIN;
                        let level = sim.max(by_size.max(0.0) as u32) as usize;
                        sp.order.prefix[level.min(sp.order.prefix.len() - 1)]
                    };
                    // The tree's group, and the one it is fading out of after a regroup.
                    let switch = self.switches[i].fading(self.time, self.regroup_fade);
                    let sw = self.switches[i];
                    run.stats.group_changes += (!shadow_only
                        && sw.from != u32::MAX
                        && sw.at > previous
                        && sw.at <= self.time)
                        as usize;
                    for (group, old) in
                        [(*g, false)].into_iter().chain(switch.map(|(_, f)| (f, true)))
                    {
                        let own = sp.lane_base * LANES + sp.lane_of[group as usize] as usize;
                        // A tree cast only into the shadow map needs the joints of the
                        // level it casts and simulates nothing of its own beyond the trunk
                        // (every lane steps that), and what it shows does not hold joints
                        // the simulation drops: as it leaves the view, its crown's joints go
                        // at once, as when it was culled whole, and its shadow bends with
                        // the trunk alone (they blend in from rest when it comes back, as
                        // for any tree entering the view). Two other ways were measured
                        // and not kept (docs/benchmarks.md): simulating its cast level's
                        // joints (with every tree simulated on its own such a simulation
                        // wants a prefix no other in its lane group does: scene C's step
                        // took 45–48 ms instead of 30–32), and letting its shown joints
                        // fade out computed (a 300-tree stand stepped 27 % more joints).
                        let (need, want) = if shadow_only {
                            (casts(a), sp.order.trunk)
                        } else {
                            seen_max.raise(own, joints(a) as u32);
                            (joints(a), moving)
                        };
                        need_max.raise(own, need as u32);
                        want_max.raise(own, want as u32);
                        for level in a..=b {
                            run.by_key[(key_base + level * n_species + p.species) as usize].push(
                                i as u32
                                    | if switch.is_some() { REGROUPING } else { 0 }
                                    | if old { OLD_GROUP } else { 0 },
                            );
                        }
                    }
                    if shadow_only {
                        run.stats.shadow_only += 1;
                        continue;
                    }
                    run.stats.drawn += 1;
                    run.stats.regrouping += switch.is_some() as usize;
                    run.stats.fading += (a != b) as usize;
                    run.stats.impostors += (lod.geometry && b >= lod.far_level.min(chain)) as usize;
                }
            });
        out.past_cap = past_cap;
        out.need.clear();
        out.need.extend(out.need_max.0.iter().map(|m| m.load(Ordering::Relaxed)));
        out.want.clear();
        out.want.extend(out.want_max.0.iter().map(|m| m.load(Ordering::Relaxed)));
        for run in &out.runs[..runs] {
            let r = &run.stats;
            stats.level_changes += r.level_changes;
            stats.group_changes += r.group_changes;
            stats.drawn += r.drawn;
            stats.shadow_only += r.shadow_only;
            stats.regrouping += r.regrouping;
            stats.fading += r.fading;
            stats.impostors += r.impostors;
        }
        // Into (level, species) order, trees in order within each: key by key, each run's
        // draws of that key in run order, as a stable sort of the runs' draws by key would
        // put them.
        for k in 0..all_keys {
            for run in &out.runs[..runs] {
                out.keys.extend(run.by_key[k].iter().map(|&tagged| (k as u32, tagged)));
            }
        }
        // The draws: a run of equal keys is one species at one level, one bucket (impostors
        // are bucketed as level `chain`, one past the last mesh). Within each bucket drawn
        // as meshes, the trees nearest the camera first (the impostors, two triangles each,
        // are left in tree order).
        out.buckets.clear();
        let mut run = 0;
        while run < out.keys.len() {
            let key = out.keys[run].0;
            let end = run + out.keys[run..].iter().take_while(|k| k.0 == key).count();
            let (species, level) = split(key);
            let shadow_only = key as usize >= n_keys;
            let sp = &self.species[species as usize];
            let far = impostor(species, level);
            let bucket_lod = if far { sp.model.lods.len() as u32 } else { level };
            let count = (end - run) as u32;
            match out.buckets.last_mut() {
                Some(b)
                    if b.species == species
                        && b.lod == bucket_lod
                        && b.shadow_only == shadow_only =>
                {
                    b.count += count
                }
                _ => {
                    stats.draw_calls += if shadow_only {
                        0
                    } else if far {
                        1
                    } else {
                        2
                    };
                    out.buckets.push(Bucket {
                        species,
                        lod: bucket_lod,
                        first: run as u32,
                        count,
                        shadow_only,
                    })
                }
            }
            if !shadow_only {
                stats.triangles +=
                    (end - run) * if far { 2 } else { sp.model.lods[level as usize].triangles() };
            }
            if !far {
                // (squared distance, tree) pairs in the distance-sort scratch:
                // no allocation once it has grown. Squared distances are non-negative, so
                // their bits order as they do; equal distances go by tree, then the old
                // group's draw after the new one's: a total order.
                let eye = camera.eye;
                out.sorted.clear();
                out.sorted.extend(out.keys[run..end].iter().map(|&(_, tagged)| {
                    let p = self.trees[(tagged & TREE_BITS) as usize].0.position;
                    ((0..3).map(|k| (p[k] - eye[k]).powi(2)).sum::<f32>().to_bits(), tagged)
                }));
                out.sorted.sort_unstable_by_key(|&(d, tagged)| (d, tagged & !REGROUPING));
                for (k, &(_, tagged)) in out.keys[run..end].iter_mut().zip(&out.sorted) {
                    k.1 = tagged;
                }
            }
            run = end;
        }
        // Palettes of the simulations that are drawn: the prefix of joints their finest
        // drawn level uses (a contiguous run: the batch lays palettes out joint-major).
        // First where each lane group's go and how they are laid out, then the copies, lane
        // groups in parallel over disjoint parts of the buffer. Written over the last
        // frame's palettes: only growth is zero-filled.
        out.slots.clear();
        out.slots.resize(self.lane_groups * LANES, PaletteSlot::default());
        out.copies.clear();
        let mut len = 0;
        for (si, s) in self.species.iter().enumerate() {
            for k in 0..s.batch.groups() {
                let Some(copy) = lay_out(s, si, k, &out.need, len) else { continue };
                let sims = s.lane_base * LANES + k * LANES..;
                let slots = &mut out.slots[sims][..copy.used as usize];
                match copy.kind {
                    Layout::Rows => {
                        // Each simulation's own prefix, in a row.
                        let mut at = len;
                        let need = &out.need[s.lane_base * LANES + k * LANES..][..slots.len()];
                        for (&m, slot) in need.iter().zip(slots.iter_mut()) {
                            *slot = PaletteSlot { base: at as u32, stride: 1 };
                            at += 12 * (m as usize).min(s.batch.species().len());
                        }
                    }
                    Layout::Rest | Layout::Lanes => {
                        for (l, slot) in slots.iter_mut().enumerate() {
                            *slot = PaletteSlot { base: (len + l) as u32, stride: copy.used };
                        }
                    }
                }
                len += copy.len;
                out.copies.push(copy);
            }
            stats.simulated += s.groups.len();
            stats.coarse_wind += s.coarse_wind;
            stats.near_wind += s.near_wind;
            stats.joints += s.batch.joint_updates();
            stats.state_bytes += s.batch.stored_bytes();
            stats.state_capped += s.capped;
        }
        let buf = overwrite(&mut out.palettes, len);
        copy_palettes(&self.species, &out.need, &out.slots, &out.copies, buf);
        out.palettes.truncate(len);
        for (a, &v) in self.want.iter().zip(&out.want) {
            a.store(v, Ordering::Relaxed);
        }
        // What the trees in view show: joints beyond it that the next step drops go at
        // once, whatever trees out of view cast with them.
        for (a, m) in self.shown.iter().zip(&out.seen_max.0) {
            a.store(m.load(Ordering::Relaxed), Ordering::Relaxed);
        }
        // One instance per draw, in runs in parallel.
        let (keys, states, slots) = (&out.keys, &out.lod_state, &out.slots);
        let instances = overwrite(&mut out.instances, keys.len());
        instances.par_chunks_mut(INSTANCE_RUN).zip(keys.par_chunks(INSTANCE_RUN)).for_each(
            |(instances, keys)| {
                // The key of the draws before (a bucket's draws are consecutive).
                let mut bucket: Option<KeyOf<'_>> = None;
                for (instance, &(key, tagged)) in instances.iter_mut().zip(keys) {
                    let KeyOf { species, level, sp, last, far, .. } = match bucket {
                        Some(b) if b.key == key => b,
                        _ => {
                            let (species, level) = split(key);
                            let sp = &self.species[species as usize];
                            let last = lod.far_level.min(sp.model.lods.len() as u32);
                            let far = impostor(species, level);
                            *bucket.insert(KeyOf { key, species, level, sp, last, far })
                        }
                    };
                    let i = (tagged & TREE_BITS) as usize;
                    let (p, now) = self.trees[i];
                    // Share of the dither range this draw's group keeps: after a regroup the
                    // old group's draws keep [0, 1 − v) and the new one's [1 − v, 1).
                    let fading = if tagged & REGROUPING != 0 {
                        self.switches[i].fading(self.time, self.regroup_fade)
                    } else {
                        None
                    };
                    let (g, lo, hi) = match fading {
                        Some((v, from)) if tagged & OLD_GROUP != 0 => (from, 0.0, 1.0 - v),
                        Some((v, _)) => (now, 1.0 - v, 1.0),
                        None => (now, 0.0, 1.0),
                    };
                    let group = &sp.groups[g as usize];
                    // Within the group's share, two levels split it as [lo, lo + (1 − w)(hi −
                    // lo)) and the rest; a range reaching 1 is written open to 2.
                    let w = if lod.geometry {
                        let (a, b, w) = blend_levels(states[i], last, lod.band);
                        match (a == b, level == a) {
                            (true, _) => None,
                            (false, true) => Some((true, w)),
                            (false, false) => Some((false, w)),
                        }
                    } else {
                        None
                    };
                    let (lo, hi) = match w {
                        None => (lo, hi),
                        Some((true, w)) => (lo, lo + (1.0 - w) * (hi - lo)),
                        Some((false, w)) => (lo + (1.0 - w) * (hi - lo), hi),
                    };
                    let fade = [lo, if hi >= 1.0 { 2.0 } else { hi }];
                    *instance = Instance {
                        position: p.position,
                        yaw: group.yaw,
                        scale: p.scale,
                        palette: slots[sp.lane_base * LANES + sp.lane_of[g as usize] as usize],
                        leaf_phase: group.leaf.phase,
                        leaf_amplitude: group.leaf.amplitude,
                        fade,
                        lean: group.lean.map(|v| half::f16::from_f32(v).to_bits()),
                        tilt: group.tilt.map(|v| half::f16::from_f32(v).to_bits()),
                        tag: if far { 15 } else { level.min(14) }
                            | (species.min(15) << 4)
                            | (g << 8),
                    };
                }
            },
        );
        out.instances.truncate(out.keys.len());
        stats.uploaded_bytes =
            4 * out.palettes.len() + std::mem::size_of::<Instance>() * out.instances.len();
        stats.sim_ms = self.last_sim_ms;
        let w = self.wind_at([0.0, 0.0, 20.0], self.time);
        out.wind = w;
        out.stats = stats;
    }
}

/// Where the camera starts: the scene's path at time 0, or its default viewpoint.
fn start_camera(spec: &SceneSpec, radius: f32) -> Camera {
    let base = default_camera(spec, radius);
    if spec.camera_path.is_empty() { base } else { camera_on_path(&spec.camera_path, 0.0, &base) }
}

/// [`Instance::tilt`] from the crown's shear and its turned vertical `t` (tree space): the
/// horizontal part along the shear, and one minus the vertical part.
fn tilt_along(shear: [f32; 2], t: [f32; 3]) -> [f32; 2] {
    let len = (shear[0] * shear[0] + shear[1] * shear[1]).sqrt();
    let along = if len > 1e-6 { (t[0] * shear[0] + t[1] * shear[1]) / len } else { 0.0 };
    [along, 1.0 - t[2]]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_species_the_layout_gave_no_tree_simulates_nothing() {
        // The small scene's five trees, and a fourth species of so small a share that none
        // of them draws it: every tree is simulated on its own (wind-field LOD off), so each
        // species simulates exactly its own trees, and the one without trees none.
        let mut spec = SceneSpec::builtin("small").expect("small");
        spec.species.push(crate::SpeciesShare { name: "black_tupelo".into(), weight: 1e-6 });
        for wind in [false, true] {
            spec.lod.wind = wind;
            let mut forest = Forest::new(&spec).expect("forest");
            let mut planted = vec![0; forest.species.len()];
            for (p, _) in &forest.trees {
                planted[p.species as usize] += 1;
            }
            assert_eq!(planted[3], 0, "the fourth species drew no tree");
            assert_eq!(forest.species[3].simulated(), 0, "wind LOD {wind}");
            let simulated: Vec<usize> = forest.species.iter().map(|s| s.simulated()).collect();
            if !wind {
                assert_eq!(simulated, planted, "each tree its own simulation");
            }
            assert!(simulated.iter().zip(&planted).all(|(&s, &p)| s <= p && (s > 0) == (p > 0)));
            // It still steps and builds frames.
            let cam = forest.default_camera();
            let mut f = FrameData::default();
            forest.step(1.0 / 30.0);
            forest.frame(&cam, 4.0 / 3.0, &mut f);
            assert_eq!(f.stats.simulated, simulated.iter().sum::<usize>());
            assert!(f.stats.drawn > 0);
        }
    }

    #[test]
    fn simulations_that_need_the_same_joints_are_stepped_together() {
        // Scene A from its default viewpoint: a few trees at full detail, most impostors.
        let spec = SceneSpec::builtin("A").expect("A");
        let mut forest = Forest::new(&spec).expect("forest");
        let cam = forest.default_camera();
        let mut f = FrameData::default();
        let dt = 1.0 / 30.0;
        // Long enough for the joints switched off to fade out (blend_time, 0.5 s).
        for _ in 0..30 {
            forest.step(dt);
            forest.frame(&cam, 4.0 / 3.0, &mut f);
        }
        forest.step(dt);
        let (mut packed, mut scattered, mut sorted, mut stepped) = (0, 0, 0, 0);
        for s in &forest.species {
            // The step just packed the lanes; `want` is what each lane's simulation asked
            // for (the trunk at least: a lane group steps no less).
            packed += lanes::stepped(&s.want) as usize;
            // Each simulation in the lane of its own number, as if nothing had been moved.
            let own: Vec<u32> = s.lane_of.iter().map(|&l| s.want[l as usize]).collect();
            scattered += lanes::stepped(&own) as usize;
            let mut w = s.want.clone();
            w.sort_unstable_by(|a, b| b.cmp(a));
            sorted += lanes::stepped(&w) as usize;
            stepped += s.batch.joint_updates();
            for (g, &l) in s.lane_of.iter().enumerate() {
                assert_eq!(s.group_of[l as usize] as usize, g, "lanes and groups agree");
            }
        }
        eprintln!(
            "joint updates: packed {packed}, scattered {scattered}, sorted longest first {sorted}"
        );
        assert_eq!(stepped, packed, "the batch steps what the packed lanes want");
        assert!(packed <= sorted, "packed {packed}, sorted {sorted}");
        assert!(packed * 10 < scattered * 9, "packed {packed}, scattered {scattered}");
    }
}
