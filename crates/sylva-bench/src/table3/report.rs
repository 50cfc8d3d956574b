//! Table 3's outputs: the Markdown tables, the CSV and the chart.

use std::fmt::Write as _;

use super::Table3Bench;
use super::measure::{CONFIGS, Cell, PAPER, PARTS, command_line};
use super::metrics::{Floor, flip_ssim, per_scene, speed_up_range};
use sylva_wind::io::atomic::write_atomic;

/// One scene's results: its name, trees and one cell per configuration ([`CONFIGS`]).
type SceneCells = (String, usize, Vec<Cell>);

/// Write `table3.md`, `.csv` and `.png` into `a.out` and print the Markdown.
pub(super) fn write_outputs(
    a: &Table3Bench,
    machine: &str,
    adapter: &str,
    (w, h): (u32, u32),
    results: &[SceneCells],
    floors: &[Floor],
    popping: Option<&str>,
) -> anyhow::Result<()> {
    let mut md = String::new();
    let header: Vec<String> = results.iter().map(|(n, t, _)| format!("{n} ({t} trees)")).collect();
    fps_table(&mut md, a, machine, adapter, (w, h), results, &header);
    overlapped_table(&mut md, a, results, &header);
    passes_table(&mut md, results);
    let csv = per_configuration(&mut md, results);
    floors_text(&mut md, floors);
    speed_up_table(&mut md, a, results, &header);
    worst_paths(&mut md, results, floors);
    if let Some(p) = popping {
        md.push_str(p);
    }
    write_atomic(&a.out.join("table3.md"), md.as_bytes())?;
    write_atomic(&a.out.join("table3.csv"), csv.as_bytes())?;
    chart(a, results)?;
    println!("{md}");
    println!("wrote {}/table3.md, table3.csv, table3.png", a.out.display());
    Ok(())
}

/// The title, the command and machine, and frames per second beside the paper's.
fn fps_table(
    md: &mut String,
    a: &Table3Bench,
    machine: &str,
    adapter: &str,
    (w, h): (u32, u32),
    results: &[SceneCells],
    header: &[String],
) {
    let _ = writeln!(md, "# Table 3 on this machine\n");
    let _ =
        writeln!(md, "`{}`; machine: {machine}; adapter: {adapter}.\n", command_line(a, (w, h)));
    let _ = writeln!(
        md,
        "Frames per second (paper's figure in brackets: GeForce 6600 GT, 1024×768):\n"
    );
    let _ = writeln!(md, "| | {} |", header.join(" | "));
    let _ = writeln!(md, "|---|{}", "---|".repeat(results.len()));
    for (row, (label, ..)) in CONFIGS.iter().enumerate() {
        let cells: Vec<String> = results
            .iter()
            .map(|(name, _, cells)| {
                let col = ["A", "B", "C", "D"].iter().position(|s| s == name);
                let paper = col.map_or(String::new(), |c| format!(" ({})", PAPER[row][c]));
                let fps = cells[row].fps().map_or("—".into(), |f| format!("{f:.2}"));
                format!("{fps}{paper}")
            })
            .collect();
        let _ = writeln!(md, "| {label} | {} |", cells.join(" | "));
    }
}

/// Frames per second with the CPU's and the GPU's work overlapped (`--overlapped`).
fn overlapped_table(md: &mut String, a: &Table3Bench, results: &[SceneCells], header: &[String]) {
    if results.iter().any(|(_, _, cells)| cells.iter().any(|c| !c.overlapped.is_empty())) {
        let _ = writeln!(
            md,
            "\nFrames per second with the CPU's work on each frame overlapping the GPU's on the ones before (`--overlapped`: {}, as an interactive loop runs; the figures above add the two):\n",
            match a.in_flight {
                1 => "one frame in flight".to_string(),
                n => format!("up to {n} frames in flight"),
            }
        );
        let _ = writeln!(md, "| | {} |", header.join(" | "));
        let _ = writeln!(md, "|---|{}", "---|".repeat(results.len()));
        for (row, (label, ..)) in CONFIGS.iter().enumerate() {
            let cells: Vec<String> = results
                .iter()
                .map(|(_, _, cells)| {
                    cells[row].overlapped_fps().map_or("—".into(), |f| format!("{f:.2}"))
                })
                .collect();
            let _ = writeln!(md, "| {label} | {} |", cells.join(" | "));
        }
    }
}

