//! Scene descriptions (TOML) and the deterministic forest layout: Poisson-disk spacing, a
//! weighted species mix, random rotation and scale per tree, on gentle terrain.

use std::collections::BTreeMap;
use std::f32::consts::{PI, TAU};

use serde::{Deserialize, Serialize};
use sylva_core::SplitMix64 as Rng;
use sylva_sway::{LeafParams, SwayParams};
use sylva_wind::Preset;
use thiserror::Error;

use crate::camera::Camera;

mod layout;
mod path;

pub use layout::{Placement, Terrain, layout};
pub use path::{
    BUILTIN_PATHS, EYE_HEIGHT, FLIGHT_LOOK_AHEAD, FLIGHT_OVER_CANOPY, FLIGHT_SPEED, FLY_IN,
    LOW_FLIGHT, WALK, WALK_SECONDS, WALK_SPEED, camera_on_path, default_camera,
    default_camera_path, low_flight_path, walk_path,
};

/// A scene file that could not be used.
#[derive(Debug, Error)]
pub enum SceneError {
    /// TOML syntax or a wrong type; the message names the key and line.
    #[error("{file}: {message}")]
    Parse {
        /// File name.
        file: String,
        /// What toml reported (key, line and column).
        message: String,
    },
    /// A value out of its range.
    #[error("{file}: `{field}` = {value} is invalid ({expected})")]
    Value {
        /// File name.
        file: String,
        /// Key.
        field: &'static str,
        /// Value found.
        value: String,
        /// What is allowed.
        expected: &'static str,
    },
    /// No scene of that name.
    #[error("no scene named `{0}` (built in: small, A, B, C, D, E; or give a .toml file)")]
    Unknown(String),
}

/// Where a scene's (or a command's) wind comes from, parsed once from the one text form every
/// command and scene file uses (`--wind`, the scene key `wind`):
/// - a preset, `calm`, `breeze`, `strong` or `storm`: a synthesised turbulent field;
/// - a speed in m/s (0 … 100, e.g. `12`): a steady, uniform wind, the same everywhere and
///   always (for probes and controlled tests);
/// - a wind file, `.swf`, `.npy` (with its sidecar) or `.zarr`: a field made earlier, by
///   Sylva or converted; it tiles the forest periodically and keeps its own direction.
#[derive(Debug, Clone, PartialEq)]
pub enum WindSource {
    /// A named wind condition (its U* and profile, see [`Preset`]).
    Preset(Preset),
    /// A steady uniform wind of this speed, m/s.
    Steady(f64),
    /// A wind field file.
    File(std::path::PathBuf),
}

impl WindSource {
    /// Parse the text form; the error says what is accepted.
    pub fn parse(s: &str) -> Result<WindSource, String> {
        let t = s.trim();
        if let Some(p) = Preset::from_name(t) {
            return Ok(WindSource::Preset(p));
        }
        if let Ok(v) = t.parse::<f64>() {
            return if v.is_finite() && (0.0..=100.0).contains(&v) {
                Ok(WindSource::Steady(v))
            } else {
                Err(format!("`{s}`: a steady wind speed must be finite, 0 … 100 m/s"))
            };
        }
        let lower = t.to_ascii_lowercase();
        if [".swf", ".npy", ".zarr"].iter().any(|e| lower.ends_with(e)) {
            return Ok(WindSource::File(t.into()));
        }
        Err(format!(
            "`{s}`: expected calm, breeze, strong or storm, a steady speed in m/s (0 … 100), \
             or a wind file (.swf, .npy, .zarr)"
        ))
    }
}

impl std::fmt::Display for WindSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            WindSource::Preset(p) => f.write_str(p.name()),
            WindSource::Steady(v) => write!(f, "{v}"),
            WindSource::File(p) => write!(f, "{}", p.display()),
        }
    }
}

impl std::str::FromStr for WindSource {
    type Err = String;
    fn from_str(s: &str) -> Result<WindSource, String> {
        WindSource::parse(s)
    }
}

