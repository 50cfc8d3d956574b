//! Synthesis of the fluctuations by the spectral representation (paper eqs. 6–7,
//! Shinozuka & Deodatis), in two methods that draw the same phases.
//!
//! For each component ε and frequency line ω_j = jΔω (j = 1 … M/2−1) the CPSDM is
//! S(ω_j) = H H^T and the record at point i is
//!   ε_i(t) = Re Σ_j B_ij e^{iω_j t},  B_j = 2 √Δω · H(ω_j) e_j,  e_jk = e^{iφ_jk},
//! computed as one inverse real FFT per point (coefficients X_j = B_j / 2 in the FFT's
//! unnormalised convention, DC and Nyquist zero). The phases φ_jk are uniform, fixed per
//! (component, line j, Cholesky column k) and drawn from a counter-based hash of the seed,
//! so any block of them can be regenerated in any order: results are bit-identical for any
//! thread count and any memory blocking.
//!
//! * [`Method::Cholesky`] — the paper's literal method: the dense CPSDM (eq. 5 coherence times
//!   √(S0_a S0_b)) and its Cholesky factor per line, in f64. O(N n³): a reference for small
//!   grids.
//! * [`Method::Separable`] — exact and fast. With one speed in the coherence denominator,
//!   the coherence matrix on a rectilinear grid is R_z ⊗ R_y ⊗ R_x with R\[a,b\] = e^{−a|p_a − p_b|}
//!   per axis, whose Cholesky factor is L_z ⊗ L_y ⊗ L_x, each an AR(1) recursion
//!   y_0 = e_0, y_i = ρ_i y_{i−1} + √(1−ρ_i²) e_i with ρ_i = e^{−a·gap_i} (√(1−ρ²) evaluated as
//!   √(−expm1(−2a·gap)) for accuracy at low frequency). Height-dependent spectra stay exact since
//!   chol(D C D) = D chol(C). O(n N) + O(n N log N).
//!
//! * [`Method::Embedding`] — exact in the CPSDM for either coherence speed, on regular x–y
//!   grids: circulant embedding across x and y with one dense nz × nz block per horizontal
//!   wavenumber (`synth/embed.rs`). The only fast method for the paper's pair-mean speed on several
//!   heights, whose coherence matrix is no Kronecker product.
//!
//! [`Method::fastest`] picks the separable method where it is exact and the embedding
//! otherwise.
//!
//! Taylor advection multiplies every coefficient by e^{−iω (x − x_c)/U_c}: gusts travel
//! downwind at one convection speed U_c at every height ([`convection_speed`]), so the lag
//! over Δx is Δx/U_c. x_c is the middle of the grid's x range. The factor is diagonal and
//! unitary: it keeps every factorisation exact and leaves the coherence magnitudes of eq. 5
//! untouched, and being the same at every height it adds no phase between heights: the
//! vertical co-coherence is eq. 5's at every x. (Each height at its own Ū(z) would add
//! ω (x − x_c)(1/Ū_h − 1/Ū_k) between heights, and the co-coherence 57 m from the middle of a
//! grid turned negative where eq. 5 gives +0.36; a canopy's large eddies convect at one
//! speed across heights anyway, Finnigan 2000.)
//!
//! Memory and order of work: the separable method walks the grid one x-column at a time,
//! carrying the x-recursion state from column to column; each column is transformed and
//! staged, and every 16 columns the staged records are written frame-major. Its working
//! memory is a few columns' worth (two coefficient columns of nz·ny·(M/2+1) complex values
//! and 16 staged record columns), whatever nx: the output itself is the only large buffer.

use std::f64::consts::PI;

use rayon::prelude::*;
use realfft::RealFftPlanner;
use realfft::num_complex::Complex;
use serde::{Deserialize, Serialize};
use sylva_core::simd_kernel;

use crate::error::WindError;
use crate::grid::Grid;
use crate::params::{CoherenceSpeed, Component, WindParams};
use crate::spectrum;

type C64 = Complex<f64>;

mod embed;
mod estimate;
mod methods;
mod phases;
mod sample;

