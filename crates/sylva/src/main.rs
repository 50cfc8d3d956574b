//! The `sylva` command: wind fields now; trees, animation and the forest viewer as they land.
//!
//! Arguments are parsed in two stages (raw clap flags -> validated settings in `wind.rs`),
//! so every check happens once, at the edge, with an error that names the flag.

mod bench;
mod wind;

use clap::{Parser, Subcommand};

/// Forests in wind: stochastic wind fields from wind-engineering spectra and coherence.
#[derive(Debug, Parser)]
#[command(name = "sylva", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// The main job on built-in defaults: generate the default wind field, check it
    /// against the model and plot it, into `out/`.
    Demo(wind::DemoArgs),
    /// Generate, inspect, plot and export stochastic wind fields.
    #[command(subcommand)]
    Wind(Box<wind::WindCommand>),
    /// Benchmarks (figures with the machine they ran on).
    #[command(subcommand)]
    Bench(bench::BenchCommand),
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Demo(a) => wind::demo(a),
        Command::Wind(c) => wind::run(*c),
        Command::Bench(c) => bench::run(c),
    }
}
