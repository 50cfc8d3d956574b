//! Wind model parameters (paper §3, eqs. 1, 3–5; Tables 1–2).
//!
//! [`WindParams`] gathers everything that defines the *statistics* of a field: the mean
//! profile Ū(z), the friction velocity U* that scales both the profile and the spectra, the
//! spectral model, the coherence decay constants, the mean direction and Taylor advection.
//! The *sampling* of a field (grid, frames, time step, seed) lives in [`crate::Grid`] and
//! [`crate::SynthParams`]. Parameters are validated once by [`WindParams::validate`]; the
//! synthesis trusts them afterwards.

use serde::{Deserialize, Serialize};

use crate::error::ParamError;

/// von Kármán's constant κ of the log law.
pub const KARMAN: f64 = 0.4;

/// Density of air ρ in kg/m³ used by the drag law (eq. 8).
pub const AIR_DENSITY: f64 = 1.2;

/// One of the three velocity components of the wind frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Component {
    /// Longitudinal (along the mean wind), `u`.
    U,
    /// Lateral (horizontal, across the wind), `v`.
    V,
    /// Vertical, `w`.
    W,
}

impl Component {
    /// The three components in storage order.
    pub const ALL: [Component; 3] = [Component::U, Component::V, Component::W];

    /// Index 0, 1, 2 in storage order.
    pub fn index(self) -> usize {
        match self {
            Component::U => 0,
            Component::V => 1,
            Component::W => 2,
        }
    }

    /// Lower-case letter, `u`, `v` or `w`.
    pub fn name(self) -> &'static str {
        match self {
            Component::U => "u",
            Component::V => "v",
            Component::W => "w",
        }
    }
}

/// Mean wind speed profile Ū(z).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Profile {
    /// Logarithmic law Ū(z) = (U*/κ) ln((z − d)/z0), κ = 0.4, using [`WindParams::u_star`].
    /// Over a forest canopy of height h: d ≈ ⅔h, z0 ≈ 0.1h. Below d + z0 the speed is
    /// clamped to its value at d + 2·z0 (the law is not defined inside the canopy).
    Log {
        /// Roughness length z0 in m (> 0). Forest canopy: ≈ 0.1 × canopy height.
        z0: f64,
        /// Zero-plane displacement d in m (≥ 0). Forest canopy: ≈ ⅔ × canopy height.
        d: f64,
    },
    /// Over and in a forest: the log law of `z0`, `d` above the canopy top `h`, and inside it
    /// the exponential law Ū(z) = Ū(h) exp(a (z/h − 1)) (Cionco 1965, "A mathematical model
    /// for air flow in a vegetative canopy", J. Appl. Meteorol. 4), continuous at h, with the
    /// canopy's attenuation `a` ([`canopy_attenuation`] from its leaf area).
    Canopy {
        /// Canopy top h in m (> d + z0).
        h: f64,
        /// Attenuation a (0 < a ≤ 10): about 1–4 in forests (Cionco 1965, 1978).
        a: f64,
        /// Roughness length z0 of the log law above, m (> 0).
        z0: f64,
        /// Zero-plane displacement d of the log law above, m (≥ 0).
        d: f64,
    },
    /// Power law Ū(z) = U_ref (z / z_ref)^a.
    Power {
        /// Reference speed U_ref in m/s (> 0).
        u_ref: f64,
        /// Reference height z_ref in m (> 0).
        z_ref: f64,
        /// Exponent a (0 ≤ a ≤ 1). Open country ≈ 0.14, forest/suburbs ≈ 0.25–0.3.
        alpha: f64,
    },
}

