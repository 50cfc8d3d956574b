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
//!   the coherence matrix on a rectilinear grid is R_z ⊗ R_y ⊗ R_x with R[a,b] = e^{−a|p_a − p_b|}
//!   per axis, whose Cholesky factor is L_z ⊗ L_y ⊗ L_x, each an AR(1) recursion
//!   y_0 = e_0, y_i = ρ_i y_{i−1} + √(1−ρ_i²) e_i with ρ_i = e^{−a·gap_i} (√(1−ρ²) evaluated as
//!   √(−expm1(−2a·gap)) for accuracy at low frequency). Height-dependent spectra stay exact since
//!   chol(D C D) = D chol(C). O(n N) + O(n N log N).
//!
//! Taylor advection multiplies every coefficient by e^{−iω x/U_c} (U_c: the reference speed),
//! a diagonal unitary factor that keeps both factorisations exact.
//!
//! Memory: the separable method works on blocks of x-columns holding all frequency lines,
//! carrying the x-recursion state from block to block, so its working memory is bounded
//! (about [`BLOCK_BYTES`]) whatever the grid size; the output itself is the only large buffer.

use std::f64::consts::PI;

use rayon::prelude::*;
use realfft::RealFftPlanner;
use realfft::num_complex::Complex;
use serde::{Deserialize, Serialize};

use crate::error::WindError;
use crate::grid::Grid;
use crate::params::{CoherenceSpeed, Component, WindParams};
use crate::spectrum;

type C64 = Complex<f64>;

/// Working memory the separable method aims at for its coefficient block, in bytes.
pub const BLOCK_BYTES: usize = 256 << 20;

/// Synthesis method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Exact Kronecker/AR(1) factor plus inverse real FFT (default). O(n N log N).
    #[default]
    Separable,
    /// The paper's dense CPSDM Cholesky per frequency line, in f64. O(N n³); small grids only.
    Cholesky,
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

/// A number type the synthesis can write (f32 for fields, f64 for reference checks).
pub trait Sample: Copy + Send + Sync + Default + 'static {
    /// Convert from the f64 the synthesis computes in.
    fn from_f64(x: f64) -> Self;
}
impl Sample for f32 {
    fn from_f64(x: f64) -> Self {
        x as f32
    }
}
impl Sample for f64 {
    fn from_f64(x: f64) -> Self {
        x
    }
}

/// SplitMix64 finaliser (Steele, Lea & Flood 2014): a bijective 64-bit mixer.
#[inline]
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

const GOLDEN: u64 = 0x9e37_79b9_7f4a_7c15;

/// Key of the phase stream of one (seed, component, frequency line).
#[inline]
fn line_key(seed: u64, comp: Component, j: usize) -> u64 {
    let s = mix64(seed ^ GOLDEN.wrapping_mul(comp.index() as u64 + 1));
    mix64(s ^ (j as u64).wrapping_mul(0xd6e8_feb8_6659_fd93))
}

