//! `sylva wind …` and `sylva demo`: raw flags -> validated settings -> the wind library.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, bail};
use clap::{Args, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use sylva_wind::stats::{FieldStats, ensemble_stats_at, field_stats};
use sylva_wind::synth::{cholesky_estimate, memory_estimate};
use sylva_wind::{
    CoherenceSpeed, Grid, Method, Preset, Profile, SpectrumModel, SynthParams, WindField,
    WindParams, io,
};

use sylva_frames::plot::write_stats_plots;

#[derive(Debug, Subcommand)]
pub enum WindCommand {
    /// Synthesise a periodic wind field and write it to a file.
    Generate(Box<GenerateArgs>),
    /// σ per component against the model, captured variance, and the spectral and
    /// coherence error tables of a field file.
    Stats(StatsArgs),
    /// Plot a field's spectra against eq. 4 and its co-coherence against eq. 5 (PNG).
    Plot(PlotArgs),
    /// What a wind file holds: its grid, time axis and, per height, the mean speed and σ of
    /// each component. Reads .swf, .npy (with sidecar), .zarr and TurbSim .bts (TurbSim's
    /// own files included).
    Info(InfoArgs),
    /// The wind field on built-in defaults: generate, check against the model and plot,
    /// into `out/`.
    Demo(DemoArgs),
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum PresetArg {
    Calm,
    Breeze,
    Strong,
    Storm,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum ProfileArg {
    /// Log law Ū = (U*/κ) ln((z − d)/z0).
    Log,
    /// Power law Ū = U_ref (z/z_ref)^alpha.
    Power,
    /// The log law over a forest and Ū(h) exp(a (z/h − 1)) inside it (Cionco 1965).
    Canopy,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum SpectrumArg {
    /// The paper's eq. 4 with Table 1.
    Paper,
    /// IEC 61400-1 Kaimal.
    Kaimal,
    /// IEC 61400-1 von Kármán.
    VonKarman,
}

#[derive(Debug, Clone, Copy, ValueEnum, PartialEq, Eq)]
pub enum MethodArg {
    /// The fastest exact method for the model and grid (default): separable where one speed
    /// divides every separation, else the embedding (regular x–y), else the dense Cholesky.
    Auto,
    /// Exact Kronecker/AR(1) factor + FFT (one coherence speed).
    Separable,
    /// Circulant embedding across x–y, dense over heights (the pair-mean speed on several
    /// heights; regular x–y).
    Embedding,
    /// The paper's dense CPSDM Cholesky (reference; small grids only).
    Cholesky,
}

#[derive(Debug, Clone, Copy, ValueEnum, PartialEq, Eq)]
pub enum CoherenceSpeedArg {
    /// The paper's pair mean Ū_m = (Ū_j + Ū_k)/2 (default with --spectrum paper).
    PairMean,
    /// One reference speed, Ū averaged over the heights (TurbSim's and IEC's convention;
    /// default with --spectrum kaimal and von-karman).
    Reference,
}

#[derive(Debug, Clone, Copy, ValueEnum, PartialEq, Eq)]
pub enum FormatArg {
    /// Sylva's compact int16 format with header and checksum.
    Swf,
    /// NumPy float32 array (frames, 3, ny, nx), or (frames, 3, nz, ny, nx) with several heights, plus a JSON sidecar.
    Npy,
    /// TurbSim binary full-field (one y–z plane over time).
    Bts,
    /// Zarr v3 store (a folder), streamed: fields larger than memory; chunks of 32
    /// x-columns, read directly by xarray and zarr-python. Separable method only.
    Zarr,
}

/// Wind model flags shared by `generate` and `demo`.
#[derive(Debug, Args)]
pub struct ModelArgs {
    /// Named wind condition over a 15 m forest (sets U*).
    #[arg(long, value_enum, default_value = "breeze")]
    preset: PresetArg,
    /// Friction velocity U* in m/s (overrides the preset). σ_u = 2.5 U*.
    #[arg(value_parser = crate::finite::<f64>, long, allow_negative_numbers = true)]
    u_star: Option<f64>,
    /// Mean profile.
    #[arg(long, value_enum, default_value = "log")]
    profile: ProfileArg,
    /// Log law: roughness length z0 in m (forest ≈ 0.1 × canopy height).
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = 1.5, allow_negative_numbers = true)]
    z0: f64,
    /// Log law: zero-plane displacement d in m (forest ≈ ⅔ × canopy height).
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = 10.0, allow_negative_numbers = true)]
    displacement: f64,
    /// Canopy profile: the canopy top h in m (log law above, exponential below).
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = 15.0)]
    canopy_height: f64,
    /// Canopy profile: the attenuation a inside the canopy (forests about 1–4; from a leaf
    /// area index L, c_d L / (2 · 0.3²) with c_d = 0.2: L = 3 gives 3.3).
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = 3.0)]
    attenuation: f64,
    /// Power law: reference speed in m/s.
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = 8.0)]
    u_ref: f64,
    /// Power law: reference height in m.
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = 20.0)]
    z_ref: f64,
    /// Power law: exponent.
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = 0.2)]
    alpha: f64,
    /// Point spectrum.
    #[arg(long, value_enum, default_value = "paper")]
    spectrum: SpectrumArg,
    /// Direction the wind blows towards, degrees counter-clockwise from +x.
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = 0.0, allow_negative_numbers = true)]
    direction: f64,
    /// Mean speed dividing the separations in eq. 5 (default: pair-mean with the paper's
    /// spectrum, reference with the IEC ones).
    #[arg(long, value_enum)]
    coherence_speed: Option<CoherenceSpeedArg>,
    /// Turn Taylor advection of gusts off (with the pair-mean speed, reproduces the paper's
    /// coherence exactly). With it on, gusts travel at one convection speed at every height.
    #[arg(long)]
    no_advection: bool,
    /// The convection speed gusts travel at, m/s, (0, 100] (default: the mean of Ū over the
    /// grid's heights). A canopy's large eddies travel at about 1.8 Ū(h), h its top.
    #[arg(long, value_parser = sylva_frames::finite::<f64>)]
    convection_speed: Option<f64>,
}

