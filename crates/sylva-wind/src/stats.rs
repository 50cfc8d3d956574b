//! Statistics of a synthesised field against its model: σ per component, Welch
//! auto-spectra in log-spaced bands against eq. 4, and pooled co-coherence against eq. 5.
//!
//! Estimators: Welch's method with a Hann window, 50 % overlap and the record mean removed;
//! one-sided PSD per Hz. Co-coherence is the real part of the cross-spectrum normalised by the
//! auto-spectra, *pooled* over every pair of points at one separation before normalising
//! (Σ Re S_ab / √(Σ S_aa Σ S_bb)). A single-record magnitude coherence is biased upwards
//! (≈ 0.18 where the truth is 0), which is why it is not used.
//!
//! With Taylor advection the model co-coherence along x is Coh(f, Δx) · cos(ωΔx/U_c), U_c
//! the one convection speed of every height; between heights it is eq. 5's.
//!
//! Every estimate comes with the scatter one expects from the model for this grid and this
//! number of realisations ([`line_power_scatter`]): with random phases a synthesised line's
//! power is fixed at each point only up to how its points share it, and the slow lines,
//! coherent over the whole grid, scatter as a single sample. The lowest bands, where few
//! such lines fall, therefore scatter most; they are held to their scatter, not excluded.

use std::f64::consts::PI;
use std::sync::Arc;

use rayon::prelude::*;

use realfft::RealFftPlanner;
use realfft::num_complex::Complex;
use serde::{Deserialize, Serialize};

use crate::field::WindField;
use crate::params::{CoherenceSpeed, Component};
use crate::spectrum;
use crate::synth;

/// Windowed segment spectra of one record (one FFT per segment).
pub type Segments = Vec<Vec<Complex<f64>>>;

/// Welch estimator: segment length, time step and the FFT plan.
#[derive(Clone)]
pub struct Welch {
    segment: usize,
    dt: f64,
    window: Vec<f64>,
    fft: Arc<dyn realfft::RealToComplex<f64>>,
}

impl std::fmt::Debug for Welch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Welch").field("segment", &self.segment).field("dt", &self.dt).finish()
    }
}

/// Bins beyond which a line's power leaks through the Hann window by less than 1e-10 (its
/// gain falls as δ⁻⁶).
const HANN_REACH: f64 = 48.0;

impl Welch {
    /// An estimator with segments of `segment` samples (made even, at least 4) at step `dt`.
    pub fn new(segment: usize, dt: f64) -> Welch {
        let n = (segment & !1).max(4);
        let window = (0..n).map(|i| 0.5 - 0.5 * (2.0 * PI * i as f64 / n as f64).cos()).collect();
        let fft = RealFftPlanner::<f64>::new().plan_fft_forward(n);
        Welch { segment: n, dt, window, fft }
    }

    /// Segment length in samples.
    pub fn segment(&self) -> usize {
        self.segment
    }

    /// Frequencies of the one-sided bins, k = 0 … segment/2, in Hz.
    pub fn freqs(&self) -> Vec<f64> {
        (0..=self.segment / 2).map(|k| k as f64 / (self.segment as f64 * self.dt)).collect()
    }

    /// Windowed spectra of every segment of a record (record mean removed, 50 % overlap).
    ///
    /// The record is one period of a loop, so segments wrap around its end: starts at
    /// s·segment/2 for s = 0 … 2M/segment − 1. Every synthesised line then enters the set of
    /// segments with the same weight and the cross terms between lines cancel over the set,
    /// so the estimate carries the field's own scatter, not the segmentation's. (For a
    /// record that is not periodic, pass a segment length that divides nothing special:
    /// the wrap only costs one spurious seam per segment that crosses it.)
    pub fn spectra(&self, rec: &[f64]) -> Segments {
        let n = self.segment;
        let m = rec.len();
        let mean = rec.iter().sum::<f64>() / m as f64;
        let count = (2 * m / n).max(1);
        let mut out = Vec::with_capacity(count);
        let mut buf = vec![0.0; n];
        for s in 0..count {
            let start = s * n / 2;
            for i in 0..n {
                buf[i] = (rec[(start + i) % m] - mean) * self.window[i];
            }
            let mut spec = self.fft.make_output_vec();
            if self.fft.process(&mut buf, &mut spec).is_err() {
                unreachable!("segment lengths are fixed by construction");
            }
            out.push(spec);
        }
        out
    }

