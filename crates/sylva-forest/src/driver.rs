//! The per-frame driver: time step → wind sample per simulated tree → sway step →
//! palettes → [`FrameData`].
//!
//! **Instance groups.** Each species runs one [`SwayBatch`]; a scene's
//! `sim_joint_budget` (joint updates per frame) is shared among species in proportion to
//! their tree counts, and a species whose trees do not all fit shares simulations: its
//! trees, in Morton order of position (so neighbours together), are cut into as many runs
//! as fit, and each run is one simulated instance, driven by the wind at the run's centre.
//! Trees that share a simulation share its yaw, so the wind bends them all downwind.
//!
//! **Geometry LOD.** A tree's level comes from the fraction `h` of the image height its
//! crown covers: level 0 while `h ≥ h₀`, then one level coarser per factor 3 smaller
//! (`⌈log₃(h₀ / h)⌉`), down to the chain's last; `h₀` is [`Forest::set_lod_fraction`]
//! (default [`DEFAULT_LOD_FRACTION`]: full detail only for a tree as tall as the image). Trees outside the view cone are culled.

use std::time::Instant;

use bytemuck::{Pod, Zeroable};
use rayon::prelude::*;
use sylva_sway::{LANES, LeafParams, LeafSway, SwayBatch, SwayParams, SwaySpecies};

use sylva_tree::Species;
use sylva_tree::mesh::{LOD_LEVELS, TreeModel};
use sylva_wind::{Grid, Preset, SynthParams, WindField, WindParams};
use thiserror::Error;

use crate::camera::Camera;
use crate::scene::{Placement, SceneSpec, Terrain, default_camera, layout};

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
}

/// One tree drawn this frame, as the vertex shaders read it (36 bytes).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct Instance {
    /// Trunk base, world m.
    pub position: [f32; 3],
    /// Rotation about z, rad.
    pub yaw: f32,
    /// Uniform scale.
    pub scale: f32,
    /// Index in [`FrameData::palettes`] of element 0 of the instance's joint-0 palette;
    /// element e (row-major 3×4) of joint j is at `palette + (12 j + e) · palette_stride`.
    pub palette: u32,
    /// Leaf flutter phase, rad.
    pub leaf_phase: f32,
    /// Leaf flutter amplitude, rad.
    pub leaf_amplitude: f32,
    /// Distance between consecutive palette elements: the simulated instances whose
    /// palettes are interleaved with this one's (its lane group, up to 16).
    pub palette_stride: u32,
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
}

/// Figures of one frame.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameStats {
    /// Trees in the scene.
    pub trees: usize,
    /// Trees drawn (not culled).
    pub drawn: usize,
    /// Triangles drawn (branches and leaf billboards).
    pub triangles: usize,
    /// Simulated instances (instance groups).
    pub simulated: usize,
    /// Joints stepped by the last simulation step.
    pub joints: usize,
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
    /// Buckets in (species, LOD) order.
    pub buckets: Vec<Bucket>,
    /// Joint palettes of every simulated instance (3×4 row-major, rest → animated, tree
    /// space), as the simulation computes them: per species, per lane group of up to 16
    /// simulated instances, per joint, per matrix element, the group's values side by side
    /// (see [`Instance::palette`]). No padding.
    pub palettes: Vec<f32>,
    /// Mean wind at the scene centre, 20 m up, world m/s.
    pub wind: [f32; 3],
    /// Figures.
    pub stats: FrameStats,
    keys: Vec<(u32, u32)>,
}

/// One species of a forest: its model, simulation and instance groups.
#[derive(Debug)]
pub struct SpeciesRuntime {
    /// Name as given in the scene.
    pub name: String,
    /// Geometry, LOD chain and textures.
    pub model: TreeModel,
    batch: SwayBatch,
    /// Per group: wind sample point (world), yaw, leaf flutter.
    groups: Vec<Group>,
    winds: Vec<[f32; 3]>,
    /// Offset of this species' palettes in [`FrameData::palettes`].
    palette_base: usize,
}

#[derive(Debug, Clone, Copy)]
struct Group {
    sample: [f64; 3],
    yaw: f32,
    leaf: LeafSway,
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
    wind: WindField,
    leaf_params: LeafParams,
    /// Radius of the forest (trunks), m.
    pub radius: f32,
    time: f64,
    gain: f32,
    turn: f32,
    last_sim_ms: f64,
    lod_fraction: f32,
}

/// Default image-height fraction above which a tree is drawn at full detail.
pub const DEFAULT_LOD_FRACTION: f32 = 1.0;