use phases::*;
pub use sample::Sample;

pub use estimate::{
    CHOLESKY_FLOPS_PER_S, CholeskyEstimate, check_config, cholesky_estimate, memory_estimate,
    streaming_memory_estimate,
};

/// Synthesis method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Exact Kronecker/AR(1) factor plus inverse real FFT (default). O(n N log N). Exact with
    /// one coherence speed: the reference speed, or any speed on one height.
    #[default]
    Separable,
    /// Circulant embedding across x and y, dense over heights: exact in distribution for the
    /// pair-mean speed on several heights; regular x and y only. About nz²/6 + 4 log P
    /// times the separable cost per point.
    Embedding,
    /// The paper's dense CPSDM Cholesky per frequency line, in f64. O(N n³); small grids only.
    Cholesky,
}

impl Method {
    /// The fastest method that is exact for these parameters on this grid: the separable
    /// factor when one speed divides every separation, else the embedding on regular x–y
    /// grids, else the dense Cholesky.
    pub fn fastest(params: &WindParams, grid: &Grid) -> Method {
        if params.coherence_speed == CoherenceSpeed::Reference || grid.nz() == 1 {
            Method::Separable
        } else if Grid::regular_spacing(&grid.xs).is_some()
            && Grid::regular_spacing(&grid.ys).is_some()
        {
            Method::Embedding
        } else {
            Method::Cholesky
        }
    }

    /// Lower-case name, as on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Method::Separable => "separable",
            Method::Embedding => "embedding",
            Method::Cholesky => "cholesky",
        }
    }
}

/// How to synthesise: seed and method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub struct SynthParams {
    /// Seed of every random phase. Same seed, same bits.
    pub seed: u64,
    /// Method. Default [`Method::Separable`].
    pub method: Method,
}

/// Largest point count the dense Cholesky method accepts (its matrix is n² f64 per line).
pub const CHOLESKY_MAX_POINTS: usize = 4096;

simd_kernel! {
    /// One row of the y recursion: out = x for the first row, else out = ρ ⊙ prev + s ⊙ x.
    fn y_row(x: &[C64], prev: Option<&[C64]>, ar: (&[f64], &[f64]), out: &mut [C64]) {
        match prev {
            None => out.copy_from_slice(x),
            Some(prev) => {
                for ((((o, x), p), r), s) in out.iter_mut().zip(x).zip(prev).zip(ar.0).zip(ar.1) {
                    *o = C64::new(p.re * r + x.re * s, p.im * r + x.im * s);
                }
            }
        }
    }
}

simd_kernel! {
    /// One AR(1) step on a vector of lines: cur = ρ ⊙ prev + s ⊙ cur.
    fn ar1_step(prev: &[C64], cur: &mut [C64], rho: &[f64], s: &[f64]) {
        for (((c, p), r), s) in cur.iter_mut().zip(prev).zip(rho).zip(s) {
            *c = C64::new(p.re * r + c.re * s, p.im * r + c.im * s);
        }
    }
}

/// Precomputed per-line quantities of one component.
struct Lines {
    /// Number of complex coefficients per point, M/2 + 1 (DC … Nyquist).
    nc: usize,
    /// ω_j in rad/s, j = 0 … M/2.
    omega: Vec<f64>,
    /// Key of the phase stream of each line.
    keys: Vec<u64>,
    /// √Δω · √S0(ω_j, z) per (z, j); zero at DC and Nyquist.
    scale: Vec<f64>,
    /// Reference speed U_c (m/s) for the coherence of the separable method.
    u_ref: f64,
    /// The convection speed U_c (m/s) every height advects at.
    u_conv: f64,
    /// Origin x_c of the advection phase: the middle of the grid's x range (m).
    x_mid: f64,
    /// √Δω.
    sqrt_dw: f64,
}