    /// |Ŵ(δ)|² of the Hann window's DFT at a distance of δ bins (δ real), from the closed
    /// form Ŵ = ½D(δ) − ¼D(δ−1) − ¼D(δ+1) with the Dirichlet kernel
    /// D(δ) = e^{−iπδ(n−1)/n} sin(πδ)/sin(πδ/n).
    fn hann_gain(&self, delta: f64) -> f64 {
        let n = self.segment as f64;
        let d = |x: f64| -> Complex<f64> {
            let s = (PI * x / n).sin();
            let mag = if s.abs() < 1e-12 {
                n * (PI * x).cos().signum() * (PI * x / n).cos().signum()
            } else {
                (PI * x).sin() / s
            };
            Complex::from_polar(1.0, -PI * x * (n - 1.0) / n) * mag
        };
        (d(delta) * 0.5 - d(delta - 1.0) * 0.25 - d(delta + 1.0) * 0.25).norm_sqr()
    }

    /// Expected value of the estimator, bin by bin, for a record of `m` samples made of the
    /// lines j = 1 … m/2 − 1 (frequency j/(m dt)) with random phases and variance
    /// `line_power(j)`. For [`Welch::psd`] this is the model *as the estimator sees it*,
    /// leakage of the window included; the ratio of two such sums (cross over auto) is the
    /// expected pooled co-coherence.
    pub fn expected(&self, m: usize, line_power: &dyn Fn(usize) -> f64) -> Vec<f64> {
        let n = self.segment;
        let norm = self.dt / self.window.iter().map(|w| w * w).sum::<f64>();
        let powers: Vec<f64> =
            (0..m / 2).map(|j| if j == 0 { 0.0 } else { line_power(j) }).collect();
        const REACH: f64 = HANN_REACH;
        let per_bin = m as f64 / n as f64;
        (0..=n / 2)
            .map(|k| {
                let one_sided = if k == 0 || k == n / 2 { 1.0 } else { 2.0 };
                let kf = k as f64;
                let lo = (((kf - REACH) * per_bin).floor().max(1.0)) as usize;
                let hi = (((kf + REACH) * per_bin).ceil() as usize).min(powers.len());
                let mut sum: f64 = (lo..hi)
                    .map(|j| {
                        let c = j as f64 / per_bin;
                        0.5 * powers[j] * self.hann_gain(kf - c)
                    })
                    .sum();
                // Mirror image of the negative frequencies, near DC only.
                let hi_img = (((REACH - kf).max(0.0) * per_bin).ceil() as usize).min(powers.len());
                sum += (1..hi_img)
                    .map(|j| 0.5 * powers[j] * self.hann_gain(kf + j as f64 / per_bin))
                    .sum::<f64>();
                one_sided * norm * sum
            })
            .collect()
    }

    /// One-sided PSD per Hz averaged over all records' segments.
    pub fn psd<'a>(&self, records: impl IntoIterator<Item = &'a Segments>) -> Vec<f64> {
        let norm = self.dt / self.window.iter().map(|w| w * w).sum::<f64>();
        let mut acc = vec![0.0; self.segment / 2 + 1];
        let mut count = 0usize;
        for spec in records.into_iter().flatten() {
            for (a, s) in acc.iter_mut().zip(spec) {
                *a += s.norm_sqr();
            }
            count += 1;
        }
        let last = acc.len() - 1;
        for (k, a) in acc.iter_mut().enumerate() {
            let one_sided = if k == 0 || k == last { 1.0 } else { 2.0 };
            *a *= one_sided * norm / count.max(1) as f64;
        }
        acc
    }

    /// Pooled co-coherence Σ Re S_ab / √(Σ S_aa Σ S_bb) over all pairs' segments.
    pub fn pooled_cocoherence<'a>(
        &self,
        pairs: impl IntoIterator<Item = (&'a Segments, &'a Segments)>,
    ) -> Vec<f64> {
        let nb = self.segment / 2 + 1;
        let (mut sab, mut saa, mut sbb) = (vec![0.0; nb], vec![0.0; nb], vec![0.0; nb]);
        for (sa, sb) in pairs {
            for (x, y) in sa.iter().zip(sb) {
                for k in 0..nb {
                    sab[k] += (x[k] * y[k].conj()).re;
                    saa[k] += x[k].norm_sqr();
                    sbb[k] += y[k].norm_sqr();
                }
            }
        }
        (0..nb)
            .map(|k| if saa[k] > 0.0 { sab[k] / (saa[k] * sbb[k]).sqrt() } else { 0.0 })
            .collect()
    }
}