/// A scene's changes to the sway model (a `[sway]` table): each key set replaces that
/// [`SwayParams`] field for every species; a key left out keeps each species' own value
/// (conifers, for instance, keep their needle drag).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SwayOverrides {
    /// Young's modulus of green wood, Pa.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub youngs_modulus: Option<f32>,
    /// Density of green wood, kg/m³.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wood_density: Option<f32>,
    /// Damping ratio of every joint.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping_ratio: Option<f32>,
    /// Drag coefficient of a branch segment.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wood_drag: Option<f32>,
    /// Drag coefficient of leaves per one-sided leaf area.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub leaf_drag: Option<f32>,
    /// Speed at which leaves have halved their drag, m/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub leaf_reconfiguration_speed: Option<f32>,
    /// Whole-crown drag coefficient at 20 m/s on the silhouette (0: calibration off).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub crown_drag: Option<f32>,
    /// Air density, kg/m³.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub air_density: Option<f32>,
    /// Blend time of the animation LOD, s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub blend_time: Option<f32>,
}

impl SwayOverrides {
    /// `base` with the keys this table sets replaced.
    pub fn apply(&self, base: SwayParams) -> SwayParams {
        SwayParams {
            youngs_modulus: self.youngs_modulus.unwrap_or(base.youngs_modulus),
            wood_density: self.wood_density.unwrap_or(base.wood_density),
            damping_ratio: self.damping_ratio.unwrap_or(base.damping_ratio),
            wood_drag: self.wood_drag.unwrap_or(base.wood_drag),
            leaf_drag: self.leaf_drag.unwrap_or(base.leaf_drag),
            leaf_reconfiguration_speed: self
                .leaf_reconfiguration_speed
                .unwrap_or(base.leaf_reconfiguration_speed),
            crown_drag: self.crown_drag.unwrap_or(base.crown_drag),
            air_density: self.air_density.unwrap_or(base.air_density),
            blend_time: self.blend_time.unwrap_or(base.blend_time),
        }
    }
}

/// One species of the mix.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpeciesShare {
    /// Preset name (see `sylva tree list`) or path of a species file.
    pub name: String,
    /// Relative share of the trees (> 0).
    #[serde(default = "one")]
    pub weight: f32,
    /// The seed the species' tree is grown from: the tree `sylva tree generate --seed N`
    /// and `sylva tree stats --seed N` show (each placed tree then scaled by the scene's
    /// `scale_variation`). Default: the scene's seed + 1 000 × the entry's index + 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
}

fn one() -> f32 {
    1.0
}

/// Viewpoint of a scene.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    /// Eye, world m.
    pub eye: [f32; 3],
    /// Target, world m.
    pub target: [f32; 3],
    /// Vertical field of view, degrees (1 … 150). Default 55.
    #[serde(default = "fov")]
    pub fov_deg: f32,
}

fn fov() -> f32 {
    55.0
}

