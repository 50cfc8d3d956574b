//! Building a forest: layout, tree models in LOD order, simulations within the memory cap,
//! first instance groups, and the wind field.

use rayon::prelude::*;
use sylva_sway::{CrownLean, LANES, LeafSway, SwayBatch, SwayParams, SwaySpecies};
use sylva_tree::mesh::{LOD_LEVELS, TreeModel};
use sylva_tree::{LodOrder, Species, lod_order};
use sylva_wind::OwnedPyramid;

use super::lod::LodSettings;
use super::regroup::{REGROUP_FADE, Switch, regroup_species};
use super::{Forest, ForestError, Group, SpeciesRuntime};
use crate::camera::Camera;
use crate::cells::Cells;
use crate::groups::{morton, partition};
use crate::lanes;
use crate::scene::{
    CameraKey, Placement, SceneSpec, Terrain, camera_on_path, default_camera, layout,
};
use crate::wind::{SceneWind, wind_field_over};

/// The trees' feet and heights as separate arrays (what culling reads, in the layout that
/// lets [`may_see_trees`] test many trees at a time).
#[derive(Debug, Clone, Default)]
pub(super) struct Crowns {
    pub(super) x: Vec<f32>,
    pub(super) y: Vec<f32>,
    pub(super) z: Vec<f32>,
    pub(super) h: Vec<f32>,
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

impl Forest {
    /// Build the forest of `spec`: layout, tree models, simulations and wind field.
    pub fn new(spec: &SceneSpec) -> Result<Forest, ForestError> {
        Forest::with_species(spec, &[])
    }

