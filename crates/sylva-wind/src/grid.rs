//! The sampling grid of a wind field: rectilinear points in the wind frame (x along the
//! mean wind, y across it, z up), possibly unevenly spaced, and the time axis.
//!
//! The time axis has `frames` samples at step `dt`; the field is periodic with period
//! `frames · dt`. `frames` must be even (the FFT's Nyquist line is dropped).

use serde::{Deserialize, Serialize};

use crate::error::ParamError;

/// Rectilinear grid and time axis of a wind field.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Grid {
    /// Along-wind coordinates in m, strictly increasing (at least one).
    pub xs: Vec<f64>,
    /// Lateral coordinates in m, strictly increasing (at least one).
    pub ys: Vec<f64>,
    /// Heights above ground in m, strictly increasing and > 0 (at least one).
    pub zs: Vec<f64>,
    /// Number of time frames (even, ≥ 4). The loop period is `frames · dt`.
    pub frames: usize,
    /// Time step in s (> 0). Resolves frequencies up to 1/(2 dt) Hz.
    pub dt: f64,
}

/// Largest number of points × frames accepted (about 4·10¹⁰ values): a guard against a
/// typing slip that would ask for terabytes.
pub const MAX_VALUES: u128 = 40_000_000_000;

impl Grid {
    /// A regular grid of `nx × ny` points at `spacing` metres, starting at the origin, on
    /// the given heights.
    pub fn regular(nx: usize, ny: usize, spacing: f64, zs: &[f64], frames: usize, dt: f64) -> Grid {
        Grid {
            xs: (0..nx).map(|i| i as f64 * spacing).collect(),
            ys: (0..ny).map(|i| i as f64 * spacing).collect(),
            zs: zs.to_vec(),
            frames,
            dt,
        }
    }

    /// Number of points along x.
    pub fn nx(&self) -> usize {
        self.xs.len()
    }
    /// Number of points along y.
    pub fn ny(&self) -> usize {
        self.ys.len()
    }
    /// Number of heights.
    pub fn nz(&self) -> usize {
        self.zs.len()
    }
    /// Points per frame and component.
    pub fn points(&self) -> usize {
        self.nx() * self.ny() * self.nz()
    }
    /// Middle of the x range, m: the origin of the advection phase.
    pub fn x_mid(&self) -> f64 {
        0.5 * (self.xs[0] + self.xs[self.xs.len() - 1])
    }

    /// Loop period in s.
    pub fn period(&self) -> f64 {
        self.frames as f64 * self.dt
    }

    /// Spacing of an axis if it is regular (all gaps equal to 1e-9 relative), else `None`.
    /// A single point counts as regular with spacing 1.
    pub fn regular_spacing(axis: &[f64]) -> Option<f64> {
        if axis.len() < 2 {
            return Some(1.0);
        }
        let d = axis[1] - axis[0];
        axis.windows(2).all(|w| ((w[1] - w[0]) - d).abs() <= 1e-9 * d.abs().max(1.0)).then_some(d)
    }

    /// Check sizes, ordering and ranges; errors name the field.
    pub fn validate(&self) -> Result<(), ParamError> {
        for (name, axis) in [("grid.xs", &self.xs), ("grid.ys", &self.ys), ("grid.zs", &self.zs)] {
            if axis.is_empty() {
                return Err(ParamError::new(name, 0.0, "at least one point"));
            }
            if let Some(v) = axis.iter().find(|v| !v.is_finite()) {
                return Err(ParamError::new(name, *v, "finite coordinates"));
            }
            if let Some(w) = axis.windows(2).find(|w| w[1] <= w[0]) {
                return Err(ParamError::new(name, w[1], "strictly increasing coordinates"));
            }
        }
        if let Some(z) = self.zs.iter().find(|z| **z <= 0.0) {
            return Err(ParamError::new("grid.zs", *z, "heights > 0 m"));
        }
        if self.frames < 4 || !self.frames.is_multiple_of(2) {
            return Err(ParamError::new("grid.frames", self.frames as f64, "an even number ≥ 4"));
        }
        if !(self.dt > 0.0 && self.dt.is_finite()) {
            return Err(ParamError::new("grid.dt", self.dt, "> 0 s"));
        }
        let values = self.points() as u128 * self.frames as u128 * 3;
        if values > MAX_VALUES {
            return Err(ParamError::new("grid", values as f64, "at most 4e10 values in all"));
        }
        Ok(())
    }
}