impl Lines {
    fn new(params: &WindParams, grid: &Grid, comp: Component, seed: u64) -> Lines {
        let m = grid.frames;
        let nc = m / 2 + 1;
        let dw = 2.0 * PI / (m as f64 * grid.dt);
        let omega: Vec<f64> = (0..nc).map(|j| j as f64 * dw).collect();
        let keys = (0..nc).map(|j| line_key(seed, comp, j)).collect();
        let mut scale = vec![0.0; grid.nz() * nc];
        for (iz, &z) in grid.zs.iter().enumerate() {
            for j in 1..nc - 1 {
                scale[iz * nc + j] = (dw * spectrum::two_sided(params, comp, omega[j], z)).sqrt();
            }
        }
        let u_ref = reference_speed(params, grid);
        let u_conv = convection_speed(params, grid);
        let x_mid = grid.x_mid();
        Lines { nc, omega, keys, scale, u_ref, u_conv, x_mid, sqrt_dw: dw.sqrt() }
    }

    /// Emission factors of the column at along-wind position `x`, per (height, line): the
    /// Taylor-advection phase e^{−iω_j (x − x_c)/U_c} (1 when `advect` is off) times √Δω·√S0
    /// (`with_spectrum`) or √Δω alone (a factor that already holds √S0).
    fn column_factors(&self, advect: bool, x: f64, with_spectrum: bool, out: &mut [C64]) {
        let u = self.u_conv;
        for (iz, f) in out.chunks_mut(self.nc).enumerate() {
            for (j, f) in f.iter_mut().enumerate() {
                let amp = if with_spectrum { self.scale[iz * self.nc + j] } else { self.sqrt_dw };
                *f = if advect {
                    C64::from_polar(amp, -self.omega[j] * (x - self.x_mid) / u)
                } else {
                    C64::new(amp, 0.0)
                };
            }
        }
    }

    /// AR(1) factors (ρ, √(1−ρ²)) per line for a gap of `gap` metres with decay constant `c`.
    fn ar1(&self, c: f64, gap: f64) -> (Vec<f64>, Vec<f64>) {
        let mut rho = vec![0.0; self.nc];
        let mut s = vec![0.0; self.nc];
        for j in 1..self.nc - 1 {
            let a = self.omega[j] / (2.0 * PI) * c * gap / self.u_ref;
            rho[j] = (-a).exp();
            s[j] = (-(-2.0 * a).exp_m1()).sqrt();
        }
        (rho, s)
    }
}

/// The reference mean speed: Ū averaged over the grid's heights.
pub fn reference_speed(params: &WindParams, grid: &Grid) -> f64 {
    grid.zs.iter().map(|&z| params.mean_speed(z)).sum::<f64>() / grid.nz() as f64
}

/// The speed U_c gusts advect at on `grid`, m/s: the parameters' own
/// [`WindParams::convection_speed`], else the [`reference_speed`].
pub fn convection_speed(params: &WindParams, grid: &Grid) -> f64 {
    params.convection_speed.unwrap_or_else(|| reference_speed(params, grid))
}

/// A raw view of an output buffer that tasks write to at disjoint indices.
struct OutPtr<T>(*mut T, usize);
// SAFETY: every task writes a disjoint set of indices (one (z, y) row of one component), and
// the buffer outlives the parallel scope that uses the pointer.
unsafe impl<T: Send> Sync for OutPtr<T> {}
impl<T: Copy> OutPtr<T> {
    /// # Safety
    /// `i < len`, and no other thread reads or writes index `i` concurrently.
    #[inline]
    unsafe fn write(&self, i: usize, v: T) {
        debug_assert!(i < self.1);
        // SAFETY: guaranteed by the caller.
        unsafe { *self.0.add(i) = v };
    }
}

/// A raw view of a coefficient buffer whose tasks own disjoint line ranges of every row.
#[derive(Clone, Copy)]
struct RowsPtr(*mut C64, usize);
// SAFETY: tasks only form slices of disjoint index ranges (see the call sites), and the
// buffer outlives the parallel scope.
unsafe impl Sync for RowsPtr {}
// SAFETY: as for Sync: the pointer only moves to tasks that use disjoint ranges.
unsafe impl Send for RowsPtr {}
impl RowsPtr {
    /// # Safety
    /// `[at, at + len)` lies in the buffer and no other live slice overlaps it mutably.
    #[allow(clippy::mut_from_ref)]
    unsafe fn slice<'a>(self, at: usize, len: usize) -> &'a mut [C64] {
        debug_assert!(at + len <= self.1, "rows [{at}, {}) past the buffer's {}", at + len, self.1);
        // SAFETY: guaranteed by the caller.
        unsafe { std::slice::from_raw_parts_mut(self.0.add(at), len) }
    }
}