/// Everything that defines a scene. All fields but `name`, `trees` and `species` have
/// defaults.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    /// Scene name.
    pub name: String,
    /// Seed of the layout, the trees and the wind (0 … 2⁶³ − 1: TOML integers are signed
    /// 64-bit).
    #[serde(default)]
    pub seed: u64,
    /// Number of trees (1 … 1 000 000).
    pub trees: usize,
    /// Poisson-disk minimum distance between trunks, m (1 … 1 000: closer, the trees would
    /// be a pile, not a stand). Default 7.
    #[serde(default = "spacing")]
    pub spacing: f32,
    /// Species mix.
    pub species: Vec<SpeciesShare>,
    /// Relative scale variation per tree: scale = 1 ± this (0 … 0.9). Default 0.15.
    #[serde(default = "scale_v")]
    pub scale_variation: f32,
    /// Terrain: height amplitude, m (0 … 1 000). Default 2.
    #[serde(default = "amp")]
    pub terrain_amplitude: f32,
    /// Terrain: wavelength of the hills, m (1 … 1 000 000). Default 150.
    #[serde(default = "wavelength")]
    pub terrain_wavelength: f32,
    /// What lies around the forest (see [`Surround`]): `"open"` ground to the horizon
    /// (default) or distant `"woodland"` beyond a meadow.
    #[serde(default)]
    pub surround: Surround,
    /// The wind (see [`WindSource`]): a preset (calm, breeze, strong, storm), a steady
    /// speed in m/s, or a wind file (.swf, .npy, .zarr; a relative path is taken from the
    /// scene file's folder). Default breeze.
    #[serde(default = "breeze")]
    pub wind: String,
    /// Friction velocity U*, m/s (0 … 20], replacing the preset's: the turbulence and mean
    /// speed scale with it. Only with a preset.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub u_star: Option<f64>,
    /// Taylor advection of the gusts (`WindParams::advection`), replacing the preset's
    /// (on). Only with a preset.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wind_advection: Option<bool>,
    /// The speed gusts travel at, m/s, (0, 100] (`WindParams::convection_speed`). Default,
    /// with a log-law profile: [`CANOPY_CONVECTION`](crate::wind::CANOPY_CONVECTION) times
    /// Ū at the canopy top the profile stands for (1.5 times its displacement height d),
    /// the speed a canopy's large eddies travel at. Only with a preset.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wind_convection_speed: Option<f64>,
    /// Mean wind profile replacing the preset's (a table: `kind = "log"` with `z0`, `d`, or
    /// `kind = "power"` with `u_ref`, `z_ref`, `alpha`; see `sylva_wind::Profile`). Only
    /// with a preset.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wind_profile: Option<sylva_wind::Profile>,
    /// The canopy's own wind (`sylva_forest::canopy`), default on with a preset or a wind
    /// file: a preset's profile becomes the stand's (log law over it, exponential inside,
    /// from its trees' mean height and leaf area) unless `wind_profile` is set; every joint
    /// feels the mean wind of its own height and gusts of the canopy's size there; trees
    /// near the windward edge a mix with the open ground's wind that loads them as measured
    /// edges are (ForestGALES' edge factor). Off: one wind per tree, sampled at 0.7 of its
    /// height, the same at every joint.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub canopy_wind: Option<bool>,
    /// Direction the wind blows towards, degrees counter-clockwise from +x. Default 20.
    #[serde(default = "wind_dir")]
    pub wind_direction_deg: f32,
    /// Joint updates the simulation may spend per frame, across the forest. Trees of one
    /// species beyond what fits share simulations (instance groups). Default 1 000 000.
    #[serde(default = "budget")]
    pub sim_joint_budget: usize,
    /// Cap on the forest's animation state, MB (1 … 1 000 000; default 6000). A scene whose
    /// simulation would need more even at its coarsest is refused before anything is
    /// allocated: every joint of every simulation without the animation LOD, their trunks
    /// with it. With the animation LOD a lane group stores only the joints it simulates, and
    /// one that would grow past its species' share of the cap stays at a coarser prefix
    /// (`FrameStats::state_capped`). Raise it deliberately for a machine with the memory.
    #[serde(default = "state_mb")]
    pub max_state_mb: usize,
    /// Changes to the sway model for every species (a `[sway]` table; keys as
    /// [`SwayParams`]'s fields).
    #[serde(default)]
    pub sway: SwayOverrides,
    /// Leaf flutter constants (a `[leaves]` table; keys as [`LeafParams`]'s fields; every
    /// key optional).
    #[serde(default)]
    pub leaves: LeafParams,
    /// Viewpoint; default: from the forest's south-west edge, looking across it.
    #[serde(default)]
    pub camera: Option<CameraSpec>,
    /// Sun, sky and fog (a `[lighting]` table; every key optional).
    #[serde(default)]
    pub lighting: Lighting,
    /// The three LODs on or off and the geometry-LOD thresholds (a `[lod]` table).
    #[serde(default)]
    pub lod: LodSpec,
    /// A keyframed camera path (`[[camera_path]]` entries, times increasing): `sylva render`
    /// follows it and `sylva bench table3` runs along it. Without one, `render` stands at
    /// the viewpoint and the benchmark flies in from it ([`default_camera_path`]).
    #[serde(default)]
    pub camera_path: Vec<CameraKey>,
    /// Named camera paths (`[[paths.NAME]]` entries, as `camera_path`'s). `walk` and
    /// `low-flight` replace the generated paths of those names ([`walk_path`],
    /// [`low_flight_path`]); any other name adds a path of the scene's own.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub paths: BTreeMap<String, Vec<CameraKey>>,
    /// The camera path `sylva render --camera-path` and the benchmarks follow: `fly-in`
    /// (`camera_path`, or the default fly-in), `walk` (at eye height through the forest),
    /// `low-flight` (across the canopy), or a name of `paths`. Default `fly-in`.
    #[serde(default = "fly_in", skip_serializing_if = "is_fly_in")]
    pub path: String,
}

