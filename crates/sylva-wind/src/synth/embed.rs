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
//! the two methods agree in distribution, not bit for bit. A block that is not positive
//! semidefinite (a coherence model that is not a valid covariance) is refused, as the dense
//! Cholesky refuses it.
//!
//! Cost per line: nz² (P_x + P_y) for the kernels, P_x P_y nz³/6 for the blocks and
//! nz P_x P_y log(P_x P_y) for the FFTs; lines are independent and run in parallel.

use std::f64::consts::PI;
use std::sync::Arc;

use rustfft::{Fft, FftPlanner};

use super::C64;
use crate::error::WindError;
use crate::grid::Grid;
use crate::params::{CoherenceSpeed, Component, WindParams};

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
    for (k, o) in out.iter_mut().enumerate() {
        // 1 − (−1)^κ ρ^m, accurate when ρ^m is close to 1.
        let lead = if k.is_multiple_of(2) { -(-m * a).exp_m1() } else { 1.0 + (-m * a).exp() };
        let s = (PI * k as f64 / p as f64).sin();
        *o = lead * one_minus_rho2 / (em1 * em1 + 4.0 * rho * s * s);
    }
}

/// Precomputed geometry and FFT plans of one component.
pub(super) struct Embedding {
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
    fft_x: Arc<dyn Fft<f64>>,
    fft_y: Arc<dyn Fft<f64>>,
}

/// Index of the pair (h, k), k ≤ h, in a packed lower triangle.
#[inline]
fn pair(h: usize, k: usize) -> usize {
    h * (h + 1) / 2 + k
}

/// Per-thread work buffers of [`Embedding::line`].
pub(super) struct Scratch {
    kx: Vec<f64>,
    ky: Vec<f64>,
    z: Vec<f64>,
    m: Vec<f64>,
    v: Vec<C64>,
    t: Vec<C64>,
    fft: Vec<C64>,
    /// The line's coherence field, laid out (z, y, x).
    pub(super) w: Vec<C64>,
}

