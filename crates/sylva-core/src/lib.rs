//! Sylva's shared primitives, the floor every other crate stands on (no dependencies):
//!
//! - [`rng`]: SplitMix64, the one seeded generator behind every random choice (layout,
//!   tree growth, textures), so a seed means the same stream everywhere;
//! - [`lanes`]: lane-interleaved 3×4 matrices (a SIMD step's palettes) to one row per
//!   lane, transposed eight lanes at a time where the CPU has AVX;
//! - [`memory`]: the memory the machine has free, for estimates made before allocating;
//! - [`mat4`]: column-major 4×4 product and inverse (camera and renderer);
//! - [`quat`]: unit quaternions from and to rotation matrices, slerp (glTF animation);
//! - [`v3`]: helpers on `[f32; 3]`, the vector type of every public struct (plain, `Pod`,
//!   serde-friendly, so no conversion at crate boundaries);
//! - [`simd_kernel!`]: one CPU-feature dispatch — a kernel compiled for AVX-512, AVX2 and
//!   the baseline from one body, the widest picked at run time.
#![warn(missing_docs)]

pub mod lanes;
pub mod mat4;
pub mod memory;
pub mod quat;
pub mod rng;
pub mod simd;
pub mod v3;

pub use rng::SplitMix64;
