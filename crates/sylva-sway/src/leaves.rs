//! Leaf-cluster flutter (paper §4.2): each cluster swings about its hanging point on top of
//! its branch's motion, faster and wider as the local wind grows.
//!
//! Empirical model (documented choice, not a fit to a data set): frequency
//! f = f0 + f1·U (Hz) and amplitude A = A_max U² / (U² + U_half²) (rad), with U the local
//! wind speed. Defaults f0 = 1 Hz, f1 = 0.25 Hz per m/s, A_max = 0.35 rad, U_half = 6 m/s
//! put a breeze (5 m/s) at 2.25 Hz and 0.14 rad and a gale (15 m/s) at 4.75 Hz and 0.30 rad,
//! within the 1–5 Hz range in which broadleaf leaves are seen to flutter.
//!
//! The phase is integrated on the CPU (φ += 2πf dt) so a changing wind never makes the
//! swing jump; a vertex shader evaluates A·sin(φ + φ_cluster) with a per-cluster offset.

use serde::{Deserialize, Serialize};

/// Constants of the flutter model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LeafParams {
    /// Frequency in still air, Hz. Default 1.0.
    pub f0: f32,
    /// Frequency gain, Hz per m/s. Default 0.25.
    pub f1: f32,
    /// Largest swing, rad. Default 0.35.
    pub amp_max: f32,
    /// Wind speed at half the largest swing, m/s. Default 6.
    pub u_half: f32,
}

impl Default for LeafParams {
    fn default() -> Self {
        LeafParams { f0: 1.0, f1: 0.25, amp_max: 0.35, u_half: 6.0 }
    }
}

impl LeafParams {
    /// Check every field; the error names it and its range.
    pub fn validate(&self) -> Result<(), crate::SwayParamError> {
        let fields = [
            ("f0", self.f0, self.f0 > 0.0 && self.f0 <= 20.0, "in (0, 20] Hz"),
            ("f1", self.f1, (0.0..=5.0).contains(&self.f1), "in [0, 5] Hz per m/s"),
            ("amp_max", self.amp_max, (0.0..=1.5).contains(&self.amp_max), "in [0, 1.5] rad"),
            ("u_half", self.u_half, self.u_half > 0.0 && self.u_half <= 100.0, "in (0, 100] m/s"),
        ];
        for (field, value, ok, expected) in fields {
            if !(ok && value.is_finite()) {
                return Err(crate::SwayParamError { field, value, expected });
            }
        }
        Ok(())
    }
}

/// Flutter state of one tree's leaves, as the vertex shader reads it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[repr(C)]
pub struct LeafSway {
    /// Accumulated phase, rad (wrapped to [0, 2π)).
    pub phase: f32,
    /// Swing amplitude, rad.
    pub amplitude: f32,
}

impl LeafParams {
    /// Flutter frequency at wind speed `u` (m/s), Hz.
    pub fn frequency(&self, u: f32) -> f32 {
        self.f0 + self.f1 * u.max(0.0)
    }

    /// Flutter amplitude at wind speed `u` (m/s), rad.
    pub fn amplitude(&self, u: f32) -> f32 {
        let u2 = u * u;
        self.amp_max * u2 / (u2 + self.u_half * self.u_half)
    }

    /// Advance `s` by `dt` seconds at wind speed `u`.
    pub fn step(&self, s: &mut LeafSway, u: f32, dt: f32) {
        let tau = std::f32::consts::TAU;
        s.phase = (s.phase + tau * self.frequency(u) * dt).rem_euclid(tau);
        s.amplitude = self.amplitude(u);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flutter_grows_with_wind_and_its_phase_is_continuous() {
        let p = LeafParams::default();
        assert!(p.frequency(15.0) > p.frequency(5.0) && p.frequency(5.0) > p.frequency(0.0));
        assert!(p.amplitude(15.0) > p.amplitude(5.0) && p.amplitude(0.0) == 0.0);
        assert!((p.amplitude(6.0) - 0.175).abs() < 1e-6);
        let mut s = LeafSway::default();
        let mut last = s.phase;
        for k in 0..1000 {
            p.step(&mut s, if k < 500 { 2.0 } else { 20.0 }, 1.0 / 60.0);
            let d = (s.phase - last).rem_euclid(std::f32::consts::TAU);
            assert!(d < 2.0 * std::f32::consts::PI * 6.5 / 60.0, "phase jumped by {d}");
            last = s.phase;
        }
    }
}