    /// [`Forest::new`], with species already read: an entry of `spec.species` whose name is
    /// one of `given`'s is grown from that species instead of being looked up as a preset or
    /// a file (a host without a file system, such as a web page, reads the files itself).
    pub fn with_species(
        spec: &SceneSpec,
        given: &[(String, Species)],
    ) -> Result<Forest, ForestError> {
        let terrain = Terrain::new(spec);
        let placements = layout(spec, &terrain);
        let radius = placements
            .iter()
            .map(|p| (p.position[0].powi(2) + p.position[1].powi(2)).sqrt())
            .fold(0.0, f32::max);
        let models = load_models(spec, given)?;
        let mut species = Vec::with_capacity(models.len());
        let mut trees: Vec<(Placement, u32)> = placements.iter().map(|&p| (p, 0)).collect();
        let total = trees.len().max(1);
        // Each tree's height, m (in layout order).
        let heights: Vec<f32> = placements
            .iter()
            .map(|p| models[p.species as usize].tree.stats.height * p.scale)
            .collect();
        let canopy = heights.iter().copied().fold(0.0, f32::max);
        // Groups are first formed for where the camera starts.
        let path = super::path_keys(spec, &terrain, radius, canopy);
        let eye = start_camera(spec, &path, radius).eye;
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
        // What each species makes of its model alone (its simulations' batch, its lean,
        // its levels' errors), the species in parallel; then, in species order, its trees'
        // groups and lanes.
        let n_groups: Vec<usize> = models
            .iter()
            .enumerate()
            .map(|(si, m)| simulations(members_of(si), m.tree.skeleton.len()))
            .collect();
        let made: Vec<Result<Made, ForestError>> = models
            .into_par_iter()
            .zip(orders.par_iter())
            .zip(n_groups.par_iter())
            .enumerate()
            .map(|(si, ((original, order), &n))| make_species(spec, si, original, order, n))
            .collect();
        for (si, (made, order)) in made.into_iter().zip(orders).enumerate() {
            let n_groups = n_groups[si];
            let first = FirstGroups { side, eye, n_groups };
            let state_cap = allowance(si);
            species
                .push(new_species(spec, si, made?, order, &mut trees, first, lane_base, state_cap));
            lane_base += n_groups.div_ceil(LANES);
        }
        let canopy_wind = super::shelter::canopy_of(spec, &trees, &species);
        let stand = canopy_wind.as_ref().map(|c| c.0);
        let SceneWind { field, near } = wind_field_over(spec, radius, stand)?;
        let wind = OwnedPyramid::new(field);
        // The trees renumbered in the cells' order (tree 0 stays the centre tree). What is
        // made above from the trees in layout order does not depend on their numbers after.
        let (mut cells, order) = Cells::new(&placements, &heights, spec.spacing);
        let mut renamed = vec![0usize; order.len()];
        for (k, &o) in order.iter().enumerate() {
            renamed[o as usize] = k;
        }
        let trees: Vec<(Placement, u32)> = order.iter().map(|&o| trees[o as usize]).collect();
        for s in &mut species {
            // The same trees in the same (Morton) order, renamed.
            s.members.iter_mut().for_each(|t| *t = renamed[*t]);
        }
        let n_trees = trees.len();
        let crowns = Crowns::new(&trees, |s| species[s as usize].model.tree.stats.height);
        cells.order_by_draw(|t| super::lod::thin_draw(t, spec.seed));
        let mut forest = Forest {
            spec: spec.clone(),
            terrain,
            species,
            trees,
            crowns,
            cells,
            leaf_shortcut: true,
            wind,
            near,
            leaf_params: spec.leaves,
            radius,
            canopy,
            path,
            time: 0.0,
            gain: 1.0,
            turn: 0.0,
            last_sim_ms: 0.0,
            lod: LodSettings {
                geometry: spec.lod.geometry,
                animation: spec.lod.animation,
                fraction: spec.lod.fraction,
                far_level: spec.lod.far_level,
                error_budget: spec.lod.error_px,
                occlusion: spec.lod.occlusion,
                thin_px: spec.lod.thin_px,
                ..LodSettings::default()
            },
            lane_groups: lane_base,
            // Before any frame every joint is simulated: a forest stepped and then drawn (or
            // read through `tree_palettes`) shows every joint's motion. A caller that draws
            // builds a frame first, so that the first step already follows the animation LOD
            // (and holds only the state it needs).
            want: vec![u32::MAX; lane_base * LANES],
            shown: vec![u32::MAX; lane_base * LANES],
            switches: vec![Switch::NONE; n_trees],
            eye: None,
            grouped: (eye, 0.0),
            regroup_fade: REGROUP_FADE,
            canopy_wind,
            eddies: None,
        };
        forest.apply_height_factors();
        Ok(forest)
    }
}

/// Where the camera starts: on the fly-in, the scene's `camera_path` at time 0 or its
/// default viewpoint; on any other path, that path at time 0.
fn start_camera(spec: &SceneSpec, path: &[CameraKey], radius: f32) -> Camera {
    let base = default_camera(spec, radius);
    if spec.path != crate::scene::FLY_IN {
        return camera_on_path(path, 0.0, &base);
    }
    if spec.camera_path.is_empty() { base } else { camera_on_path(&spec.camera_path, 0.0, &base) }
}

/// Models, one per species, in parallel (deterministic: each from its own seed).
fn load_models(
    spec: &SceneSpec,
    given: &[(String, Species)],
) -> Result<Vec<TreeModel>, ForestError> {
    let models: Vec<Result<TreeModel, ForestError>> = spec
        .species
        .par_iter()
        .enumerate()
        .map(|(i, s)| {
            let sp = match given.iter().find(|(n, _)| *n == s.name) {
                Some((_, sp)) => sp.clone(),
                None => Species::load(&s.name).map_err(|e| ForestError::Species {
                    name: s.name.clone(),
                    message: e.to_string(),
                })?,
            };
            let seed = s.seed.unwrap_or_else(|| spec.seed.wrapping_add(1000 * i as u64 + 1));
            sp.model(seed, LOD_LEVELS)
                .map_err(|e| ForestError::Species { name: s.name.clone(), message: e.to_string() })
        })
        .collect();
    models.into_iter().collect()
}

/// How a species' first instance groups are formed: the scene's side (for Morton codes),
/// where the camera starts, and how many groups.
struct FirstGroups {
    side: f32,
    eye: [f32; 3],
    n_groups: usize,
}

/// Species `si` of `spec` with what it `made` of its model (in LOD `order`): its trees
/// (Morton order) put in their first instance groups, lanes starting at lane group
/// `lane_base`, and a cap of `state_cap` bytes of animation state.
fn new_species(
    spec: &SceneSpec,
    si: usize,
    made: Made,
    order: LodOrder,
    trees: &mut [(Placement, u32)],
    first: FirstGroups,
    lane_base: usize,
    state_cap: usize,
) -> SpeciesRuntime {
    let Made { model, lean, batch, level_error } = made;
    let FirstGroups { side, eye, n_groups } = first;
    let mut members: Vec<usize> =
        (0..trees.len()).filter(|&t| trees[t].0.species == si as u32).collect();
    members.sort_by_key(|&t| (morton(trees[t].0.position[0], trees[t].0.position[1], side), t));
    let codes: Vec<u64> = members
        .iter()
        .map(|&t| morton(trees[t].0.position[0], trees[t].0.position[1], side))
        .collect();
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
            lean: [0; 2],
            tilt: [0; 2],
        });
    }
    let slots: Vec<u32> = (0..runs.len() as u32).collect();
    regroup_species(trees, &mut groups, &members, &runs, &slots, height, |_, _| {});
    SpeciesRuntime {
        occluder: std::sync::OnceLock::new(),
        name: spec.species[si].name.clone(),
        level_error,
        model,
        batch,
        lean,
        winds: vec![[0.0; 3]; n_groups],
        groups,
        members,
        codes,
        lane_base,
        state_cap,
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
        mean_speed: 0.0,
    }
}

