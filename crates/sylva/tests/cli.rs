//! The command line: bad input is refused with an error naming the flag, field or byte;
//! a generated file round-trips through `stats`.

use std::process::Command;

use sylva_testkit::TempPath;

fn sylva(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_sylva")).args(args).output().expect("run sylva");
    let text =
        format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    (out.status.success(), text)
}

/// `name` in a temporary folder of its own, removed when the test is done with it.
fn temp(name: &str) -> TempPath {
    TempPath::new("sylva-cli", name)
}

#[test]
fn bad_grid_and_model_flags_name_what_is_wrong() {
    let out = temp("bad.swf");
    let o = out.to_str().expect("utf-8 path");
    for (args, needle) in [
        (vec!["--frames", "7"], "grid.frames"),
        (vec!["--spacing", "-2"], "--spacing"),
        (vec!["--heights", "20,10"], "grid.zs"),
        (vec!["--u-star", "-1"], "u_star"),
        (vec!["--xs", "0,5,5"], "grid.xs"),
    ] {
        let mut all = vec!["wind", "generate", "--out", o];
        all.extend(args.iter());
        let (ok, text) = sylva(&all);
        assert!(!ok, "{args:?} must fail");
        assert!(text.contains(needle), "{args:?}: error does not name {needle}: {text}");
        assert!(!text.contains("panicked"), "{text}");
    }
}

#[test]
fn generate_then_stats_and_a_cut_file_is_refused() {
    let path = temp("small.swf");
    let p = path.to_str().expect("utf-8 path");
    let (ok, text) =
        sylva(&["wind", "generate", "--nx", "8", "--ny", "8", "--frames", "256", "--out", p]);
    assert!(ok, "{text}");
    let (ok, text) = sylva(&["wind", "stats", p]);
    assert!(ok, "{text}");
    assert!(text.contains("captured") && text.contains("co-coherence"), "{text}");
    let bytes = std::fs::read(&path).expect("read");
    let cut = temp("cut.swf");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).expect("write");
    let (ok, text) = sylva(&["wind", "stats", cut.to_str().expect("utf-8 path")]);
    assert!(!ok);
    assert!(text.contains("truncated") && text.contains("byte"), "{text}");
    assert!(!text.contains("panicked"), "{text}");
}

/// `wind info` reports the same plane from the .swf and from its .bts export: the mean u
/// and σ of each component at each height agree within the .bts quantisation.
#[test]
fn wind_info_reads_swf_and_bts_alike() {
    let (swf, bts) = (temp("info.swf"), temp("info.bts"));
    for out in [&swf, &bts] {
        let o = out.to_str().expect("utf-8 path");
        let (ok, text) = sylva(&[
            "wind",
            "generate",
            "--nx",
            "1",
            "--ny",
            "6",
            "--heights",
            "10,20",
            "--frames",
            "64",
            "--out",
            o,
        ]);
        assert!(ok, "{text}");
    }
    let table = |path: &std::path::Path| -> Vec<Vec<f64>> {
        let (ok, text) = sylva(&["wind", "info", path.to_str().expect("utf-8 path")]);
        assert!(ok, "{text}");
        text.lines()
            .filter_map(|l| l.split_whitespace().map(|w| w.parse::<f64>().ok()).collect())
            .filter(|r: &Vec<f64>| r.len() == 5)
            .collect()
    };
    let (a, b) = (table(&swf), table(&bts));
    assert_eq!(a.len(), 2, "two heights: {a:?}");
    assert_eq!(a.len(), b.len());
    for (ra, rb) in a.iter().zip(&b) {
        assert_eq!(ra[0], rb[0], "heights");
        for k in 1..5 {
            assert!((ra[k] - rb[k]).abs() <= 2e-3, "{ra:?} vs {rb:?}");
        }
    }
    // stats needs the model, which a .bts does not carry: a clear refusal.
    let (ok, text) = sylva(&["wind", "stats", bts.to_str().expect("utf-8 path")]);
    assert!(!ok && text.contains("wind info"), "{text}");
}