/// Log-spaced bands over bins 1 … n−2 (DC and Nyquist excluded: the synthesis leaves both
/// empty, so the window's leakage biases the Nyquist bin low). Each band lists its bin
/// indices; `per_decade` bands per decade; empty bands are dropped.
pub fn log_bands(freqs: &[f64], per_decade: f64) -> Vec<Vec<usize>> {
    let (f1, fmax) = (freqs[1], freqs[freqs.len() - 1]);
    let nb = ((fmax / f1).log10() * per_decade).ceil().max(1.0) as usize;
    let mut bands = vec![Vec::new(); nb];
    for (k, &f) in freqs.iter().enumerate().take(freqs.len() - 1).skip(1) {
        let b = (((f / f1).log10() * per_decade) as usize).min(nb - 1);
        bands[b].push(k);
    }
    bands.retain(|b| !b.is_empty());
    bands
}

/// One row of a spectral comparison.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BandRow {
    /// Geometric centre frequency of the band, Hz.
    pub f: f64,
    /// Measured value averaged over the band.
    pub measured: f64,
    /// Model value the estimator expects (the discrete model lines seen through the window,
    /// leakage included), averaged over the band.
    pub model: f64,
    /// Expected scatter (one standard deviation) over realisations, from the model, for
    /// Gaussian amplitudes: of `measured/model − 1` for spectra ([`line_power_scatter`] over
    /// the band's lines), of `measured − model` for co-coherence (the delta method over the
    /// pooled pairs, which share their slow lines; for two heights at the same points it
    /// reduces to (1 − γ²)/√(2n), Bendat & Piersol, *Random Data*, §9.2).
    pub scatter: f64,
}

impl BandRow {
    /// Relative error measured/model − 1.
    pub fn rel_error(&self) -> f64 {
        self.measured / self.model - 1.0
    }
}

/// Co-coherence against eq. 5 at one separation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CoherenceRow {
    /// Axis of the separation: "x", "y" or "z".
    pub axis: String,
    /// Separation in grid steps.
    pub steps: usize,
    /// Separation in m.
    pub metres: f64,
    /// Bands (f, measured, expected model) — only bands where the model exceeds 0.02.
    pub bands: Vec<BandRow>,
}

impl CoherenceRow {
    /// Largest |measured − model| over bands where the model exceeds `above`.
    pub fn max_abs_error(&self, above: f64) -> f64 {
        self.bands
            .iter()
            .filter(|b| b.model > above)
            .map(|b| (b.measured - b.model).abs())
            .fold(0.0, f64::max)
    }
}

/// Per-component statistics of a field.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ComponentStats {
    /// Component letter.
    pub component: String,
    /// Measured σ of the fluctuations (all points and frames at this height, all fields), m/s.
    pub sigma: f64,
    /// σ of the discrete target Σ 2 S0 Δω, m/s.
    pub sigma_target: f64,
    /// σ/σ_target − 1.
    pub sigma_error: f64,
    /// σ²/σ_target² − 1 (about twice `sigma_error`).
    pub variance_error: f64,
    /// Expected scatter (one standard deviation) of `sigma_error` over realisations of this
    /// grid with this many fields, from the model ([`line_power_scatter`]).
    pub sigma_scatter: f64,
    /// σ of the model (infinite loop), m/s.
    pub sigma_model: f64,
    /// Measured mean, m/s.
    pub mean: f64,
    /// Auto-spectrum against eq. 4 in log bands.
    pub spectrum: Vec<BandRow>,
    /// Co-coherence against eq. 5 at several separations.
    pub coherence: Vec<CoherenceRow>,
}

