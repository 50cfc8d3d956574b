//! Circulant embedding across x and y, dense over heights ([`super::Method::Embedding`]).
//!
//! With the paper's pair-mean speed Ū_m = (Ū_h + Ū_k)/2 in eq. 5, the coherence of two
//! points at heights h, k and horizontal offset (Δx, Δy) is
//!   Coh = Z_hk · e^{−f C_x |Δx| / Ū_m} · e^{−f C_y |Δy| / Ū_m},  Z_hk = e^{−f C_z |z_h − z_k| / Ū_m},
//! separable in x and y for each pair of heights, but with a different decay per pair: the
//! matrix is no Kronecker product, and no AR(1) chain reproduces it. It is, however,
//! stationary along x and y. On a regular grid each per-pair 1-D kernel e^{−a|d|} (d in grid
//! steps) is embedded in a circulant of period P = 2m ≥ 2(n − 1) (the kernel folded:
//! c(d) = e^{−a·min(d, P − d)}), whose DFT has the closed form
//!   ĉ(κ) = (1 − (−1)^κ e^{−am}) (1 − e^{−2a}) / (1 − 2e^{−a} cos(2πκ/P) + e^{−2a}) ≥ 0.
//! On the P_x × P_y torus the cross-spectral density matrix is therefore diagonal in the
//! horizontal wavenumber κ, with one nz × nz block per κ:
//!   M_hk(κ) = Z_hk · ĉ^x_hk(κ_x) · ĉ^y_hk(κ_y).
//! Each block is factored (Cholesky, nz³/6), multiplied by nz unit phasors e^{iφ} drawn for
//! (line, height column, κ), and one inverse 2-D FFT per height brings the coefficients back
//! to the grid. Restricted to the grid, the covariance of the result equals the dense CPSDM
//! exactly (the circulant agrees with the kernel at every offset the grid holds); the
//! realisation differs from the dense Cholesky one (another factor of the same matrix), so
//! the two methods agree in distribution, not bit for bit.
//!
//! The pair-mean coherence is not always a valid covariance: at low frequency, over a grid
//! many coherence lengths wide, M(κ) ∝ [Ū_m²]_hk near κ = 0, and [(Ū_h + Ū_k)²] is
//! indefinite (for v on 24 × 24 points 4 m apart at 15/20/30 m, line 1, the dense matrix
//! has an eigenvalue of −0.51). The dense Cholesky then fails. Here a block that is not
//! semidefinite is replaced by its nearest semidefinite matrix (negative eigenvalues set to
//! zero, Jacobi eigen-decomposition), and the sum of the removed eigenvalues over κ, divided
//! by P_x P_y, bounds the change of every coherence on the grid (c(Δ) = Σ_κ M(κ) e^{iκΔ}/N):
//! the synthesis reports that bound, the largest over lines and components.
//!
//! Cost per line: nz² (P_x + P_y) for the kernels, P_x P_y nz³/6 for the blocks and
//! nz P_x P_y log(P_x P_y) for the FFTs; lines are independent and run in parallel.
//!
//! Precision: the kernels and the blocks' factors are computed in f64; the phasors, the
//! factors' products with them and the spatial FFTs run in the output's type `T`. For the
//! f32 fields the engine stores, the covariance is then exact to f32's precision (1e-7 on
//! the test grid, against 1e-15 in f64), and the FFTs, the largest part of the cost, run
//! twice as many vector lanes.

use std::f64::consts::PI;
use std::sync::Arc;

use rustfft::{Fft, FftPlanner};

use sylva_core::simd_kernel;

#[cfg(test)]
use super::cholesky_lower;
use super::{C64, Sample};
use crate::error::WindError;
use crate::grid::Grid;
use crate::params::{CoherenceSpeed, Component, WindParams};
use realfft::num_complex::Complex;

/// Smallest even period P = 2m with m ≥ n − 1 whose factors are 2, 3 and 5 (fast FFTs);
/// 1 for a single point.
fn period(n: usize) -> usize {
    if n <= 1 {
        return 1;
    }
    let smooth = |mut p: usize| {
        for f in [2, 3, 5] {
            while p.is_multiple_of(f) {
                p /= f;
            }
        }
        p == 1
    };
    (n - 1..).map(|m| 2 * m).find(|&p| smooth(p)).unwrap_or(2 * (n - 1))
}

