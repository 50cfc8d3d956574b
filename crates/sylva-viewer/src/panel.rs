//! The control panel (egui): wind, LOD, scene, figures, plots and the selected tree. It reads
//! the [`Viewer`] and answers with [`Action`]s; it changes nothing itself.

use egui::{Color32, RichText, Ui};
use egui_plot::{Line, Plot};

use super::input::KEYS;
use super::state::{Action, MAX_SUBSTEPS, PRESETS, SCENES, SUBSTEP, Viewer};

/// What the panel edits before it is applied (the scene is rebuilt only on "Rebuild").
#[derive(Debug, Clone, PartialEq)]
pub struct Draft {
    /// Scene name or file.
    pub scene: String,
    /// Trees.
    pub trees: usize,
    /// Seed.
    pub seed: u64,
    /// Species mix: names and weights.
    pub species: Vec<sylva_forest::SpeciesShare>,
}

impl Draft {
    /// The viewer's current scene.
    pub fn of(v: &Viewer) -> Draft {
        Draft {
            scene: v.settings.scene.clone(),
            trees: v.settings.trees,
            seed: v.settings.seed,
            species: v.forest.spec.species.clone(),
        }
    }
}

/// Draw the panel (when shown), the key help (when asked) and the slow-motion mark.
/// Returns the width the panel takes on the left, in egui points (0 without it).
pub fn show(ui: &mut Ui, v: &Viewer, draft: &mut Draft, out: &mut Vec<Action>) -> f32 {
    let mut width = 0.0;
    if v.panel {
        let shown = egui::Panel::left("sylva-panel").default_size(300.0).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| contents(ui, v, draft, out));
        });
        width = shown.response.rect.width();
    }
    if v.clock.slow {
        egui::Area::new(egui::Id::unique("slow"))
            .anchor(egui::Align2::RIGHT_TOP, [-12.0, 12.0])
            .show(ui.ctx(), |ui| {
                ui.label(
                    RichText::new(format!(
                        "slow motion: frames take over {:.0} ms; the simulation keeps {:.2} s a frame",
                        1e3 * MAX_SUBSTEPS as f32 * SUBSTEP / v.settings.time_scale,
                        MAX_SUBSTEPS as f32 * SUBSTEP
                    ))
                    .color(Color32::from_rgb(255, 200, 60))
                    .strong(),
                );
            });
    }
    if v.help {
        let keys = egui::Window::new("Keys (F1)").collapsible(false).resizable(false);
        keys.anchor(egui::Align2::CENTER_CENTER, [0.0, 0.0]).show(ui.ctx(), |ui| {
            egui::Grid::new("keys").striped(true).show(ui, |ui| {
                for (key, what) in KEYS {
                    ui.label(RichText::new(key).monospace());
                    ui.label(what);
                    ui.end_row();
                }
            });
        });
    }
    width
}

fn contents(ui: &mut Ui, v: &Viewer, draft: &mut Draft, out: &mut Vec<Action>) {
    ui.heading("sylva");
    if let Some((what, secs)) = v.busy() {
        ui.horizontal(|ui| {
            ui.spinner();
            ui.label(format!("{what}… {secs:.1} s"));
        });
    }
    if let Some(e) = &v.error {
        ui.colored_label(Color32::from_rgb(255, 120, 100), e);
    }
    figures(ui, v);
    gpu_passes(ui, v, out);
    egui::CollapsingHeader::new("Wind").default_open(true).show(ui, |ui| wind(ui, v, out));
    egui::CollapsingHeader::new("Level of detail")
        .default_open(true)
        .show(ui, |ui| lod(ui, v, out));
    egui::CollapsingHeader::new("Scene")
        .default_open(false)
        .show(ui, |ui| scene(ui, v, draft, out));
    egui::CollapsingHeader::new("Camera").default_open(false).show(ui, |ui| camera(ui, v, out));
    egui::CollapsingHeader::new("Selected tree").default_open(true).show(ui, |ui| selected(ui, v));
    egui::CollapsingHeader::new("Plots (last 30 s)").default_open(true).show(ui, |ui| plots(ui, v));
}

