//! What a synthesis will cost, estimated before any work: the memory a field needs, the dense
//! method's time and memory, and the checks that refuse a configuration with the figure.

use super::*;
use crate::error::ParamError;
use crate::params::Profile;

/// What the dense Cholesky method will cost on a grid, estimated before it starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CholeskyEstimate {
    /// Peak working memory beside the output, bytes: the n × n matrix and the coefficients.
    pub bytes: f64,
    /// Floating-point operations of the factorisations, all lines and components.
    pub flops: f64,
    /// Time at [`CHOLESKY_FLOPS_PER_S`], s.
    pub seconds: f64,
}

/// Throughput the dense factorisation reaches on one core (it runs on one), flop/s; measured
/// on a 2-core AMD EPYC (800 points, 256 frames: 6.6e10 flops in 57 s, 1.2e9) and rounded down.
pub const CHOLESKY_FLOPS_PER_S: f64 = 1.0e9;

impl std::fmt::Display for CholeskyEstimate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:.0} MB of memory and about {:.0} s", self.bytes / 1e6, self.seconds.ceil())
    }
}

/// Estimate the dense Cholesky method's memory and time on `grid`: per component and line,
/// n³/3 flops for the factor and n² for the matrix; memory n² f64 plus n (M/2 + 1) complex.
pub fn cholesky_estimate(grid: &Grid) -> CholeskyEstimate {
    let n = grid.points() as f64;
    let lines = (grid.frames / 2).saturating_sub(1) as f64;
    let flops = 3.0 * lines * (n * n * n / 3.0 + 4.0 * n * n);
    let bytes = 8.0 * n * n + 16.0 * n * (grid.frames / 2 + 1) as f64;
    CholeskyEstimate { bytes, flops, seconds: flops / CHOLESKY_FLOPS_PER_S }
}

/// Peak memory of [`crate::WindField::generate`] on `grid` with `method`, bytes: the f32
/// output (3 components × points × frames) plus the method's working set — a few columns
/// for the separable method, every point's coefficients for the embedding (in f32: 8 bytes
/// × points × (M/2 + 1)) and the dense Cholesky (in f64: 16 bytes), plus the latter's n × n
/// matrix.
pub fn memory_estimate(grid: &Grid, method: Method) -> f64 {
    let n = grid.points() as f64;
    let nc = (grid.frames / 2 + 1) as f64;
    let output = 12.0 * n * grid.frames as f64;
    let column = (grid.nz() * grid.ny()) as f64;
    let working = match method {
        Method::Separable => {
            32.0 * column * nc + 4.0 * EMIT_COLUMNS as f64 * column * grid.frames as f64
        }
        Method::Embedding => 8.0 * n * nc,
        Method::Cholesky => cholesky_estimate(grid).bytes,
    };
    output + working
}

/// Check that the parameters, grid and method can be synthesised together.
pub fn check_config(params: &WindParams, grid: &Grid, synth: SynthParams) -> Result<(), WindError> {
    params.validate()?;
    grid.validate()?;
    check_profile(params, grid)?;
    if synth.method == Method::Separable
        && params.coherence_speed == CoherenceSpeed::PairMean
        && grid.nz() > 1
    {
        return Err(WindError::Unsupported(
            "pair-mean coherence speed on several heights needs --method embedding (or \
             cholesky); the separable method uses one reference speed"
                .into(),
        ));
    }
    if synth.method == Method::Embedding
        && (Grid::regular_spacing(&grid.xs).is_none() || Grid::regular_spacing(&grid.ys).is_none())
    {
        return Err(WindError::Unsupported(
            "the embedding method needs regularly spaced x and y; use --method cholesky on \
             small uneven grids"
                .into(),
        ));
    }
    if synth.method == Method::Cholesky && grid.points() > CHOLESKY_MAX_POINTS {
        return Err(WindError::Unsupported(format!(
            "the Cholesky method is limited to {CHOLESKY_MAX_POINTS} points; this grid has {} \
             (estimated {})",
            grid.points(),
            cholesky_estimate(grid)
        )));
    }
    Ok(())
}

/// Peak working memory of [`synthesize_streaming`], bytes: the staged block of
/// [`EMIT_COLUMNS`] columns of f32 records, two coefficient columns and the per-line factors
/// — independent of nx, so of the output's size.
pub fn streaming_memory_estimate(grid: &Grid) -> f64 {
    let column = (grid.nz() * grid.ny()) as f64;
    let nc = (grid.frames / 2 + 1) as f64;
    let cols = EMIT_COLUMNS.min(grid.nx()) as f64;
    4.0 * cols * column * grid.frames as f64 + 2.0 * 16.0 * column * nc + 64.0 * column * nc
}

/// The mean profile must give every height of the grid a finite mean speed of at most
/// [`crate::field::MAX_MEAN_SPEED`]: parameters each in range can still combine into an
/// infinite or absurd profile (a power law with `z_ref` = 1e-300), which would be
/// synthesised into a field of infinities. The error names the parameter that makes it so.
fn check_profile(params: &WindParams, grid: &Grid) -> Result<(), WindError> {
    const EXPECTED: &str =
        "a profile whose mean speed is finite and at most 100 m/s at every height of the grid";
    for &z in &grid.zs {
        let u = params.mean_speed(z);
        if u.is_finite() && u.abs() <= crate::field::MAX_MEAN_SPEED {
            continue;
        }
        let (field, value) = match params.profile {
            Profile::Power { u_ref, z_ref, alpha } => {
                let ratio = (z.max(1e-3) / z_ref).powf(alpha);
                if ratio.is_finite() && ratio <= 1e3 {
                    ("profile.u_ref", u_ref)
                } else {
                    ("profile.z_ref", z_ref)
                }
            }
            Profile::Log { z0, d } | Profile::Canopy { z0, d, .. } => {
                let ln = ((z - d).max(2.0 * z0) / z0).ln();
                if ln.is_finite() { ("u_star", params.u_star) } else { ("profile.z0", z0) }
            }
        };
        return Err(ParamError::new(field, value, EXPECTED).into());
    }
    Ok(())
}