/// DFT of the exponential kernel e^{−a·min(d, P − d)} on a period of `out.len()` points.
fn folded_spectrum(a: f64, out: &mut [f64]) {
    let p = out.len();
    if p == 1 {
        out[0] = 1.0;
        return;
    }
    if a <= 0.0 {
        // Fully coherent: the kernel is 1 at every offset, all power at κ = 0.
        out.fill(0.0);
        out[0] = p as f64;
        return;
    }
    let m = (p / 2) as f64;
    let rho = (-a).exp();
    let one_minus_rho2 = -(-2.0 * a).exp_m1();
    let em1 = (-a).exp_m1();
    for k in 0..=p / 2 {
        // 1 − (−1)^κ ρ^m, accurate when ρ^m is close to 1.
        let lead = if k.is_multiple_of(2) { -(-m * a).exp_m1() } else { 1.0 + (-m * a).exp() };
        let s = (PI * k as f64 / p as f64).sin();
        out[k] = lead * one_minus_rho2 / (em1 * em1 + 4.0 * rho * s * s);
    }
    // The kernel is even, so is its spectrum: ĉ(P − κ) = ĉ(κ), exactly.
    for k in p / 2 + 1..p {
        out[k] = out[p - k];
    }
}

/// Precomputed geometry and FFT plans of one component; the spatial FFTs run in `T`.
pub(super) struct Embedding<T: Sample> {
    nx: usize,
    ny: usize,
    nz: usize,
    px: usize,
    py: usize,
    /// Grid steps along x and y, m.
    gx: f64,
    gy: f64,
    zs: Vec<f64>,
    /// Coherence speed of every pair (h ≥ k), indexed by [`pair`].
    pair_speed: Vec<f64>,
    cx: f64,
    cy: f64,
    cz: f64,
    fft_x: Arc<dyn Fft<T>>,
    fft_y: Arc<dyn Fft<T>>,
}

/// Index of the pair (h, k), k ≤ h, in a packed lower triangle.
#[inline]
fn pair(h: usize, k: usize) -> usize {
    h * (h + 1) / 2 + k
}

/// Fills its slice with the phasors of a height column from a wavenumber on (see
/// [`Embedding::line`]).
pub(super) type Phasors<'a, T> = dyn Fn(usize, usize, &mut [Complex<T>]) + 'a;

/// Per-thread work buffers of [`Embedding::line`].
pub(super) struct Scratch<T> {
    kx: Vec<f64>,
    ky: Vec<f64>,
    z: Vec<f64>,
    m: Vec<f64>,
    e: Vec<f64>,
    /// The coefficients on the torus, (height, κy, κx), then their x transforms.
    v: Vec<Complex<T>>,
    /// The columns the grid keeps, (x, κy), then their y transforms.
    t: Vec<Complex<T>>,
    fft: Vec<Complex<T>>,
    /// One row κy of blocks, pair by pair across κx, and which of them failed.
    lanes: Vec<f64>,
    fail: Vec<f64>,
    /// The factored lanes of a row mirrored over all κx, in `T`, each value twice (beside
    /// the real and imaginary parts it multiplies).
    full: Vec<T>,
    /// The factor's per-lane scale and running sum.
    work: Vec<f64>,
    /// The phasors of one row κy, height column by height column.
    xi: Vec<Complex<T>>,
}

