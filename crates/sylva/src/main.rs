//! The `sylva` command: forests in wind (demo, render, view), wind fields, trees, sway probes
//! and benchmarks.
//!
//! Arguments are parsed in two stages (raw clap flags -> validated settings in `wind.rs`),
//! so every check happens once, at the edge, with an error that names the flag.

mod forest;
mod gallery;
mod tree;
mod wind;

use sylva_bench as bench;
use sylva_frames::{available_memory, finite, render};
use sylva_viewer as view;

use clap::{Parser, Subcommand};

/// Forests in wind: wind-engineering wind fields, Weber–Penn trees, swaying branches, rendered.
#[derive(Debug, Parser)]
#[command(name = "sylva", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// The main job on built-in defaults: a forest in wind. Opens the viewer when a display
    /// exists; otherwise renders a ~5 s clip of scene A headless into `out/demo/`.
    Demo(DemoArgs),
    /// A window onto a scene: orbit/fly camera, live wind controls, live figures.
    View(view::ViewArgs),
    /// Generate, inspect, plot and export stochastic wind fields.
    #[command(subcommand)]
    Wind(Box<wind::WindCommand>),
    /// Render a scene headless: PNG frames, an animated GIF (and MP4 with ffmpeg).
    Render(render::RenderArgs),
    /// Weber–Penn species: list, document, generate and inspect trees.
    #[command(subcommand)]
    Tree(tree::TreeCommand),
    /// A scene's trees as one animated glTF.
    #[command(subcommand)]
    Forest(forest::ForestCommand),
    /// Branch sway: probe how a tree moves in wind.
    #[command(subcommand)]
    Sway(tree::SwayCommand),
    /// Render the gallery: every preset close up in calm and storm, scenes A and D.
    Gallery(gallery::GalleryArgs),
    /// Benchmarks (figures with the machine they ran on).
    #[command(subcommand)]
    Bench(bench::BenchCommand),
}

#[derive(Debug, clap::Args)]
struct DemoArgs {
    /// Render the clip even when a display exists.
    #[arg(long)]
    headless: bool,
    /// Output folder of the headless clip.
    #[arg(long, default_value = "out/demo")]
    out: std::path::PathBuf,
}

fn demo(a: DemoArgs) -> anyhow::Result<()> {
    if !a.headless && view::display_available() {
        println!(
            "sylva demo: scene A in the viewer (drag to orbit, WASD to move, arrows for wind, F1 for keys)"
        );
        let a = view::ViewArgs {
            scene: "A".into(),
            lod_fraction: None,
            wind: None,
            no_panel: false,
            camera_path: None,
            lod: Default::default(),
        };
        match view::view(&a) {
            Ok(()) => return Ok(()),
            Err(e) => eprintln!("viewer unavailable ({e:#}); rendering headless instead"),
        }
    }
    // Headless: scene A, 5 s at 10 frames per second at its default level of detail, sized
    // so that a software rasteriser finishes in about a minute.
    let args = render::RenderArgs {
        scene: "A".into(),
        seconds: 5.0,
        fps: 10.0,
        size: "800x600".into(),
        out: a.out,
        wind: None,
        lod_fraction: None,
        no_gif: false,
        camera_path: false,
        gpu_passes: false,
        lod: render::LodArgs::default(),
    };
    println!(
        "sylva demo: no display, rendering scene A (1000 trees in strong wind), 5 s at 10 fps, 800×600"
    );
    let r = render::render(&args, 0)?;
    render::print_report(&args, &r);
    Ok(())
}

fn main() -> std::process::ExitCode {
    // Piping into `head` must end the program quietly, as for any Unix tool.
    #[cfg(unix)]
    // SAFETY: restoring the default disposition of SIGPIPE before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    // Mesa's Vulkan window-system code complains on stderr when XDG_RUNTIME_DIR is unset
    // (headless machines, containers), although nothing needs it then: give it a private
    // empty folder.
    #[cfg(target_os = "linux")]
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        use std::os::unix::fs::DirBuilderExt;
        // SAFETY: getuid has no preconditions and cannot fail.
        let uid = unsafe { libc::getuid() };
        let dir = std::env::temp_dir().join(format!("sylva-runtime-{uid}"));
        let made = std::fs::DirBuilder::new().mode(0o700).create(&dir);
        if made.is_ok() || dir.is_dir() {
            // SAFETY: no other thread exists yet, so nothing reads the environment meanwhile.
            unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
        }
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
        Command::Demo(a) => demo(a),
        Command::View(a) => view::view(&a),
        Command::Wind(c) => wind::run(*c),
        Command::Render(a) => {
            let r = render::render(&a, 0)?;
            render::print_report(&a, &r);
            Ok(())
        }
        Command::Tree(c) => tree::run_tree(c),
        Command::Sway(c) => tree::run_sway(c),
        Command::Forest(c) => forest::run(c),
        Command::Bench(c) => bench::run(c),
        Command::Gallery(a) => gallery::gallery(&a),
    }
}
