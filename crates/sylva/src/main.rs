//! The `sylva` command: wind fields, trees and their sway now; the forest viewer as it lands.
//!
//! Arguments are parsed in two stages (raw clap flags -> validated settings in `wind.rs`),
//! so every check happens once, at the edge, with an error that names the flag.

mod bench;
mod render;
mod tree;
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
    /// Render a scene headless: PNG frames, an animated GIF (and MP4 with ffmpeg).
    Render(render::RenderArgs),
    /// Weber–Penn species: list, document, generate and inspect trees.
    #[command(subcommand)]
    Tree(tree::TreeCommand),
    /// Branch sway: probe how a tree moves in wind.
    #[command(subcommand)]
    Sway(tree::SwayCommand),
    /// Benchmarks (figures with the machine they ran on).
    #[command(subcommand)]
    Bench(bench::BenchCommand),
}

fn main() -> std::process::ExitCode {
    // Piping into `head` must end the program quietly, as for any Unix tool.
    #[cfg(unix)]
    // SAFETY: restoring the default disposition of SIGPIPE before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    match run(Cli::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Demo(a) => wind::demo(a),
        Command::Wind(c) => wind::run(*c),
        Command::Render(a) => {
            let r = render::render(&a)?;
            render::print_report(&a, &r);
            Ok(())
        }
        Command::Tree(c) => tree::run_tree(c),
        Command::Sway(c) => tree::run_sway(c),
        Command::Bench(c) => bench::run(c),
    }
}