impl<T: Sample> Embedding<T> {
    /// Set up the embedding of `comp` on `grid`; x and y must be regularly spaced.
    pub(super) fn new(
        params: &WindParams,
        grid: &Grid,
        comp: Component,
        u_ref: f64,
    ) -> Result<Embedding<T>, WindError> {
        let (Some(gx), Some(gy)) =
            (Grid::regular_spacing(&grid.xs), Grid::regular_spacing(&grid.ys))
        else {
            return Err(WindError::Unsupported(
                "the embedding method needs regularly spaced x and y (uneven axes: use \
                 --method cholesky on small grids, or the reference coherence speed)"
                    .into(),
            ));
        };
        let (nx, ny, nz) = (grid.nx(), grid.ny(), grid.nz());
        let speeds: Vec<f64> = grid.zs.iter().map(|&z| params.mean_speed(z)).collect();
        let mut pair_speed = vec![0.0; nz * (nz + 1) / 2];
        for h in 0..nz {
            for k in 0..=h {
                pair_speed[pair(h, k)] = match params.coherence_speed {
                    CoherenceSpeed::Reference => u_ref,
                    CoherenceSpeed::PairMean => 0.5 * (speeds[h] + speeds[k]),
                };
            }
        }
        let (px, py) = (period(nx), period(ny));
        let mut planner = FftPlanner::<T>::new();
        let c = params.coherence[comp.index()];
        Ok(Embedding {
            nx,
            ny,
            nz,
            px,
            py,
            gx,
            gy,
            zs: grid.zs.clone(),
            pair_speed,
            cx: c.cx,
            cy: c.cy,
            cz: c.cz,
            fft_x: planner.plan_fft_inverse(px),
            fft_y: planner.plan_fft_inverse(py),
        })
    }

    /// Number of wavenumbers κ on the torus, P_x · P_y.
    pub(super) fn wavenumbers(&self) -> usize {
        self.px * self.py
    }

    /// Work buffers for one thread.
    pub(super) fn scratch(&self) -> Scratch<T> {
        let np = self.nz * (self.nz + 1) / 2;
        let fft_len =
            self.fft_x.get_inplace_scratch_len().max(self.fft_y.get_inplace_scratch_len());
        Scratch {
            kx: vec![0.0; np * self.px],
            ky: vec![0.0; np * self.py],
            z: vec![0.0; np],
            m: vec![0.0; self.nz * self.nz],
            e: vec![0.0; self.nz * self.nz],
            v: vec![Complex::default(); self.nz * self.wavenumbers()],
            t: vec![Complex::default(); self.nx * self.py],
            fft: vec![Complex::default(); fft_len],
            lanes: vec![0.0; np * (self.px / 2 + 1)],
            fail: vec![0.0; self.px / 2 + 1],
            full: vec![T::default(); 2 * np * self.px],
            work: vec![0.0; 2 * (self.px / 2 + 1)],
            xi: vec![Complex::default(); self.nz * self.px],
        }
    }