impl ComponentStats {
    /// The σ error in units of its expected scatter (∞ when no scatter is expected and the
    /// error is not zero).
    pub fn sigma_deviations(&self) -> f64 {
        let e = self.sigma_error.abs();
        if self.sigma_scatter > 0.0 {
            e / self.sigma_scatter
        } else if e > 0.0 {
            f64::INFINITY
        } else {
            0.0
        }
    }
}

/// Statistics of every component at one height.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FieldStats {
    /// Height (m) the statistics were taken at.
    pub height: f64,
    /// Index of that height in the grid.
    pub height_index: usize,
    /// Number of fields (realisations) pooled.
    pub fields: usize,
    /// Mean speed in the coherence denominator of eq. 5 for two points at this height, m/s
    /// (the reference speed, or Ū(z) itself with the pair-mean speed).
    pub coherence_speed: f64,
    /// Welch segment length used.
    pub segment: usize,
    /// Per component u, v, w.
    pub components: Vec<ComponentStats>,
}

/// Statistics of `field` at its first height. Separations of 1, 2 and 4 grid steps along x
/// and y (those that fit) and one step up where there is a second height. `segment`: Welch
/// segment length (None: frames/8, at least 32).
pub fn field_stats(field: &WindField, segment: Option<usize>) -> FieldStats {
    ensemble_stats(std::slice::from_ref(field), segment)
}

/// [`ensemble_stats_at`] at the first height.
pub fn ensemble_stats(fields: &[WindField], segment: Option<usize>) -> FieldStats {
    ensemble_stats_at(fields, segment, 0)
}

/// Relative scatter of the power one synthesised line carries at one height, averaged over
/// the height's points: the variance of Y_j = (1/N) Σ_p |w_p|² with w the line's unit
/// coherence field, Var Y_j ≤ (1/N²) Σ_pq |Coh_pq|² (equality for Gaussian amplitudes; random
/// phases on a factor scatter a little less, so this is an upper bound). Coh is separable
/// along x and y at one height, so the double sum is a product of two 1-D sums. Lines
/// coherent over the whole grid (the slow ones) scatter as one sample; lines whose
/// coherence length is below the spacing average over all N points.
pub fn line_power_scatter(xs: &[f64], ys: &[f64], cx: f64, cy: f64, f: f64, u: f64) -> f64 {
    let axis_sum = |c: &[f64], k: f64| -> f64 {
        let a = 2.0 * f * k / u;
        if let Some(g) = crate::Grid::regular_spacing(c) {
            let n = c.len();
            let rho = (-a * g).exp();
            let mut s = n as f64;
            let mut r = 1.0;
            for d in 1..n {
                r *= rho;
                if r < 1e-18 {
                    break;
                }
                s += 2.0 * (n - d) as f64 * r;
            }
            s
        } else {
            c.iter().map(|p| c.iter().map(|q| (-a * (p - q).abs()).exp()).sum::<f64>()).sum()
        }
    };
    let n = (xs.len() * ys.len()) as f64;
    axis_sum(xs, cx) * axis_sum(ys, cy) / (n * n)
}

/// Variance of one line's contribution to a pooled co-coherence estimate between points
/// `s` steps apart along an axis with coordinates `c` (other axis: coordinates `o`), for
/// Gaussian amplitudes, by the delta method: with A = Σ Re w_a w_b*, B = Σ |w_a|²,
/// D = Σ |w_b|² over the pairs and γ the band's model co-coherence,
///   Var = [Var A + γ²/4 (Var B + Var D + 2 Cov(B, D)) − γ (Cov(A, B) + Cov(A, D))] / N_p²,
/// every term a product of a sum along the axis and Σ Coh² across it (the horizontal
/// coherence is separable). `a`, `a_o`: decay per metre e^{−a|Δ|} along and across.
/// Neighbouring pairs share their slow lines, so this is much larger than (1 − γ²)²/(2N).
fn pair_line_variance(c: &[f64], o: &[f64], s: usize, a: f64, a_o: f64, gamma: f64) -> f64 {
    let n = c.len();
    if s >= n {
        return 0.0;
    }
    let x = |i: usize, k: usize| (-a * (c[i] - c[k]).abs()).exp();
    let (mut taa, mut tbb, mut tdd, mut tbd, mut tab, mut tad) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for i in 0..n - s {
        for k in 0..n - s {
            let (ik, is_ks, i_ks, is_k) = (x(i, k), x(i + s, k + s), x(i, k + s), x(i + s, k));
            taa += 0.5 * (ik * is_ks + i_ks * is_k);
            tbb += ik * ik;
            tdd += is_ks * is_ks;
            tbd += i_ks * i_ks;
            tab += ik * is_k;
            tad += i_ks * is_ks;
        }
    }
    let across: f64 =
        o.iter().map(|p| o.iter().map(|q| (-2.0 * a_o * (p - q).abs()).exp()).sum::<f64>()).sum();
    let np = ((n - s) * o.len()) as f64;
    let v = taa + gamma * gamma / 4.0 * (tbb + tdd + 2.0 * tbd) - gamma * (tab + tad);
    (v.max(0.0) * across) / (np * np)
}