/// Point spectrum model of the fluctuations.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SpectrumModel {
    /// The paper's eq. 4 with its Table-1 constants:
    /// f·S(f)/U*² = A ν / (1 + B ν)^{5/3}, ν = f z / Ū(z).
    /// Integrates to σ_u = 2.5 U*, σ_v = 2.0 U*, σ_w = 1.25 U*.
    Paper,
    /// Kaimal form of IEC 61400-1 (ed. 3, annex B):
    /// f·S(f)/σ² = 4 f L/Ū / (1 + 6 f L/Ū)^{5/3}, with L_u = 8.1Λ, L_v = 2.7Λ, L_w = 0.66Λ,
    /// Λ = 0.7 min(z, 60 m), and σ_u:σ_v:σ_w = 2.5:2.0:1.25 U* as in the paper.
    Kaimal,
    /// Isotropic von Kármán form of IEC 61400-1 (ed. 2): for u
    /// f·S/σ² = 4 f L/Ū / (1 + 70.8 (f L/Ū)²)^{5/6}, for v and w
    /// f·S/σ² = 4 f L/Ū (1 + 755.2 (f L/Ū)²) / (1 + 283.2 (f L/Ū)²)^{11/6},
    /// L = 3.5 × 0.7 min(z, 60 m), σ as for [`SpectrumModel::Kaimal`].
    VonKarman,
}

/// Constants A, B of eq. 4 for one component (paper Table 1).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SpectrumConstants {
    /// Numerator constant A (dimensionless, > 0).
    pub a: f64,
    /// Denominator constant B (dimensionless, > 0).
    pub b: f64,
}

/// Coherence decay constants C_x, C_y, C_z of eq. 5 for one component (paper Table 2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CoherenceConstants {
    /// Decay per along-wind separation (dimensionless, ≥ 0).
    pub cx: f64,
    /// Decay per lateral separation (dimensionless, ≥ 0).
    pub cy: f64,
    /// Decay per vertical separation (dimensionless, ≥ 0).
    pub cz: f64,
}

/// Which mean speed divides the separation in eq. 5.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum CoherenceSpeed {
    /// One reference speed for the whole grid: Ū averaged over the grid's heights
    /// (TurbSim's convention). Exact for the fast separable synthesis at any number of heights.
    #[default]
    Reference,
    /// The paper's pair average Ū_m = (Ū_j + Ū_k)/2. On several heights it needs the
    /// `Embedding` (or dense `Cholesky`) method; on one height it equals `Reference`.
    PairMean,
}

impl CoherenceSpeed {
    /// Name as on the command line and in file metadata: `reference` or `pair-mean`.
    pub fn name(self) -> &'static str {
        match self {
            CoherenceSpeed::Reference => "reference",
            CoherenceSpeed::PairMean => "pair-mean",
        }
    }
}

/// Everything that defines the statistics of a wind field.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WindParams {
    /// Friction velocity U* in m/s (> 0). Scales the log profile and the spectra
    /// (σ_u = 2.5 U*). Default 1.0 (a fresh breeze over a forest).
    pub u_star: f64,
    /// Mean profile. Default: log law over a 15 m canopy, z0 = 1.5 m, d = 10 m.
    pub profile: Profile,
    /// Spectrum model. Default [`SpectrumModel::Paper`].
    pub spectrum: SpectrumModel,
    /// Eq.-4 constants for u, v, w (Table 1). Used by [`SpectrumModel::Paper`].
    pub spectrum_constants: [SpectrumConstants; 3],
    /// Eq.-5 constants for u, v, w (Table 2).
    pub coherence: [CoherenceConstants; 3],
    /// Mean speed in the coherence denominator. Default [`CoherenceSpeed::Reference`] (exact
    /// with the fast separable factor, and what the forest's two-height field uses); the
    /// command line defaults to the paper's [`CoherenceSpeed::PairMean`] with its spectrum.
    pub coherence_speed: CoherenceSpeed,
    /// Direction the wind blows *towards*, in degrees counter-clockwise from world +x.
    /// Default 0.
    pub direction_deg: f64,
    /// Taylor advection: gusts travel downwind at one convection speed U_c at every height
    /// (multiplies each coefficient by e^{−iω(x − x_c)/U_c}), so the field is the same,
    /// statistic for statistic, at every x. Default `true`; `false` reproduces the paper's
    /// real coherence (with [`CoherenceSpeed::PairMean`], exactly).
    pub advection: bool,
    /// The convection speed U_c of the advection, m/s (0 … 100]; `None`: the reference
    /// speed, the mean of Ū over the grid's heights ([`crate::synth::convection_speed`]). A
    /// forest's scene sets 1.8 Ū(h) at its canopy top h, the speed its large eddies travel
    /// at (Finnigan 2000, "Turbulence in plant canopies", Annu. Rev. Fluid Mech. 32: 1.5–2
    /// Ū(h); Shaw, Brunet, Finnigan & Raupach 1995: 1.8 Ū(h)).
    #[serde(default)]
    pub convection_speed: Option<f64>,
}