fn figures(ui: &mut Ui, v: &Viewer) {
    let f = &v.figures;
    let s = &v.frame.stats;
    egui::Grid::new("figures").num_columns(2).show(ui, |ui| {
        let mut row = |k: &str, val: String| {
            ui.label(k);
            ui.label(val);
            ui.end_row();
        };
        // Both from the smoothed rate, so they agree (the last frame alone jumps about).
        let ms = if f.fps > 0.0 { 1e3 / f.fps } else { 0.0 };
        row("frames per second", format!("{:.1} ({ms:.0} ms a frame)", f.fps));
        row("simulation", format!("{:.1} ms ({} substeps)", f.sim_ms, f.substeps));
        row("frame building", format!("{:.1} ms", f.build_ms));
        row("rendering", format!("{:.1} ms", f.render_ms));
        row("triangles", format!("{:.2} M", s.triangles as f64 / 1e6));
        row("draw calls", s.draw_calls.to_string());
        row("trees drawn", format!("{} of {} ({} impostors)", s.drawn, s.trees, s.impostors));
        row("shadow only", format!("{} trees out of view", s.shadow_only));
        // The frame's per-tree work: the trees of the forest's squares in view.
        row("trees visited", format!("{} (squares tested: {})", s.trees_visited, s.cells_visited));
        if s.thinned > 0 {
            row("thinned", format!("{} far trees left out", s.thinned));
        }
        row(
            "occluded",
            if v.forest.lod().occlusion {
                format!("{} trees hidden by nearer ones", s.occluded)
            } else {
                "culling off".to_string()
            },
        );
        row(
            "joints stepped",
            if v.settings.paused {
                format!("none, paused ({} in the last step)", s.joints)
            } else {
                s.joints.to_string()
            },
        );
        row("uploaded", format!("{:.2} MB a frame", s.uploaded_bytes as f64 / 1e6));
        let capped = match s.state_capped {
            0 => String::new(),
            n => format!(", {n} groups held coarser by the cap"),
        };
        row("animation state", format!("{:.1} MB{capped}", s.state_bytes as f64 / 1e6));
        row("simulated time", format!("{:.1} s", v.forest.time()));
    });
}

/// The switch for the GPU's time by part of the frame, and those times.
fn gpu_passes(ui: &mut Ui, v: &Viewer, out: &mut Vec<Action>) {
    let mut on = v.gpu_passes;
    if ui.checkbox(&mut on, "GPU time by part (timestamp queries)").changed() {
        out.push(Action::GpuPasses(on));
    }
    if !v.gpu_passes {
        return;
    }
    match v.figures.passes {
        Some(p) => {
            egui::Grid::new("gpu passes").num_columns(2).show(ui, |ui| {
                for (name, ms) in sylva_render::PASS_PARTS.iter().zip(p) {
                    ui.label(format!("  {name}"));
                    ui.label(format!("{ms:.2} ms"));
                    ui.end_row();
                }
            });
        }
        None => {
            ui.label("  no times yet (or no timestamps on this adapter)");
        }
    }
}

