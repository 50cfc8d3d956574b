//! A scene's wind: the field over the whole forest and the near tile at the tree spacing
//! ([`wind_field`], [`SceneWind`]), and how the driver reads them (`wind_near`).

use sylva_core::rng::mix64;
use sylva_wind::{FieldView, Grid, NearField, SynthParams, WindField, WindParams};

use crate::canopy::Stand;
use crate::driver::ForestError;
use crate::scene::{SceneSpec, WindSource};

/// Wind at world point `p` and time `t` from the full-resolution `view`, blended with the
/// `near` field by the horizontal distance from `centre`; and whether the near field
/// counted.
pub(crate) fn wind_near(
    view: FieldView<'_>,
    near: Option<&NearField>,
    centre: [f32; 3],
    p: [f64; 3],
    t: f64,
) -> ([f64; 3], bool) {
    let Some(near) = near else { return (view.sample(p, t), false) };
    let d = (p[0] - centre[0] as f64).hypot(p[1] - centre[1] as f64);
    match near.weight(d) {
        w if w <= 0.0 => (view.sample(p, t), false),
        // Wholly within the tile: the coarse field is not read.
        w if w >= 1.0 => (near.sample(p, t), true),
        w => (near.blend(view.sample(p, t), p, t, w), true),
    }
}

/// A field velocity `w` scaled by `gain` and turned by `turn` rad (the live controls).
pub(crate) fn steer(w: [f64; 3], gain: f32, turn: f32) -> [f32; 3] {
    let (s, c) = turn.sin_cos();
    [
        gain * (c * w[0] as f32 - s * w[1] as f32),
        gain * (s * w[0] as f32 + c * w[1] as f32),
        gain * w[2] as f32,
    ]
}

/// Wind grid points per side: enough to resolve twice the tree spacing across the forest,
/// within 32 … [`MAX_WIND_POINTS`].
pub fn wind_points(spec: &SceneSpec, radius: f32) -> usize {
    let half = (radius as f64 + 30.0) * std::f64::consts::SQRT_2;
    ((2.0 * half / (2.0 * spec.spacing as f64)).ceil() as usize + 1).clamp(32, MAX_WIND_POINTS)
}

/// Cap on wind grid points per side (96² points × 2 heights × 3 components × 512 frames of
/// f32: 113 MB).
pub const MAX_WIND_POINTS: usize = 96;

/// Radius around the camera within which the near field is read, m (its outer
/// [`NEAR_BAND`] fading out), when the tile holds it.
pub const NEAR_REACH: f64 = 160.0;

/// Width of the near field's fade, as a fraction of its reach.
pub const NEAR_BAND: f64 = 0.25;

/// Cap on the near tile's points per side (64² points × 2 heights × 3 components × 512
/// frames of f32: 50 MB); with trees closer than 5 m the reach shrinks to half the tile.
pub const MAX_NEAR_POINTS: usize = 64;

/// A scene's wind: the field over the whole forest, and where that field is coarser than
/// the tree spacing, a fine tile read near the camera ([`NearField`]).
#[derive(Debug, Clone)]
pub struct SceneWind {
    /// The field covering the forest.
    pub field: WindField,
    /// The near field, at the tree spacing; `None` where the field resolves the trees
    /// already, and for steady winds and wind files.
    pub near: Option<NearField>,
}

/// The scene's wind ([`WindSource`]): a preset (with the scene's U* when set) in the
/// scene's direction over a grid covering the forest ([`wind_points`] a side, two heights),
/// looping every 51.2 s; a steady uniform wind in the scene's direction; or a wind file,
/// which tiles the forest periodically and keeps its own direction.
///
/// For a preset whose grid is coarser than the tree spacing (every scene but the smallest:
/// the grid resolves twice the spacing, and has at most [`MAX_WIND_POINTS`] a side), a
/// second realisation of the same model at the tree spacing is made as well, a tile of up to
/// [`MAX_NEAR_POINTS`] a side (seed derived from the scene's) read within [`NEAR_REACH`] of
/// the camera: near trees feel gusts of their own size rather than a bilinear mix of records
/// tens of metres apart (in scene D, about three quarters of the model's variance against
/// under half; in the middle of a 60 m cell the mix keeps a fifth of it).
pub fn wind_field(spec: &SceneSpec, radius: f32) -> Result<SceneWind, ForestError> {
    wind_field_over(spec, radius, None)
}

