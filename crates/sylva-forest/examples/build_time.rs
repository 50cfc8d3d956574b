//! Times building forests of built-in scenes or scene files (`Forest::new`: the layout,
//! the species' models and simulations, the wind field, the cells), each as often as it is
//! named: `cargo run --release -p sylva-forest --example build_time -- E E A scene.toml`.

use std::time::Instant;

use anyhow::Context;
use sylva_forest::{Forest, SceneSpec};

fn main() -> anyhow::Result<()> {
    let names: Vec<String> = std::env::args().skip(1).collect();
    anyhow::ensure!(!names.is_empty(), "usage: build_time SCENE… (built-in names or .toml files)");
    for name in &names {
        let spec = if name.ends_with(".toml") {
            let text = std::fs::read_to_string(name).with_context(|| format!("reading {name}"))?;
            SceneSpec::from_toml(name, &text)?
        } else {
            SceneSpec::builtin(name)?
        };
        let t = Instant::now();
        let forest = Forest::new(&spec)?;
        let secs = t.elapsed().as_secs_f64();
        println!(
            "{name}: {} trees, {} species, built in {secs:.3} s",
            spec.trees,
            forest.species.len()
        );
    }
    Ok(())
}