/// Statistics pooled over an ensemble of fields that share grid and parameters (different
/// seeds), at height index `iz`: the mean, variance, spectra and co-coherence estimators
/// average over every field's records. One realisation of a grid only holds as many
/// independent samples of a low frequency as the grid spans coherence lengths at that
/// frequency; an ensemble adds more, and the scatter estimates shrink with it.
///
/// The models are those the fields were generated with: the coherence speed of
/// [`crate::WindParams::coherence_speed`], and with advection the x co-coherence
/// Coh · cos(ωΔx/Ū(z)) and the z co-coherence Coh times the mean over the grid's x of
/// cos(ω (x − x_c)(1/Ū_h − 1/Ū_k)).
///
/// # Panics
/// If `fields` is empty, the fields' grids differ or `iz` is outside the grid (a programming
/// error, not input).
pub fn ensemble_stats_at(fields: &[WindField], segment: Option<usize>, iz: usize) -> FieldStats {
    let e = Ensemble::new(fields, segment, iz);
    let components = Component::ALL.into_iter().map(|comp| e.component(comp)).collect();
    FieldStats {
        height: e.z,
        height_index: iz,
        fields: fields.len(),
        coherence_speed: e.u_same,
        segment: e.welch.segment(),
        components,
    }
}

/// What every table of [`ensemble_stats_at`] shares: the fields at one height, the Welch
/// estimator and its bands, and the model's speeds there.
struct Ensemble<'a> {
    fields: &'a [WindField],
    g: &'a crate::grid::Grid,
    p: &'a crate::params::WindParams,
    iz: usize,
    m: usize,
    welch: Welch,
    freqs: Vec<f64>,
    bands: Vec<Vec<usize>>,
    z: f64,
    u_local: f64,
    u_same: f64,
    /// The convection speed U_c the field advects at.
    u_conv: f64,
    df: f64,
    per_bin: f64,
    nfields: f64,
    per_field: usize,
}

/// One component's estimates and the model's line powers, shared by its tables.
struct ComponentEstimate<'a> {
    e: &'a Ensemble<'a>,
    comp: Component,
    cc: crate::params::CoherenceConstants,
    specs: Vec<Segments>,
    /// Scatter of each line's power over realisations (pooled fields are independent).
    line_var: Vec<f64>,
    expected_auto: Vec<f64>,
}