/// Where the records of one component go in a frame-major buffer.
struct OutLayout {
    /// Elements between consecutive frames.
    frame_stride: usize,
    /// Offset of this component's first point in a frame.
    offset: usize,
    /// Elements between consecutive point rows (the output's x-columns: the grid's nx, or
    /// a block's width).
    row: usize,
    /// The grid's x index of the output's first column (0, or a block's first column).
    x0: usize,
    /// Added to every sample at height index z (the mean speed for `u`, else 0).
    add: Vec<f64>,
}

/// Columns of records gathered before they are written out frame-major: 32 f32 make a
/// 128-byte run of a frame row per write burst.
pub const EMIT_COLUMNS: usize = 32;

/// Turns columns of coefficients into records and writes them frame-major.
///
/// Each column (all points at one x) is multiplied per line and height by its factor
/// (√Δω·√S0 and the column's advection) and inverse-FFT'd point by point into a staging
/// buffer; every [`EMIT_COLUMNS`] columns the
/// buffer is transposed into the output in tiles of frames, so reads and writes stay in cache.
struct Emitter<'a, T> {
    grid: &'a Grid,
    layout: &'a OutLayout,
    out: Sink<'a, T>,
    c2r: std::sync::Arc<dyn realfft::ComplexToReal<T>>,
    /// Records staged as (column in batch, point p = iz·ny + iy, frame).
    rec: Vec<T>,
    /// First x index of the batch and columns staged.
    x0: usize,
    staged: usize,
    /// One past the last column emitted: the staged columns are flushed there.
    end: usize,
}

/// One column's coefficients for [`Emitter::push`]: in f64, or already in the output's type.
#[derive(Clone, Copy)]
enum Col<'a, T> {
    Wide(&'a [C64]),
    Own(&'a [Complex<T>]),
}

/// Where emitted records go: a frame-major buffer, or a callback that takes each block of
/// staged columns as it is ready (streaming).
enum Sink<'a, T> {
    Buffer(OutPtr<T>),
    Stream(&'a mut StreamFn<'a, T>),
}

/// Receives (first column x0, columns, records laid out (column, point p = iz·ny + iy, frame)).
type StreamFn<'a, T> = dyn FnMut(usize, usize, &[T]) -> Result<(), WindError> + 'a;

impl<'a, T: Sample> Emitter<'a, T> {
    fn new(grid: &'a Grid, layout: &'a OutLayout, out: Sink<'a, T>, end: usize) -> Self {
        let np = grid.nz() * grid.ny();
        let c2r = RealFftPlanner::<T>::new().plan_fft_inverse(grid.frames);
        Emitter {
            grid,
            layout,
            out,
            c2r,
            rec: vec![T::default(); EMIT_COLUMNS.min(grid.nx()) * np * grid.frames],
            x0: 0,
            staged: 0,
            end,
        }
    }