/// What a species makes of its model alone, before its trees are grouped.
struct Made {
    /// The model, its joints in LOD order.
    model: TreeModel,
    lean: CrownLean,
    /// The simulations' batch, `n_groups` of them, with the LOD order's prefixes.
    batch: SwayBatch,
    level_error: Vec<f32>,
}

/// [`Made`] for species `si` of `spec`: `original` reordered by `order`, `n_groups`
/// simulations.
fn make_species(
    spec: &SceneSpec,
    si: usize,
    original: TreeModel,
    order: &LodOrder,
    n_groups: usize,
) -> Result<Made, ForestError> {
    let failed =
        |e: String| ForestError::Species { name: spec.species[si].name.clone(), message: e };
    let model = original.reordered(&order.order).map_err(|e| failed(e.to_string()))?;
    let sway = SwaySpecies::new(
        &model.tree.skeleton,
        spec.sway.apply(SwayParams::for_leaves(model.leaves.needles)),
    )
    .map_err(|e| failed(e.to_string()))?;
    let lean = CrownLean::new(&sway, &model.tree.skeleton);
    let mut batch = SwayBatch::new(sway, n_groups);
    let mut prefixes = order.prefix.clone();
    prefixes.push(order.trunk);
    batch.set_prefixes(&prefixes);
    let level_error = level_errors(&model);
    Ok(Made { model, lean, batch, level_error })
}

/// A species' mesh levels' errors as shares of its tree's height
/// ([`TreeModel::level_errors`](sylva_tree::TreeModel::level_errors)).
fn level_errors(model: &TreeModel) -> Vec<f32> {
    let height = model.tree.stats.height.max(1e-3);
    model.level_errors().iter().map(|v| v / height).collect()
}

/// The crown radius of a species' unscaled tree, m: the distance from the trunk within
/// which 90 % of its full-detail leaf clusters hang, plus half a card.
pub(super) fn crown_radius(model: &TreeModel) -> f32 {
    let clusters = model.lods.first().map(|l| &l.clusters[..]).unwrap_or(&[]);
    let mut d: Vec<f32> = clusters
        .iter()
        .map(|c| (c.center[0] * c.center[0] + c.center[1] * c.center[1]).sqrt())
        .collect();
    d.sort_by(f32::total_cmp);
    let card = clusters.first().map(|c| 0.5 * c.size).unwrap_or(0.0);
    d.get(d.len() * 9 / 10).copied().unwrap_or(0.0) + card
}
