//! Sylva in a browser: the engine compiled to WebAssembly (`wasm32-unknown-unknown`), with
//! the wgpu renderer on the page's WebGPU, and the page in `web/` driving it (`./run web`
//! builds both into `target/web/site/`, a static folder any web server can host).
//!
//! On the web the crate exports `app::App` to JavaScript (through wasm-bindgen): it
//! opens the GPU on a canvas, grows a scene, steps it with the desktop viewer's fixed
//! substeps and draws it each animation frame, and takes the page's camera moves, wind,
//! level-of-detail and scene choices. Natively only [`files`] is compiled: how the page
//! reads a file dropped onto it, with the same readers as the command line (tested here,
//! without a browser).

pub mod files;

#[cfg(target_arch = "wasm32")]
pub mod app;
