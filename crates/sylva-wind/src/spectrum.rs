//! Point spectra (paper eq. 4) and coherence (paper eq. 5).
//!
//! Conventions — the main pitfall of the paper: eq. 4 prints the **one-sided spectrum per
//! hertz** S1(f), whose integral over f ∈ (0, ∞) is the variance σ². The spectral
//! representation of eqs. 6–7 needs the **two-sided spectrum per rad/s**,
//! S0(ω) = S1(ω/2π) / (4π), whose integral over ω ∈ (−∞, ∞) is σ². Feeding S1 to eq. 6
//! inflates σ by √(4π) ≈ 3.54.
//!
//! A synthesised record of `M` frames at step `dt` holds the lines ω_j = j Δω,
//! Δω = 2π/(M dt), j = 1 … M/2 − 1 (DC and Nyquist are zero), so its variance is the
//! discrete sum Σ 2 S0(ω_j) Δω ([`discrete_variance`]), a fraction of σ² that
//! [`captured_fraction`] reports: slow gusts longer than the loop are lost.

use std::f64::consts::PI;

use crate::params::{Component, SpectrumModel, WindParams};

/// Ratio σ/U* of each component (paper: integrals of eq. 4 with Table 1).
pub const SIGMA_PER_U_STAR: [f64; 3] = [2.5, 2.0, 1.25];

/// IEC length-scale parameter Λ = 0.7 min(z, 60 m).
fn iec_lambda(z: f64) -> f64 {
    0.7 * z.clamp(1.0, 60.0)
}

/// One-sided point spectrum S1(f) in (m/s)²/Hz of `comp` at frequency `f` (Hz, > 0) and
/// height `z` (m).
pub fn one_sided(params: &WindParams, comp: Component, f: f64, z: f64) -> f64 {
    let ubar = params.mean_speed(z);
    let c = comp.index();
    match params.spectrum {
        SpectrumModel::Paper => {
            let k = params.spectrum_constants[c];
            let nu = f * z / ubar;
            params.u_star * params.u_star * k.a * nu / (1.0 + k.b * nu).powf(5.0 / 3.0) / f
        }
        SpectrumModel::Kaimal => {
            let sigma = SIGMA_PER_U_STAR[c] * params.u_star;
            let l = iec_lambda(z) * [8.1, 2.7, 0.66][c];
            let x = f * l / ubar;
            sigma * sigma * 4.0 * x / (1.0 + 6.0 * x).powf(5.0 / 3.0) / f
        }
        SpectrumModel::VonKarman => {
            let sigma = SIGMA_PER_U_STAR[c] * params.u_star;
            let x = f * 3.5 * iec_lambda(z) / ubar;
            let fs = if c == 0 {
                4.0 * x / (1.0 + 70.8 * x * x).powf(5.0 / 6.0)
            } else {
                4.0 * x * (1.0 + 755.2 * x * x) / (1.0 + 283.2 * x * x).powf(11.0 / 6.0)
            };
            sigma * sigma * fs / f
        }
    }
}

/// Two-sided spectrum S0(ω) in (m/s)²/(rad/s) at angular frequency ω (rad/s):
/// S0(ω) = S1(ω/2π)/(4π).
pub fn two_sided(params: &WindParams, comp: Component, omega: f64, z: f64) -> f64 {
    one_sided(params, comp, omega / (2.0 * PI), z) / (4.0 * PI)
}

/// The model variance σ² of `comp` in (m/s)² (the integral of S1 over all frequencies).
///
/// For the paper's spectrum this is the closed form 1.5 A/B U*²; the IEC forms are
/// normalised to σ = (2.5, 2.0, 1.25) U*.
pub fn model_variance(params: &WindParams, comp: Component) -> f64 {
    let c = comp.index();
    match params.spectrum {
        SpectrumModel::Paper => {
            let k = params.spectrum_constants[c];
            1.5 * k.a / k.b * params.u_star * params.u_star
        }
        SpectrumModel::Kaimal | SpectrumModel::VonKarman => {
            (SIGMA_PER_U_STAR[c] * params.u_star).powi(2)
        }
    }
}

/// Variance Σ_j 2 S0(ω_j) Δω actually present in a loop of `frames` frames at step `dt`.
pub fn discrete_variance(
    params: &WindParams,
    comp: Component,
    z: f64,
    frames: usize,
    dt: f64,
) -> f64 {
    let dw = 2.0 * PI / (frames as f64 * dt);
    (1..frames / 2).map(|j| 2.0 * two_sided(params, comp, j as f64 * dw, z) * dw).sum()
}