impl<'a> Ensemble<'a> {
    fn new(fields: &'a [WindField], segment: Option<usize>, iz: usize) -> Ensemble<'a> {
        let field = &fields[0];
        assert!(fields.iter().all(|f| f.grid == field.grid), "ensemble fields must share a grid");
        let g = &field.grid;
        assert!(iz < g.nz(), "height index {iz} outside the grid");
        let m = g.frames;
        let welch = Welch::new(segment.unwrap_or((m / 8).max(32)).min(m), g.dt);
        let seg = welch.segment();
        let freqs = welch.freqs();
        let bands = log_bands(&freqs, 8.0);
        let z = g.zs[iz];
        let p = &field.params;
        let u_local = p.mean_speed(z);
        let u_same = match p.coherence_speed {
            CoherenceSpeed::Reference => synth::reference_speed(p, g),
            CoherenceSpeed::PairMean => u_local,
        };
        let u_conv = synth::convection_speed(p, g);
        let df = 1.0 / (m as f64 * g.dt);
        let per_bin = m as f64 / seg as f64;
        let nfields = fields.len() as f64;
        let per_field = g.nx() * g.ny();
        Ensemble {
            fields,
            g,
            p,
            iz,
            m,
            welch,
            freqs,
            bands,
            z,
            u_local,
            u_same,
            u_conv,
            df,
            per_bin,
            nfields,
            per_field,
        }
    }

    /// Rows of measured against model per band, the bands where `keep` holds of the model.
    fn band_rows(
        &self,
        meas: &[f64],
        model: &[f64],
        keep: &dyn Fn(f64) -> bool,
        scatter: &dyn Fn(&[usize], f64) -> f64,
    ) -> Vec<BandRow> {
        let (bands, freqs) = (&self.bands, &self.freqs);
        let mut rows = Vec::new();
        for b in bands {
            let mv = b.iter().map(|&k| model[k]).sum::<f64>() / b.len() as f64;
            if !keep(mv) {
                continue;
            }
            let me = b.iter().map(|&k| meas[k]).sum::<f64>() / b.len() as f64;
            let f = (freqs[b[0]] * freqs[b[b.len() - 1]]).sqrt();
            rows.push(BandRow { f, measured: me, model: mv, scatter: scatter(b, mv) });
        }
        rows
    }

    /// Every field's record of `comp` at height index `level`, point by point.
    fn records(&self, comp: Component, level: usize) -> Vec<Vec<f64>> {
        let g = self.g;
        self.fields
            .iter()
            .flat_map(|f| {
                (0..self.per_field).map(move |q| f.record(comp, level, q / g.nx(), q % g.nx()))
            })
            .collect()
    }

    /// The statistics of one component: σ against its target, the spectrum by band, and
    /// the co-coherence along x, y and one step up.
    fn component(&self, comp: Component) -> ComponentStats {
        let (g, p, m, z) = (self.g, self.p, self.m, self.z);
        let welch = &self.welch;
        let recs = self.records(comp, self.iz);
        let n = (recs.len() * m) as f64;
        let mean = recs.iter().flatten().sum::<f64>() / n;
        let var = recs.iter().flatten().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
        let specs: Vec<Segments> = recs.par_iter().map(|r| welch.spectra(r)).collect();
        let psd = welch.psd(&specs);
        let cc = p.coherence[comp.index()];
        let (df, nfields, u_same) = (self.df, self.nfields, self.u_same);
        let line_var: Vec<f64> = (0..m / 2)
            .map(|j| {
                if j == 0 {
                    0.0
                } else {
                    line_power_scatter(&g.xs, &g.ys, cc.cx, cc.cy, j as f64 * df, u_same) / nfields
                }
            })
            .collect();
        let line = |j: usize| spectrum::one_sided(p, comp, j as f64 * df, z) * df;
        let expected_auto = welch.expected(m, &line);
        let est = ComponentEstimate { e: self, comp, cc, specs, line_var, expected_auto };
        let all_lines: Vec<(usize, f64)> = (1..m / 2).map(|j| (j, est.line(j))).collect();
        let spectrum =
            self.band_rows(&psd, &est.expected_auto, &|_| true, &|b, _| est.band_scatter(b));
        let mut coherence = est.xy_coherence();
        coherence.extend(est.z_coherence());
        let cap = self.fields[0].captured();
        let sigma_target = spectrum::discrete_variance(p, comp, z, m, g.dt).sqrt();
        let sigma = var.sqrt();
        ComponentStats {
            component: comp.name().into(),
            sigma,
            sigma_target,
            sigma_error: sigma / sigma_target - 1.0,
            variance_error: var / (sigma_target * sigma_target) - 1.0,
            sigma_scatter: 0.5 * weighted_scatter(&all_lines, &|j| est.line_var[j]),
            sigma_model: cap.sigma_model[comp.index()],
            mean,
            spectrum,
            coherence,
        }
    }
}

/// The scatter of a sum of line powers `w` (line, power), each line's power scattering by
/// `var(line)`, relative to the sum.
fn weighted_scatter(w: &[(usize, f64)], var: &dyn Fn(usize) -> f64) -> f64 {
    let pw: f64 = w.iter().map(|p| p.1).sum();
    let v: f64 = w.iter().map(|&(j, p)| p * p * var(j)).sum();
    if pw > 0.0 { v.sqrt() / pw } else { 0.0 }
}

impl ComponentEstimate<'_> {
    /// The model's power in synthesised line `j`.
    fn line(&self, j: usize) -> f64 {
        let e = self.e;
        spectrum::one_sided(e.p, self.comp, j as f64 * e.df, e.z) * e.df
    }