impl ModelArgs {
    fn params(&self) -> anyhow::Result<WindParams> {
        let preset = match self.preset {
            PresetArg::Calm => Preset::Calm,
            PresetArg::Breeze => Preset::Breeze,
            PresetArg::Strong => Preset::Strong,
            PresetArg::Storm => Preset::Storm,
        };
        let mut p = preset.params();
        if let Some(u) = self.u_star {
            p.u_star = u;
        }
        p.profile = match self.profile {
            ProfileArg::Log => Profile::Log { z0: self.z0, d: self.displacement },
            ProfileArg::Canopy => Profile::Canopy {
                h: self.canopy_height,
                a: self.attenuation,
                z0: self.z0,
                d: self.displacement,
            },
            ProfileArg::Power => {
                Profile::Power { u_ref: self.u_ref, z_ref: self.z_ref, alpha: self.alpha }
            }
        };
        p.spectrum = match self.spectrum {
            SpectrumArg::Paper => SpectrumModel::Paper,
            SpectrumArg::Kaimal => SpectrumModel::Kaimal,
            SpectrumArg::VonKarman => SpectrumModel::VonKarman,
        };
        p.coherence_speed = match self.coherence_speed {
            Some(CoherenceSpeedArg::PairMean) => CoherenceSpeed::PairMean,
            Some(CoherenceSpeedArg::Reference) => CoherenceSpeed::Reference,
            None => CoherenceSpeed::for_spectrum(p.spectrum),
        };
        p.direction_deg = self.direction;
        p.advection = !self.no_advection;
        p.convection_speed = self.convection_speed;
        p.validate().context("invalid wind model")?;
        Ok(p)
    }
}

