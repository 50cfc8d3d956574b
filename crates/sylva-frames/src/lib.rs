//! What Sylva's commands share: headless frames of a scene and what writes them.
//!
//! [`render`] is the engine of `sylva render` (and of `bench render` and the headless
//! demo): a scene stepped along its camera path and drawn offscreen, its frames written as
//! PNG, an animated GIF and, with ffmpeg, an MP4 ([`render::ClipWriter`], which the viewer's
//! clip recording uses too). [`plot`] draws the PNG charts of `wind plot` and
//! `bench table3`. The flag parsers every command uses ([`finite`], [`at_least_one`]) name
//! the flag in their errors.

pub mod plot;
pub mod render;

/// The value parser of every floating-point flag: a finite number. NaN and ±∞ parse as
/// floats but are never meaningful input; clap names the flag in the error.
pub fn finite<T>(s: &str) -> Result<T, String>
where
    T: std::str::FromStr + Copy + Into<f64>,
    T::Err: std::fmt::Display,
{
    let v: T = s.trim().parse().map_err(|e| format!("`{s}` is not a number ({e})"))?;
    if v.into().is_finite() { Ok(v) } else { Err(format!("`{s}` is not a finite number")) }
}

/// A count flag of at least 1 (`--frames 0` is an error naming the flag, not one frame in
/// silence).
pub fn at_least_one(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(0) => Err("must be at least 1".into()),
        Ok(v) => Ok(v),
        Err(e) => Err(format!("`{s}` is not a count ({e})")),
    }
}

pub use sylva_core::memory::available_memory;