    /// The synthesised lines a band of Welch bins sees, each with the power it brings to
    /// the band through the window (the Hann main lobe spans ±2 bins, so the slow, strong
    /// lines just below a band weigh on it). A line is summed over the band's bins within
    /// [`HANN_REACH`] of it only, beyond which the window passes less than 1e-10 of its
    /// power: so a band costs its lines, not its lines times its bins, and the statistics
    /// of a long record grow as its length, not its square.
    fn band_lines(&self, b: &[usize]) -> Vec<(usize, f64)> {
        let (m, per_bin) = (self.e.m, self.e.per_bin);
        let lo = ((b[0] as f64 - 4.0) * per_bin).floor().max(1.0) as usize;
        let hi = (((b[b.len() - 1] as f64 + 4.0) * per_bin).ceil() as usize).min(m / 2);
        (lo..hi)
            .map(|j| {
                let c = j as f64 / per_bin;
                let near = b.partition_point(|&k| (k as f64) < c - HANN_REACH)
                    ..b.partition_point(|&k| (k as f64) <= c + HANN_REACH);
                let gain: f64 = b[near].iter().map(|&k| self.e.welch.hann_gain(k as f64 - c)).sum();
                (j, self.line(j) * gain)
            })
            .collect()
    }

    fn band_scatter(&self, b: &[usize]) -> f64 {
        weighted_scatter(&self.band_lines(b), &|j| self.line_var[j])
    }

    /// Pooled co-coherence at 1, 2 and 4 grid steps along x and along y.
    fn xy_coherence(&self) -> Vec<CoherenceRow> {
        let e = self.e;
        let (g, p, m, comp, cc) = (e.g, e.p, e.m, self.comp, self.cc);
        let (df, nfields, u_same, u_conv) = (e.df, e.nfields, e.u_same, e.u_conv);
        let (fields, per_field, welch, specs) = (e.fields, e.per_field, &e.welch, &self.specs);
        let line = |j: usize| self.line(j);
        let mut coherence = Vec::new();
        for (axis, coords, n_axis) in [("x", &g.xs, g.nx()), ("y", &g.ys, g.ny())] {
            for steps in [1usize, 2, 4] {
                if steps >= n_axis {
                    continue;
                }
                let metres = coords[steps] - coords[0];
                let mut pairs = Vec::new();
                for base in (0..fields.len()).map(|i| i * per_field) {
                    for iy in 0..g.ny() {
                        for ix in 0..g.nx() {
                            let (jx, jy) =
                                if axis == "x" { (ix + steps, iy) } else { (ix, iy + steps) };
                            if jx < g.nx() && jy < g.ny() {
                                pairs.push((base + iy * g.nx() + ix, base + jy * g.nx() + jx));
                            }
                        }
                    }
                }
                let coh =
                    welch.pooled_cocoherence(pairs.iter().map(|&(a, b)| (&specs[a], &specs[b])));
                let d = if axis == "x" { [metres, 0.0, 0.0] } else { [0.0, metres, 0.0] };
                let model = |f: f64| {
                    let c = spectrum::coherence(p, comp, f, d, u_same);
                    if p.advection { c * (2.0 * PI * f * d[0] / u_conv).cos() } else { c }
                };
                let cross = welch.expected(m, &|j| line(j) * model(j as f64 * df));
                let expected: Vec<f64> =
                    cross.iter().zip(&self.expected_auto).map(|(c, a)| c / a).collect();
                let (along, across, c_along, c_across) = if axis == "x" {
                    (&g.xs, &g.ys, cc.cx, cc.cy)
                } else {
                    (&g.ys, &g.xs, cc.cy, cc.cx)
                };
                let pair_scatter = |b: &[usize], gamma: f64| {
                    let var = |j: usize| {
                        let f = j as f64 * df;
                        let (a, a_o) = (f * c_along / u_same, f * c_across / u_same);
                        pair_line_variance(along, across, steps, a, a_o, gamma) / nfields
                    };
                    weighted_scatter(&self.band_lines(b), &var)
                };
                let bands = e.band_rows(&coh, &expected, &|mv| mv > 0.02, &pair_scatter);
                coherence.push(CoherenceRow { axis: axis.into(), steps, metres, bands });
            }
        }
        coherence
    }

