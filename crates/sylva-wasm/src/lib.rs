//! Sylva's simulation in WebAssembly (`wasm32-unknown-unknown`): the GPU-free crates —
//! wind, trees, sway, forest — compiled to a module that needs no imports, with one export
//! that grows a built-in forest, steps it and builds frames, and sums what it computed.
//! Rayon's pool runs on the calling thread where there are no threads; a step reports
//! 0 ms there (no clock).
//!
//! CI builds the module and runs it in Node (`.ci/wasm-check.mjs`), comparing the sum with
//! the native build's (`cargo run -p sylva-wasm --example summary`): the same simulation,
//! within the last bits that a different `libm` and no SIMD leave.
//!
//! ```
//! let s = sylva_wasm::summary(3);
//! assert!(s.is_finite() && s > 0.0);
//! ```

use sylva_forest::{Forest, FrameData, SceneSpec};

/// Grow the built-in scene `small`, step it `steps` times by 1/30 s with a frame from its
/// camera after each, and return the sum of the absolute values of the last frame's joint
/// palettes and of the wind at the scene's middle, 10 m up (NaN if the scene fails).
pub fn summary(steps: u32) -> f64 {
    let Ok(spec) = SceneSpec::builtin("small") else { return f64::NAN };
    let Ok(mut forest) = Forest::new(&spec) else { return f64::NAN };
    let camera = forest.default_camera();
    let mut frame = FrameData::with_rows(768);
    for _ in 0..steps {
        forest.step(1.0 / 30.0);
        forest.frame(&camera, 4.0 / 3.0, &mut frame);
    }
    let palettes: f64 = frame.palettes.iter().map(|&v| f64::from(v.abs())).sum();
    let wind: f64 = forest.wind_sample([0.0, 0.0, 10.0]).iter().map(|&v| f64::from(v.abs())).sum();
    palettes + wind
}

/// [`summary`] for a WebAssembly host.
#[unsafe(no_mangle)]
pub extern "C" fn sylva_summary(steps: u32) -> f64 {
    summary(steps)
}
