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
//! from the sun ([`ShadowSweep`](crate::camera::ShadowSweep)) may reach the cone, and it may cast into the shadow
//! map's far cascade ([`ShadowBox`](crate::camera::ShadowBox); outside it nothing takes a shadow). They are drawn
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

use sylva_sway::{CrownLean, LeafParams, LeafSway, SwayBatch};
use sylva_tree::LodOrder;
use sylva_tree::mesh::TreeModel;
use sylva_wind::{NearField, OwnedPyramid};
use thiserror::Error;

use crate::cells::Cells;
use crate::lanes;
use crate::scene::{CameraKey, Placement, SceneSpec, Terrain};
pub use crate::wind::{
    MAX_NEAR_POINTS, MAX_WIND_POINTS, NEAR_BAND, NEAR_REACH, SceneWind, wind_field,
    wind_field_over, wind_points,
};

mod build;
mod frame;
mod frame_data;
mod lod;
mod palettes;
mod query;
mod regroup;
mod shelter;
mod step;
#[cfg(test)]
mod tests;

use build::Crowns;
pub use frame_data::{Bucket, FrameData, FrameStats, Instance};
pub use lod::{
    ANIMATION_FRACTION, DEFAULT_FAR_LEVEL, DEFAULT_IMAGE_ROWS, DEFAULT_LOD_FRACTION,
    FAR_WIND_LEVEL, LodSettings, SHADOW_COARSER, SIM_MARGIN, THIN_BAND, THIN_MIN_KEEP,
    blend_levels, error_coordinate, hysteresis, level_thresholds, lod_cap, lod_coordinate,
    next_lod_state, past_cap_error_fraction, past_cap_fraction, shadow_level, thinning,
};
use regroup::Switch;
pub use regroup::{REGROUP_FADE, REGROUP_TRAVEL};

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
    /// A camera path that the scene does not have.
    #[error("camera path {0}")]
    Path(String),
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
/// `max_state_mb`. (On a 32-bit target, such as WebAssembly, the whole address space.)
pub const MAX_STATE_BYTES: usize =
    if usize::MAX as u64 > 6_000_000_000 { 6_000_000_000u64 as usize } else { usize::MAX };

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
    /// Per mesh level, its geometric error against full detail as a share of the tree's
    /// height (the geometry LOD's error budget reads it).
    pub level_error: Vec<f32>,
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
    /// What of its tree surely stops the eye (occlusion culling), and its bounds: measured
    /// the first time occlusion culling asks for it ([`SpeciesRuntime::occluder`]).
    occluder: std::sync::OnceLock<crate::occlusion::Occluder>,
    /// Simulated instances that read the coarse wind in the last step.
    coarse_wind: usize,
    /// Simulated instances that read the near field in the last step.
    near_wind: usize,
    /// The field's mean speed at the species' sample height, m/s, with the canopy wind (the
    /// mean its gusts are taken about); 0 without.
    mean_speed: f32,
}

impl SpeciesRuntime {
    /// What of its tree surely stops the eye, for occlusion culling, and its bounds: its
    /// full detail's bole and crown core (`Occluder::of`), measured on the first call (a
    /// few tenths of a second a species; forests that never cull do not pay it).
    pub fn occluder(&self) -> &crate::occlusion::Occluder {
        self.occluder.get_or_init(|| crate::occlusion::Occluder::of(&self.model))
    }

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
    /// [`Instance::tilt`]): half-precision bits, as every instance of the group takes them.
    lean: [u16; 2],
    tilt: [u16; 2],
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
    /// The cell hierarchy the trees are ordered by (`crate::cells`).
    cells: Cells,
    /// Whether a leaf wholly in view and far has its thinned-out trees decided at once
    /// (always, but in the test that compares it with deciding tree by tree).
    leaf_shortcut: bool,
    /// The wind field and its mip pyramid (the wind-field LOD).
    wind: OwnedPyramid,
    /// The fine tile read near the camera, where the field is coarser than the trees.
    near: Option<NearField>,
    leaf_params: LeafParams,
    /// Radius of the forest (trunks), m.
    pub radius: f32,
    /// Height of the tallest tree above the ground, m.
    canopy: f32,
    /// The keys of the camera path the forest follows (`spec.path`), made once.
    path: Vec<CameraKey>,
    time: f64,
    gain: f32,
    turn: f32,
    last_sim_ms: f64,
    lod: LodSettings,
    lane_groups: usize,
    /// Per lane (lane group · 16 + lane, all species in a row): joints to simulate for its
    /// simulation, as the last frame asked (animation LOD).
    want: Vec<u32>,
    /// Per lane (as `want`): joints the last frame drew of its simulation.
    shown: Vec<u32>,
    /// Per tree: the instance group it is fading out of, if it changed group lately.
    switches: Vec<Switch>,
    /// Where the last frame's camera was.
    eye: Option<[f32; 3]>,
    /// Where the camera was, and when, the last time groups were formed.
    grouped: ([f32; 3], f64),
    /// Seconds a tree that changed group cross-fades (0: it switches at once).
    regroup_fade: f32,
    /// The canopy wind: the stand and each point's shelter (`None` with it off).
    canopy_wind: Option<(crate::canopy::Stand, crate::canopy::Shelter)>,
    /// The canopy's mixing-layer eddies (with the canopy wind).
    eddies: Option<crate::canopy::Eddies>,
}

/// The keys of the camera path `spec.path` of a forest on `terrain` whose trees stand
/// within `radius` of the centre, the tallest `canopy` m high (see [`Forest::path_keys`]).
fn path_keys(spec: &SceneSpec, terrain: &Terrain, radius: f32, canopy: f32) -> Vec<CameraKey> {
    use crate::scene::{FLY_IN, LOW_FLIGHT, WALK, default_camera_path, low_flight_path, walk_path};
    match spec.path.as_str() {
        FLY_IN if spec.camera_path.is_empty() => default_camera_path(spec, radius),
        FLY_IN => spec.camera_path.clone(),
        name => match spec.paths.get(name) {
            Some(keys) => keys.clone(),
            None if name == WALK => walk_path(terrain),
            None if name == LOW_FLIGHT => low_flight_path(terrain, radius, canopy),
            None => Vec::new(),
        },
    }
}