    /// Emit column `ix`: coefficients `col` (point-major, nc lines each) times the factor
    /// `scale[iz·nc + j]` of the point's height (√Δω·√S0 and the column's advection), then
    /// one inverse FFT per point.
    fn push(&mut self, ix: usize, col: Col<'_, T>, scale: &[C64]) -> Result<(), WindError> {
        let (ny, m) = (self.grid.ny(), self.grid.frames);
        let nc = m / 2 + 1;
        let np = self.grid.nz() * ny;
        let slot = &mut self.rec[self.staged * np * m..(self.staged + 1) * np * m];
        let c2r = &self.c2r;
        let add = &self.layout.add;
        slot.par_chunks_mut(m).enumerate().for_each_init(
            || (c2r.make_input_vec(), c2r.make_scratch_vec()),
            |(spec, scratch), (p, dst)| {
                let iz = p / ny;
                let sc = &scale[iz * nc..(iz + 1) * nc];
                match col {
                    Col::Wide(c) => T::scale_into(&c[p * nc..(p + 1) * nc], sc, spec),
                    Col::Own(c) => T::scale_own_into(&c[p * nc..(p + 1) * nc], sc, spec),
                }
                // DC and Nyquist are exactly zero, as the real inverse FFT requires.
                spec[0] = Complex::default();
                spec[nc - 1] = Complex::default();
                if c2r.process_with_scratch(spec, dst, scratch).is_err() {
                    unreachable!("FFT buffer lengths are fixed by construction");
                }
                let mean = T::from_f64_sample(add[iz]);
                for d in dst.iter_mut() {
                    *d = *d + mean;
                }
            },
        );
        if self.staged == 0 {
            self.x0 = ix;
        }
        self.staged += 1;
        if self.staged == EMIT_COLUMNS || ix + 1 == self.end {
            self.flush()?;
        }
        Ok(())
    }

    /// Write the staged columns frame-major, one task per point row, in tiles of frames (or
    /// hand them to the stream).
    fn flush(&mut self) -> Result<(), WindError> {
        const TILE: usize = 64;
        let m = self.grid.frames;
        let np = self.grid.nz() * self.grid.ny();
        let (bw, x0, rec, layout) = (self.staged, self.x0, &self.rec, self.layout);
        self.staged = 0;
        let out = match &mut self.out {
            Sink::Buffer(out) => &*out,
            Sink::Stream(f) => return f(x0, bw, &rec[..bw * np * m]),
        };
        (0..np).into_par_iter().for_each(|p| {
            let base = layout.offset + p * layout.row + x0 - layout.x0;
            for t0 in (0..m).step_by(TILE) {
                let t1 = (t0 + TILE).min(m);
                for t in t0..t1 {
                    let row = base + t * layout.frame_stride;
                    for b in 0..bw {
                        // SAFETY: (frame t, point row p, column x0 + b) belongs to this task
                        // alone and lies inside the buffer sized by the caller.
                        unsafe { out.write(row + b, rec[(b * np + p) * m + t]) };
                    }
                }
            }
        });
        Ok(())
    }
}

/// Synthesise the fluctuations of one component into `out` (frame-major, layout described
/// by `layout`), calling `progress` with the fraction of this component done. Returns the
/// bound on the coherence error (0 for an exact synthesis; see `synth/embed.rs`).
#[allow(clippy::too_many_arguments)]
fn synth_component<'a, T: Sample>(
    params: &WindParams,
    grid: &'a Grid,
    synth: SynthParams,
    comp: Component,
    out: Sink<'a, T>,
    layout: &'a OutLayout,
    columns: std::ops::Range<usize>,
    spare: &mut Vec<Complex<T>>,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<f64, WindError> {
    let lines = Lines::new(params, grid, comp, synth.seed);
    let mut coherence_error = 0.0;
    let mut emitter = Emitter::new(grid, layout, out, columns.end);
    use methods::{cholesky, embedding, separable};
    match synth.method {
        Method::Separable => {
            separable(params, grid, comp, &lines, &mut emitter, columns, progress)?;
        }
        Method::Cholesky => cholesky(params, grid, comp, &lines, &mut emitter, progress)?,
        Method::Embedding => {
            coherence_error = embedding(params, grid, comp, &lines, &mut emitter, spare, progress)?;
        }
    }
    Ok(coherence_error)
}

/// In-place lower Cholesky factor of a symmetric positive semidefinite matrix (lower
/// triangle of `a`, row-major n × n), for the dense method and the embedding's blocks. A pivot within 1e-12 of the largest diagonal entry of
/// zero marks a dependent row: its column is set to zero (the factor of a singular matrix).
/// A pivot below −1e-9 of it means the matrix is not semidefinite: the row is returned.
fn cholesky_lower(a: &mut [f64], n: usize) -> Result<(), usize> {
    let scale = (0..n).map(|i| a[i * n + i]).fold(0.0, f64::max);
    for i in 0..n {
        for j in 0..=i {
            let (ri, rj) = (i * n, j * n);
            let mut sum = a[ri + j];
            for k in 0..j {
                sum -= a[ri + k] * a[rj + k];
            }
            if i == j {
                if sum < -1e-9 * scale || !sum.is_finite() {
                    return Err(i);
                }
                a[ri + i] = if sum > 1e-12 * scale { sum.sqrt() } else { 0.0 };
            } else {
                let d = a[rj + j];
                a[ri + j] = if d > 0.0 { sum / d } else { 0.0 };
            }
        }
    }
    Ok(())
}