fn wind(ui: &mut Ui, v: &Viewer, out: &mut Vec<Action>) {
    let mut preset = v.settings.wind.clone();
    egui::ComboBox::from_label("wind").selected_text(&preset).show_ui(ui, |ui| {
        for p in PRESETS {
            ui.selectable_value(&mut preset, p.to_string(), p);
        }
    });
    if preset != v.settings.wind {
        out.push(Action::Wind(preset));
    }
    let is_preset = PRESETS.contains(&v.settings.wind.as_str());
    if is_preset {
        let params = sylva_wind::Preset::from_name(&v.settings.wind).map(|p| p.params().u_star);
        let mut u = v.settings.u_star.or(params).unwrap_or(1.0);
        // Up to 8 m/s: every preset (the storm's 6) and beyond.
        let r =
            ui.add(egui::Slider::new(&mut u, 0.1..=U_STAR_MAX).text("U*, m/s (re-synthesised)"));
        if r.drag_stopped() || (r.changed() && !r.dragged()) {
            out.push(Action::UStar(u));
        }
    }
    let (gain, turn) = v.forest.wind_control();
    let (mut g, mut t) = (gain, turn);
    if ui.add(egui::Slider::new(&mut g, 0.0..=4.0).text("speed ×")).changed() {
        out.push(Action::WindGain(g));
    }
    if ui.add(egui::Slider::new(&mut t, -180.0..=180.0).text("turn, °")).changed() {
        out.push(Action::WindTurn(t));
    }
    if is_preset {
        profile(ui, v, out);
    }
    let mut adv = v.settings.advection;
    if is_preset && ui.checkbox(&mut adv, "advection (gusts travel downwind)").changed() {
        out.push(Action::Advection(adv));
    }
    let mut scale = v.settings.time_scale;
    if ui
        .add(egui::Slider::new(&mut scale, 0.05..=4.0).logarithmic(true).text("time scale"))
        .changed()
    {
        out.push(Action::TimeScale(scale));
    }
    ui.horizontal(|ui| {
        let mut paused = v.settings.paused;
        if ui.checkbox(&mut paused, "paused").changed() {
            out.push(Action::Pause(paused));
        }
        if ui.add_enabled(v.settings.paused, egui::Button::new("step")).clicked() {
            out.push(Action::Step);
        }
    });
    let w = v.frame.wind;
    ui.label(format!("wind at 20 m, now: {:.1} m/s", (w[0] * w[0] + w[1] * w[1]).sqrt()));
}

/// The U* slider's end, m/s: above every preset's (the storm's is 6).
pub const U_STAR_MAX: f64 = 8.0;

/// The mean profile's parameters (applied, and re-synthesised, when a drag ends).
fn profile(ui: &mut Ui, v: &Viewer, out: &mut Vec<Action>) {
    use sylva_wind::Profile;
    // A preset's profile over a forest with the canopy wind is its stand's.
    let preset = sylva_wind::Preset::from_name(&v.settings.wind)
        .map(|p| v.forest.stand().map_or(p.params().profile, |s| s.profile()));
    let Some(mut p) = v.settings.profile.or(preset) else { return };
    let mut done = false;
    let mut slider =
        |ui: &mut Ui, value: &mut f64, range: std::ops::RangeInclusive<f64>, text: &str| {
            let r = ui.add(egui::Slider::new(value, range).text(text));
            done |= r.drag_stopped() || (r.changed() && !r.dragged());
        };
    match &mut p {
        Profile::Log { z0, d } => {
            ui.label("log-law profile");
            slider(ui, z0, 0.05..=5.0, "z0, m");
            slider(ui, d, 0.0..=30.0, "d, m");
        }
        Profile::Canopy { h, a, z0, d } => {
            ui.label("canopy profile (log law over, exponential in)");
            slider(ui, h, 2.0..=60.0, "canopy top h, m");
            slider(ui, a, 0.1..=10.0, "attenuation a");
            slider(ui, z0, 0.05..=5.0, "z0, m");
            slider(ui, d, 0.0..=30.0, "d, m");
        }
        Profile::Power { u_ref, z_ref, alpha } => {
            ui.label("power-law profile");
            slider(ui, u_ref, 0.5..=60.0, "U_ref, m/s");
            slider(ui, z_ref, 2.0..=100.0, "z_ref, m");
            slider(ui, alpha, 0.0..=1.0, "exponent");
        }
    }
    if done {
        out.push(Action::Profile(p));
    }
}

