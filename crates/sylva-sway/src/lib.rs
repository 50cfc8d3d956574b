//! Quasi-physical tree animation (paper §4.2, §4.3): every active joint of a tree skeleton
//! is a damped angular spring with two bending angles driven by the eq.-8 drag of the wind
//! on what it carries; joint rotations compose into one matrix palette per tree; leaf
//! clusters flutter on top; the animation LOD simulates only the heaviest joints.
//!
//! * [`SwayParams`] — material and model constants, with sources.
//! * [`SwaySpecies`] — a skeleton prepared once: inertia, stiffness from the cantilever
//!   frequency, damping, drag areas, joint priorities.
//! * [`SwayBatch`] — many instances stepped together with an exact (any-dt) integrator,
//!   active-joint budgets with smooth blending, palettes; parallel and deterministic.
//! * [`leaves`] — the flutter model a vertex shader evaluates.
//! * [`CrownLean`] — the crown's static lean in wind, for a stand-in bent at the trunk only.
#![warn(missing_docs)]

pub mod batch;
pub mod frontal;
pub mod lean;
pub mod leaves;
pub mod params;
pub mod probe;
pub mod species;

pub use batch::{
    IDENTITY, LANES, Lanes, Palette, PaletteSlot, STATE_BYTES, SwayBatch, TRIM_STEPS, rotation_of,
    transform,
};
pub use frontal::{Frontal, frontal_area};
pub use lean::CrownLean;
pub use leaves::{LeafParams, LeafSway};
pub use params::{CROWN_DRAG_SPEED, NEEDLE_LEAF_DRAG, SwayParamError, SwayParams};
pub use species::{JointSpring, SwaySpecies};