/// A wind file that cannot be read is named once, with the system's reason once, whatever
/// the command and the format; a malformed file is named with the byte where it goes wrong.
#[test]
fn unreadable_wind_files_are_named_once_with_their_reason() {
    let dir = temp("missing");
    let folder = dir.to_str().expect("utf-8 path");
    std::fs::create_dir_all(&dir).expect("temp folder");
    for (command, file) in [("info", "gone.swf"), ("info", "gone.bts"), ("stats", "gone.npy")] {
        let path = format!("{folder}/{file}");
        let (ok, text) = sylva(&["wind", command, &path]);
        assert!(!ok, "{text}");
        assert_eq!(text.matches(path.as_str()).count(), 1, "the file named once: {text}");
        assert_eq!(text.matches("No such file").count(), 1, "the reason given once: {text}");
    }
    let (ok, text) = sylva(&["wind", "info", folder]);
    assert!(!ok && text.matches(folder).count() == 1, "a folder is named once: {text}");
    let short = format!("{folder}/short.swf");
    std::fs::write(&short, b"SWF").expect("write a truncated file");
    let (ok, text) = sylva(&["wind", "info", &short]);
    assert!(!ok && text.contains(&format!("reading {short}")) && text.contains("byte"), "{text}");
}

/// `--max-memory` sets the forest's animation-state cap: below what the scene needs (every
/// joint of every tree, without the animation LOD), the render is refused before the
/// simulation is built, naming the cap and how to raise it.
#[test]
fn render_refuses_a_forest_over_its_memory_cap() {
    let out = temp("capped");
    let o = out.to_str().expect("utf-8 path");
    let (ok, text) = sylva(&[
        "render",
        "--scene",
        "small",
        "--no-wind-lod",
        "--no-animation-lod",
        "--max-memory",
        "0.0001",
        "--out",
        o,
    ]);
    assert!(!ok, "{text}");
    assert!(text.contains("over the 1 MB cap") && text.contains("--max-memory"), "{text}");
    let (ok, text) = sylva(&["render", "--scene", "small", "--max-memory", "nan", "--out", o]);
    assert!(!ok && text.contains("--max-memory"), "{text}");
}

/// One glTF file per LOD with `--lod all` (editors import every scene of a file at once),
/// each a single scene; a level that does not exist is refused naming the range.
#[test]
fn tree_generate_writes_a_file_per_lod() {
    let out = temp("lods/fir.glb");
    let o = out.to_str().expect("utf-8 path");
    let (ok, text) =
        sylva(&["tree", "generate", "--species", "douglas_fir", "--lod", "all", "--out", o]);
    assert!(ok, "{text}");
    for l in 0..6 {
        let f = out.with_file_name(format!("fir.lod{l}.glb"));
        let b = std::fs::read(&f).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        let json_len = u32::from_le_bytes([b[12], b[13], b[14], b[15]]) as usize;
        let json = std::str::from_utf8(&b[20..20 + json_len]).expect("JSON chunk");
        assert_eq!(json.matches("\"primitives\"").count(), 1, "LOD {l}: one mesh");
        assert!(json.contains(&format!("\"name\":\"lod{l}\"")), "LOD {l}");
    }
    assert!(!out.exists(), "no all-LOD file under the plain name");
    let (ok, text) =
        sylva(&["tree", "generate", "--species", "douglas_fir", "--lod", "6", "--out", o]);
    assert!(!ok && text.contains("0 … 5"), "{text}");
}