/// What lies around a forest, out to the horizon.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Surround {
    /// Open ground (grass and soil) to the horizon: the forest stands alone on a plain.
    #[default]
    Open,
    /// Woodland beyond a meadow around the forest: from [`Surround::woodland_start`] out to
    /// the horizon the ground is shaded as a forest canopy seen from afar (crowns at the
    /// scene's spacing, spheroids lit by the sun that stand up from the ground and hide one
    /// another and the floor between them, the mix's darker species as darker cones,
    /// near crowns in leaf clumps, broken by clearings a few hundred metres across).
    /// The ground's shader draws it, not trees: no sway, no shadows, no trunks, and it
    /// costs no triangles. It is meant for what lies a hundred metres and more beyond the
    /// camera, so the forest does not end as an island; closer, its crowns read as balls
    /// with smooth outlines.
    Woodland,
}

impl Surround {
    /// Distance from the forest's centre where the woodland starts (it thickens over
    /// [`Surround::woodland_ramp`]): past a meadow of three tree spacings.
    pub fn woodland_start(radius: f32, spacing: f32) -> f32 {
        radius + 3.0 * spacing
    }

    /// Width of the woodland's edge, m: six tree spacings.
    pub fn woodland_ramp(spacing: f32) -> f32 {
        6.0 * spacing
    }
}

/// The LOD switches of a scene (paper §4.3; Table 3 switches each off in turn).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LodSpec {
    /// Geometry LOD: mesh levels by projected size, impostors far away, cross-faded.
    /// Off: every tree at full detail. Default on.
    pub geometry: bool,
    /// Animation LOD: each group simulates only the joints its drawn levels use. Default on.
    pub animation: bool,
    /// Wind-field LOD: neighbouring trees share one simulation driven by the wind at their
    /// centre (instance groups, within `sim_joint_budget`). Off: every tree simulated on its
    /// own, each with its own wind sample and yaw. Default on.
    pub wind: bool,
    /// Image-height fraction from which a tree is drawn at full detail. Default 0.2
    /// (`DEFAULT_LOD_FRACTION`).
    pub fraction: f32,
    /// First level drawn as an impostor (1 … 6). Default 1 (`DEFAULT_FAR_LEVEL`): full
    /// detail, then the impostor.
    pub far_level: u32,
    /// Screen-space error budget, pixels (0 … 64). Above 0, each tree is drawn at the
    /// coarsest level whose geometric error against full detail spans at most this many
    /// pixels, and `fraction` is unused. Default 0: levels by `fraction`.
    pub error_px: f32,
    /// Occlusion culling: trees hidden behind nearer trunks and crown cores are not drawn
    /// (they still cast their shadows). Default off: in the built-in scenes it hides few
    /// trees for the time it costs (docs/decisions/0014-occlusion-culling.md).
    pub occlusion: bool,
    /// Thinning of far impostors, pixels (0 … 256): trees drawn as impostors and shorter
    /// in the image than this are thinned out stochastically, the ones kept drawn wider so
    /// the far canopy covers the image as before (`LodSettings::thin_px`). Default 0: off.
    pub thin_px: f32,
}

impl Default for LodSpec {
    fn default() -> LodSpec {
        LodSpec {
            geometry: true,
            animation: true,
            wind: true,
            fraction: crate::driver::DEFAULT_LOD_FRACTION,
            far_level: crate::driver::DEFAULT_FAR_LEVEL,
            error_px: 0.0,
            occlusion: false,
            thin_px: 0.0,
        }
    }
}