/// Synthesise the fluctuations of one component in f64, layout (frame, z, y, x), with no
/// mean added: the reference path for checking the methods against each other.
pub fn synthesize_component_f64(
    params: &WindParams,
    grid: &Grid,
    synth: SynthParams,
    comp: Component,
) -> Result<Vec<f64>, WindError> {
    check_config(params, grid, synth)?;
    let n = grid.points();
    let mut out = vec![0.0f64; n * grid.frames];
    let add = vec![0.0; grid.nz()];
    let layout = OutLayout { frame_stride: n, offset: 0, row: grid.nx(), x0: 0, add };
    let sink = Sink::Buffer(OutPtr(out.as_mut_ptr(), out.len()));
    synth_component(
        params,
        grid,
        synth,
        comp,
        sink,
        &layout,
        0..grid.nx(),
        &mut Vec::new(),
        &|_| {},
    )?;
    Ok(out)
}

/// What each height's records of `comp` get added: Ū(z) for `u`, nothing for `v` and `w`.
fn mean_added(params: &WindParams, grid: &Grid, comp: Component) -> Vec<f64> {
    grid.zs.iter().map(|&z| if comp == Component::U { params.mean_speed(z) } else { 0.0 }).collect()
}

/// Synthesise all three components into a frame-major f32 buffer laid out
/// (frame, component, z, y, x) holding full velocities (Ū(z) added to `u`). Returns the
/// largest bound on the coherence error over the components (0 when exact).
pub(crate) fn synthesize_into(
    params: &WindParams,
    grid: &Grid,
    synth: SynthParams,
    out: &mut [f32],
    progress: &(dyn Fn(f64) + Sync),
) -> Result<f64, WindError> {
    check_config(params, grid, synth)?;
    let n = grid.points();
    let mut worst: f64 = 0.0;
    // The embedding's coefficient block, kept from one component to the next.
    let mut spare = Vec::new();
    for comp in Component::ALL {
        let add = mean_added(params, grid, comp);
        let (offset, row) = (comp.index() * n, grid.nx());
        let layout = OutLayout { frame_stride: 3 * n, offset, row, x0: 0, add };
        let c = comp.index() as f64;
        let sink = Sink::Buffer(OutPtr(out.as_mut_ptr(), out.len()));
        let e = synth_component(
            params,
            grid,
            synth,
            comp,
            sink,
            &layout,
            0..grid.nx(),
            &mut spare,
            &|f| progress((c + f) / 3.0),
        )?;
        worst = worst.max(e);
    }
    Ok(worst)
}

/// Receives each finished block of [`synthesize_streaming`]: (component, first column x0,
/// columns, records laid out (column, point p = iz·ny + iy, frame)).
pub type ColumnSink<'a> = dyn FnMut(Component, usize, usize, &[f32]) -> Result<(), WindError> + 'a;

/// Synthesise all three components without holding the field: every block of up to
/// [`EMIT_COLUMNS`] x-columns of one component is handed to `emit` as soon as it is ready,
/// as (component, first column x0, columns, records laid out (column, point p = iz·ny + iy,
/// frame)) holding full velocities (Ū(z) added to `u`). Components come in the order u, v,
/// w, columns in increasing x. Working memory is [`streaming_memory_estimate`], whatever nx.
/// The separable method only (the others need every point's coefficients at once).
pub fn synthesize_streaming(
    params: &WindParams,
    grid: &Grid,
    synth: SynthParams,
    emit: &mut ColumnSink<'_>,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<(), WindError> {
    stream_columns(params, grid, synth, 0..grid.nx(), emit, progress)
}