impl Embedding {
    /// Set up the embedding of `comp` on `grid`; x and y must be regularly spaced.
    pub(super) fn new(
        params: &WindParams,
        grid: &Grid,
        comp: Component,
        u_ref: f64,
    ) -> Result<Embedding, WindError> {
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
        let mut planner = FftPlanner::new();
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
    pub(super) fn scratch(&self) -> Scratch {
        let np = self.nz * (self.nz + 1) / 2;
        let fft_len =
            self.fft_x.get_inplace_scratch_len().max(self.fft_y.get_inplace_scratch_len());
        Scratch {
            kx: vec![0.0; np * self.px],
            ky: vec![0.0; np * self.py],
            z: vec![0.0; np],
            m: vec![0.0; self.nz * self.nz],
            v: vec![C64::default(); self.nz * self.wavenumbers()],
            t: vec![C64::default(); self.nx * self.py],
            fft: vec![C64::default(); fft_len],
            w: vec![C64::default(); self.nz * self.ny * self.nx],
        }
    }

    /// The unit-variance coherence field of the line at frequency `f` (Hz) into `s.w`, laid
    /// out (z, y, x), with the phasor of height column `m` and wavenumber `κ = κy·P_x + κx`
    /// given by `xi(m, κ)`. Fails with the height row whose block is not positive
    /// semidefinite.
    pub(super) fn line(
        &self,
        f: f64,
        xi: &dyn Fn(usize, usize) -> C64,
        s: &mut Scratch,
    ) -> Result<(), usize> {
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
        for ky in 0..py {
            for kx in 0..px {
                let kappa = ky * px + kx;
                for h in 0..nz {
                    for k in 0..=h {
                        let q = pair(h, k);
                        s.m[h * nz + k] = s.z[q] * s.kx[q * px + kx] * s.ky[q * py + ky] * norm;
                    }
                }
                semidefinite_cholesky(&mut s.m, nz)?;
                for h in 0..nz {
                    let mut acc = C64::default();
                    for m in 0..=h {
                        let l = s.m[h * nz + m];
                        if l != 0.0 {
                            acc += xi(m, kappa) * l;
                        }
                    }
                    s.v[h * px * py + kappa] = acc;
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
            for ix in 0..nx {
                for ky in 0..py {
                    s.t[ix * py + ky] = plane[ky * px + ix];
                }
            }
            if py > 1 {
                self.fft_y.process_with_scratch(&mut s.t, &mut s.fft);
            }
            for iy in 0..ny {
                for ix in 0..nx {
                    s.w[(h * ny + iy) * nx + ix] = s.t[ix * py + iy];
                }
            }
        }
        Ok(())
    }
}

/// In-place lower Cholesky factor of a symmetric positive semidefinite matrix (lower
/// triangle of `a`, row-major n × n). A pivot within 1e-12 of the largest diagonal entry of
/// zero marks a dependent row: its column is set to zero (the factor of a singular matrix).
/// A pivot below −1e-9 of it means the matrix is not semidefinite: the row is returned.
fn semidefinite_cholesky(a: &mut [f64], n: usize) -> Result<(), usize> {
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

    /// The covariance the method produces, built column by column from unit phasors, equals
    /// the dense eq.-5 matrix with the pair-mean speed at every pair of points.
    #[test]
    fn covariance_equals_the_dense_pair_mean_cpsdm() {
        let params =
            WindParams { coherence_speed: CoherenceSpeed::PairMean, ..WindParams::default() };
        let grid = Grid::regular(5, 4, 3.0, &[13.0, 20.0, 38.0], 64, 0.1);
        let n = grid.points();
        let speeds: Vec<f64> = grid.zs.iter().map(|&z| params.mean_speed(z)).collect();
        for comp in Component::ALL {
            let emb = Embedding::new(&params, &grid, comp, 0.0).expect("regular grid");
            let mut s = emb.scratch();
            for f in [0.002, 0.05, 0.4, 2.5] {
                let mut cov = vec![C64::default(); n * n];
                for col in 0..grid.nz() * emb.wavenumbers() {
                    let unit = |m: usize, k: usize| {
                        C64::new(if m * emb.wavenumbers() + k == col { 1.0 } else { 0.0 }, 0.0)
                    };
                    emb.line(f, &unit, &mut s).expect("pair-mean blocks are PSD here");
                    for a in 0..n {
                        for b in 0..n {
                            cov[a * n + b] += s.w[a] * s.w[b].conj();
                        }
                    }
                }
                let pos = |p: usize| {
                    let (ix, iy, iz) = (p % 5, (p / 5) % 4, p / 20);
                    ([grid.xs[ix], grid.ys[iy], grid.zs[iz]], speeds[iz])
                };
                let mut worst: f64 = 0.0;
                for a in 0..n {
                    for b in 0..n {
                        let ((pa, ua), (pb, ub)) = (pos(a), pos(b));
                        let d = [pa[0] - pb[0], pa[1] - pb[1], pa[2] - pb[2]];
                        let want = spectrum::coherence(&params, comp, f, d, 0.5 * (ua + ub));
                        let got = cov[a * n + b];
                        worst = worst.max((got.re - want).abs()).max(got.im.abs());
                    }
                }
                assert!(worst < 1e-9, "{comp:?} f {f}: largest covariance error {worst:e}");
            }
        }
    }

    #[test]
    fn semidefinite_cholesky_zeroes_dependent_rows_and_refuses_indefinite_ones() {
        // Rank one: the second row repeats the first.
        let mut a = vec![4.0, 0.0, 4.0, 4.0];
        semidefinite_cholesky(&mut a, 2).expect("semidefinite");
        assert_eq!((a[0], a[2], a[3]), (2.0, 2.0, 0.0));
        let mut bad = vec![1.0, 0.0, 2.0, 1.0];
        assert_eq!(semidefinite_cholesky(&mut bad, 2), Err(1));
    }
}