fn lod(ui: &mut Ui, v: &Viewer, out: &mut Vec<Action>) {
    let lod = v.forest.lod();
    let mut l = lod;
    ui.checkbox(&mut l.geometry, "geometry LOD (meshes, then impostors)");
    ui.add_enabled(
        l.geometry,
        egui::Slider::new(&mut l.fraction, 0.05..=20.0)
            .logarithmic(true)
            .text("h₀ (full detail above)"),
    );
    ui.add_enabled(l.geometry, egui::Slider::new(&mut l.band, 0.0..=1.0).text("cross-fade band"));
    ui.add_enabled(l.geometry, egui::Slider::new(&mut l.hysteresis, 0.0..=0.5).text("hysteresis"));
    ui.add_enabled(l.geometry, egui::Slider::new(&mut l.far_level, 1..=6).text("impostor level"));
    ui.add_enabled(l.geometry, egui::Slider::new(&mut l.error_budget, 0.0..=8.0).text("error, px"))
        .on_hover_text(
            "mesh levels by screen-space error: the coarsest level within this many pixels \
             of full detail (0: by h₀)",
        );
    ui.add_enabled(l.geometry, egui::Slider::new(&mut l.thin_px, 0.0..=32.0).text("thinning, px"))
        .on_hover_text("far impostors thinned below this image height (0: off)");
    ui.checkbox(&mut l.animation, "animation LOD (joints by projected size)");
    ui.checkbox(&mut l.occlusion, "occlusion culling (hidden trees not drawn)");
    if l != lod {
        out.push(Action::Lod(l));
    }
    let mut overlay = v.overlay;
    ui.horizontal(|ui| {
        ui.label("overlay (O)");
        ui.selectable_value(&mut overlay, sylva_render::Overlay::Off, "off");
        ui.selectable_value(&mut overlay, sylva_render::Overlay::Level, "level");
        ui.selectable_value(&mut overlay, sylva_render::Overlay::Group, "group");
    });
    if overlay != v.overlay {
        out.push(Action::Overlay(overlay));
    }
    if v.overlay == sylva_render::Overlay::Level {
        ui.label("full detail white, levels 1–5 yellow to blue, impostors cyan");
    }
    let mut wind_lod = v.settings.wind_lod;
    if ui.checkbox(&mut wind_lod, "wind-field LOD (instance groups; rebuilds)").changed() {
        out.push(Action::WindLod(wind_lod));
    }
}

fn scene(ui: &mut Ui, v: &Viewer, draft: &mut Draft, out: &mut Vec<Action>) {
    ui.horizontal(|ui| {
        egui::ComboBox::from_id_salt("scene").selected_text(&draft.scene).show_ui(ui, |ui| {
            for s in SCENES {
                ui.selectable_value(&mut draft.scene, s.to_string(), s);
            }
        });
        ui.text_edit_singleline(&mut draft.scene).on_hover_text("a built-in name or a .toml file");
    });
    ui.add(egui::DragValue::new(&mut draft.trees).range(1..=200_000).prefix("trees "));
    ui.add(egui::DragValue::new(&mut draft.seed).prefix("seed "));
    ui.label("species mix (weight 0 leaves one out)");
    egui::Grid::new("species").num_columns(2).show(ui, |ui| {
        for s in &mut draft.species {
            ui.label(&s.name);
            ui.add(egui::DragValue::new(&mut s.weight).range(0.0..=100.0).speed(0.05));
            ui.end_row();
        }
    });
    let mut add = String::new();
    egui::ComboBox::from_id_salt("add species").selected_text("add a species").show_ui(ui, |ui| {
        for (name, _) in sylva_tree::PRESETS {
            if !draft.species.iter().any(|s| s.name == *name) {
                ui.selectable_value(&mut add, name.to_string(), *name);
            }
        }
    });
    if !add.is_empty() {
        draft.species.push(sylva_forest::SpeciesShare { name: add, weight: 1.0, seed: None });
    }
    if ui.add_enabled(v.job.is_none(), egui::Button::new("rebuild")).clicked() {
        out.push(Action::Scene {
            scene: draft.scene.clone(),
            trees: draft.trees,
            seed: draft.seed,
            species: draft.species.clone(),
        });
    }
}