/// Grid and sampling flags shared by `generate` and `demo`.
#[derive(Debug, Args)]
pub struct GridArgs {
    /// Points along the wind (x).
    #[arg(long, default_value_t = 64)]
    nx: usize,
    /// Points across the wind (y).
    #[arg(long, default_value_t = 64)]
    ny: usize,
    /// Regular spacing of x and y in m.
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = 4.0, allow_negative_numbers = true)]
    spacing: f64,
    /// Uneven x coordinates in m, comma-separated and increasing (overrides --nx/--spacing).
    #[arg(value_parser = crate::finite::<f64>, long, value_delimiter = ',', allow_negative_numbers = true)]
    xs: Option<Vec<f64>>,
    /// Uneven y coordinates in m (overrides --ny/--spacing).
    #[arg(value_parser = crate::finite::<f64>, long, value_delimiter = ',', allow_negative_numbers = true)]
    ys: Option<Vec<f64>>,
    /// Heights in m, comma-separated and increasing.
    #[arg(value_parser = crate::finite::<f64>, long, value_delimiter = ',', default_value = "20")]
    heights: Vec<f64>,
    /// Frames in the loop (even). Loop length = frames × dt; longer loops keep more of the
    /// slow gusts' variance (reported as the captured fraction).
    #[arg(long, default_value_t = 2048)]
    frames: usize,
    /// Time step in s; resolves up to 1/(2 dt) Hz.
    #[arg(value_parser = crate::finite::<f64>, long, default_value_t = 0.1, allow_negative_numbers = true)]
    dt: f64,
    /// Seed of the random phases. Same seed, same bits.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Synthesis method.
    #[arg(long, value_enum, default_value = "auto")]
    method: MethodArg,
}

/// Most grid points along x or y: a million (a 4 km side at 4 mm); checked before the
/// coordinate arrays are built, so a mistyped size is refused at once, not after gigabytes
/// are allocated.
const MAX_POINTS_A_SIDE: usize = 1_000_000;

impl GridArgs {
    fn grid(&self, params: &WindParams) -> anyhow::Result<(Grid, SynthParams)> {
        if self.nx == 0 || self.ny == 0 {
            bail!("--nx and --ny must be at least 1 (got {} and {})", self.nx, self.ny);
        }
        for (flag, n) in [("--nx", self.nx), ("--ny", self.ny)] {
            if n > MAX_POINTS_A_SIDE {
                bail!("{flag} {n}: at most {MAX_POINTS_A_SIDE} points a side");
            }
        }
        if !(self.spacing > 0.0 && self.spacing.is_finite()) {
            bail!("--spacing must be a positive number of metres (got {})", self.spacing);
        }
        let mut g =
            Grid::regular(self.nx, self.ny, self.spacing, &self.heights, self.frames, self.dt);
        if let Some(xs) = &self.xs {
            g.xs = xs.clone();
        }
        if let Some(ys) = &self.ys {
            g.ys = ys.clone();
        }
        g.validate()
            .context("invalid grid (see --nx/--ny/--spacing/--xs/--ys/--heights/--frames/--dt)")?;
        let method = match self.method {
            MethodArg::Auto => Method::fastest(params, &g),
            MethodArg::Separable => Method::Separable,
            MethodArg::Embedding => Method::Embedding,
            MethodArg::Cholesky => Method::Cholesky,
        };
        Ok((g, SynthParams { seed: self.seed, method }))
    }
}

#[derive(Debug, Args)]
pub struct GenerateArgs {
    #[command(flatten)]
    model: ModelArgs,
    #[command(flatten)]
    grid: GridArgs,
    /// Output file (.swf, .npy or .bts) or Zarr store (.zarr, streamed).
    #[arg(long, short, default_value = "out/wind.swf")]
    out: PathBuf,
    /// File format (default: from the extension of --out).
    #[arg(long, value_enum)]
    format: Option<FormatArg>,
    /// For .bts: which x column of the grid becomes the y–z plane.
    #[arg(long, default_value_t = 0)]
    bts_x_index: usize,
    /// Memory the synthesis may use, GB (default: three quarters of what the machine has
    /// free). A larger figure is taken as given: the field is refused only above it.
    #[arg(long, value_parser = crate::finite::<f64>)]
    max_memory: Option<f64>,
}