    /// Pooled co-coherence of every point with the point one height above it, if any.
    fn z_coherence(&self) -> Option<CoherenceRow> {
        let e = self.e;
        let (g, p, m, comp, z, iz) = (e.g, e.p, e.m, self.comp, e.z, e.iz);
        let (df, u_same, u_local, welch) = (e.df, e.u_same, e.u_local, &e.welch);
        if iz + 1 >= g.nz() {
            return None;
        }
        let line = |j: usize| self.line(j);
        // Two heights at the same points: the classic (1 − γ²)/√(2n), n the band's effective
        // number of independent samples.
        let coh_scatter = |b: &[usize], gamma: f64| {
            (1.0 - gamma * gamma).max(0.0) * self.band_scatter(b) / std::f64::consts::SQRT_2
        };
        let z2 = g.zs[iz + 1];
        let upper: Vec<Segments> =
            e.records(comp, iz + 1).par_iter().map(|r| welch.spectra(r)).collect();
        let coh = welch.pooled_cocoherence(self.specs.iter().zip(&upper));
        let u_up = p.mean_speed(z2);
        let um = match p.coherence_speed {
            CoherenceSpeed::Reference => u_same,
            CoherenceSpeed::PairMean => 0.5 * (u_local + u_up),
        };
        // Every height advects at the one convection speed: no phase between heights.
        let model = |f: f64| spectrum::coherence(p, comp, f, [0.0, 0.0, z2 - z], um);
        // The two heights have different spectra: the expected pooled co-coherence is the
        // cross term over the geometric mean of the two auto terms.
        let line_up = |j: usize| spectrum::one_sided(p, comp, j as f64 * df, z2) * df;
        let cross = welch.expected(m, &|j| (line(j) * line_up(j)).sqrt() * model(j as f64 * df));
        let auto_up = welch.expected(m, &line_up);
        let expected: Vec<f64> = cross
            .iter()
            .zip(self.expected_auto.iter().zip(&auto_up))
            .map(|(c, (a, b))| c / (a * b).sqrt())
            .collect();
        let bands = e.band_rows(&coh, &expected, &|mv| mv > 0.02, &coh_scatter);
        Some(CoherenceRow { axis: "z".into(), steps: 1, metres: z2 - z, bands })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welch_of_a_sine_puts_its_power_at_its_frequency() {
        let dt = 0.1;
        let n = 4096;
        let f0 = 1.25; // exactly on a bin of a 256-sample segment: 1.25 · 25.6 = 32
        let amp: f64 = 2.0;
        let rec: Vec<f64> = (0..n).map(|i| amp * (2.0 * PI * f0 * i as f64 * dt).sin()).collect();
        let w = Welch::new(256, dt);
        let psd = w.psd([&w.spectra(&rec)]);
        let df = 1.0 / (256.0 * dt);
        let total: f64 = psd.iter().sum::<f64>() * df;
        assert!((total / (amp * amp / 2.0) - 1.0).abs() < 0.01, "power {total}");
        let peak = psd.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).map(|p| p.0);
        assert_eq!(peak, Some(32));
    }

    #[test]
    fn cocoherence_of_identical_and_opposite_records() {
        let rec: Vec<f64> = (0..1024).map(|i| ((i * 7919) % 101) as f64 - 50.0).collect();
        let neg: Vec<f64> = rec.iter().map(|x| -x).collect();
        let w = Welch::new(128, 1.0);
        let (a, b) = (w.spectra(&rec), w.spectra(&neg));
        let same = w.pooled_cocoherence([(&a, &a)]);
        let opp = w.pooled_cocoherence([(&a, &b)]);
        for k in 1..64 {
            assert!((same[k] - 1.0).abs() < 1e-12 && (opp[k] + 1.0).abs() < 1e-12);
        }
    }
}