/// Table 1 of the paper: A and B of eq. 4 for u, v, w.
pub const PAPER_SPECTRUM: [SpectrumConstants; 3] = [
    SpectrumConstants { a: 252.625, b: 60.62 },
    SpectrumConstants { a: 53.76, b: 20.16 },
    SpectrumConstants { a: 5.125, b: 4.92 },
];

/// Table 2 of the paper: C_x, C_y, C_z of eq. 5 for u, v, w.
pub const PAPER_COHERENCE: [CoherenceConstants; 3] = [
    CoherenceConstants { cx: 3.0, cy: 19.7, cz: 9.5 },
    CoherenceConstants { cx: 6.0, cy: 12.0, cz: 7.0 },
    CoherenceConstants { cx: 0.5, cy: 7.5, cz: 3.7 },
];

/// Named wind conditions over a 15 m forest canopy (log law, z0 = 1.5 m, d = 10 m).
/// Mean speeds quoted at 20 m, i.e. 5 m above the canopy: Ū(20) ≈ 4.74 U*.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Preset {
    /// U* = 0.3 m/s, Ū(20 m) ≈ 1.4 m/s: leaves stir.
    Calm,
    /// U* = 1.0 m/s, Ū(20 m) ≈ 4.7 m/s: branches sway. The default.
    Breeze,
    /// U* = 2.5 m/s, Ū(20 m) ≈ 11.9 m/s: whole trees move.
    Strong,
    /// U* = 6.0 m/s, Ū(20 m) ≈ 28 m/s: a storm.
    Storm,
}

impl Preset {
    /// All presets, mildest first.
    pub const ALL: [Preset; 4] = [Preset::Calm, Preset::Breeze, Preset::Strong, Preset::Storm];

    /// The preset's name as written on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Calm => "calm",
            Preset::Breeze => "breeze",
            Preset::Strong => "strong",
            Preset::Storm => "storm",
        }
    }

    /// Parse a preset name (case-insensitive).
    pub fn from_name(s: &str) -> Option<Preset> {
        Preset::ALL.into_iter().find(|p| p.name().eq_ignore_ascii_case(s))
    }

    /// Friction velocity of the preset in m/s.
    pub fn u_star(self) -> f64 {
        match self {
            Preset::Calm => 0.3,
            Preset::Breeze => 1.0,
            Preset::Strong => 2.5,
            Preset::Storm => 6.0,
        }
    }

    /// Full parameters of the preset (the coherence speed [`CoherenceSpeed::Reference`], as
    /// a forest's two-height field takes it).
    pub fn params(self) -> WindParams {
        WindParams { u_star: self.u_star(), ..WindParams::default() }
    }

    /// The preset's parameters for a field of its own, as `sylva wind generate` and the
    /// Python package's `generate` make it: [`Preset::params`] with the coherence speed
    /// [`CoherenceSpeed::for_spectrum`] gives the paper's spectrum.
    pub fn field_params(self) -> WindParams {
        let p = self.params();
        WindParams { coherence_speed: CoherenceSpeed::for_spectrum(p.spectrum), ..p }
    }
}