#[derive(Debug, Args)]
pub struct InfoArgs {
    /// The file (.swf, .npy, .zarr or .bts).
    file: PathBuf,
}

#[derive(Debug, Args)]
pub struct StatsArgs {
    /// Field files (.swf, .npy with its .json sidecar, or a .zarr store). Several files of one grid and
    /// model (different seeds) are pooled: the estimates average over them and their
    /// expected scatter shrinks accordingly.
    #[arg(required = true)]
    files: Vec<PathBuf>,
    /// Height index to report (default: every height).
    #[arg(long)]
    height: Option<usize>,
    /// Welch segment length in frames: even, 4 … the field's frames (default frames/8, at
    /// least 32).
    #[arg(long)]
    segment: Option<usize>,
    /// Print the statistics as JSON instead of tables.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
pub struct PlotArgs {
    /// A field file (.swf, or .npy with its .json sidecar).
    file: PathBuf,
    /// Folder for spectra.png and coherence.png (default: the file's folder).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Welch segment length in frames: even, 4 … the field's frames.
    #[arg(long)]
    segment: Option<usize>,
}

#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Output folder.
    #[arg(long, default_value = "out")]
    out: PathBuf,
}

pub fn run(cmd: WindCommand) -> anyhow::Result<()> {
    match cmd {
        WindCommand::Demo(a) => demo(a),
        WindCommand::Generate(a) => {
            let params = a.model.params()?;
            let (grid, synth) = a.grid.grid(&params)?;
            let format = match a.format {
                Some(f) => f,
                None => format_of(&a.out)?,
            };
            // Everything that can fail on the output is checked before the synthesis: its
            // folder exists (or is made) and takes a file.
            check_out_folder(&a.out)?;
            if format == FormatArg::Bts {
                io::check_bts(&grid, a.bts_x_index)?;
            }
            if let Some(gb) = a.max_memory.filter(|&g| g <= 0.0) {
                bail!("--max-memory {gb}: a memory budget must be a positive number of GB");
            }
            let streaming = format == FormatArg::Zarr;
            if streaming && synth.method != Method::Separable {
                bail!(
                    "--out {}: streaming to Zarr needs the separable method, and this model on \
                     this grid needs {}; add --coherence-speed reference (or use one height), \
                     or write .swf/.npy in memory",
                    a.out.display(),
                    synth.method.name()
                );
            }
            preflight(&params, &grid, synth, a.max_memory.map(|gb| gb * 1e9), streaming)?;
            if streaming {
                generate_zarr(&params, &grid, synth, &a.out)?;
            } else {
                let field = generate(&params, &grid, synth)?;
                write(&field, &a.out, format, a.bts_x_index)?;
            }
            println!("wrote {}", a.out.display());
            Ok(())
        }
        WindCommand::Info(a) => info(&a.file),
        WindCommand::Stats(a) => {
            let fields = a.files.iter().map(|f| read(f)).collect::<anyhow::Result<Vec<_>>>()?;
            for (f, path) in fields.iter().zip(&a.files).skip(1) {
                if f.grid != fields[0].grid || f.params != fields[0].params {
                    bail!(
                        "{} has another grid or model than {}: only realisations of one grid \
                         and model can be pooled",
                        path.display(),
                        a.files[0].display()
                    );
                }
            }
            let nz = fields[0].grid.nz();
            let heights: Vec<usize> = match a.height {
                Some(h) if h >= nz => {
                    bail!("--height {h} is outside the grid ({nz} heights, so 0 … {})", nz - 1)
                }
                Some(h) => vec![h],
                None => (0..nz).collect(),
            };
            check_segment(a.segment, fields[0].grid.frames)?;
            let stats: Vec<FieldStats> =
                heights.iter().map(|&h| ensemble_stats_at(&fields, a.segment, h)).collect();
            if a.json {
                println!("{}", serde_json::to_string_pretty(&stats)?);
            } else {
                for s in &stats {
                    print_stats(&fields[0], s);
                }
            }
            Ok(())
        }
        WindCommand::Plot(a) => {
            let field = read(&a.file)?;
            check_segment(a.segment, field.grid.frames)?;
            let dir =
                a.out.unwrap_or_else(|| a.file.parent().map(Path::to_path_buf).unwrap_or_default());
            std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
            for p in write_stats_plots(&field_stats(&field, a.segment), &dir)? {
                println!("wrote {}", p.display());
            }
            Ok(())
        }
    }
}

