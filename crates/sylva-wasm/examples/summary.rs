//! The native build's [`sylva_wasm::summary`], for comparison with the WebAssembly module's:
//! `cargo run -p sylva-wasm --example summary -- 30`.

fn main() {
    let steps = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(30);
    println!("{:.9e}", sylva_wasm::summary(steps));
}