impl CoherenceSpeed {
    /// The coherence speed a field takes by default with `spectrum`: the paper's pair mean
    /// with the paper's spectrum (its eq. 5), one reference speed with the IEC spectra (as
    /// IEC 61400-1 defines their coherence). One rule for the command line and Python.
    pub fn for_spectrum(spectrum: SpectrumModel) -> CoherenceSpeed {
        match spectrum {
            SpectrumModel::Paper => CoherenceSpeed::PairMean,
            _ => CoherenceSpeed::Reference,
        }
    }
}

impl Default for WindParams {
    fn default() -> Self {
        WindParams {
            u_star: Preset::Breeze.u_star(),
            profile: Profile::Log { z0: 1.5, d: 10.0 },
            spectrum: SpectrumModel::Paper,
            spectrum_constants: PAPER_SPECTRUM,
            coherence: PAPER_COHERENCE,
            coherence_speed: CoherenceSpeed::Reference,
            direction_deg: 0.0,
            advection: true,
            convection_speed: None,
        }
    }
}

fn check(
    ok: bool,
    field: &'static str,
    value: f64,
    expected: &'static str,
) -> Result<(), ParamError> {
    if ok && value.is_finite() { Ok(()) } else { Err(ParamError::new(field, value, expected)) }
}

impl WindParams {
    /// Check every field; errors name the offending field and its valid range.
    pub fn validate(&self) -> Result<(), ParamError> {
        check(self.u_star > 0.0 && self.u_star <= 20.0, "u_star", self.u_star, "in (0, 20] m/s")?;
        match self.profile {
            Profile::Log { z0, d } => {
                check(z0 > 0.0 && z0 <= 10.0, "profile.z0", z0, "in (0, 10] m")?;
                check((0.0..=100.0).contains(&d), "profile.d", d, "in [0, 100] m")?;
            }
            Profile::Canopy { h, a, z0, d } => {
                check(z0 > 0.0 && z0 <= 10.0, "profile.z0", z0, "in (0, 10] m")?;
                check((0.0..=100.0).contains(&d), "profile.d", d, "in [0, 100] m")?;
                check(h > d + z0 && h <= 200.0, "profile.h", h, "in (d + z0, 200] m")?;
                check(a > 0.0 && a <= 10.0, "profile.a", a, "in (0, 10]")?;
            }
            Profile::Power { u_ref, z_ref, alpha } => {
                check(u_ref > 0.0 && u_ref <= 100.0, "profile.u_ref", u_ref, "in (0, 100] m/s")?;
                check(z_ref > 0.0, "profile.z_ref", z_ref, "> 0 m")?;
                check((0.0..=1.0).contains(&alpha), "profile.alpha", alpha, "in [0, 1]")?;
            }
        }
        for (i, c) in self.spectrum_constants.iter().enumerate() {
            let name = ["spectrum_constants.u", "spectrum_constants.v", "spectrum_constants.w"][i];
            check(c.a > 0.0, name, c.a, "A > 0")?;
            check(c.b > 0.0, name, c.b, "B > 0")?;
        }
        for (i, c) in self.coherence.iter().enumerate() {
            let name = ["coherence.u", "coherence.v", "coherence.w"][i];
            for v in [c.cx, c.cy, c.cz] {
                check(v >= 0.0, name, v, "decay constants ≥ 0")?;
            }
        }
        check(self.direction_deg.is_finite(), "direction_deg", self.direction_deg, "finite")?;
        if let Some(u) = self.convection_speed {
            check(u > 0.0 && u <= 100.0, "convection_speed", u, "in (0, 100] m/s")?;
        }
        Ok(())
    }