/// [`synthesize_streaming`] for the x-columns `columns` alone: the same records, bit for
/// bit, as the whole field holds there. Each block of columns can be made on its own, in
/// any order, on any machine: the x recursion of each frequency line is run over the
/// columns before `columns.start` from the same counter-based phases (no FFT), which
/// carries its state into the block exactly as the whole field's synthesis does. Costs
/// the block's share of the field plus a phase sweep over the columns before it.
pub fn synthesize_columns_streaming(
    params: &WindParams,
    grid: &Grid,
    synth: SynthParams,
    columns: std::ops::Range<usize>,
    emit: &mut ColumnSink<'_>,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<(), WindError> {
    stream_columns(params, grid, synth, columns, emit, progress)
}

/// The x-columns `columns` of all three components, laid out (frame, component, z, y,
/// column) as a [`crate::WindField`]'s data is over the whole grid, full velocities: the
/// whole field's records there, bit for bit ([`synthesize_columns_streaming`]). A block of
/// a field larger than memory, or than one machine (Python's `generate_lazy`).
pub fn synthesize_columns(
    params: &WindParams,
    grid: &Grid,
    synth: SynthParams,
    columns: std::ops::Range<usize>,
) -> Result<Vec<f32>, WindError> {
    check_columns(params, grid, synth, &columns)?;
    let (np, w) = (grid.nz() * grid.ny(), columns.len());
    let mut out = vec![0.0f32; grid.frames * 3 * np * w];
    // The embedding's coefficient block: unused here (`check_columns` admits the separable
    // method only).
    let mut spare = Vec::new();
    for comp in Component::ALL {
        let add = mean_added(params, grid, comp);
        let (offset, x0) = (comp.index() * np * w, columns.start);
        let layout = OutLayout { frame_stride: 3 * np * w, offset, row: w, x0, add };
        let sink = Sink::Buffer(OutPtr(out.as_mut_ptr(), out.len()));
        synth_component(
            params,
            grid,
            synth,
            comp,
            sink,
            &layout,
            columns.clone(),
            &mut spare,
            &|_| {},
        )?;
    }
    Ok(out)
}

/// What streaming and blocks of columns need before they start: the configuration the
/// synthesis checks, the separable method (the others hold every point's coefficients at
/// once) and a non-empty range of the grid's columns.
fn check_columns(
    params: &WindParams,
    grid: &Grid,
    synth: SynthParams,
    columns: &std::ops::Range<usize>,
) -> Result<(), WindError> {
    check_config(params, grid, synth)?;
    if synth.method != Method::Separable {
        return Err(WindError::Unsupported(format!(
            "streaming and blocks of columns need the separable method (one coherence speed, \
             or one height); the {} method holds every point's coefficients at once",
            synth.method.name()
        )));
    }
    if columns.start >= columns.end || columns.end > grid.nx() {
        return Err(WindError::Unsupported(format!(
            "columns {}..{}: expected a non-empty range within the grid's {} x-columns",
            columns.start,
            columns.end,
            grid.nx()
        )));
    }
    Ok(())
}

fn stream_columns(
    params: &WindParams,
    grid: &Grid,
    synth: SynthParams,
    columns: std::ops::Range<usize>,
    emit: &mut ColumnSink<'_>,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<(), WindError> {
    check_columns(params, grid, synth, &columns)?;
    // The embedding's coefficient block: unused here (`check_columns` admits the separable
    // method only).
    let mut spare = Vec::new();
    for comp in Component::ALL {
        let add = mean_added(params, grid, comp);
        let layout = OutLayout { frame_stride: 0, offset: 0, row: 0, x0: 0, add };
        let c = comp.index() as f64;
        let mut each = |x0: usize, cols: usize, rec: &[f32]| emit(comp, x0, cols, rec);
        let sink = Sink::Stream(&mut each);
        synth_component(
            params,
            grid,
            synth,
            comp,
            sink,
            &layout,
            columns.clone(),
            &mut spare,
            &|f| progress((c + f) / 3.0),
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests;