/// `--wind` is one type everywhere: the probe takes a preset, a steady speed or a wind file;
/// text that is none of them is refused naming what is accepted, by `sway probe` and `render`.
#[test]
fn wind_flags_take_a_preset_a_speed_or_a_file() {
    let field = temp("probe-wind.swf");
    let f = field.to_str().expect("utf-8 path");
    let (ok, text) = sylva(&["wind", "generate", "--nx", "4", "--ny", "4", "--out", f]);
    assert!(ok, "{text}");
    let csv = temp("probe-wind.csv");
    let c = csv.to_str().expect("utf-8 path");
    for wind in ["storm", "7.5", f] {
        let (ok, text) = sylva(&[
            "sway",
            "probe",
            "--species",
            "quaking_aspen",
            "--wind",
            wind,
            "--seconds",
            "1",
            "--csv",
            c,
        ]);
        assert!(ok, "--wind {wind}: {text}");
        // A steady wind is written as it was given; the others vary.
        let rows = std::fs::read_to_string(&csv).expect("csv");
        let first = rows.lines().nth(1).unwrap_or_default().to_string();
        assert_eq!(wind == "7.5", first.contains(",7.5000,0.0000,0.0000,"), "{wind}: {first}");
        // The crown's static lean in the steady part of the wind: downwind, some centimetres
        // for an aspen in 7.5 m/s.
        if wind == "7.5" {
            let line = text.lines().find(|l| l.starts_with("crown lean")).unwrap_or_default();
            let metres = number_after(line, ": ").unwrap_or(0.0);
            assert!(line.contains("steady 7.5 m/s") && (0.02..0.3).contains(&metres), "{text}");
            // And the leaves turned from the sky by the same bends: the mean of their
            // vertical's vertical part a little below one.
            let line = text.lines().find(|l| l.starts_with("leaves turned")).unwrap_or_default();
            let up = number_after(line, "on average ").unwrap_or(1.0);
            assert!((0.85..0.995).contains(&up), "{text}");
        }
    }
    for cmd in
        [vec!["sway", "probe", "--species", "quaking_aspen"], vec!["render", "--scene", "small"]]
    {
        let mut args = cmd.clone();
        args.extend(["--wind", "gale"]);
        let (ok, text) = sylva(&args);
        assert!(!ok && text.contains("calm, breeze, strong or storm"), "{cmd:?}: {text}");
    }
}

#[test]
fn tree_and_sway_commands_work_and_refuse_bad_species_files() {
    let (ok, text) = sylva(&["tree", "list"]);
    assert!(ok && text.contains("quaking_aspen") && text.contains("douglas_fir"), "{text}");
    let (ok, text) = sylva(&["tree", "stats", "--species", "quaking_aspen", "--seed", "3"]);
    assert!(ok && text.contains("joints") && text.contains("height"), "{text}");
    let bad = temp("bad_species.toml");
    std::fs::write(&bad, "Shape = 7\n\n1DownAngle = 500\n").expect("write");
    let (ok, text) = sylva(&["tree", "stats", "--species", bad.to_str().expect("utf-8 path")]);
    assert!(!ok && text.contains("1DownAngle") && text.contains("line 3"), "{text}");
    assert!(!text.contains("panicked"), "{text}");
    let csv = temp("probe.csv");
    let c = csv.to_str().expect("utf-8 path");
    let (ok, text) = sylva(&[
        "sway",
        "probe",
        "--species",
        "douglas_fir",
        "--release",
        "--seconds",
        "12",
        "--fps",
        "30",
        "--csv",
        c,
    ]);
    assert!(ok && text.contains("frequency") && text.contains("damping ratio"), "{text}");
    // Two seconds of free decay are about one swing: the ratio is not read from it.
    let (ok, short) = sylva(&[
        "sway",
        "probe",
        "--species",
        "quaking_aspen",
        "--release",
        "--seconds",
        "2",
        "--csv",
        c,
    ]);
    assert!(ok && short.contains("not measured") && !short.contains("NaN"), "{short}");
    let rows = std::fs::read_to_string(&csv).expect("csv");
    assert!(
        rows.starts_with("time_s,wind_u") && rows.lines().count() > 900,
        "{}",
        rows.lines().count()
    );
}