/// The unit phasor e^{iφ_jk} of Cholesky column `k` on the line with key `key`: a point
/// drawn uniformly in the unit disc by rejection and normalised, so φ is exactly uniform.
#[inline]
fn phasor(key: u64, k: usize) -> C64 {
    let mut attempt = 0u64;
    loop {
        let h = mix64(key.wrapping_add((k as u64 * 8 + attempt).wrapping_mul(GOLDEN)));
        let a = (h >> 32) as f64 * (2.0 / 4_294_967_296.0) - 1.0;
        let b = (h & 0xffff_ffff) as f64 * (2.0 / 4_294_967_296.0) - 1.0;
        let r2 = a * a + b * b;
        if r2 <= 1.0 && r2 > 1e-12 {
            let inv = 1.0 / r2.sqrt();
            return C64::new(a * inv, b * inv);
        }
        attempt += 1;
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
    /// Reference speed U_c (m/s) for coherence and advection.
    u_ref: f64,
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
        Lines { nc, omega, keys, scale, u_ref, sqrt_dw: dw.sqrt() }
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

/// Where the records of one component go in a frame-major buffer.
struct OutLayout {
    /// Elements between consecutive frames.
    frame_stride: usize,
    /// Offset of this component's first point in a frame.
    offset: usize,
    /// Added to every sample at height index z (the mean speed for `u`, else 0).
    add: Vec<f64>,
}

/// Synthesise the fluctuations of one component into `out` (frame-major, layout described
/// by `layout`), calling `progress` with the fraction of this component done.
fn synth_component<T: Sample>(
    params: &WindParams,
    grid: &Grid,
    synth: SynthParams,
    comp: Component,
    out: &mut [T],
    layout: &OutLayout,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<(), WindError> {
    let lines = Lines::new(params, grid, comp, synth.seed);
    let (nx, ny, nz) = (grid.nx(), grid.ny(), grid.nz());
    let nc = lines.nc;
    let col_len = nz * ny * nc;
    let ptr = OutPtr(out.as_mut_ptr(), out.len());
    let mut planner = RealFftPlanner::<f64>::new();
    let c2r = planner.plan_fft_inverse(grid.frames);

    match synth.method {
        Method::Separable => {
            let cc = params.coherence[comp.index()];
            let gaps = |axis: &[f64], c: f64| -> Vec<(Vec<f64>, Vec<f64>)> {
                axis.windows(2).map(|w| lines.ar1(c, w[1] - w[0])).collect()
            };
            let (gx, gy, gz) =
                (gaps(&grid.xs, cc.cx), gaps(&grid.ys, cc.cy), gaps(&grid.zs, cc.cz));
            let bx = (BLOCK_BYTES / (col_len * 16).max(1)).clamp(1, nx);
            let mut block = vec![C64::default(); bx * col_len];
            let mut carry = vec![C64::default(); col_len];
            let mut x0 = 0;
            while x0 < nx {
                let x1 = (x0 + bx).min(nx);
                let blk = &mut block[..(x1 - x0) * col_len];
                // Phasors, then the y and z recursions, column by column (independent).
                blk.par_chunks_mut(col_len).enumerate().for_each(|(bxi, col)| {
                    let ix = x0 + bxi;
                    for (p, v) in col.chunks_mut(nc).enumerate() {
                        let k = p * nx + ix; // p = iz·ny + iy, k = (iz·ny + iy)·nx + ix
                        v[0] = C64::default();
                        v[nc - 1] = C64::default();
                        for j in 1..nc - 1 {
                            v[j] = phasor(lines.keys[j], k);
                        }
                    }
                    for iz in 0..nz {
                        for iy in 1..ny {
                            let (rho, s) = &gy[iy - 1];
                            let (a, b) = col.split_at_mut((iz * ny + iy) * nc);
                            ar1_step(&a[(iz * ny + iy - 1) * nc..], &mut b[..nc], rho, s);
                        }
                    }
                    for iz in 1..nz {
                        let (rho, s) = &gz[iz - 1];
                        let (a, b) = col.split_at_mut(iz * ny * nc);
                        let prev = &a[(iz - 1) * ny * nc..];
                        for iy in 0..ny {
                            let r = iy * nc..(iy + 1) * nc;
                            ar1_step(&prev[r.clone()], &mut b[r], rho, s);
                        }
                    }
                });
                // The x recursion: sequential over columns, parallel over points.
                for ix in x0..x1 {
                    if ix == 0 {
                        continue;
                    }
                    let (rho, s) = &gx[ix - 1];
                    let bxi = ix - x0;
                    let (before, cur) = blk.split_at_mut(bxi * col_len);
                    let prev = if bxi == 0 { &carry[..] } else { &before[(bxi - 1) * col_len..] };
                    cur[..col_len]
                        .par_chunks_mut(nc)
                        .zip(prev.par_chunks(nc))
                        .for_each(|(c, p)| ar1_step(p, c, rho, s));
                }
                carry.copy_from_slice(&blk[(x1 - x0 - 1) * col_len..]);
                let adv = params.advection;
                emit_block(grid, &lines, adv, true, blk, x0, x1, &c2r, &ptr, layout);
                progress(x1 as f64 / nx as f64);
                x0 = x1;
            }
        }
        Method::Cholesky => {
            let n = grid.points();
            if n > CHOLESKY_MAX_POINTS {
                return Err(WindError::Unsupported(format!(
                    "the Cholesky method is limited to {CHOLESKY_MAX_POINTS} points; this grid has {n}"
                )));
            }
            let pos = |k: usize| {
                let (ix, iy, iz) = (k % nx, (k / nx) % ny, k / (nx * ny));
                [grid.xs[ix], grid.ys[iy], grid.zs[iz], params.mean_speed(grid.zs[iz])]
            };
            let pts: Vec<[f64; 4]> = (0..n).map(pos).collect();
            // Coefficients laid out (x, z, y, j) like a separable block spanning all columns.
            let mut block = vec![C64::default(); nx * col_len];
            let mut mat = vec![0.0f64; n * n];
            let mut e = vec![C64::default(); n];
            for j in 1..nc - 1 {
                let f = lines.omega[j] / (2.0 * PI);
                for a in 0..n {
                    let sa = lines.scale[(a / (nx * ny)) * nc + j];
                    for b in 0..=a {
                        let sb = lines.scale[(b / (nx * ny)) * nc + j];
                        let d =
                            [pts[a][0] - pts[b][0], pts[a][1] - pts[b][1], pts[a][2] - pts[b][2]];
                        let um = match params.coherence_speed {
                            CoherenceSpeed::Reference => lines.u_ref,
                            CoherenceSpeed::PairMean => 0.5 * (pts[a][3] + pts[b][3]),
                        };
                        // √S0_a √S0_b Coh_ab (the √Δω factors are applied at emission).
                        let s0 = sa * sb / lines.sqrt_dw.powi(2);
                        mat[a * n + b] = s0 * spectrum::coherence(params, comp, f, d, um);
                    }
                }
                cholesky_lower(&mut mat, n).map_err(|row| {
                    WindError::Unsupported(format!(
                        "CPSDM not positive definite at line {j} (f = {f:.4} Hz), row {row}"
                    ))
                })?;
                for (k, ek) in e.iter_mut().enumerate() {
                    *ek = phasor(lines.keys[j], k);
                }
                for a in 0..n {
                    let row = &mat[a * n..a * n + a + 1];
                    let v: C64 = row.iter().zip(&e).map(|(l, ek)| ek * *l).sum();
                    let (ix, p) = (a % nx, a / nx);
                    block[ix * col_len + p * nc + j] = v;
                }
                progress(j as f64 / (nc - 2) as f64);
            }
            // The dense factor already holds √S0: emit without scaling again.
            let (adv, scale) = (params.advection, false);
            emit_block(grid, &lines, adv, scale, &mut block, 0, nx, &c2r, &ptr, layout);
        }
    }
    Ok(())
}

/// One AR(1) step on a vector of lines: cur = ρ ⊙ prev + s ⊙ cur.
#[inline]
fn ar1_step(prev: &[C64], cur: &mut [C64], rho: &[f64], s: &[f64]) {
    for (((c, p), r), s) in cur.iter_mut().zip(prev).zip(rho).zip(s) {
        *c = *p * *r + *c * *s;
    }
}

/// Scale a block of unit-variance coefficients by √Δω √S0(z) (when `scale`; the dense
/// method's coefficients carry √S0 already and only need √Δω), apply advection,
/// inverse-FFT every point and write the records frame-major.
fn emit_block<T: Sample>(
    grid: &Grid,
    lines: &Lines,
    advection: bool,
    scale: bool,
    blk: &mut [C64],
    x0: usize,
    x1: usize,
    c2r: &std::sync::Arc<dyn realfft::ComplexToReal<f64>>,
    out: &OutPtr<T>,
    layout: &OutLayout,
) {
    let (nx, ny, nz, m) = (grid.nx(), grid.ny(), grid.nz(), grid.frames);
    let nc = lines.nc;
    let col_len = nz * ny * nc;
    let bw = x1 - x0;
    // Scale and advect, column by column.
    blk.par_chunks_mut(col_len).enumerate().for_each(|(bxi, col)| {
        let x = grid.xs[x0 + bxi];
        let adv: Vec<C64> = (0..nc)
            .map(|j| {
                if advection {
                    C64::from_polar(1.0, -lines.omega[j] * x / lines.u_ref)
                } else {
                    C64::new(1.0, 0.0)
                }
            })
            .collect();
        for (p, v) in col.chunks_mut(nc).enumerate() {
            if scale {
                let sc = &lines.scale[(p / ny) * nc..(p / ny + 1) * nc];
                for ((c, s), a) in v.iter_mut().zip(sc).zip(&adv) {
                    *c *= *a * *s;
                }
            } else {
                for (c, a) in v.iter_mut().zip(&adv) {
                    *c *= *a * lines.sqrt_dw;
                }
            }
        }
    });
    let blk: &[C64] = blk;
    // One task per (z, y) row: FFT its points, then write frame by frame.
    (0..nz * ny).into_par_iter().for_each_init(
        || (vec![C64::default(); nc], vec![0.0f64; bw * m], c2r.make_scratch_vec()),
        |(spec, rec, scratch), p| {
            for bxi in 0..bw {
                spec.copy_from_slice(&blk[bxi * col_len + p * nc..bxi * col_len + (p + 1) * nc]);
                // DC and Nyquist are exactly zero, as the real inverse FFT requires.
                let dst = &mut rec[bxi * m..(bxi + 1) * m];
                if c2r.process_with_scratch(spec, dst, scratch).is_err() {
                    unreachable!("FFT buffer lengths are fixed by construction");
                }
            }
            let add = layout.add[p / ny];
            let base = layout.offset + p * nx + x0;
            for t in 0..m {
                let row = base + t * layout.frame_stride;
                for bxi in 0..bw {
                    // SAFETY: index (t, this row, x0 + bxi) belongs to this task alone and
                    // lies inside the buffer sized by the caller.
                    unsafe { out.write(row + bxi, T::from_f64(rec[bxi * m + t] + add)) };
                }
            }
        },
    );
}

/// In-place lower Cholesky factor of the symmetric matrix whose lower triangle is in `a`
/// (row-major n×n). Returns the failing row if the matrix is not positive definite.
fn cholesky_lower(a: &mut [f64], n: usize) -> Result<(), usize> {
    for i in 0..n {
        for j in 0..=i {
            let (ri, rj) = (i * n, j * n);
            let mut sum = a[ri + j];
            for k in 0..j {
                sum -= a[ri + k] * a[rj + k];
            }
            if i == j {
                if sum <= 0.0 || !sum.is_finite() {
                    return Err(i);
                }
                a[ri + i] = sum.sqrt();
            } else {
                a[ri + j] = sum / a[rj + j];
            }
        }
    }
    Ok(())
}

/// Check that the parameters, grid and method can be synthesised together.
pub fn check_config(params: &WindParams, grid: &Grid, synth: SynthParams) -> Result<(), WindError> {
    params.validate()?;
    grid.validate()?;
    if synth.method == Method::Separable
        && params.coherence_speed == CoherenceSpeed::PairMean
        && grid.nz() > 1
    {
        return Err(WindError::Unsupported(
            "pair-mean coherence speed on several heights needs --method cholesky; \
             the separable method uses one reference speed"
                .into(),
        ));
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
    let layout = OutLayout { frame_stride: n, offset: 0, add: vec![0.0; grid.nz()] };
    synth_component(params, grid, synth, comp, &mut out, &layout, &|_| {})?;
    Ok(out)
}

/// Synthesise all three components into a frame-major f32 buffer laid out
/// (frame, component, z, y, x) holding full velocities (Ū(z) added to `u`).
pub(crate) fn synthesize_into(
    params: &WindParams,
    grid: &Grid,
    synth: SynthParams,
    out: &mut [f32],
    progress: &(dyn Fn(f64) + Sync),
) -> Result<(), WindError> {
    check_config(params, grid, synth)?;
    let n = grid.points();
    for comp in Component::ALL {
        let add = grid
            .zs
            .iter()
            .map(|&z| if comp == Component::U { params.mean_speed(z) } else { 0.0 })
            .collect();
        let layout = OutLayout { frame_stride: 3 * n, offset: comp.index() * n, add };
        let c = comp.index() as f64;
        synth_component(params, grid, synth, comp, out, &layout, &|f| progress((c + f) / 3.0))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phasors_are_unit_and_uniform_in_angle() {
        let key = line_key(7, Component::U, 3);
        let n = 200_000;
        let mut hist = [0usize; 16];
        for k in 0..n {
            let p = phasor(key, k);
            assert!((p.norm() - 1.0).abs() < 1e-12);
            let a = p.im.atan2(p.re) + PI;
            hist[((a / (2.0 * PI) * 16.0) as usize).min(15)] += 1;
        }
        // Each bin expects n/16 = 12500 with σ ≈ 108: 6σ bounds.
        for h in hist {
            assert!((h as f64 - 12_500.0).abs() < 650.0, "{hist:?}");
        }
    }

    #[test]
    fn cholesky_factor_reproduces_the_matrix() {
        let n = 5;
        let full: Vec<f64> = (0..n * n)
            .map(|k| {
                let (i, j) = (k / n, k % n);
                0.7f64.powi((i as i32 - j as i32).abs()) + if i == j { 0.1 } else { 0.0 }
            })
            .collect();
        let mut l = full.clone();
        cholesky_lower(&mut l, n).expect("positive definite");
        for i in 0..n {
            for j in 0..=i {
                let s: f64 = (0..=j).map(|k| l[i * n + k] * l[j * n + k]).sum();
                assert!((s - full[i * n + j]).abs() < 1e-12);
            }
        }
        let mut bad = vec![1.0, 0.0, 2.0, 1.0];
        assert_eq!(cholesky_lower(&mut bad, 2), Err(1));
    }
}
