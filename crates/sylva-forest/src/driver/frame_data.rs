//! What a frame hands the renderer ([`FrameData`]: instances, buckets, palettes, figures)
//! and the scratch the frame pass keeps in it between frames.

use std::sync::atomic::{AtomicU32, Ordering};

use bytemuck::{Pod, Zeroable};
use sylva_sway::PaletteSlot;

use super::SpeciesRuntime;
use super::palettes::PaletteCopy;

/// One tree drawn this frame, as the vertex shaders read it (60 bytes; sylva-render maps
/// each field to a vertex attribute by its offset). The default is an upright tree of
/// scale 1 drawn whole, its palette at 0.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
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
    /// one over `[1 − v, 1)`, each range split between two levels the same way. A far tree
    /// fading out by thinning ([`LodSettings::thin_px`](super::LodSettings::thin_px)) keeps
    /// a narrower range, at a place in [0, 1) fixed per tree.
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
    /// How much wider than its tree an impostor is drawn, across the line of sight (1; more
    /// for the far trees thinning keeps, `LodSettings::thin_px`). Mesh levels do not read it.
    pub spread: f32,
}

impl Default for Instance {
    fn default() -> Instance {
        Instance {
            position: [0.0; 3],
            yaw: 0.0,
            scale: 1.0,
            palette: PaletteSlot::default(),
            leaf_phase: 0.0,
            leaf_amplitude: 0.0,
            fade: [0.0, 2.0],
            tag: 0,
            lean: [0; 2],
            tilt: [0; 2],
            spread: 1.0,
        }
    }
}

/// A run of instances of one species at one LOD: one instanced draw.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Bucket {
    /// Species index.
    pub species: u32,
    /// LOD level.
    pub lod: u32,
    /// The mesh level its trees cast their shadows with: no finer than `lod` (its joints
    /// are a prefix of the drawn ones); `lod` itself for impostors.
    pub shadow_lod: u32,
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
    /// Cells of the forest's hierarchy tested against the view (`crate::cells`): those in
    /// view and the ones beside them, not the whole forest's.
    pub cells_visited: usize,
    /// Trees in the cells in view: the frame's per-tree work, which grows with what is in
    /// view, not with the forest (less those of a far leaf the thinning leaves out at once,
    /// `thinned_by_leaf`, which are not visited one by one).
    pub trees_visited: usize,
    /// Trees drawn (not culled).
    pub drawn: usize,
    /// Trees outside the view drawn into the shadow map only, as their shadow may fall in
    /// view (not counted in `drawn`, `triangles` or `draw_calls`).
    pub shadow_only: usize,
    /// Trees in the view cone hidden behind nearer trunks and crowns
    /// ([`LodSettings::occlusion`](super::LodSettings::occlusion)): not drawn, and counted
    /// in `shadow_only` where their shadow may fall in view. Trees in the view cone are
    /// `drawn + occluded`.
    pub occluded: usize,
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
    /// Trees in view left out by the thinning of far impostors (`LodSettings::thin_px`).
    pub thinned: usize,
    /// Of `thinned`, those left out with the rest of their leaf of the cells, which the
    /// frame did not visit one by one (the leaf wholly in view, and far).
    pub thinned_by_leaf: usize,
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
    /// Rows of the image this view is drawn into, pixels (0:
    /// [`DEFAULT_IMAGE_ROWS`](super::lod::DEFAULT_IMAGE_ROWS)): what an error budget in
    /// pixels is measured against. Set it where the image's size is known.
    pub image_rows: u32,
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
    pub(super) keys: Vec<(u32, u32)>,
    /// Distance-sort scratch.
    pub(super) sorted: Vec<(u32, u32)>,
    /// Per tree: continuous level after hysteresis, capped at [`lod_cap`] (NaN: not seen
    /// yet).
    pub(super) lod_state: Vec<f32>,
    /// Per simulation (lane group · 16 + lane, all species in a row): joints its drawn
    /// trees read (a prefix; 0: not drawn).
    pub(super) need: Vec<u32>,
    /// Per simulation: where its palettes lie in `palettes`.
    pub(super) slots: Vec<PaletteSlot>,
    /// Per simulation (as `need`): joints the next step is to simulate for it.
    pub(super) want: Vec<u32>,
    /// The pass over the trees, a run (a leaf of the cells in view) at a time.
    pub(super) runs: Vec<TreeRun>,
    /// The cells this view visited in its last frame.
    pub(super) visit: crate::cells::Visit,
    /// Per leaf of the cells: from which of its trees in draw order on every state is at
    /// its cap (the leaf's size where that is not known), for the levels `settled_far`.
    pub(super) settled: Vec<u32>,
    pub(super) settled_far: Vec<u32>,
    /// Per species, the image fraction below which a tree goes to its LOD cap
    /// ([`past_cap_fraction`]).
    pub(super) past_cap: Vec<f32>,
    /// Scratch: per species, the levels' fraction thresholds when levels go by error, and
    /// the first level drawn as its impostor.
    pub(super) thresholds: Vec<Vec<f32>>,
    pub(super) far: Vec<u32>,
    /// Scratch: per species, the level its trees cast their shadows with at least.
    pub(super) cast_floor: Vec<u32>,
    /// Per lane group drawn: where its palettes go.
    pub(super) copies: Vec<PaletteCopy>,
    /// The occlusion depth buffer of this view's last frame.
    pub(super) occlusion: crate::occlusion::DepthBuffer,
    /// Scratch: the trees writing occluders, by depth.
    pub(super) occluder_order: Vec<(f32, u32)>,
    /// `need` and `want` as the runs raise them, and `need` of the trees in view alone.
    pub(super) need_max: Maxima,
    pub(super) want_max: Maxima,
    pub(super) seen_max: Maxima,
}