#[test]
fn render_renders_frames_deterministically_and_says_what_to_install_without_a_driver() {
    let dir = temp("render");
    let d = dir.to_str().expect("utf-8 path");
    let args = [
        "render",
        "--scene",
        "small",
        "--seconds",
        "0.2",
        "--fps",
        "10",
        "--size",
        "96x64",
        "--out",
        d,
    ];
    let (ok, text) = sylva(&args);
    assert!(ok, "{text}");
    assert!(text.contains("triangles per frame"), "{text}");
    let first = std::fs::read(dir.join("frame_0001.png")).expect("frame written");
    assert!(dir.join("forest.gif").exists());
    // Again with the GPU's time read by part: the same frame, and the five parts' medians.
    let timed: Vec<&str> = args.iter().copied().chain(["--gpu-passes"]).collect();
    let (ok, text) = sylva(&timed);
    assert!(ok, "{text}");
    assert_eq!(
        first,
        std::fs::read(dir.join("frame_0001.png")).expect("frame"),
        "same scene, same frame, timed or not"
    );
    let line = text.lines().find(|l| l.starts_with("GPU ms by part")).unwrap_or("");
    assert!(
        ["shadows", "trees", "impostors", "ground", "sky", "sum"].iter().all(|p| line.contains(p)),
        "{text}"
    );
    // No Vulkan driver at all: the error names the packages to install.
    let out = Command::new(env!("CARGO_BIN_EXE_sylva"))
        .args(args)
        .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
        .env("VK_DRIVER_FILES", "/nonexistent/icd.json")
        .output()
        .expect("run sylva");
    let text = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(text.contains("mesa-vulkan-drivers"), "{text}");
    // Bad flags name the flag.
    for (flag, value) in
        [("--size", "12x"), ("--fps", "0"), ("--scene", "nowhere"), ("--wind", "gale")]
    {
        let mut a: Vec<&str> = vec!["render", "--out", d];
        a.extend([flag, value]);
        let (ok, text) = sylva(&a);
        assert!(!ok && (text.contains(flag) || text.contains(value)), "{flag} {value}: {text}");
        assert!(!text.contains("panicked"), "{text}");
    }
}

/// `bench render --frames N` times N frames after its warm-up frame: the warm-up is left out
/// of the count and of the medians.
#[test]
fn bench_render_reports_the_frames_it_timed() {
    let dir = temp("bench");
    std::fs::create_dir_all(&dir).expect("temp folder");
    let out = Command::new(env!("CARGO_BIN_EXE_sylva"))
        .args(["bench", "render", "--scene", "small", "--frames", "2", "--size", "96x64"])
        .current_dir(&dir)
        .output()
        .expect("run sylva");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}{}", String::from_utf8_lossy(&out.stderr));
    let line = text.lines().find(|l| l.contains("frames at")).unwrap_or("");
    assert!(line.starts_with("2 frames at 96x64"), "{text}");
    assert!(dir.join("out/bench-render/frame_0002.png").exists(), "three frames rendered");
}

#[test]
fn lod_flags_are_checked_before_any_work() {
    for (args, needle) in [
        (vec!["--far-level", "9"], "--far-level"),
        (vec!["--lod-fraction", "0"], "--lod-fraction"),
        (vec!["--lod-fraction", "NaN"], "--lod-fraction"),
    ] {
        let mut all = vec!["render", "--scene", "small", "--seconds", "0.1", "--no-gif"];
        all.extend(args.iter());
        let (ok, text) = sylva(&all);
        assert!(!ok, "{args:?} must fail");
        assert!(text.contains(needle), "{args:?}: error does not name {needle}: {text}");
        assert!(!text.contains("panicked"), "{text}");
    }
}