/// The main job until the forest renderer lands: generate, check and plot the default field.
pub fn demo(a: DemoArgs) -> anyhow::Result<()> {
    let params =
        WindParams { coherence_speed: CoherenceSpeed::PairMean, ..Preset::Breeze.params() };
    let grid = Grid::regular(64, 64, 4.0, &[20.0], 2048, 0.1);
    let synth = SynthParams { seed: 1, method: Method::fastest(&params, &grid) };
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    println!(
        "sylva wind demo: breeze over a 15 m forest, 64×64 points at 4 m, 2048 frames at 0.1 s"
    );
    let field = generate(&params, &grid, synth)?;
    let path = a.out.join("wind.swf");
    write(&field, &path, FormatArg::Swf, 0)?;
    let stats = field_stats(&field, None);
    print_stats(&field, &stats);
    let plots = write_stats_plots(&stats, &a.out)?;
    println!("\nwrote {}", path.display());
    for p in plots {
        println!("wrote {}", p.display());
    }
    Ok(())
}

/// The folder `out` is written into exists (made if missing) and is a folder, checked
/// before minutes of synthesis rather than after.
fn check_out_folder(out: &std::path::Path) -> anyhow::Result<()> {
    let dir =
        out.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(std::path::Path::new("."));
    std::fs::create_dir_all(dir)
        .with_context(|| format!("--out {}: creating {}", out.display(), dir.display()))?;
    if !dir.is_dir() {
        bail!("--out {}: {} is not a folder", out.display(), dir.display());
    }
    Ok(())
}

/// Refuse a Welch segment the estimate would have to change: under 4 frames, odd, or longer
/// than the field's `frames`.
fn check_segment(segment: Option<usize>, frames: usize) -> anyhow::Result<()> {
    match segment {
        Some(n) if n < 4 || n % 2 == 1 || n > frames => {
            bail!("--segment {n}: an even number of frames, 4 … {frames} (the field's frames)")
        }
        _ => Ok(()),
    }
}