/// A draw's tree, tagged: the tree's index in the low bits (a scene holds at most a million
/// trees), whether the tree is cross-fading between two instance groups, and whether the
/// draw is its old group's.
pub(super) const TREE_BITS: u32 = (1 << 30) - 1;
pub(super) const REGROUPING: u32 = 1 << 30;
pub(super) const OLD_GROUP: u32 = 1 << 31;

/// What a bucket key says of its draws: species, level, the species' runtime and last
/// level, whether drawn as an impostor.
#[derive(Clone, Copy)]
pub(super) struct KeyOf<'a> {
    pub(super) key: u32,
    pub(super) species: u32,
    pub(super) level: u32,
    pub(super) sp: &'a SpeciesRuntime,
    pub(super) last: u32,
    pub(super) far: bool,
}

/// Instances a frame writes at a time (the runs go in parallel).
pub(super) const INSTANCE_RUN: usize = 2048;

/// What a run of trees adds to a frame: per bucket key, its draws' tagged trees in tree
/// order; and its counts.
#[derive(Debug, Clone, Default)]
pub(super) struct TreeRun {
    pub(super) by_key: Vec<Vec<u32>>,
    pub(super) stats: FrameStats,
    /// Per tree of the run: whether it may be in view.
    pub(super) seen: Vec<bool>,
    /// Per tree of the run: whether its shadow may fall in view (first cut).
    pub(super) shade: Vec<bool>,
    /// Trees of the run (indices in the forest) that write their occluders.
    pub(super) occluders: Vec<u32>,
    /// Scratch: the trees of a far leaf its thinning may keep (`Forest::thinned_out`).
    pub(super) kept: Vec<u32>,
}

/// Per-simulation maxima that the runs of trees raise together.
#[derive(Debug, Default)]
pub(super) struct Maxima(pub(super) Vec<AtomicU32>);

impl Clone for Maxima {
    fn clone(&self) -> Maxima {
        Maxima(self.0.iter().map(|m| AtomicU32::new(m.load(Ordering::Relaxed))).collect())
    }
}

impl Maxima {
    /// `n` zeros (no allocation once grown).
    pub(super) fn reset(&mut self, n: usize) {
        self.0.clear();
        self.0.resize_with(n, || AtomicU32::new(0));
    }

    /// Raise entry `i` to `v` at least (a plain load where it is already there, as it is for
    /// most trees of a group).
    pub(super) fn raise(&self, i: usize, v: u32) {
        let m = &self.0[i];
        if m.load(Ordering::Relaxed) < v {
            m.fetch_max(v, Ordering::Relaxed);
        }
    }
}

impl FrameData {
    /// An empty frame for a view whose image is `rows` pixels tall.
    pub fn with_rows(rows: u32) -> FrameData {
        FrameData { image_rows: rows, ..FrameData::default() }
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

/// The first `n` values of `buf`, for the caller to write every one of: a frame's palettes
/// and instances written over the last frame's, so that only growth is filled (cleared and
/// refilled each frame, zeroing scene A's 15 MB of palettes cost about 0.4 ms of its 4 ms
/// of frame building). The caller truncates the buffer to `n` after.
pub(super) fn overwrite<T: Copy + Default>(buf: &mut Vec<T>, n: usize) -> &mut [T] {
    if buf.len() < n {
        buf.resize(n, T::default());
    }
    &mut buf[..n]
}