fn camera(ui: &mut Ui, v: &Viewer, out: &mut Vec<Action>) {
    ui.horizontal(|ui| {
        let rec = v.recording.is_some();
        if ui.button(if rec { "stop recording" } else { "record (R)" }).clicked() {
            out.push(Action::Record(!rec));
        }
        let play = v.replaying.is_some();
        let can = !v.path.is_empty() && !rec;
        if ui
            .add_enabled(can || play, egui::Button::new(if play { "stop" } else { "replay (P)" }))
            .clicked()
        {
            out.push(Action::Replay(!play));
        }
        if ui.button("screenshot (F12)").clicked() {
            out.push(Action::Screenshot);
        }
    });
    if ui.button(if v.clip { "stop the clip" } else { "record a clip (C)" }).clicked() {
        out.push(Action::Clip(!v.clip));
    }
    match (&v.recording, v.replaying) {
        (Some((keys, t)), _) => ui.label(format!("recording: {} keys, {t:.1} s", keys.len())),
        (None, Some(t)) => {
            ui.label(format!("replaying: {t:.1} of {:.1} s", v.path.last().map_or(0.0, |k| k.t)))
        }
        _ => {
            ui.label(format!("path: {} keys (written to {})", v.path.len(), v.path_file.display()))
        }
    };
    if let Some(s) = &v.status {
        ui.label(s);
    }
}

/// A figure's plot: it follows its data, and takes neither the mouse wheel (which scrolls
/// the panel over it) nor drags, so it never shows an empty stretch. The x axis is the
/// simulation's time, s; the y axis starts at 0 and spans at least `min_span`.
fn plot(name: &str, unit: &str, min_span: f64) -> Plot<'static> {
    Plot::new(name.to_owned())
        .height(90.0)
        .allow_zoom(false)
        .allow_scroll(false)
        .allow_drag(false)
        .allow_boxed_zoom(false)
        .allow_double_click_reset(false)
        .include_y(0.0)
        .include_y(min_span)
        .x_axis_label("time, s")
        .y_axis_label(unit.to_owned())
}

fn plots(ui: &mut Ui, v: &Viewer) {
    let wind: Vec<[f64; 2]> = v.history.iter().map(|&(t, w, _)| [t, w as f64]).collect();
    let sway: Vec<[f64; 2]> = v.history.iter().map(|&(t, _, s)| [t, s as f64]).collect();
    ui.label("wind speed at the probe");
    plot("wind", "m/s", 1.0).show(ui, |p| p.line(Line::new("wind", wind)));
    ui.label(if v.selected.is_some() {
        "trunk-top displacement of the selected tree"
    } else {
        "trunk-top displacement: click a tree"
    });
    plot("sway", "m", 0.05).show(ui, |p| p.line(Line::new("trunk top", sway)));
}

fn selected(ui: &mut Ui, v: &Viewer) {
    let Some(t) = v.selected else {
        ui.label("none (click a tree)");
        return;
    };
    let Some(info) = v.forest.tree_info(t) else { return };
    egui::Grid::new("tree").num_columns(2).show(ui, |ui| {
        let mut row = |k: &str, val: String| {
            ui.label(k);
            ui.label(val);
            ui.end_row();
        };
        row("tree", format!("#{t}, {}", info.species));
        row("height", format!("{:.1} m", info.height));
        row("DBH (1.3 m)", format!("{:.2} m", info.dbh));
        row("trunk frequency", format!("{:.2} Hz", info.trunk_frequency));
        row("instance group", format!("{} ({} trees)", info.group, info.group_size));
        row(
            "drawn at level",
            v.frame
                .level(t)
                .map_or("— (not in view, or geometry LOD off)".into(), |l| l.to_string()),
        );
    });
}