    /// Mean speed Ū(z) in m/s at height z (m).
    pub fn mean_speed(&self, z: f64) -> f64 {
        match self.profile {
            Profile::Log { z0, d } => {
                let zz = (z - d).max(2.0 * z0);
                self.u_star / KARMAN * (zz / z0).ln()
            }
            Profile::Canopy { h, a, z0, d } => {
                let log = |z: f64| self.u_star / KARMAN * ((z - d) / z0).ln();
                if z >= h { log(z) } else { log(h) * (a * (z.max(0.0) / h - 1.0)).exp() }
            }
            Profile::Power { u_ref, z_ref, alpha } => u_ref * (z.max(1e-3) / z_ref).powf(alpha),
        }
    }

    /// Lowest height (m) where the mean profile is the law it names: d + 2·z0 for the log
    /// law (below it [`WindParams::mean_speed`] holds the speed at d + 2·z0, the floor);
    /// `None` for the power law, valid down to the ground.
    pub fn log_law_floor(&self) -> Option<f64> {
        match self.profile {
            Profile::Log { z0, d } => Some(d + 2.0 * z0),
            Profile::Canopy { .. } | Profile::Power { .. } => None,
        }
    }

    /// Unit vector (x, y) of the mean wind direction in world coordinates.
    pub fn direction(&self) -> [f64; 2] {
        let a = self.direction_deg.to_radians();
        [a.cos(), a.sin()]
    }
}

/// A canopy's attenuation a for [`Profile::Canopy`] from its leaf area index `lai`
/// (one-sided leaf area per ground area, spread evenly over its height) and leaf drag
/// coefficient `c_d`: a = c_d · LAI / (2 β²), β = u*/Ū(h) = 0.3. Inside a dense canopy the
/// mixing length is l = 2 β³ L_c with L_c = 1 / (c_d · leaf area density) (Harman &
/// Finnigan 2007, "A simple unified theory for flow in the canopy and roughness sublayer",
/// Boundary-Layer Meteorol. 123), which makes the mean speed fall as exp(β (z − h) / l);
/// over the canopy's height h that is Cionco's a = β h / l. With c_d = 0.2 a canopy of
/// LAI 2 gets a ≈ 2.2, LAI 5 a ≈ 5.6; clamped to Cionco's (0, 10].
pub fn canopy_attenuation(lai: f64, c_d: f64) -> f64 {
    const BETA: f64 = 0.3;
    (c_d * lai / (2.0 * BETA * BETA)).clamp(1e-3, 10.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_profile_follows_the_law_and_clamps_in_the_canopy() {
        let p = WindParams::default();
        // (U*/κ) ln((20 − 10)/1.5) with U* = 1.
        let expect = 1.0 / 0.4 * (10.0f64 / 1.5).ln();
        assert!((p.mean_speed(20.0) - expect).abs() < 1e-12);
        assert!(p.mean_speed(40.0) > p.mean_speed(20.0));
        // Inside the canopy: clamped, positive, constant.
        assert!(p.mean_speed(5.0) > 0.0);
        assert_eq!(p.mean_speed(5.0), p.mean_speed(1.0));
    }

    #[test]
    fn validation_names_the_field() {
        let p = WindParams { u_star: -1.0, ..WindParams::default() };
        let e = p.validate().expect_err("negative U* must be refused");
        assert_eq!(e.field, "u_star");
        let p = WindParams { profile: Profile::Log { z0: 0.0, d: 1.0 }, ..WindParams::default() };
        assert_eq!(p.validate().expect_err("z0 = 0").field, "profile.z0");
        assert!(WindParams::default().validate().is_ok());
    }

    #[test]
    fn presets_get_stronger() {
        let speeds: Vec<f64> = Preset::ALL.iter().map(|p| p.params().mean_speed(20.0)).collect();
        assert!(speeds.windows(2).all(|w| w[1] > w[0]), "{speeds:?}");
        assert_eq!(Preset::from_name("STORM"), Some(Preset::Storm));
        assert_eq!(Preset::from_name("hurricane"), None);
    }
}