    /// The unit-variance coherence field of the line at frequency `f` (Hz) into `w`, laid
    /// out (x, z, y), the order of the synthesis' coefficient columns. `xi(m, κ0, out)`
    /// fills `out` with the phasors of height column `m` at the wavenumbers `κ0 …`, where
    /// `κ = κy·P_x + κx`. Returns the bound on the coherence error from blocks that had to
    /// be projected onto semidefinite ones (0 when the model is a valid covariance).
    ///
    /// The blocks of one row κy are factored side by side, each pair's entries of every κx in
    /// one array, so the arithmetic runs in vector lanes; each lane computes what
    /// [`cholesky_lower`] computes, operation for operation, and a lane whose block is not
    /// semidefinite is redone alone with [`nearest_semidefinite_root`].
    pub(super) fn line(
        &self,
        f: f64,
        xi: &Phasors<'_, T>,
        s: &mut Scratch<T>,
        w: &mut [Complex<T>],
    ) -> f64 {
        let (nz, px, py) = (self.nz, self.px, self.py);
        for h in 0..nz {
            for k in 0..=h {
                let q = pair(h, k);
                let u = self.pair_speed[q];
                s.z[q] = (-f * self.cz * (self.zs[h] - self.zs[k]).abs() / u).exp();
                folded_spectrum(f * self.cx * self.gx / u, &mut s.kx[q * px..(q + 1) * px]);
                folded_spectrum(f * self.cy * self.gy / u, &mut s.ky[q * py..(q + 1) * py]);
            }
        }
        let norm = 1.0 / self.wavenumbers() as f64;
        let mut clipped = 0.0;
        // ĉ(κ) = ĉ(P − κ): the blocks of κy and P_y − κy are equal, and within a row those of
        // κx and P_x − κx; only the lanes κx ≤ P_x/2 of rows κy ≤ P_y/2 are factored.
        let wh = px / 2 + 1;
        for ky in 0..=py / 2 {
            block_row(&s.z, &s.kx, &s.ky[..], ky, py, norm, &mut s.lanes, &mut s.fail);
            lower_factor_lanes(&mut s.lanes, nz, &mut s.fail, &mut s.work);
            mirror_lanes(&s.lanes, wh, &mut s.full);
            let any_fail = s.fail.iter().any(|&f| f != 0.0);
            for ky in [ky, py - ky] {
                if ky == py {
                    continue; // κy = 0 has no mirror
                }
                let row = ky * px;
                for m in 0..nz {
                    xi(m, row, &mut s.xi[m * px..(m + 1) * px]);
                }
                for h in 0..nz {
                    let out = &mut s.v[h * px * py + row..h * px * py + row + px];
                    T::apply_factor_row(&s.full, &s.xi, h, px, out);
                }
                let failed = (0..px).filter(|&kx| any_fail && s.fail[kx.min(px - kx)] != 0.0);
                for kx in failed {
                    // This block is not semidefinite: the square root of its nearest
                    // semidefinite matrix (full) instead.
                    for h in 0..nz {
                        for k in 0..=h {
                            let q = pair(h, k);
                            let v = s.z[q] * s.kx[q * px + kx] * s.ky[q * py + ky] * norm;
                            s.m[h * nz + k] = v;
                            s.m[k * nz + h] = v;
                        }
                    }
                    clipped += nearest_semidefinite_root(&mut s.m, &mut s.e, nz);
                    for h in 0..nz {
                        let mut acc = C64::default();
                        for m in 0..nz {
                            let l = s.m[h * nz + m];
                            if l != 0.0 {
                                let x = s.xi[m * px + kx];
                                acc += C64::new(x.re.to_f64_sample(), x.im.to_f64_sample()) * l;
                            }
                        }
                        s.v[h * px * py + row + kx] =
                            Complex::new(T::from_f64_sample(acc.re), T::from_f64_sample(acc.im));
                    }
                }
                if py - ky == ky {
                    break; // κy = P_y/2 is its own mirror
                }
            }
        }
        // Back to the grid: rows (x) of every height, then the columns the grid keeps.
        let (nx, ny) = (self.nx, self.ny);
        for h in 0..nz {
            let plane = &mut s.v[h * px * py..(h + 1) * px * py];
            if px > 1 {
                self.fft_x.process_with_scratch(plane, &mut s.fft);
            }
            // Transposed in strips of 8 columns: each row gives a run of 8 values at once.
            for ix0 in (0..nx).step_by(8) {
                let ix1 = (ix0 + 8).min(nx);
                for ky in 0..py {
                    let src = &plane[ky * px + ix0..ky * px + ix1];
                    for (d, &v) in src.iter().enumerate() {
                        s.t[(ix0 + d) * py + ky] = v;
                    }
                }
            }
            if py > 1 {
                self.fft_y.process_with_scratch(&mut s.t, &mut s.fft);
            }
            for ix in 0..nx {
                let at = (ix * nz + h) * ny;
                w[at..at + ny].copy_from_slice(&s.t[ix * py..ix * py + ny]);
            }
        }
        clipped
    }
}

simd_kernel! {
    /// The blocks M(κ) of one row κy, pair by pair across the first `fail.len()` κx
    /// (`lanes[q·w + κx]`, q the packed pair index): Z_hk · ĉ^x_hk(κx) · ĉ^y_hk(κy) /
    /// (P_x P_y). Clears `fail`.
    fn block_row(
        z: &[f64],
        kx: &[f64],
        ky: &[f64],
        row: usize,
        py: usize,
        norm: f64,
        lanes: &mut [f64],
        fail: &mut [f64],
    ) {
        let w = fail.len();
        let px = kx.len() / z.len();
        for (q, &zq) in z.iter().enumerate() {
            let cy = ky[q * py + row];
            let (spec, out) = (&kx[q * px..q * px + w], &mut lanes[q * w..(q + 1) * w]);
            for (o, &cx) in out.iter_mut().zip(spec) {
                *o = zq * cx * cy * norm;
            }
        }
        fail.fill(0.0);
    }
}