/// Check a camera path: finite eyes apart from their targets, times increasing.
fn validate_camera_path(file: &str, name: &str, path: &[CameraKey]) -> Result<(), SceneError> {
    // `camera_path` itself, or a path of `paths` (named in the value).
    let (eye_field, t_field) = if name.is_empty() {
        ("camera_path.eye", "camera_path.t")
    } else {
        ("paths.eye", "paths.t")
    };
    let at =
        |k: usize| if name.is_empty() { format!("key {k}") } else { format!("{name}, key {k}") };
    let bad = |field, value: String, expected| SceneError::Value {
        file: file.to_string(),
        field,
        value,
        expected,
    };
    for (k, key) in path.iter().enumerate() {
        if !key.t.is_finite() || (k > 0 && key.t <= path[k - 1].t) {
            let value = format!("{} ({})", key.t, at(k));
            return Err(bad(t_field, value, "finite, increasing from key to key"));
        }
        let finite = key.eye.iter().chain(&key.target).all(|v| v.is_finite());
        if !finite || key.eye == key.target {
            let value = format!("{:?} ({}, target {:?})", key.eye, at(k), key.target);
            return Err(bad(eye_field, value, "finite, eye and target apart"));
        }
    }
    Ok(())
}

/// A camera path on its own: the `[[camera_path]]` entries of a scene file, which is what
/// `sylva view` records and replays (`--camera-path`), and what a scene file takes as is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraPathFile {
    camera_path: Vec<CameraKey>,
}

/// Read a camera path from TOML text (`[[camera_path]]` entries with `t`, `eye`, `target`);
/// `file` names it in errors.
pub fn camera_path_from_toml(file: &str, text: &str) -> Result<Vec<CameraKey>, SceneError> {
    let f: CameraPathFile = toml::from_str(text)
        .map_err(|e| SceneError::Parse { file: file.to_string(), message: e.to_string() })?;
    validate_camera_path(file, "", &f.camera_path)?;
    Ok(f.camera_path)
}

/// A camera path as TOML text that [`camera_path_from_toml`] and a scene file read.
pub fn camera_path_to_toml(path: &[CameraKey]) -> String {
    let f = CameraPathFile { camera_path: path.to_vec() };
    // Plain numbers and arrays: serialising cannot fail.
    toml::to_string(&f).unwrap_or_default()
}

/// One key of a camera path.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraKey {
    /// Time, s.
    pub t: f32,
    /// Eye, world m.
    pub eye: [f32; 3],
    /// Point looked at, world m.
    pub target: [f32; 3],
}

/// Sun, sky and fog of a scene: what the renderer lights and fogs with. Colours are linear
/// RGB in 0 … 1 (before the sRGB encoding of the output).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Lighting {
    /// Direction towards the sun, world (z up); normalised on use. Default (−0.35, −0.55, 0.75).
    pub sun_direction: [f32; 3],
    /// Sun intensity multiplying `sun_colour`. Default 1.1.
    pub sun_intensity: f32,
    /// Sun colour. Default (1.0, 0.95, 0.85).
    pub sun_colour: [f32; 3],
    /// Ambient light from the sky (surfaces facing up). Default (0.32, 0.38, 0.48).
    pub ambient_sky: [f32; 3],
    /// Ambient light from the ground (surfaces facing down). Default (0.22, 0.2, 0.16).
    pub ambient_ground: [f32; 3],
    /// Sky colour at the zenith. Default (0.08, 0.22, 0.62).
    pub sky_zenith: [f32; 3],
    /// Sky colour at the horizon (the haze the distance fades into). Default (0.5, 0.62, 0.78).
    pub sky_horizon: [f32; 3],
    /// Aerial perspective (exponential fog towards the sky's colour in each direction),
    /// per metre, ≥ 0. Default: scaled to the scene ([`Lighting::fog_for_radius`]), so a
    /// large forest still reads to the horizon.
    pub fog_density: Option<f32>,
    /// The sun casts shadows (a shadow map over the near view). Default true.
    pub shadows: bool,
}

impl Default for Lighting {
    fn default() -> Lighting {
        Lighting {
            sun_direction: [-0.35, -0.55, 0.75],
            sun_intensity: 1.1,
            sun_colour: [1.0, 0.95, 0.85],
            ambient_sky: [0.32, 0.38, 0.48],
            ambient_ground: [0.22, 0.2, 0.16],
            sky_zenith: [0.08, 0.22, 0.62],
            sky_horizon: [0.5, 0.62, 0.78],
            fog_density: None,
            shadows: true,
        }
    }
}