fn morton(x: f32, y: f32, side: f32) -> u64 {
    let q = |v: f32| (((v / side + 0.5).clamp(0.0, 1.0)) * 65535.0) as u64;
    let spread = |mut v: u64| {
        v &= 0xffff;
        v = (v | (v << 8)) & 0x00ff_00ff;
        v = (v | (v << 4)) & 0x0f0f_0f0f;
        v = (v | (v << 2)) & 0x3333_3333;
        (v | (v << 1)) & 0x5555_5555
    };
    spread(q(x)) | (spread(q(y)) << 1)
}

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
        let mut species = Vec::with_capacity(models.len());
        let mut trees: Vec<(Placement, u32)> = placements.iter().map(|&p| (p, 0)).collect();
        let total = trees.len().max(1);
        let side = spec.side();
        let mut palette_base = 0;
        for (si, m) in models.into_iter().enumerate() {
            let model = m?;
            let joints = model.tree.skeleton.len();
            let mut members: Vec<usize> =
                (0..trees.len()).filter(|&t| trees[t].0.species == si as u32).collect();
            members.sort_by_key(|&t| {
                (morton(trees[t].0.position[0], trees[t].0.position[1], side), t)
            });
            let share = spec.sim_joint_budget as f64 * members.len() as f64 / total as f64;
            let n_groups = ((share / joints as f64) as usize).clamp(1, members.len().max(1));
            let height = model.tree.stats.height;
            let mut groups = Vec::with_capacity(n_groups);
            for g in 0..n_groups {
                let run =
                    &members[g * members.len() / n_groups..(g + 1) * members.len() / n_groups];
                let yaw = run.first().map(|&t| trees[t].0.yaw).unwrap_or(0.0);
                let mut c = [0.0f64; 3];
                for &t in run {
                    trees[t].1 = g as u32;
                    trees[t].0.yaw = yaw;
                    let p = trees[t].0;
                    c[0] += p.position[0] as f64;
                    c[1] += p.position[1] as f64;
                    c[2] += (p.position[2] + 0.7 * height * p.scale) as f64;
                }
                let k = run.len().max(1) as f64;
                groups.push(Group {
                    sample: [c[0] / k, c[1] / k, c[2] / k],
                    yaw,
                    leaf: LeafSway::default(),
                });
            }
            let sway =
                SwaySpecies::new(&model.tree.skeleton, SwayParams::default()).map_err(|e| {
                    ForestError::Species {
                        name: spec.species[si].name.clone(),
                        message: e.to_string(),
                    }
                })?;
            let batch = SwayBatch::new(sway, n_groups);
            species.push(SpeciesRuntime {
                name: spec.species[si].name.clone(),
                model,
                batch,
                winds: vec![[0.0; 3]; n_groups],
                groups,
                palette_base,
            });
            palette_base += n_groups * joints * 12;
        }
        let wind = wind_field(spec, radius)?;
        Ok(Forest {
            spec: spec.clone(),
            terrain,
            species,
            trees,
            wind,
            leaf_params: LeafParams::default(),
            radius,
            time: 0.0,
            gain: 1.0,
            turn: 0.0,
            last_sim_ms: 0.0,
            lod_fraction: DEFAULT_LOD_FRACTION,
        })
    }

    /// The scene's default viewpoint.
    pub fn default_camera(&self) -> Camera {
        default_camera(&self.spec, self.radius)
    }

    /// Geometry-LOD threshold: the image-height fraction `h₀` above which a tree is drawn at
    /// full detail (larger: coarser everywhere). Clamped to 0.01 … 100.
    pub fn set_lod_fraction(&mut self, h0: f32) {
        self.lod_fraction =
            if h0.is_finite() { h0.clamp(0.01, 100.0) } else { DEFAULT_LOD_FRACTION };
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

    /// Number of trees.
    pub fn trees(&self) -> usize {
        self.trees.len()
    }

    fn wind_at(&self, p: [f64; 3], t: f64) -> [f32; 3] {
        sample_wind(&self.wind, self.gain, self.turn, p, t)
    }

    /// Advance the simulation by `dt` seconds (> 0; others are ignored).
    pub fn step(&mut self, dt: f32) {
        if !(dt > 0.0 && dt.is_finite()) {
            return;
        }
        let start = Instant::now();
        self.time += dt as f64;
        let t = self.time;
        let leaf = self.leaf_params;
        let (field, gain, turn) = (&self.wind, self.gain, self.turn);
        // Species in parallel; each samples the shared, read-only field for its groups.
        self.species.par_iter_mut().for_each(|s| {
            for (g, out) in s.groups.iter_mut().zip(&mut s.winds) {
                let w = sample_wind(field, gain, turn, g.sample, t);
                let (sn, cs) = g.yaw.sin_cos();
                *out = [cs * w[0] + sn * w[1], -sn * w[0] + cs * w[1], w[2]];
                let speed = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
                leaf.step(&mut g.leaf, speed, dt);
            }
            s.batch.step(dt, &s.winds);
        });
        self.last_sim_ms = start.elapsed().as_secs_f64() * 1e3;
    }

    /// Fill `out` for `camera` and an image of `aspect` = width / height. Allocates only
    /// while `out`'s arrays grow.
    pub fn frame(&self, camera: &Camera, aspect: f32, out: &mut FrameData) {
        out.time = self.time;
        out.keys.clear();
        let mut stats = FrameStats { trees: self.trees.len(), ..FrameStats::default() };
        for (i, (p, _)) in self.trees.iter().enumerate() {
            let sp = &self.species[p.species as usize];
            let h = sp.model.tree.stats.height * p.scale;
            let c = [p.position[0], p.position[1], p.position[2] + 0.5 * h];
            if !camera.may_see(c, 0.75 * h, aspect) {
                continue;
            }
            let frac = camera.screen_fraction(c, h);
            let last = sp.model.lods.len() as u32 - 1;
            let lod = if frac >= self.lod_fraction {
                0
            } else {
                ((self.lod_fraction / frac.max(1e-9)).ln() / 3f32.ln())
                    .ceil()
                    .clamp(0.0, last as f32) as u32
            };
            out.keys.push(((p.species << 8) | lod, i as u32));
        }
        out.keys.sort_unstable();
        out.instances.clear();
        out.buckets.clear();
        for &(key, i) in &out.keys {
            let (p, g) = self.trees[i as usize];
            let sp = &self.species[p.species as usize];
            let group = &sp.groups[g as usize];
            let (species, lod) = (key >> 8, key & 0xff);
            match out.buckets.last_mut() {
                Some(b) if b.species == species && b.lod == lod => b.count += 1,
                _ => out.buckets.push(Bucket {
                    species,
                    lod,
                    first: out.instances.len() as u32,
                    count: 1,
                }),
            }
            stats.triangles += sp.model.lods[lod as usize].triangles();
            // Lane group of this simulated instance: its first palette and its width.
            let joints = sp.model.tree.skeleton.len();
            let first_lane = g as usize / LANES * LANES;
            let used = (sp.groups.len() - first_lane).min(LANES);
            let block = first_lane * joints * 12;
            out.instances.push(Instance {
                position: p.position,
                yaw: p.yaw,
                scale: p.scale,
                palette: (sp.palette_base + block + g as usize % LANES) as u32,
                leaf_phase: group.leaf.phase,
                leaf_amplitude: group.leaf.amplitude,
                palette_stride: used as u32,
            });
        }
        stats.drawn = out.instances.len();
        out.palettes.clear();
        for s in &self.species {
            // The batch pads its last lane group to 16; copy only the simulated lanes.
            let n = s.batch.species().len();
            for (k, block) in s.batch.lane_palettes().chunks(n).enumerate() {
                let used = (s.groups.len() - k * LANES).min(LANES);
                if used == LANES {
                    out.palettes.extend_from_slice(block.as_flattened().as_flattened());
                } else {
                    for lanes in block.iter().flatten() {
                        out.palettes.extend_from_slice(&lanes[..used]);
                    }
                }
            }
            stats.simulated += s.groups.len();
            stats.joints += s.groups.len() * s.batch.species().len();
        }
        stats.sim_ms = self.last_sim_ms;
        let w = self.wind_at([0.0, 0.0, 20.0], self.time);
        out.wind = w;
        out.stats = stats;
    }
}

