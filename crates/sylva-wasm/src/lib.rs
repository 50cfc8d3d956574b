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

/// A forest held between calls, for timing its steps from the host ([`prepare`], [`steps`]).
struct Held {
    forest: Forest,
    frame: FrameData,
    camera: sylva_forest::Camera,
}

thread_local! {
    static HELD: std::cell::RefCell<Option<Held>> = const { std::cell::RefCell::new(None) };
}

/// Grow the built-in scene `name` (`small`, `A` … `D`) and hold it for [`steps`]; returns
/// its number of trees (`None` if it fails).
pub fn prepare(name: &str) -> Option<usize> {
    let spec = SceneSpec::builtin(name).ok()?;
    let forest = Forest::new(&spec).ok()?;
    let camera = forest.default_camera();
    let trees = forest.trees();
    HELD.with(|h| {
        *h.borrow_mut() = Some(Held { forest, frame: FrameData::with_rows(768), camera })
    });
    Some(trees)
}

/// Step the held forest `n` times by 1/60 s, building a frame from its camera after each (a
/// page's work per frame, less the drawing), and return the sum of the last frame's palettes
/// (NaN if nothing is held).
pub fn steps(n: u32) -> f64 {
    HELD.with(|h| {
        let mut held = h.borrow_mut();
        let Some(Held { forest, frame, camera }) = held.as_mut() else { return f64::NAN };
        for _ in 0..n {
            forest.step(1.0 / 60.0);
            forest.frame(camera, 4.0 / 3.0, frame);
        }
        frame.palettes.iter().map(|&v| f64::from(v.abs())).sum()
    })
}

/// [`prepare`] for a WebAssembly host: scene `index` of [`sylva_forest::SCENES`]; returns
/// the trees, or −1.
#[unsafe(no_mangle)]
pub extern "C" fn sylva_prepare(index: u32) -> f64 {
    sylva_forest::SCENES
        .get(index as usize)
        .and_then(|(name, _)| prepare(name))
        .map_or(-1.0, |t| t as f64)
}

/// [`steps`] for a WebAssembly host.
#[unsafe(no_mangle)]
pub extern "C" fn sylva_steps(n: u32) -> f64 {
    steps(n)
}
