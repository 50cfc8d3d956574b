//! Stochastic wind fields for forests in wind (paper §3: "Construction of the wind field").
//!
//! The velocity at Q = (x, y, z) is U = Ū(z) + u, V = v, W = w (eq. 1), with u, v, w
//! independent stationary Gaussian processes described by the point spectra of eq. 4
//! ([`spectrum`]) and the coherence of eq. 5, synthesised by the spectral representation of
//! eqs. 6–7 ([`synth`]) either literally (dense Cholesky, the reference), by the exact
//! separable factorisation (one coherence speed; thousands of times faster), or by circulant
//! embedding (the paper's pair-mean speed on several heights). The result is a periodic
//! loop ([`WindField`]) sampled smoothly in space and time, with a mip pyramid for the wind LOD,
//! the drag force of eq. 8, file formats ([`io`]) and statistics against the model ([`stats`]).
//!
//! ```
//! use sylva_wind::{Grid, Preset, SynthParams, WindField};
//! let grid = Grid::regular(16, 16, 4.0, &[20.0], 256, 0.1);
//! let field = WindField::generate(&Preset::Breeze.params(), &grid, SynthParams::default(), &|_| {})?;
//! let v = field.view().sample([10.0, 20.0, 20.0], 3.7); // m/s, world axes
//! assert!(v[0] > 0.0);
//! # Ok::<(), sylva_wind::WindError>(())
//! ```
#![warn(missing_docs)]

pub mod error;
pub mod field;
pub mod grid;
pub mod io;
pub mod near;
pub mod params;
pub mod spectrum;
pub mod stats;
pub mod synth;

pub use error::{ParamError, WindError};
pub use field::{Captured, FieldView, MipPyramid, OwnedPyramid, WindField, drag};
pub use grid::Grid;
pub use near::NearField;
pub use params::{
    AIR_DENSITY, CoherenceSpeed, Component, KARMAN, Preset, Profile, SpectrumModel, WindParams,
    canopy_attenuation,
};
pub use synth::{Method, SynthParams};