/// Checks before a synthesis starts: the method fits the model and grid, the memory it needs
/// is there, the dense method's cost is stated, and heights under the log law's floor are
/// named.
fn preflight(
    params: &WindParams,
    grid: &Grid,
    synth: SynthParams,
    max_bytes: Option<f64>,
    streaming: bool,
) -> anyhow::Result<()> {
    sylva_wind::synth::check_config(params, grid, synth)?;
    let need = if streaming {
        sylva_wind::synth::streaming_memory_estimate(grid)
    } else {
        memory_estimate(grid, synth.method)
    };
    // A quarter of what is free stays free for the writer and the rest of the machine,
    // unless the user set the budget.
    let budget = match max_bytes {
        Some(b) => Some((b, "the --max-memory budget".to_string())),
        None => crate::available_memory().map(|a| {
            (0.75 * a, format!("three quarters of the {:.1} GB this machine has free", a / 1e9))
        }),
    };
    if let Some((limit, what)) = budget
        && need > limit
    {
        bail!(
            "this field needs about {:.2} GB ({} points × 3 components × {} frames, method {}), \
             more than {what} ({:.2} GB); reduce --frames, --nx/--ny or --heights, or set \
             --max-memory",
            need / 1e9,
            grid.points(),
            grid.frames,
            synth.method.name(),
            limit / 1e9
        );
    }
    if synth.method == Method::Cholesky {
        let est = cholesky_estimate(grid);
        eprintln!("dense Cholesky on {} points: {est}", grid.points());
        if est.seconds > 60.0 {
            eprintln!(
                "warning: the dense method is a reference for small grids; --method auto gives \
                 the same statistics in a fraction of the time"
            );
        }
    }
    if let Some(floor) = params.log_law_floor() {
        for &z in grid.zs.iter().filter(|&&z| z < floor) {
            eprintln!(
                "warning: height {z} m is below d + 2·z0 = {floor} m, where the log law ends; its \
                 mean speed is held at the floor's, {:.2} m/s",
                params.mean_speed(floor)
            );
        }
    }
    Ok(())
}

fn format_of(path: &Path) -> anyhow::Result<FormatArg> {
    match path.extension().and_then(|e| e.to_str()) {
        Some("swf") => Ok(FormatArg::Swf),
        Some("npy") => Ok(FormatArg::Npy),
        Some("bts") => Ok(FormatArg::Bts),
        Some("zarr") => Ok(FormatArg::Zarr),
        _ => bail!(
            "cannot tell the format of {}: use .swf, .npy, .bts or .zarr, or --format",
            path.display()
        ),
    }
}