/// [`wind_field`] over a forest whose canopy is `stand`: a preset's profile becomes the
/// stand's ([`Stand::profile`]) unless the scene sets `wind_profile` (what
/// [`crate::Forest::new`] synthesises with the canopy wind on; [`crate::Forest::stand`]).
pub fn wind_field_over(
    spec: &SceneSpec,
    radius: f32,
    stand: Option<Stand>,
) -> Result<SceneWind, ForestError> {
    let field = coarse_wind_field(spec, radius, stand)?;
    let spacing = spec.spacing as f64;
    let xs = &field.grid.xs;
    let coarse = if xs.len() > 1 { xs[1] - xs[0] } else { f64::INFINITY };
    let preset = matches!(spec.wind_source(), Ok(WindSource::Preset(_)));
    if !preset || coarse <= 1.01 * spacing {
        return Ok(SceneWind { field, near: None });
    }
    let points = ((2.0 * NEAR_REACH / spacing).ceil() as usize + 1).clamp(16, MAX_NEAR_POINTS);
    let reach = NEAR_REACH.min(0.5 * spacing * (points - 1) as f64);
    let synth = SynthParams { seed: mix64(spec.seed ^ NEAR_SEED), ..Default::default() };
    let g = &field.grid;
    let near = NearField::generate(
        &field.params,
        points,
        spacing,
        &g.zs,
        g.frames,
        g.dt,
        synth,
        reach,
        NEAR_BAND * reach,
    )
    .map_err(|e| ForestError::Wind(format!("near field: {e}")))?;
    Ok(SceneWind { field, near: Some(near) })
}

/// Salt of the near field's seed (ASCII "near").
const NEAR_SEED: u64 = 0x6e65_6172;

/// The field over the whole forest (see [`wind_field`]).
fn coarse_wind_field(
    spec: &SceneSpec,
    radius: f32,
    stand: Option<Stand>,
) -> Result<WindField, ForestError> {
    let source = spec.wind_source().map_err(|e| ForestError::Wind(e.to_string()))?;
    let preset = match source {
        WindSource::Preset(p) => p,
        WindSource::Steady(speed) => {
            // Two points a side, two heights, four frames: every sample is the same vector,
            // along the field's own x, which sampling turns to the scene's direction.
            let grid = Grid::regular(2, 2, 1000.0, &[8.0, 22.0], 4, 0.1);
            let per = grid.points();
            let mut data = vec![0.0f32; per * 3 * grid.frames];
            for frame in data.chunks_mut(3 * per) {
                frame[..per].fill(speed as f32);
            }
            let params = WindParams {
                direction_deg: spec.wind_direction_deg as f64,
                ..WindParams::default()
            };
            return Ok(WindField {
                grid,
                params,
                synth: SynthParams::default(),
                data,
                coherence_error: 0.0,
            });
        }
        WindSource::File(path) => {
            return sylva_wind::io::read_field(&path)
                .map_err(|e| ForestError::Wind(format!("{}: {e}", path.display())));
        }
    };
    let mut params =
        WindParams { direction_deg: spec.wind_direction_deg as f64, ..preset.params() };
    if let Some(u) = spec.u_star {
        params.u_star = u;
    }
    if let Some(a) = spec.wind_advection {
        params.advection = a;
    }
    if let Some(p) = spec.wind_profile {
        params.profile = p;
    } else if let Some(stand) = stand {
        params.profile = stand.profile();
    }
    params.convection_speed = spec.wind_convection_speed.or_else(|| canopy_convection(&params));
    let half = (radius as f64 + 30.0) * std::f64::consts::SQRT_2;
    let n = wind_points(spec, radius);
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

/// A canopy's large eddies travel at about this many times the mean speed at its top
/// (Shaw, Brunet, Finnigan & Raupach 1995; Finnigan 2000 gives 1.5–2).
pub const CANOPY_CONVECTION: f64 = 1.8;

/// The convection speed of a forest's gusts: [`CANOPY_CONVECTION`] times Ū at the canopy
/// top h, the canopy profile's own h or, with a log law, h = 1.5 d (the displacement height
/// is about two thirds of the canopy's, Thom 1971; the presets' d = 10 m stands for a 15 m
/// forest). `None` for a power law or no displacement: the reference speed then.
pub fn canopy_convection(params: &WindParams) -> Option<f64> {
    match params.profile {
        sylva_wind::Profile::Log { d, .. } if d > 0.0 => {
            Some(CANOPY_CONVECTION * params.mean_speed(1.5 * d))
        }
        sylva_wind::Profile::Canopy { h, .. } => Some(CANOPY_CONVECTION * params.mean_speed(h)),
        _ => None,
    }
}