simd_kernel! {
    /// [`cholesky_lower`] of every lane's n × n block at once (`lanes` holds the packed
    /// lower triangle, pair by pair, `fail.len()` lanes each), in place, with the same
    /// operations in the same order per lane. A lane whose block is not semidefinite gets
    /// `fail` = 1 and an unusable factor. `work` holds 2 · `fail.len()` values.
    fn lower_factor_lanes(lanes: &mut [f64], n: usize, fail: &mut [f64], work: &mut [f64]) {
        let w = fail.len();
        let (scale, sum) = work.split_at_mut(w);
        scale.fill(0.0);
        for i in 0..n {
            let d = &lanes[pair(i, i) * w..(pair(i, i) + 1) * w];
            for (s, &v) in scale.iter_mut().zip(d) {
                *s = f64::max(*s, v);
            }
        }
        for i in 0..n {
            for j in 0..=i {
                sum.copy_from_slice(&lanes[pair(i, j) * w..(pair(i, j) + 1) * w]);
                for k in 0..j {
                    let (a, b) = (pair(i, k) * w, pair(j, k) * w);
                    for (l, s) in sum.iter_mut().enumerate() {
                        *s -= lanes[a + l] * lanes[b + l];
                    }
                }
                let at = pair(i, j) * w;
                if i == j {
                    for (l, (&s, bad)) in sum.iter().zip(fail.iter_mut()).enumerate() {
                        let tol = scale[l];
                        if s < -1e-9 * tol || !s.is_finite() {
                            *bad = 1.0;
                        }
                        lanes[at + l] = if s > 1e-12 * tol { s.sqrt() } else { 0.0 };
                    }
                } else {
                    let dj = pair(j, j) * w;
                    for (l, &s) in sum.iter().enumerate() {
                        let d = lanes[dj + l];
                        lanes[at + l] = if d > 0.0 { s / d } else { 0.0 };
                    }
                }
            }
        }
    }
}

/// The factored lanes κx < w of every pair spread over the whole row, in `T`, each value
/// twice: full[2(q·P_x + κx) + {0, 1}] = half[q·w + min(κx, P_x − κx)], P_x = `full.len()`
/// / (2 · pairs).
fn mirror_lanes<T: Sample>(half: &[f64], w: usize, full: &mut [T]) {
    let pairs = half.len() / w;
    let px = full.len() / (2 * pairs);
    let kept = w.min(px);
    for (h, f) in half.chunks(w).zip(full.chunks_mut(2 * px)) {
        T::narrow_pairs(&h[..kept], &mut f[..2 * kept]);
        // κx = w … P_x − 1 take the lanes P_x − κx = P_x − w … 1, in reverse.
        let (lo, hi) = f.split_at_mut(2 * kept);
        let mirrored = lo[2..2 * (px - kept + 1)].chunks_exact(2).rev();
        for (d, m) in hi.chunks_exact_mut(2).zip(mirrored) {
            d.copy_from_slice(m);
        }
    }
}

/// Row h of the factored blocks applied to the phasors, lane by lane:
/// out[κx] = Σ_{m ≤ h} L_hm(κx) ξ_m(κx), summed in the order of m, in `F`. `lanes` holds
/// each factor twice, beside the real and imaginary parts it multiplies, so the products
/// run in straight vector lanes.
#[inline(always)]
fn apply_row_in<F: Sample>(
    lanes: &[F],
    xi: &[Complex<F>],
    h: usize,
    w: usize,
    out: &mut [Complex<F>],
) {
    out.fill(Complex::default());
    for m in 0..=h {
        let q = pair(h, m);
        let (l, x) = (&lanes[2 * q * w..2 * (q + 1) * w], &xi[m * w..(m + 1) * w]);
        for ((o, l), x) in out.iter_mut().zip(l.chunks_exact(2)).zip(x) {
            *o = Complex::new(o.re + x.re * l[0], o.im + x.im * l[1]);
        }
    }
}