impl Lighting {
    /// The fog density a scene of `radius` m gets by default: 90 % fog at twelve forest
    /// radii, and never nearer than 4 km (a hazy day's visibility; the forest's far edge
    /// stays readable at any scene size).
    pub fn fog_for_radius(radius: f32) -> f32 {
        10f32.ln() / (12.0 * radius).max(4000.0)
    }

    /// The fog density in use for a forest of `radius` m: the scene's, else the default.
    pub fn fog(&self, radius: f32) -> f32 {
        self.fog_density.unwrap_or_else(|| Lighting::fog_for_radius(radius))
    }

    /// The unit direction towards the sun.
    pub fn sun_unit(&self) -> [f32; 3] {
        let [x, y, z] = self.sun_direction;
        let n = (x * x + y * y + z * z).sqrt();
        [x / n, y / n, z / n]
    }
}

fn spacing() -> f32 {
    7.0
}
/// The smallest `spacing`, m: trunks closer than a metre are not a stand of trees but a
/// pile of them (every crown overlapping the next), and a scene of thousands of them
/// drawn in one spot takes minutes a frame.
pub const MIN_SPACING: f32 = 1.0;
/// The largest `spacing`, m: trees a kilometre apart are a scattering, not a forest.
pub const MAX_SPACING: f32 = 1000.0;
/// The largest `terrain_amplitude`, m.
pub const MAX_TERRAIN_AMPLITUDE: f32 = 1000.0;
/// The shortest `terrain_wavelength`, m.
pub const MIN_TERRAIN_WAVELENGTH: f32 = 1.0;
/// The longest `terrain_wavelength`, m.
pub const MAX_TERRAIN_WAVELENGTH: f32 = 1.0e6;
fn scale_v() -> f32 {
    0.15
}
fn amp() -> f32 {
    2.0
}
fn wavelength() -> f32 {
    150.0
}
fn fly_in() -> String {
    FLY_IN.to_string()
}
fn is_fly_in(p: &String) -> bool {
    p == FLY_IN
}
fn breeze() -> String {
    "breeze".into()
}
fn wind_dir() -> f32 {
    20.0
}
fn budget() -> usize {
    1_000_000
}

fn state_mb() -> usize {
    crate::driver::MAX_STATE_BYTES / 1_000_000
}

const SMALL: &str = include_str!("../scenes/small.toml");
const SCENE_A: &str = include_str!("../scenes/A.toml");
const SCENE_B: &str = include_str!("../scenes/B.toml");
const SCENE_C: &str = include_str!("../scenes/C.toml");
const SCENE_D: &str = include_str!("../scenes/D.toml");
const SCENE_E: &str = include_str!("../scenes/E.toml");

/// Built-in scenes: (name, TOML). `A` … `D` are the paper's Table-3 scenes (1 000, 3 000,
/// 10 000 and 50 000 trees of the same species mix); `E` a million of them to the horizon.
pub const SCENES: [(&str, &str); 6] = [
    ("small", SMALL),
    ("A", SCENE_A),
    ("B", SCENE_B),
    ("C", SCENE_C),
    ("D", SCENE_D),
    ("E", SCENE_E),
];