fn generate(params: &WindParams, grid: &Grid, synth: SynthParams) -> anyhow::Result<WindField> {
    let bar = ProgressBar::new(1000);
    bar.set_style(
        ProgressStyle::with_template("synthesising {bar:40} {percent:>3}% {elapsed_precise}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let t0 = Instant::now();
    let field =
        WindField::generate(params, grid, synth, &|f| bar.set_position((f * 1000.0) as u64))?;
    bar.finish_and_clear();
    let secs = t0.elapsed().as_secs_f64();
    println!(
        "synthesised {} points × 3 components × {} frames in {:.2} s ({:.3} ms per frame)",
        grid.points(),
        grid.frames,
        secs,
        secs * 1e3 / grid.frames as f64
    );
    Ok(field)
}

/// Synthesise straight into a Zarr store, never holding the field; reports the time and the
/// peak resident memory.
fn generate_zarr(
    params: &WindParams,
    grid: &Grid,
    synth: SynthParams,
    out: &Path,
) -> anyhow::Result<()> {
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let bar = ProgressBar::new(1000);
    bar.set_style(
        ProgressStyle::with_template("synthesising {bar:40} {percent:>3}% {elapsed_precise}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let t0 = Instant::now();
    io::write_zarr_streaming(params, grid, synth, out, &|f| bar.set_position((f * 1000.0) as u64))?;
    bar.finish_and_clear();
    let output = (grid.points() * 3 * grid.frames * 4) as f64;
    println!(
        "streamed {} points × 3 components × {} frames ({:.2} GB) in {:.1} s; peak resident {}",
        grid.points(),
        grid.frames,
        output / 1e9,
        t0.elapsed().as_secs_f64(),
        peak_resident().map_or("unknown".into(), |b| format!("{:.2} GB", b / 1e9))
    );
    Ok(())
}

/// Peak resident memory of this process (VmHWM), bytes.
fn peak_resident() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    Some(line.split_whitespace().nth(1)?.parse::<f64>().ok()? * 1024.0)
}

fn write(field: &WindField, path: &Path, format: FormatArg, x_index: usize) -> anyhow::Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    match format {
        FormatArg::Swf => io::write_swf(field, path)?,
        FormatArg::Npy => io::write_npy(field, path)?,
        FormatArg::Bts => io::write_bts(field, x_index, path)?,
        FormatArg::Zarr => bail!("Zarr stores are written while synthesising (streamed)"),
    }
    Ok(())
}

pub fn read(path: &Path) -> anyhow::Result<WindField> {
    let field = match path.extension().and_then(|e| e.to_str()) {
        Some("bts") => bail!(
            "{}: a .bts file holds one y–z plane and not the wind model it came from; \
             `sylva wind info` reads it",
            path.display()
        ),
        _ => io::read_field(path),
    };
    reading(field, path)
}

/// A wind file's read error, with `reading PATH` before it unless it names the file itself
/// (an I/O error does; a malformed file's byte offset does not).
fn reading<T>(result: Result<T, sylva_wind::WindError>, path: &Path) -> anyhow::Result<T> {
    result.map_err(|e| match e {
        sylva_wind::WindError::Io { .. } => anyhow::Error::new(e),
        _ => anyhow::Error::new(e).context(format!("reading {}", path.display())),
    })
}

/// Mean and standard deviation of `values`.
fn mean_sigma(values: impl Iterator<Item = f64> + Clone) -> (f64, f64) {
    let n = values.clone().count().max(1) as f64;
    let mean = values.clone().sum::<f64>() / n;
    (mean, (values.map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt())
}

fn info(path: &Path) -> anyhow::Result<()> {
    // Per height: (z, [(mean, σ) of u, v, w]).
    let mut rows: Vec<(f64, [(f64, f64); 3])> = Vec::new();
    if path.extension().and_then(|e| e.to_str()) == Some("bts") {
        let b = reading(io::read_bts(path), path)?;
        println!(
            "TurbSim .bts ({}): {} heights × {} points across, dz {} m, dy {} m, {} tower \
             points; {} steps of {} s; hub {} m at {:.3} m/s",
            if b.periodic { "periodic" } else { "not periodic" },
            b.nz,
            b.ny,
            b.dz,
            b.dy,
            b.tower_points,
            b.frames,
            b.dt,
            b.hub_height,
            b.hub_speed
        );
        println!("description: {}", b.description.trim());
        for (iz, z) in b.zs().into_iter().enumerate() {
            let comp = |c| {
                mean_sigma(
                    (0..b.frames)
                        .flat_map(move |t| (0..b.ny).map(move |iy| (t, iy)))
                        .map(|(t, iy)| b.at(t, c, iz, iy) as f64),
                )
            };
            rows.push((z, [comp(0), comp(1), comp(2)]));
        }
    } else {
        let f = read(path)?;
        let g = &f.grid;
        println!(
            "{} × {} points × {} heights {:?} m; {} frames of {} s (a {} s loop); seed {}, {} \
             method, U* {} m/s",
            g.nx(),
            g.ny(),
            g.nz(),
            g.zs,
            g.frames,
            g.dt,
            g.period(),
            f.synth.seed,
            f.synth.method.name(),
            f.params.u_star
        );
        for (iz, &z) in g.zs.iter().enumerate() {
            let comp = |c| {
                let points = (0..g.ny()).flat_map(move |iy| (0..g.nx()).map(move |ix| (iy, ix)));
                let all = (0..g.frames).flat_map(move |t| points.clone().map(move |p| (t, p)));
                mean_sigma(all.map(|(t, (iy, ix))| f.data[f.index(t, c, iz, iy, ix)] as f64))
            };
            rows.push((z, [comp(0), comp(1), comp(2)]));
        }
    }
    println!("{:>9}{:>10}{:>9}{:>9}{:>9}", "z m", "mean u", "σ u", "σ v", "σ w");
    for (z, c) in rows {
        println!("{z:>9.2}{:>10.3}{:>9.3}{:>9.3}{:>9.3}", c[0].0, c[0].1, c[1].1, c[2].1);
    }
    Ok(())
}

fn print_stats(field: &WindField, s: &FieldStats) {
    let cap = field.captured();
    let pooled = if s.fields > 1 { format!(", {} fields pooled", s.fields) } else { String::new() };
    println!(
        "\nheight {:.1} m, Ū = {:.2} m/s, eq. 5 speed for this height {:.2} m/s ({}), Welch \
         segment {} frames{pooled}",
        s.height,
        field.params.mean_speed(s.height),
        s.coherence_speed,
        match field.params.coherence_speed {
            CoherenceSpeed::PairMean => "pair mean",
            CoherenceSpeed::Reference => "reference",
        },
        s.segment
    );
    if field.coherence_error > 0.0 {
        println!(
            "(the pair-mean model is not a valid covariance on this grid at some low lines: the \
             synthesis used its nearest valid one, coherences within {:.4} of eq. 5)",
            field.coherence_error
        );
    }
    println!(
        "{:<4}{:>9}{:>10}{:>9}{:>10}{:>10}{:>9}{:>10}  verdict",
        "", "σ meas", "σ target", "σ err", "var err", "scatter", "σ model", "captured"
    );
    for (c, comp) in s.components.iter().enumerate() {
        let k = comp.sigma_deviations();
        let verdict = if k <= 2.0 {
            format!("within scatter ({k:.1} s.d.)")
        } else {
            format!("OUTSIDE scatter ({k:.1} s.d.)")
        };
        println!(
            "{:<4}{:>9.4}{:>10.4}{:>8.2}%{:>9.2}%{:>9.2}%{:>9.4}{:>9.1}%  {verdict}",
            comp.component,
            comp.sigma,
            comp.sigma_target,
            100.0 * comp.sigma_error,
            100.0 * comp.variance_error,
            100.0 * comp.sigma_scatter,
            comp.sigma_model,
            100.0 * cap.fraction[c]
        );
    }
    println!(
        "(σ target: the loop's discrete lines Σ 2 S0 Δω; σ model: eq. 4 over all frequencies;\n \
         scatter: one standard deviation of σ err expected over realisations of this grid,\n \
         from the model — the slow lines are coherent over the whole grid)"
    );
    println!(
        "\nauto-spectrum vs eq. 4 (as the Welch estimator sees it): relative error per log band, \
         [expected scatter]"
    );
    print!("{:>9}", "f (Hz)");
    for c in &s.components {
        print!("{:>18}", c.component);
    }
    println!();
    for (i, b) in s.components[0].spectrum.iter().enumerate() {
        print!("{:>9.4}", b.f);
        for c in &s.components {
            let r = &c.spectrum[i];
            let flag = if r.rel_error().abs() > 0.03f64.max(3.0 * r.scatter) { '!' } else { ' ' };
            print!("{:>8.2}% [{:>5.2}%]{flag}", 100.0 * r.rel_error(), 100.0 * r.scatter);
        }
        println!();
    }
    println!(
        "\npooled co-coherence vs eq. 5: largest |error| where eq. 5 > 0.1, in units of its \
         expected scatter (! beyond 3 s.d. and 0.03)"
    );
    println!("{:<14}{:>18}{:>18}{:>18}", "separation", "u", "v", "w");
    for (k, row) in s.components[0].coherence.iter().enumerate() {
        print!("{:<14}", format!("d{} {:.1} m", row.axis, row.metres));
        for c in &s.components {
            let row = &c.coherence[k];
            let worst = row.bands.iter().filter(|b| b.model > 0.1).max_by(|a, b| {
                (a.measured - a.model).abs().total_cmp(&(b.measured - b.model).abs())
            });
            match worst {
                Some(b) => {
                    let e = (b.measured - b.model).abs();
                    let flag = if e > 0.03f64.max(3.0 * b.scatter) { '!' } else { ' ' };
                    print!("{:>9.4} [{:>4.1}σ]{flag}", e, e / b.scatter.max(1e-12));
                }
                None => print!("{:>18}", "—"), // eq. 5 below 0.1 at every band checked
            }
        }
        println!();
    }
}