simd_kernel! {
    /// [`apply_row_in`] in f64.
    pub(super) fn apply_factor_row(lanes: &[f64], xi: &[C64], h: usize, w: usize, out: &mut [C64]) {
        apply_row_in(lanes, xi, h, w, out)
    }
}

simd_kernel! {
    /// [`apply_row_in`] in f32.
    pub(super) fn apply_factor_row_f32(
        lanes: &[f32],
        xi: &[Complex<f32>],
        h: usize,
        w: usize,
        out: &mut [Complex<f32>],
    ) {
        apply_row_in(lanes, xi, h, w, out)
    }
}

/// Replace the symmetric matrix `a` (n × n, row-major, both triangles) by R with
/// R Rᵀ = the nearest positive semidefinite matrix (Frobenius norm): eigen-decomposition by
/// cyclic Jacobi rotations, negative eigenvalues set to zero, R = V √Λ₊. `e` is an n × n work
/// buffer. Returns the sum of the removed (negative) eigenvalues' magnitudes.
fn nearest_semidefinite_root(a: &mut [f64], e: &mut [f64], n: usize) -> f64 {
    // e ← I; rotate a towards diagonal, accumulating the rotations in e (columns: vectors).
    e.fill(0.0);
    for i in 0..n {
        e[i * n + i] = 1.0;
    }
    for _sweep in 0..64 {
        let off: f64 = (0..n)
            .flat_map(|i| (0..i).map(move |j| (i, j)))
            .map(|(i, j)| a[i * n + j].powi(2))
            .sum();
        let diag: f64 = (0..n).map(|i| a[i * n + i].powi(2)).sum();
        if off <= 1e-30 * diag.max(f64::MIN_POSITIVE) {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq == 0.0 {
                    continue;
                }
                let theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let (akp, akq) = (a[k * n + p], a[k * n + q]);
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[p * n + k], a[q * n + k]);
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
                for k in 0..n {
                    let (ekp, ekq) = (e[k * n + p], e[k * n + q]);
                    e[k * n + p] = c * ekp - s * ekq;
                    e[k * n + q] = s * ekp + c * ekq;
                }
            }
        }
    }
    let mut removed = 0.0;
    let lambda: Vec<f64> = (0..n)
        .map(|i| {
            let l = a[i * n + i];
            if l < 0.0 {
                removed -= l;
            }
            l.max(0.0).sqrt()
        })
        .collect();
    for i in 0..n {
        for k in 0..n {
            a[i * n + k] = e[i * n + k] * lambda[k];
        }
    }
    removed
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectrum;

    #[test]
    fn folded_spectrum_is_the_dft_of_the_folded_kernel() {
        for (a, p) in [(0.3, 8usize), (0.01, 10), (2.0, 6), (0.7, 2)] {
            let mut fast = vec![0.0; p];
            folded_spectrum(a, &mut fast);
            for (k, got) in fast.iter().enumerate() {
                let want: f64 = (0..p)
                    .map(|d| {
                        let lag = d.min(p - d) as f64;
                        (-a * lag).exp() * (2.0 * PI * (k * d) as f64 / p as f64).cos()
                    })
                    .sum();
                assert!((got - want).abs() < 1e-12 * p as f64, "a {a} P {p} κ {k}: {got} {want}");
                assert!(*got >= 0.0, "a circulant of a convex decreasing kernel is PSD");
            }
        }
        assert_eq!(period(1), 1);
        assert_eq!(period(2), 2);
        assert_eq!(period(100), 200); // 2·99 = 198 = 2·3²·11 is not 5-smooth; 200 is
    }

    /// The largest difference between the covariance the method produces in `T`, built
    /// column by column from unit phasors, and the dense eq.-5 matrix with the pair-mean
    /// speed, over every pair of points, component and a few frequencies.
    fn covariance_error<T: Sample>(grid: &Grid) -> f64 {
        let params =
            WindParams { coherence_speed: CoherenceSpeed::PairMean, ..WindParams::default() };
        let n = grid.points();
        let (ny, nz) = (grid.ny(), grid.nz());
        let speeds: Vec<f64> = grid.zs.iter().map(|&z| params.mean_speed(z)).collect();
        let mut worst: f64 = 0.0;
        for comp in Component::ALL {
            let emb = Embedding::<T>::new(&params, grid, comp, 0.0).expect("regular grid");
            let mut s = emb.scratch();
            let mut w = vec![Complex::<T>::default(); n];
            for f in [0.002, 0.05, 0.4, 2.5] {
                let mut cov = vec![C64::default(); n * n];
                for col in 0..grid.nz() * emb.wavenumbers() {
                    let unit = |m: usize, k0: usize, out: &mut [Complex<T>]| {
                        for (i, o) in out.iter_mut().enumerate() {
                            let hit = m * emb.wavenumbers() + k0 + i == col;
                            let one = T::from_f64_sample(if hit { 1.0 } else { 0.0 });
                            *o = Complex::new(one, T::default());
                        }
                    };
                    let clipped = emb.line(f, &unit, &mut s, &mut w);
                    assert_eq!(clipped, 0.0, "pair-mean blocks are PSD on this grid");
                    let w: Vec<C64> = w
                        .iter()
                        .map(|c| C64::new(c.re.to_f64_sample(), c.im.to_f64_sample()))
                        .collect();
                    for a in 0..n {
                        for b in 0..n {
                            cov[a * n + b] += w[a] * w[b].conj();
                        }
                    }
                }
                // Points in the order (x, z, y).
                let pos = |p: usize| {
                    let (iy, iz, ix) = (p % ny, (p / ny) % nz, p / (ny * nz));
                    ([grid.xs[ix], grid.ys[iy], grid.zs[iz]], speeds[iz])
                };
                for a in 0..n {
                    for b in 0..n {
                        let ((pa, ua), (pb, ub)) = (pos(a), pos(b));
                        let d = [pa[0] - pb[0], pa[1] - pb[1], pa[2] - pb[2]];
                        let want = spectrum::coherence(&params, comp, f, d, 0.5 * (ua + ub));
                        let got = cov[a * n + b];
                        worst = worst.max((got.re - want).abs()).max(got.im.abs());
                    }
                }
            }
        }
        worst
    }

    /// The covariance of the field equals the dense eq.-5 matrix with the pair-mean speed at
    /// every pair of points: to rounding in f64, and to f32's precision where the spatial
    /// FFTs run in f32 (the fields the engine stores).
    #[test]
    fn covariance_equals_the_dense_pair_mean_cpsdm() {
        let grid = Grid::regular(5, 4, 3.0, &[13.0, 20.0, 38.0], 64, 0.1);
        let e64 = covariance_error::<f64>(&grid);
        assert!(e64 < 1e-9, "f64: largest covariance error {e64:e}");
        let e32 = covariance_error::<f32>(&grid);
        assert!(e32 < 1e-6, "f32: largest covariance error {e32:e}");
        assert!(e32 > e64, "the f32 path must really run in f32 ({e32:e} against {e64:e})");
        println!("largest covariance error: f64 {e64:.2e}, f32 {e32:.2e}");
        // Grids one point wide along x or y (a period of 1: no FFT that way) and the
        // smallest torus, in either precision.
        for (nx, ny, zs) in
            [(1, 4, &[13.0, 20.0, 38.0][..]), (5, 1, &[15.0, 30.0]), (2, 2, &[20.0, 25.0])]
        {
            let grid = Grid::regular(nx, ny, 3.0, zs, 64, 0.1);
            let (e64, e32) = (covariance_error::<f64>(&grid), covariance_error::<f32>(&grid));
            assert!(e64 < 1e-9 && e32 < 1e-6, "{nx}×{ny}×{}: {e64:e} / {e32:e}", zs.len());
        }
    }

    #[test]
    fn nearest_semidefinite_root_keeps_valid_matrices_and_clips_invalid_ones() {
        let n = 3;
        let valid = [4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0];
        let mut a = valid;
        let mut e = [0.0; 9];
        assert!(nearest_semidefinite_root(&mut a, &mut e, n) < 1e-12);
        for i in 0..n {
            for k in 0..n {
                let rr: f64 = (0..n).map(|m| a[i * n + m] * a[k * n + m]).sum();
                assert!((rr - valid[i * n + k]).abs() < 1e-10, "R Rᵀ reproduces the matrix");
            }
        }
        // [(a + b)²] for a, b in {0, 1}: eigenvalues 2 ± √5, so −0.236 is removed.
        let mut bad = [0.0, 1.0, 0.0, 1.0, 4.0, 0.0, 0.0, 0.0, 1.0];
        let removed = nearest_semidefinite_root(&mut bad, &mut e, n);
        assert!((removed - (5f64.sqrt() - 2.0)).abs() < 1e-10, "{removed}");
    }

    /// The pair-mean model is not a valid covariance on every grid: where it is not, the
    /// embedding still synthesises, and the coherence it produces differs from eq. 5 by no
    /// more than the bound it reports.
    #[test]
    fn the_reported_bound_covers_the_projection_error() {
        let params =
            WindParams { coherence_speed: CoherenceSpeed::PairMean, ..WindParams::default() };
        let grid = Grid::regular(9, 9, 4.0, &[11.0, 30.0, 60.0], 64, 0.1);
        let n = grid.points();
        let speeds: Vec<f64> = grid.zs.iter().map(|&z| params.mean_speed(z)).collect();
        let emb = Embedding::new(&params, &grid, Component::V, 0.0).expect("regular grid");
        let mut s = emb.scratch();
        let mut w = vec![C64::default(); n];
        let mut seen_clip = false;
        for f in [0.0005, 0.002, 0.01] {
            let mut cov = vec![C64::default(); n * n];
            let mut bound: f64 = 0.0;
            for col in 0..grid.nz() * emb.wavenumbers() {
                let unit = |m: usize, k0: usize, out: &mut [C64]| {
                    for (i, o) in out.iter_mut().enumerate() {
                        let hit = m * emb.wavenumbers() + k0 + i == col;
                        *o = C64::new(if hit { 1.0 } else { 0.0 }, 0.0);
                    }
                };
                bound = emb.line(f, &unit, &mut s, &mut w);
                for a in 0..n {
                    for b in 0..n {
                        cov[a * n + b] += w[a] * w[b].conj();
                    }
                }
            }
            seen_clip |= bound > 0.0;
            let mut worst: f64 = 0.0;
            for a in 0..n {
                for b in 0..n {
                    // (x, z, y) order: 9 heights-and-rows of 27 per x.
                    let (ia, ib) = ((a / 9) % 3, (b / 9) % 3);
                    let d = [
                        grid.xs[a / 27] - grid.xs[b / 27],
                        grid.ys[a % 9] - grid.ys[b % 9],
                        grid.zs[ia] - grid.zs[ib],
                    ];
                    let want = spectrum::coherence(
                        &params,
                        Component::V,
                        f,
                        d,
                        0.5 * (speeds[ia] + speeds[ib]),
                    );
                    worst = worst.max((cov[a * n + b].re - want).abs());
                }
            }
            assert!(worst <= bound + 1e-9, "f {f}: error {worst:e} over the bound {bound:e}");
        }
        assert!(seen_clip, "this grid must exercise the projection");
    }

    #[test]
    fn semidefinite_cholesky_zeroes_dependent_rows_and_refuses_indefinite_ones() {
        // Rank one: the second row repeats the first.
        let mut a = vec![4.0, 0.0, 4.0, 4.0];
        cholesky_lower(&mut a, 2).expect("semidefinite");
        assert_eq!((a[0], a[2], a[3]), (2.0, 2.0, 0.0));
        let mut bad = vec![1.0, 0.0, 2.0, 1.0];
        assert_eq!(cholesky_lower(&mut bad, 2), Err(1));
    }
}