/// Fraction of the model variance σ² that a loop of `frames` frames at `dt` captures.
pub fn captured_fraction(
    params: &WindParams,
    comp: Component,
    z: f64,
    frames: usize,
    dt: f64,
) -> f64 {
    discrete_variance(params, comp, z, frames, dt) / model_variance(params, comp)
}

/// Coherence of eq. 5 between two points separated by (dx, dy, dz) metres, at frequency
/// `f` (Hz), with mean speed `u_m` (m/s) in the denominator.
pub fn coherence(params: &WindParams, comp: Component, f: f64, d: [f64; 3], u_m: f64) -> f64 {
    let c = params.coherence[comp.index()];
    (-f * (c.cx * d[0].abs() + c.cy * d[1].abs() + c.cz * d[2].abs()) / u_m).exp()
}

/// Integrate S1 numerically over f ∈ [1e-7, 1e6] Hz on a log grid (Simpson in ln f).
/// Used to check the closed forms of [`model_variance`].
pub fn integrate_one_sided(params: &WindParams, comp: Component, z: f64) -> f64 {
    let (a, b) = (1e-7f64.ln(), 1e6f64.ln());
    let n = 40_000;
    let h = (b - a) / n as f64;
    let g = |s: f64| {
        let f = s.exp();
        one_sided(params, comp, f, z) * f
    };
    let mut sum = g(a) + g(b);
    for i in 1..n {
        sum += g(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    sum * h / 3.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Preset;

    #[test]
    fn eq4_integrates_to_sigma_ratios_2_5_2_0_1_25_u_star() {
        // Catches the 4π pitfall and any wrong Table-1 constant.
        for preset in Preset::ALL {
            let p = preset.params();
            for (comp, ratio) in Component::ALL.into_iter().zip(SIGMA_PER_U_STAR) {
                for z in [5.0, 20.0, 60.0] {
                    let sigma = integrate_one_sided(&p, comp, z).sqrt();
                    let want = ratio * p.u_star;
                    assert!(
                        (sigma / want - 1.0).abs() < 2e-3,
                        "{preset:?} {comp:?} z={z}: σ={sigma} want {want}"
                    );
                }
            }
        }
    }

    #[test]
    fn iec_spectra_integrate_to_their_sigma() {
        for model in [SpectrumModel::Kaimal, SpectrumModel::VonKarman] {
            let p = WindParams { spectrum: model, ..WindParams::default() };
            for comp in Component::ALL {
                let got = integrate_one_sided(&p, comp, 20.0);
                let want = model_variance(&p, comp);
                assert!((got / want - 1.0).abs() < 5e-3, "{model:?} {comp:?}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn two_sided_per_rad_integrates_to_the_same_variance() {
        // ∫_{-∞}^{∞} S0(ω) dω = 2 ∫_0^∞ S1(ω/2π)/(4π) dω = ∫_0^∞ S1(f) df.
        let p = WindParams::default();
        let frames = 1 << 22;
        let dt = 0.01;
        let disc = discrete_variance(&p, Component::U, 20.0, frames, dt);
        let sigma2 = model_variance(&p, Component::U);
        assert!((disc / sigma2 - 1.0).abs() < 0.02, "{disc} vs {sigma2}");
    }

    #[test]
    fn longer_loops_capture_more_variance() {
        // DESIGN §3: 1000 frames at 20 fps keep about half of σ_u²; 10 minutes about 90 %.
        let p = WindParams::default();
        let short = captured_fraction(&p, Component::U, 20.0, 1000, 0.05);
        let long = captured_fraction(&p, Component::U, 20.0, 12000, 0.05);
        assert!(short > 0.3 && short < 0.75, "short loop keeps {short}");
        assert!(long > 0.8 && long < 1.0, "10-minute loop keeps {long}");
    }

    #[test]
    fn coherence_is_one_at_zero_separation_and_decays() {
        let p = WindParams::default();
        assert_eq!(coherence(&p, Component::U, 0.3, [0.0; 3], 5.0), 1.0);
        let c1 = coherence(&p, Component::U, 0.3, [0.0, 2.0, 0.0], 5.0);
        assert!((c1 - (-0.3f64 * 19.7 * 2.0 / 5.0).exp()).abs() < 1e-15);
        assert!(coherence(&p, Component::U, 0.6, [0.0, 2.0, 0.0], 5.0) < c1);
    }
}