/// A benchmark asked for no timed frames (runs, steps, instances) says so, naming the flag,
/// instead of timing one in silence or dividing by zero.
#[test]
fn benchmarks_refuse_zero_counts() {
    // Zero instances read "inf ns per joint"; zero frames timed one frame in silence.
    for (args, flag) in [
        (&["bench", "table3", "--scenes", "small", "--frames", "0"][..], "--frames"),
        (&["bench", "render", "--scene", "small", "--frames", "0"], "--frames"),
        (&["bench", "sway", "--instances", "0"], "--instances"),
        (&["bench", "sway", "--steps", "0"], "--steps"),
        (&["bench", "tree", "--runs", "0"], "--runs"),
        (&["bench", "wind", "--runs", "0"], "--runs"),
    ] {
        let (ok, text) = sylva(args);
        assert!(!ok, "{args:?} must fail");
        assert!(text.contains(flag) && text.contains("at least 1"), "{args:?}: {text}");
        assert!(!text.contains("panicked"), "{text}");
    }
}

#[test]
fn output_errors_come_before_the_synthesis() {
    // A .bts column outside the grid, uneven .bts heights, a field larger than the machine
    // and a dense method past its size are refused at once: nothing is synthesised (no
    // "synthesised" line) and no file is written.
    let out = temp("early.bts");
    let o = out.to_str().expect("utf-8 path");
    for (args, needle) in [
        (vec!["--nx", "8", "--bts-x-index", "8"], "--bts-x-index 8"),
        (vec!["--nx", "8", "--heights", "15,20,40"], "evenly spaced heights"),
        (vec!["--nx", "1700", "--ny", "1700", "--frames", "4096"], "GB"), // 142 GB
        (vec!["--nx", "70", "--ny", "70", "--method", "cholesky"], "4096 points"),
    ] {
        let mut all = vec!["wind", "generate", "--out", o];
        all.extend(args.iter());
        let t0 = std::time::Instant::now();
        let (ok, text) = sylva(&all);
        assert!(!ok, "{args:?} must fail");
        assert!(text.contains(needle), "{args:?}: error does not name {needle}: {text}");
        assert!(!text.contains("synthesised"), "{args:?} synthesised first: {text}");
        assert!(t0.elapsed().as_secs_f64() < 5.0, "{args:?} took {:?}", t0.elapsed());
        assert!(!out.exists(), "{args:?} wrote a file");
    }
}

#[test]
fn heights_under_the_log_law_are_named_and_seeds_pool_in_stats() {
    let (a, b) = (temp("pool-a.swf"), temp("pool-b.swf"));
    let common = ["--nx", "8", "--ny", "8", "--frames", "256", "--heights", "8,20"];
    let (ok, text) = sylva(
        &[&["wind", "generate", "--seed", "1", "--out", a.to_str().expect("utf-8")][..], &common]
            .concat(),
    );
    assert!(ok, "{text}");
    assert!(text.contains("height 8 m is below d + 2·z0 = 13 m"), "{text}");
    let (ok, text) = sylva(
        &[&["wind", "generate", "--seed", "2", "--out", b.to_str().expect("utf-8")][..], &common]
            .concat(),
    );
    assert!(ok, "{text}");
    let (ok, text) =
        sylva(&["wind", "stats", a.to_str().expect("utf-8"), b.to_str().expect("utf-8")]);
    assert!(ok, "{text}");
    assert!(text.contains("2 fields pooled") && text.contains("pair mean"), "{text}");
    assert!(text.contains("σ err") && text.contains("var err") && text.contains("scatter"));
    assert!(text.contains("dz 12.0 m"), "{text}");
}