impl SceneSpec {
    /// A built-in scene.
    pub fn builtin(name: &str) -> Result<SceneSpec, SceneError> {
        let (n, text) = SCENES
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(name))
            .ok_or_else(|| SceneError::Unknown(name.to_string()))?;
        SceneSpec::from_toml(n, text)
    }

    /// A built-in scene by name (`small`, `A` … `D`) or a scene file (`.toml`).
    pub fn load(name_or_path: &str) -> Result<SceneSpec, SceneError> {
        if let Ok(spec) = SceneSpec::builtin(name_or_path) {
            return Ok(spec);
        }
        let path = std::path::Path::new(name_or_path);
        if path.exists() || name_or_path.ends_with(".toml") {
            let text = std::fs::read_to_string(path).map_err(|e| SceneError::Parse {
                file: name_or_path.to_string(),
                message: format!("cannot read: {e}"),
            })?;
            let mut spec = SceneSpec::from_toml(name_or_path, &text)?;
            if let Ok(WindSource::File(f)) = WindSource::parse(&spec.wind)
                && f.is_relative()
                && let Some(dir) = path.parent()
            {
                spec.wind = dir.join(f).display().to_string();
            }
            return Ok(spec);
        }
        Err(SceneError::Unknown(name_or_path.to_string()))
    }

    /// Parse and validate a scene file; `file` names it in errors.
    pub fn from_toml(file: &str, text: &str) -> Result<SceneSpec, SceneError> {
        let spec: SceneSpec = toml::from_str(text)
            .map_err(|e| SceneError::Parse { file: file.to_string(), message: e.to_string() })?;
        spec.validate(file)?;
        Ok(spec)
    }

    fn validate(&self, file: &str) -> Result<(), SceneError> {
        let bad = |field, value: String, expected| SceneError::Value {
            file: file.to_string(),
            field,
            value,
            expected,
        };
        if !(1..=1_000_000).contains(&self.trees) {
            return Err(bad("trees", self.trees.to_string(), "1 … 1000000"));
        }
        // A bound above, not only finiteness: the layout's Poisson-disk test squares the
        // spacing in f32, and past about 1e19 m that square is infinite, no second tree
        // fits and the layout grows its square without end.
        if !(self.spacing >= MIN_SPACING && self.spacing <= MAX_SPACING) {
            return Err(bad("spacing", self.spacing.to_string(), "1 … 1000 m"));
        }
        if self.species.is_empty() {
            return Err(bad("species", "[]".into(), "at least one species"));
        }
        if let Some(s) = self.species.iter().find(|s| !(s.weight > 0.0 && s.weight.is_finite())) {
            return Err(bad("species.weight", s.weight.to_string(), "> 0"));
        }
        if !(0.0..=0.9).contains(&self.scale_variation) {
            return Err(bad("scale_variation", self.scale_variation.to_string(), "0 … 0.9"));
        }
        if !(0.0..=MAX_TERRAIN_AMPLITUDE).contains(&self.terrain_amplitude) {
            return Err(bad("terrain_amplitude", self.terrain_amplitude.to_string(), "0 … 1000 m"));
        }
        // Below a metre the hills are finer than a tree's footprint, and a wavelength near
        // zero makes the terrain's wavenumber infinite and its heights NaN.
        if !(MIN_TERRAIN_WAVELENGTH..=MAX_TERRAIN_WAVELENGTH).contains(&self.terrain_wavelength) {
            return Err(bad(
                "terrain_wavelength",
                self.terrain_wavelength.to_string(),
                "1 … 1000000 m",
            ));
        }
        let source = WindSource::parse(&self.wind).map_err(|_| {
            bad(
                "wind",
                self.wind.clone(),
                "calm, breeze, strong or storm, a speed 0 … 100 m/s, or a .swf/.npy/.zarr file",
            )
        })?;
        if let Some(u) = self.u_star {
            if !(u > 0.0 && u <= 20.0) {
                return Err(bad("u_star", u.to_string(), "(0, 20] m/s"));
            }
            if !matches!(source, WindSource::Preset(_)) {
                return Err(bad("u_star", u.to_string(), "set only with a wind preset"));
            }
        }
        if let Some(u) = self.wind_convection_speed {
            if !(u > 0.0 && u <= 100.0) {
                return Err(bad("wind_convection_speed", u.to_string(), "(0, 100] m/s"));
            }
            if !matches!(source, WindSource::Preset(_)) {
                return Err(bad(
                    "wind_convection_speed",
                    u.to_string(),
                    "set only with a wind preset",
                ));
            }
        }
        if let Some(p) = self.wind_profile {
            if !matches!(source, WindSource::Preset(_)) {
                return Err(bad("wind_profile", format!("{p:?}"), "set only with a wind preset"));
            }
            let params = sylva_wind::WindParams { profile: p, ..sylva_wind::WindParams::default() };
            if let Err(e) = params.validate() {
                return Err(bad("wind_profile", e.to_string(), "a valid profile"));
            }
        }
        if !self.wind_direction_deg.is_finite() {
            return Err(bad("wind_direction_deg", self.wind_direction_deg.to_string(), "finite"));
        }
        if self.sim_joint_budget == 0 {
            return Err(bad("sim_joint_budget", "0".into(), "≥ 1"));
        }
        for base in [SwayParams::for_leaves(false), SwayParams::for_leaves(true)] {
            if let Err(e) = self.sway.apply(base).validate() {
                return Err(bad("sway", format!("{} = {}", e.field, e.value), e.expected));
            }
        }
        if let Err(e) = self.leaves.validate() {
            return Err(bad("leaves", format!("{} = {}", e.field, e.value), e.expected));
        }
        if !(1..=1_000_000).contains(&self.max_state_mb) {
            return Err(bad("max_state_mb", self.max_state_mb.to_string(), "1 … 1000000 MB"));
        }
        let l = &self.lighting;
        let colours = [l.sun_colour, l.ambient_sky, l.ambient_ground, l.sky_zenith, l.sky_horizon];
        if colours.iter().flatten().any(|c| !(0.0..=10.0).contains(c)) {
            return Err(bad("lighting", "a colour".into(), "components 0 … 10"));
        }
        let [x, y, z] = l.sun_direction;
        if !(x * x + y * y + z * z > 1e-12 && (x + y + z).is_finite()) {
            return Err(bad(
                "lighting.sun_direction",
                format!("{:?}", l.sun_direction),
                "finite, non-zero",
            ));
        }
        if !(0.0..=100.0).contains(&l.sun_intensity) {
            return Err(bad("lighting.sun_intensity", l.sun_intensity.to_string(), "0 … 100"));
        }
        if let Some(f) = l.fog_density.filter(|f| !(0.0..=1.0).contains(f)) {
            return Err(bad("lighting.fog_density", f.to_string(), "0 … 1 per m"));
        }
        if !(self.lod.fraction > 0.0 && self.lod.fraction.is_finite() && self.lod.fraction <= 100.0)
        {
            return Err(bad("lod.fraction", self.lod.fraction.to_string(), "0 … 100"));
        }
        if !(0.0..=64.0).contains(&self.lod.error_px) {
            return Err(bad("lod.error_px", self.lod.error_px.to_string(), "0 … 64 pixels"));
        }
        if !(0.0..=256.0).contains(&self.lod.thin_px) {
            return Err(bad("lod.thin_px", self.lod.thin_px.to_string(), "0 … 256 pixels"));
        }
        if !(1..=6).contains(&self.lod.far_level) {
            return Err(bad("lod.far_level", self.lod.far_level.to_string(), "1 … 6"));
        }
        validate_camera_path(file, "", &self.camera_path)?;
        for (name, path) in &self.paths {
            validate_camera_path(file, name, path)?;
        }
        if !self.has_path(&self.path) {
            let expected = "fly-in, walk, low-flight or a name of `paths`";
            return Err(bad("path", self.path.clone(), expected));
        }
        if let Some(c) = &self.camera {
            if !(1.0..=150.0).contains(&c.fov_deg) {
                return Err(bad("camera.fov_deg", c.fov_deg.to_string(), "1 … 150"));
            }
            if c.eye == c.target || c.eye.iter().chain(&c.target).any(|v| !v.is_finite()) {
                return Err(bad("camera.eye", format!("{:?}", c.eye), "finite, not the target"));
            }
        }
        Ok(())
    }

    /// Whether the scene has camera path `name`: one of [`BUILTIN_PATHS`] or of its `paths`.
    pub fn has_path(&self, name: &str) -> bool {
        BUILTIN_PATHS.contains(&name) || self.paths.contains_key(name)
    }

    /// Replace the scene's wind (a command's `--wind`); a preset's U* set by the scene goes
    /// with the wind it belonged to.
    pub fn set_wind(&mut self, wind: &WindSource) {
        self.wind = wind.to_string();
        self.u_star = None;
    }

    /// The wind this scene asks for (validated when the scene was read).
    pub fn wind_source(&self) -> Result<WindSource, SceneError> {
        WindSource::parse(&self.wind).map_err(|e| SceneError::Value {
            file: self.name.clone(),
            field: "wind",
            value: self.wind.clone(),
            expected: if e.contains("0 … 100") {
                "0 … 100 m/s"
            } else {
                "a preset, a speed or a wind file"
            },
        })
    }

    /// Side of the square the trees are laid out in, m.
    pub fn side(&self) -> f32 {
        // Poisson-disk sampling packs about one point per 1.5 r²; leave room to choose from.
        self.spacing * (self.trees as f32 * 1.5).sqrt() * 1.2 + self.spacing
    }
}