/// The GPU's time in each part of the frame (`--gpu-passes`).
fn passes_table(md: &mut String, results: &[SceneCells]) {
    if results.iter().any(|(_, _, cells)| cells.iter().any(|c| !c.passes.is_empty())) {
        let _ = writeln!(
            md,
            "\nThe GPU's time in each part of the frame, ms (`--gpu-passes`: timestamp queries between the renderer's passes; medians over the timed frames; a draw still running when the next part starts shares its time with it):\n"
        );
        let _ = writeln!(
            md,
            "| scene | configuration | {} | sum |",
            sylva_render::PASS_PARTS.join(" | ")
        );
        let _ = writeln!(md, "|---|---|{}---|", "---|".repeat(PARTS));
        for (name, _, cells) in results {
            for (c, (label, ..)) in cells.iter().zip(CONFIGS) {
                if let Some(p) = c.pass_medians() {
                    let parts: Vec<String> = p.iter().map(|t| format!("{t:.2}")).collect();
                    let sum: f64 = p.iter().sum();
                    let _ = writeln!(md, "| {name} | {label} | {} | {sum:.2} |", parts.join(" | "));
                }
            }
        }
    }
}

/// The table of every configuration's figures, and the same as CSV (returned).
fn per_configuration(md: &mut String, results: &[SceneCells]) -> String {
    let _ = writeln!(
        md,
        "\nPer configuration (medians over the timed frames, and the slowest frame's simulation + frame building; means for counts):\n"
    );
    let _ = writeln!(
        md,
        "| scene | configuration | sim ms | frame ms | slowest sim + frame ms | render ms | M triangles | draws | joint updates | MB uploaded: mean / max | MB animation state | simulated trees | trees drawn | impostors | shadow only | occluded | FLIP vs full detail | SSIM vs full detail | note |"
    );
    let _ = writeln!(
        md,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    let mut csv = String::from(
        "scene,trees,configuration,fps,sim_ms,frame_ms,render_ms,triangles,draws,joint_updates,uploaded_mb,uploaded_max_mb,state_mb,simulated,impostors,shadow_only,flip,ssim,cpu_max_ms,overlapped_fps,gpu_shadows_ms,gpu_trees_ms,gpu_impostors_ms,gpu_ground_ms,gpu_sky_resolve_ms,occluded,drawn\n",
    );
    for (name, trees, cells) in results {
        for (c, (label, ..)) in cells.iter().zip(CONFIGS) {
            let opt = |v: Option<f64>, p: usize| v.map_or("—".into(), |v| format!("{v:.p$}"));
            let _ = writeln!(
                md,
                "| {name} | {label} | {:.1} | {:.1} | {:.1} | {} | {:.2} | {:.0} | {:.0} | {:.2} / {:.2} | {:.1} | {} | {:.0} | {:.0} | {:.0} | {:.0} | {} | {} | {} |",
                c.sim_ms,
                c.frame_ms,
                c.cpu_max_ms,
                opt(c.render_ms, 0),
                c.triangles / 1e6,
                c.draws,
                c.joints,
                c.upload_mb,
                c.upload_max_mb,
                c.state_mb,
                c.simulated,
                c.drawn,
                c.impostors,
                c.shadow_only,
                c.occluded,
                opt(c.flip, 3),
                opt(c.ssim, 3),
                c.note
            );
            let _ = writeln!(
                csv,
                "{name},{trees},{label},{},{:.3},{:.3},{},{:.0},{:.0},{:.0},{:.3},{:.3},{:.3},{},{:.0},{:.0},{},{},{:.3},{},{},{:.0},{:.0}",
                c.fps().map_or(String::new(), |f| format!("{f:.3}")),
                c.sim_ms,
                c.frame_ms,
                c.render_ms.map_or(String::new(), |r| format!("{r:.1}")),
                c.triangles,
                c.draws,
                c.joints,
                c.upload_mb,
                c.upload_max_mb,
                c.state_mb,
                c.simulated,
                c.impostors,
                c.shadow_only,
                c.flip.map_or(String::new(), |s| format!("{s:.4}")),
                c.ssim.map_or(String::new(), |s| format!("{s:.4}")),
                c.cpu_max_ms,
                c.overlapped_fps().map_or(String::new(), |f| format!("{f:.3}")),
                match c.pass_medians() {
                    Some(p) => p.map(|t| format!("{t:.3}")).join(","),
                    None => ",".repeat(PARTS - 1),
                },
                c.occluded,
                c.drawn
            );
        }
    }
    csv
}

/// The image error's floors: one frame of motion, the geometry LOD at rest, sampling.
fn floors_text(md: &mut String, floors: &[Floor]) {
    let _ = writeln!(
        md,
        "\nImage error floor — mean FLIP between two consecutive full-detail frames (0.1 s of wind): {}",
        per_scene(floors, |f| f.motion.map(|m| format!("{m:.3}")))
    );
    let _ = writeln!(
        md,
        "\nThe geometry LOD alone — all LODs against full detail before any step (every tree in its rest pose, nothing moving), the last timed frame's camera: {}",
        per_scene(floors, |f| f.still.map(|s| flip_ssim(s.lod)))
    );
    let _ = writeln!(
        md,
        "\nSampling alone — full detail in the rest pose against itself with the camera turned a quarter pixel aside (how much per-pixel metrics move where foliage is finer than a pixel): {}",
        per_scene(floors, |f| f.still.map(|s| flip_ssim(s.sampling)))
    );
    if floors.iter().any(|f| f.thinning.is_some()) {
        let _ = writeln!(
            md,
            "\nThinning of far impostors alone — all LODs with `thin_px` against all LODs with every far tree drawn, rest pose, the last timed frame's camera (FLIP / SSIM; then the unthinned frame against itself a quarter pixel aside): {}",
            per_scene(floors, |f| f.thinning.map(|t| format!(
                "{} (floor {})",
                flip_ssim(t.lod),
                flip_ssim(t.sampling)
            )))
        );
    }
}

/// Speed-up of each LOD: with all LODs against that one off, in frames per second, in CPU
/// time (simulation + frame building) and, with `--gpu-passes`, in the GPU's time (the
/// parts' sum), beside the paper's.
fn speed_up_table(md: &mut String, a: &Table3Bench, results: &[SceneCells], header: &[String]) {
    let _ = writeln!(
        md,
        "\nSpeed-up of each LOD (all LODs ÷ that LOD off): FPS here · CPU ms here{}{} · FPS in the paper:\n",
        if a.rounds > 1 { " (lowest–highest of the rounds)" } else { "" },
        if a.gpu_passes { " · GPU ms here" } else { "" }
    );
    let _ = writeln!(md, "| LOD | {} |", header.join(" | "));
    let _ = writeln!(md, "|---|{}", "---|".repeat(results.len()));
    for (row, (label, ..)) in CONFIGS.iter().enumerate().skip(1) {
        let cells: Vec<String> = results
            .iter()
            .map(|(name, _, cells)| {
                let (on, off) = (&cells[0], &cells[row]);
                let fps = match (on.fps(), off.fps()) {
                    (Some(x), Some(y)) => format!("×{:.2}", x / y),
                    _ => "—".into(),
                };
                let cpu_off = off.sim_ms + off.frame_ms;
                let cpu = if cpu_off > 0.0 {
                    let ratio = format!("×{:.2}", cpu_off / (on.sim_ms + on.frame_ms));
                    match speed_up_range(&on.round_cpu, &off.round_cpu) {
                        Some((lo, hi)) => format!("{ratio} ({lo:.2}–{hi:.2})"),
                        None => ratio,
                    }
                } else {
                    "—".into()
                };
                let gpu_ms = |c: &Cell| c.pass_medians().map(|p| p.iter().sum::<f64>());
                let gpu = match (gpu_ms(on), gpu_ms(off)) {
                    (Some(x), Some(y)) if x > 0.0 => format!(" · ×{:.2}", y / x),
                    _ if a.gpu_passes => " · —".into(),
                    _ => String::new(),
                };
                let col = ["A", "B", "C", "D"].iter().position(|s| s == name);
                let paper =
                    col.map_or("—".into(), |c| format!("×{:.2}", PAPER[0][c] / PAPER[row][c]));
                format!("{fps} · {cpu}{gpu} · {paper}")
            })
            .collect();
        let _ =
            writeln!(md, "| {} | {} |", label.trim_start_matches("without "), cells.join(" | "));
    }
}

/// `table3.png`: FPS against trees, one line per configuration, here and in the paper.
fn chart(a: &Table3Bench, results: &[SceneCells]) -> anyhow::Result<()> {
    // Chart: FPS against trees, one line per configuration (ours solid colours).
    let colours = [[30, 110, 40], [200, 60, 40], [40, 80, 200], [150, 120, 20]];
    let series = CONFIGS
        .iter()
        .enumerate()
        .map(|(row, (label, ..))| sylva_frames::plot::Series {
            label: label.to_uppercase(),
            color: colours[row],
            points: results
                .iter()
                .filter_map(|(_, trees, cells)| cells[row].fps().map(|f| (*trees as f64, f)))
                .collect(),
            markers: false,
        })
        .collect();
    let paper = CONFIGS
        .iter()
        .enumerate()
        .map(|(row, (label, ..))| sylva_frames::plot::Series {
            label: label.to_uppercase(),
            color: colours[row],
            points: [1000.0, 3000.0, 10000.0, 50000.0]
                .iter()
                .zip(PAPER[row])
                .map(|(t, f)| (*t, f))
                .collect(),
            markers: false,
        })
        .collect();
    let panels = [
        sylva_frames::plot::Panel {
            title: "FPS HERE".into(),
            x_label: "TREES".into(),
            y_label: "FRAMES PER SECOND".into(),
            log_x: true,
            log_y: true,
            y_range: None,
            series,
        },
        sylva_frames::plot::Panel {
            title: "FPS IN THE PAPER".into(),
            x_label: "TREES".into(),
            y_label: "FRAMES PER SECOND".into(),
            log_x: true,
            log_y: true,
            y_range: None,
            series: paper,
        },
    ];
    sylva_frames::plot::write_png(&a.out.join("table3.png"), &panels)?;
    Ok(())
}

/// Where scenes ran along several camera paths (`--path`), each scene's worst path for each
/// figure of the configuration with all LODs: the most triangles, CPU and rendering time,
/// upload, and image error over its sampling floor.
fn worst_paths(md: &mut String, results: &[SceneCells], floors: &[Floor]) {
    let scene_of = |name: &str| name.split(' ').next().unwrap_or(name).to_string();
    let mut scenes: Vec<String> = Vec::new();
    for (name, ..) in results {
        if !scenes.contains(&scene_of(name)) {
            scenes.push(scene_of(name));
        }
    }
    if results.len() == scenes.len() {
        return;
    }
    let _ = writeln!(
        md,
        "\nWorst path of each scene, all LODs (the path in brackets; image error less the path's sampling floor):\n"
    );
    let _ = writeln!(
        md,
        "| scene | M triangles | sim + frame ms | slowest sim + frame ms | render ms | MB uploaded (max) | FLIP over the floor |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|");
    let path_of = |name: &str| name.split_once(' ').map_or("fly-in", |(_, p)| p).to_string();
    for scene in scenes {
        let runs: Vec<(&String, &Cell)> = results
            .iter()
            .filter(|(n, ..)| scene_of(n) == scene)
            .map(|(n, _, cells)| (n, &cells[0]))
            .collect();
        let worst = |v: &dyn Fn(&Cell) -> Option<f64>, p: usize| {
            runs.iter()
                .filter_map(|(n, c)| v(c).map(|x| (x, path_of(n))))
                .max_by(|x, y| x.0.total_cmp(&y.0))
                .map_or("—".into(), |(x, n)| format!("{x:.p$} ({n})"))
        };
        let over_floor = |c: &Cell| {
            let name = runs.iter().find(|(_, k)| std::ptr::eq(*k, c)).map(|(n, _)| n.as_str())?;
            let floor = floors.iter().find(|f| f.scene == name)?.still?.sampling.0;
            c.flip.map(|f| f - floor)
        };
        let _ = writeln!(
            md,
            "| {scene} | {} | {} | {} | {} | {} | {} |",
            worst(&|c| Some(c.triangles / 1e6), 2),
            worst(&|c| Some(c.sim_ms + c.frame_ms), 1),
            worst(&|c| Some(c.cpu_max_ms), 1),
            worst(&|c| c.render_ms, 0),
            worst(&|c| Some(c.upload_max_mb), 2),
            worst(&over_floor, 3),
        );
    }
}