#[test]
fn nan_and_infinity_are_refused_by_float_flags_naming_the_flag() {
    let out = temp("nan.swf");
    let o = out.to_str().expect("utf-8 path");
    for (args, needle) in [
        (vec!["wind", "generate", "--out", o, "--u-star", "nan"], "--u-star"),
        (vec!["wind", "generate", "--out", o, "--dt", "inf"], "--dt"),
        (vec!["wind", "generate", "--out", o, "--heights", "20,NaN"], "--heights"),
        (vec!["wind", "generate", "--out", o, "--direction=-inf"], "--direction"),
        (vec!["sway", "probe", "--species", "quaking_aspen", "--wind", "nan"], "--wind"),
        (vec!["render", "--seconds", "nan"], "--seconds"),
        (vec!["bench", "sway", "--wind", "inf"], "--wind"),
    ] {
        let (ok, text) = sylva(&args);
        assert!(!ok, "{args:?} must fail");
        assert!(text.contains(needle) && text.contains("finite"), "{args:?}: {text}");
        assert!(!text.contains("panicked"), "{text}");
    }
    assert!(!out.exists(), "no file is written");
}

#[test]
fn resource_guards_refuse_before_work_with_what_to_change() {
    // Branch counts inside their ranges that would grow 2.4·10¹⁰ joints.
    let sp = temp("exploding.toml");
    std::fs::write(&sp, "Levels = 4\n1Branches = 2000\n2Branches = 2000\n3Branches = 2000\n")
        .expect("write species");
    let t0 = std::time::Instant::now();
    let (ok, text) = sylva(&["tree", "stats", "--species", sp.to_str().expect("utf-8")]);
    assert!(!ok && text.contains("MaxJoints") && text.contains("nBranches"), "{text}");
    assert!(t0.elapsed().as_secs_f64() < 5.0, "took {:?}", t0.elapsed());
    // A wind field over a memory budget the user set.
    let out = temp("budget.swf");
    let (ok, text) = sylva(&[
        "wind",
        "generate",
        "--nx",
        "64",
        "--ny",
        "64",
        "--max-memory",
        "0.01",
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    assert!(!ok && text.contains("--max-memory budget") && text.contains("0.12 GB"), "{text}");
    assert!(!out.exists());
    // 1500 × 1500 points × 4096 frames: 110.6 GB of output, 111.5 GB of working memory, with
    // no budget set, against this machine's free memory (on a machine with that much free it
    // would simply run).
    let free_gb = std::fs::read_to_string("/proc/meminfo").ok().and_then(|m| {
        let line = m.lines().find(|l| l.starts_with("MemAvailable:"))?.to_string();
        line.split_whitespace().nth(1)?.parse::<f64>().ok().map(|kb| kb * 1024.0 / 1e9)
    });
    if free_gb.is_some_and(|gb| gb < 140.0) {
        let t0 = std::time::Instant::now();
        let (ok, text) = sylva(&[
            "wind",
            "generate",
            "--nx",
            "1500",
            "--ny",
            "1500",
            "--frames",
            "4096",
            "--out",
            out.to_str().expect("utf-8"),
        ]);
        assert!(!ok && text.contains("111.48 GB") && text.contains("free"), "{text}");
        assert!(t0.elapsed().as_secs_f64() < 5.0, "refused up front, took {:?}", t0.elapsed());
    }
}

#[test]
fn table3_with_all_lods_only_runs_that_configuration_and_its_image_error() {
    let dir = temp("table3");
    let d = dir.to_str().expect("utf-8 path");
    let args = [
        "bench",
        "table3",
        "--scenes",
        "small",
        "--size",
        "128x96",
        "--frames",
        "1",
        "--warmup",
        "0",
        "--popping-frames",
        "0",
        "--all-lods-only",
        "--overlapped",
        "--gpu-passes",
        "--out",
        d,
    ];
    let (ok, text) = sylva(&args);
    assert!(ok, "{text}");
    let csv = std::fs::read_to_string(dir.join("table3.csv")).expect("table3.csv");
    let rows: Vec<Vec<&str>> =
        csv.lines().filter(|l| l.starts_with("small,")).map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 4, "{csv}");
    // Columns by their header. The first configuration ran and was compared with full
    // detail.
    let header: Vec<&str> = csv.lines().next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let (tris, flip, ssim) = (col("triangles"), col("flip"), col("ssim"));
    assert_eq!(rows[0][col("configuration")], "with all LODs");
    let triangles: f64 = rows[0][tris].parse().expect("triangles");
    assert!(triangles > 0.0, "{csv}");
    for c in [flip, ssim] {
        let v: f64 = rows[0][c].parse().unwrap_or_else(|_| panic!("column {c}: {csv}"));
        assert!((0.0..=1.0).contains(&v), "{csv}");
    }
    // Uploads: the largest frame's at least the mean.
    let up = |name| rows[0][col(name)].parse::<f64>().expect(name);
    assert!(up("uploaded_max_mb") >= up("uploaded_mb") && up("uploaded_mb") > 0.0, "{csv}");
    // The slowest frame's simulation + frame building: with one timed frame, that frame's.
    let (sim, frame, slowest) = (up("sim_ms"), up("frame_ms"), up("cpu_max_ms"));
    assert!(sim > 0.0 && (slowest - (sim + frame)).abs() < 0.002, "{csv}");
    // The animation state held: some, and far less than a GB for five trees.
    assert!(up("state_mb") > 0.0 && up("state_mb") < 1000.0, "{csv}");
    // With CPU and GPU overlapped the rendered configuration ran again at some frame rate;
    // a frame there costs at least its simulation and frame building.
    let overlapped = up("overlapped_fps");
    assert!(overlapped > 0.0 && overlapped < 1000.0 / sim, "{csv}");
    // The others did not run, and say so.
    for r in &rows[1..] {
        assert!(r[tris] == "0" && r[flip].is_empty(), "{csv}");
        assert!(r[col("overlapped_fps")].is_empty(), "{csv}");
    }
    let md = std::fs::read_to_string(dir.join("table3.md")).expect("table3.md");
    assert_eq!(md.matches("not run (--all-lods-only)").count(), 3, "{md}");
    assert!(md.contains("overlapping the GPU's on the ones before"), "{md}");
    // The GPU's time by part of the frame: five parts and their sum, which is within the
    // frame's rendering time (that also holds the uploads and the wait for the GPU).
    let parts = md
        .lines()
        .skip_while(|l| !l.starts_with("| scene | configuration | shadows | trees | impostors |"))
        .find(|l| l.starts_with("| small | with all LODs |"))
        .unwrap_or_else(|| panic!("no GPU time by part: {md}"));
    let ms: Vec<f64> = parts.split('|').skip(3).filter_map(|c| c.trim().parse().ok()).collect();
    assert_eq!(ms.len(), 6, "{parts}");
    let sum: f64 = ms[..5].iter().sum();
    assert!((sum - ms[5]).abs() < 0.035 && sum > 0.0, "{parts}");
    assert!(sum <= up("render_ms") + 0.05, "parts {sum} ms, rendering {} ms", up("render_ms"));
    // The same parts in the CSV, every row as many fields as the header.
    let csv_parts: f64 = ["shadows", "trees", "impostors", "ground", "sky_resolve"]
        .iter()
        .map(|p| rows[0][col(&format!("gpu_{p}_ms"))].parse::<f64>().expect("a part's ms"))
        .sum();
    assert!((csv_parts - sum).abs() < 0.03, "CSV {csv_parts} ms, Markdown {sum} ms");
    assert!(rows.iter().all(|r| r.len() == header.len()), "{csv}");
    // The speed-ups are given in the GPU's time too (none here: only all LODs ran).
    assert!(md.contains("CPU ms here · GPU ms here · FPS in the paper"), "{md}");
    assert!(dir.join("small-with-all-LODs.png").exists());
    assert!(dir.join("small-full-detail.png").exists());
}

/// The number that follows the first `key` in `line`, up to the next space.
fn number_after(line: &str, key: &str) -> Option<f64> {
    line.split(key).nth(1)?.split(' ').next()?.parse().ok()
}