/// Wind at world point `p` and time `t`, scaled by `gain` and turned by `turn` rad.
fn sample_wind(field: &WindField, gain: f32, turn: f32, p: [f64; 3], t: f64) -> [f32; 3] {
    let w = field.view().sample(p, t);
    let (s, c) = turn.sin_cos();
    [
        gain * (c * w[0] as f32 - s * w[1] as f32),
        gain * (s * w[0] as f32 + c * w[1] as f32),
        gain * w[2] as f32,
    ]
}

/// The scene's wind field: its preset and direction over a grid covering the forest
/// (about 32 × 32 points, two heights), looping every 51.2 s.
fn wind_field(spec: &SceneSpec, radius: f32) -> Result<WindField, ForestError> {
    let preset = Preset::from_name(&spec.wind)
        .ok_or_else(|| ForestError::Wind(format!("no preset `{}`", spec.wind)))?;
    let params = WindParams { direction_deg: spec.wind_direction_deg as f64, ..preset.params() };
    let half = (radius as f64 + 30.0) * std::f64::consts::SQRT_2;
    let n = 32usize;
    let spacing = 2.0 * half / (n - 1) as f64;
    let mut grid = Grid::regular(n, n, spacing, &[8.0, 22.0], 512, 0.1);
    grid.xs = (0..n).map(|i| -half + spacing * i as f64).collect();
    grid.ys = grid.xs.clone();
    WindField::generate(
        &params,
        &grid,
        SynthParams { seed: spec.seed, ..Default::default() },
        &|_| {},
    )
    .map_err(|e| ForestError::Wind(e.to_string()))
}
