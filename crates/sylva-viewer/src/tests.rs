//! The viewer without a window: actions reaching the simulation and `FrameData`, the
//! substep clock, synthetic keys and clicks, and the panel rendered offscreen.

use winit::keyboard::KeyCode;

use super::input::{Controls, Input};
use super::panel::{self, Draft};
use super::state::{Action, Clock, Finished, MAX_SUBSTEPS, SUBSTEP, Viewer};
use sylva_forest::{Forest, LodSettings, SceneSpec};

fn viewer(trees: usize) -> Viewer {
    let mut spec = SceneSpec::builtin("small").expect("small scene");
    spec.trees = trees;
    Viewer::new(Forest::new(&spec).expect("forest"), "small")
}

/// Mean wind at the probe over one loop of the scene's field (51.2 s, the simulation
/// advancing), as a speed: the fluctuations average to nothing over their loop, so this is
/// the mean wind Ū there.
fn mean_speed(v: &mut Viewer) -> f32 {
    let steps = (51.2 / SUBSTEP as f64).round() as usize;
    let mut sum = [0.0f64; 3];
    for _ in 0..steps {
        v.forest.step(SUBSTEP);
        let w = v.forest.wind_sample(v.probe());
        for c in 0..3 {
            sum[c] += w[c] as f64 / steps as f64;
        }
    }
    (sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]).sqrt() as f32
}

#[test]
fn a_wind_change_reaches_the_simulation() {
    let mut v = viewer(5);
    let preset = sylva_wind::Preset::from_name(&v.forest.spec.wind).expect("a preset scene");
    let start_u_star = v.forest.spec.u_star.unwrap_or(preset.u_star());
    let before = mean_speed(&mut v);
    // A preset is re-synthesised in the background and swapped in when done.
    v.apply(Action::Wind("storm".into()));
    assert!(v.busy().is_some());
    assert_eq!(v.poll(true), Finished::Wind);
    assert_eq!(v.forest.spec.wind, "storm");
    let storm = mean_speed(&mut v);
    // The mean wind scales with U* (the log law): the storm's over the scene's own.
    let ratio = sylva_wind::Preset::Storm.u_star() / start_u_star;
    let got = (storm / before) as f64;
    assert!(
        ratio > 1.2 && (got / ratio - 1.0).abs() < 0.03,
        "storm {storm} m/s vs {before} m/s before: ×{got}, U* ×{ratio}"
    );
    // The live gain scales the wind the trees feel, at once and exactly.
    let p = v.probe();
    let before = v.forest.wind_sample(p);
    v.apply(Action::WindGain(2.0));
    let after = v.forest.wind_sample(p);
    for c in 0..3 {
        assert!((after[c] - 2.0 * before[c]).abs() <= 1e-4 * before[c].abs().max(1.0));
    }
    // U* of a preset: the turbulence and mean wind scale with it.
    v.apply(Action::WindGain(1.0));
    v.apply(Action::UStar(0.5));
    assert_eq!(v.poll(true), Finished::Wind);
    assert_eq!(v.forest.spec.u_star, Some(0.5));
    let calmer = mean_speed(&mut v);
    let ratio = 0.5 / sylva_wind::Preset::Storm.u_star();
    let got = (calmer / storm) as f64;
    assert!((got / ratio - 1.0).abs() < 0.03, "U* 0.5: {calmer} m/s vs the storm's {storm}");
    // The mean profile: a smooth log law (z0 0.3 m) in place of the stand's canopy profile
    // speeds the wind up as the two laws say, between the field's two heights as the forest
    // interpolates them.
    let z = v.probe()[2];
    let at = |p: sylva_wind::Profile| {
        let params = sylva_wind::WindParams { u_star: 0.5, profile: p, ..Default::default() };
        let w = ((z - 8.0) / 14.0).clamp(0.0, 1.0);
        (1.0 - w) * params.mean_speed(8.0) + w * params.mean_speed(22.0)
    };
    let rough = v.forest.stand().expect("the canopy wind is on by default").profile();
    let smooth = sylva_wind::Profile::Log { z0: 0.3, d: 10.0 };
    assert_eq!(v.forest.spec.wind_profile, None);
    v.apply(Action::Profile(smooth));
    assert_eq!(v.poll(true), Finished::Wind);
    assert_eq!(v.forest.spec.wind_profile, Some(smooth));
    let faster = mean_speed(&mut v);
    let want = at(smooth) / at(rough);
    let got = (faster / calmer) as f64;
    assert!(want > 1.2 && (got / want - 1.0).abs() < 0.03, "profile: ×{got}, log law ×{want}");
    v.apply(Action::Profile(sylva_wind::Profile::Log { z0: -1.0, d: 10.0 }));
    assert!(v.error.as_deref().is_some_and(|e| e.contains("z0")) && v.job.is_none());
    // A bad wind is refused with a message, and nothing is started.
    v.apply(Action::Wind("gale".into()));
    assert!(v.error.as_deref().is_some_and(|e| e.contains("gale")) && v.job.is_none());
}

#[test]
fn a_lod_switch_reaches_frame_data() {
    let mut v = viewer(12);
    let coarse = LodSettings { fraction: 100.0, ..v.forest.lod() };
    v.apply(Action::Lod(coarse));
    v.build_frame(4.0 / 3.0);
    let with_lod = v.frame.stats;
    assert!(with_lod.impostors > 0, "a coarse h0 draws far trees as impostors: {with_lod:?}");
    v.apply(Action::Lod(LodSettings { geometry: false, ..coarse }));
    v.build_frame(4.0 / 3.0);
    let without = v.frame.stats;
    assert_eq!(without.impostors, 0);
    assert!(without.triangles > 2 * with_lod.triangles, "{without:?} vs {with_lod:?}");
    // The wind-field LOD rebuilds the scene: every tree its own simulation when off.
    v.apply(Action::WindLod(false));
    assert_eq!(v.poll(true), Finished::Scene);
    assert!(!v.forest.spec.lod.wind);
    let infos: Vec<_> = (0..v.forest.trees()).filter_map(|t| v.forest.tree_info(t)).collect();
    assert!(infos.iter().all(|i| i.group_size == 1));
}

#[test]
fn a_scene_change_rebuilds_in_the_background() {
    let mut v = viewer(5);
    let mix =
        vec![sylva_forest::SpeciesShare { name: "douglas_fir".into(), weight: 1.0, seed: None }];
    v.apply(Action::Scene { scene: "small".into(), trees: 3, seed: 9, species: mix });
    assert_eq!(v.busy().map(|b| b.0), Some("building the scene"));
    assert_eq!(v.poll(true), Finished::Scene);
    assert_eq!((v.forest.trees(), v.forest.spec.seed), (3, 9));
    assert!((0..3).all(|t| v.forest.tree_info(t).expect("tree").species == "douglas_fir"));
    assert!(v.job.is_none() && v.error.is_none());
    v.apply(Action::Scene { scene: "no-such-scene".into(), trees: 3, seed: 9, species: vec![] });
    assert!(v.error.is_some() && v.job.is_none(), "an unknown scene is an error, not a job");
    assert_eq!(v.forest.trees(), 3, "and the forest stays");
}

#[test]
fn the_clock_keeps_real_time_in_fixed_substeps_up_to_its_cap() {
    let mut c = Clock::default();
    // Whole substeps, the remainder carried: three half-substep frames make one step and a
    // half.
    let half = 0.5 * SUBSTEP;
    let steps: Vec<u32> = (0..4).map(|_| c.advance(half, 1.0)).collect();
    assert_eq!(steps.iter().sum::<u32>(), 2);
    assert!(!c.slow);
    // A slow frame: capped, marked, and the excess dropped rather than owed.
    assert_eq!(c.advance(1.0, 1.0), MAX_SUBSTEPS);
    assert!(c.slow);
    assert_eq!(c.advance(SUBSTEP * 1.001, 1.0), 1);
    assert!(!c.slow);
    // The time scale multiplies the simulated time.
    assert_eq!(c.advance(4.0 * SUBSTEP * 1.001, 0.5), 2);
    // The viewer: simulated time follows the real frame time, at most the cap per frame.
    let mut v = viewer(3);
    v.advance(0.1);
    assert!((v.forest.time() - 0.1).abs() < 1.5 * SUBSTEP as f64, "{}", v.forest.time());
    assert!(!v.clock.slow);
    let t = v.forest.time();
    v.advance(2.0);
    assert!((v.forest.time() - t - (MAX_SUBSTEPS as f32 * SUBSTEP) as f64).abs() < 1e-4);
    assert!(v.clock.slow && v.figures.frame_ms == 2000.0, "{:?}", v.figures);
    // Paused: no time passes; a step is one substep.
    v.apply(Action::Pause(true));
    let t = v.forest.time();
    v.advance(0.5);
    assert_eq!(v.forest.time(), t);
    v.apply(Action::Step);
    assert!((v.forest.time() - t - SUBSTEP as f64).abs() < 1e-6);
}

#[test]
fn gpu_time_by_part_is_asked_for_and_dropped_with_its_switch() {
    let mut v = viewer(3);
    assert!(!v.gpu_passes, "off by default: no frame needs the timestamps");
    v.figures.passes = Some([1.0; sylva_render::PASS_PARTS.len()]);
    v.apply(Action::GpuPasses(true));
    // Times from before the switch are not shown as if they were this frame's.
    assert!(v.gpu_passes && v.figures.passes.is_none());
    v.figures.passes = Some([1.0; sylva_render::PASS_PARTS.len()]);
    v.apply(Action::GpuPasses(false));
    assert!(!v.gpu_passes && v.figures.passes.is_none());
}

fn key(code: KeyCode) -> [Input; 2] {
    [
        Input::Key { code, pressed: true, repeat: false },
        Input::Key { code, pressed: false, repeat: false },
    ]
}

#[test]
fn keys_change_the_wind_pause_and_panels() {
    let mut v = viewer(3);
    let mut c = Controls::default();
    assert_eq!(v.forest.wind_control().0, 1.0);
    for _ in 0..3 {
        for i in key(KeyCode::ArrowUp) {
            c.handle(&mut v, i, 800.0, 600.0);
        }
    }
    assert!((v.forest.wind_control().0 - 1.25f32.powi(3)).abs() < 1e-5);
    for i in key(KeyCode::ArrowLeft) {
        c.handle(&mut v, i, 800.0, 600.0);
    }
    assert!((v.forest.wind_control().1 - 15.0).abs() < 1e-4);
    for k in [KeyCode::Space, KeyCode::F1, KeyCode::Tab] {
        for i in key(k) {
            c.handle(&mut v, i, 800.0, 600.0);
        }
    }
    assert!(v.settings.paused && v.help && !v.panel);
    // Keys reach the panel only while it edits text, and Tab never: with a checkbox
    // focused (no text field), Space still pauses and Tab still shows and hides the panel.
    use crate::input::panel_takes_key;
    assert!(!panel_takes_key(KeyCode::Tab, false) && !panel_takes_key(KeyCode::Tab, true));
    assert!(!panel_takes_key(KeyCode::Space, false) && panel_takes_key(KeyCode::Space, true));
    // An auto-repeated Space does not toggle again.
    c.handle(
        &mut v,
        Input::Key { code: KeyCode::Space, pressed: true, repeat: true },
        800.0,
        600.0,
    );
    assert!(v.settings.paused);
    c.handle(
        &mut v,
        Input::Key { code: KeyCode::Space, pressed: false, repeat: false },
        800.0,
        600.0,
    );
    // Held W moves the camera target forward (away from the eye) while held.
    let before = v.orbit.target;
    c.handle(
        &mut v,
        Input::Key { code: KeyCode::KeyW, pressed: true, repeat: false },
        800.0,
        600.0,
    );
    c.fly(&mut v, 0.1);
    let eye = v.orbit.camera().eye;
    let d0 = ((before[0] - eye[0]).powi(2) + (before[1] - eye[1]).powi(2)).sqrt();
    let after = v.orbit.target;
    let d1 = ((after[0] - eye[0]).powi(2) + (after[1] - eye[1]).powi(2)).sqrt();
    assert!(d1 > d0, "W moves forward: {d0} → {d1}");
    c.handle(
        &mut v,
        Input::Key { code: KeyCode::KeyW, pressed: false, repeat: false },
        800.0,
        600.0,
    );
    assert!(c.held.is_empty(), "held: {:?}", c.held);
    for i in key(KeyCode::Escape) {
        c.handle(&mut v, i, 800.0, 600.0);
    }
    assert!(v.quit);
}
#[test]
fn a_click_goes_where_the_cursor_is_at_the_click_not_where_it_was_last_frame() {
    use crate::input::panel_takes_pointer;
    // A 330-pixel panel: a click at x 200 is the panel's, at x 500 the view's, whatever the
    // panel's hover state of the last frame (the viewer asks this at the event).
    assert!(panel_takes_pointer(Some(200.0), 330.0, false));
    assert!(!panel_takes_pointer(Some(500.0), 330.0, false));
    // A slider being dragged keeps the pointer, out over the view as well.
    assert!(panel_takes_pointer(Some(500.0), 330.0, true));
    // Without a panel, or before the cursor has moved, clicks are the view's.
    assert!(!panel_takes_pointer(Some(200.0), 0.0, false));
    assert!(!panel_takes_pointer(None, 330.0, false));
    // Moving off the panel and clicking before a frame is drawn: the viewer asks with the
    // cursor of the latest event, off the panel.
    let mut v = viewer(3);
    let mut c = Controls::default();
    let (w, h) = (640.0, 480.0);
    c.handle(&mut v, Input::Cursor(100.0, 240.0), w, h);
    c.handle(&mut v, Input::Cursor(400.0, 240.0), w, h);
    assert!(!panel_takes_pointer(c.cursor().map(|p| p.0), 0.3 * w, false));
    assert_eq!(c.cursor(), Some((400.0, 240.0)));
}

/// Pixel of world point `p` in a `w × h` image from the viewer's camera.
fn project(v: &Viewer, p: [f32; 3], w: f32, h: f32) -> (f64, f64) {
    let m = v.orbit.camera().view_projection(w / h);
    let clip: [f32; 4] =
        std::array::from_fn(|r| (0..3).map(|c| m[c][r] * p[c]).sum::<f32>() + m[3][r]);
    let (x, y) = (clip[0] / clip[3], clip[1] / clip[3]);
    // The image's centre is moved right by the panel's share (`Viewer::view_shift`).
    (((x + v.view_shift + 1.0) * 0.5 * w) as f64, ((1.0 - y) * 0.5 * h) as f64)
}

#[test]
fn clicking_a_tree_selects_it_and_dragging_orbits_instead() {
    let mut v = viewer(5);
    let mut c = Controls::default();
    let (w, h) = (800.0, 600.0);
    // Each tree, clicked at the middle of its trunk, is picked (or one standing in front),
    // with the view centred in the whole window and beside a panel taking 30 % of it.
    for shift in [0.0f32, 0.3] {
        v.view_shift = shift;
        let mut hits = 0;
        for t in 0..v.forest.trees() {
            let p = v.forest.placement(t).expect("tree");
            let height = v.forest.tree_info(t).expect("info").height;
            let mid = [p.position[0], p.position[1], p.position[2] + 0.4 * height];
            let (x, y) = project(&v, mid, w, h);
            if !(0.0..w as f64).contains(&x) || !(0.0..h as f64).contains(&y) {
                continue;
            }
            for i in [Input::Cursor(x, y), Input::Left(true), Input::Left(false)] {
                c.handle(&mut v, i, w, h);
            }
            let s = v.selected.expect("a click on a trunk selects a tree");
            let eye = v.orbit.camera().eye;
            let dist = |q: [f32; 3]| ((q[0] - eye[0]).powi(2) + (q[1] - eye[1]).powi(2)).sqrt();
            let chosen = v.forest.placement(s).expect("selected").position;
            assert!(s == t || dist(chosen) < dist(p.position), "tree {t}: picked {s}, behind it");
            hits += (s == t) as usize;
        }
        assert!(hits >= 2, "only {hits} trees picked where they stand");
    }
    v.view_shift = 0.0;
    // A click where no trunk stands (the first such pixel of the top row) selects nothing.
    let empty = (0..80)
        .map(|k| (10.0 * k as f32, 2.0))
        .find(|&(x, y)| {
            let (o, d) = v.orbit.ray(x, y, w, h);
            v.forest.pick(o, d).is_none()
        })
        .expect("some sky");
    for i in [Input::Cursor(empty.0 as f64, empty.1 as f64), Input::Left(true), Input::Left(false)]
    {
        c.handle(&mut v, i, w, h);
    }
    assert_eq!(v.selected, None);
    // A drag turns the camera and selects nothing.
    let yaw = v.orbit.yaw;
    for i in [
        Input::Cursor(400.0, 300.0),
        Input::Left(true),
        Input::Cursor(460.0, 300.0),
        Input::Left(false),
    ] {
        c.handle(&mut v, i, w, h);
    }
    assert!((v.orbit.yaw - yaw + 0.3).abs() < 1e-5 && v.selected.is_none());
}

/// The panel over the small scene, offscreen (lavapipe), against its golden image.
#[test]
fn the_panel_renders_headless_like_its_golden_image() {
    const W: u32 = 640;
    const H: u32 = 720;
    let mut v = viewer(5);
    for _ in 0..30 {
        v.advance(1.0 / 30.0);
    }
    v.apply(Action::Select(Some(0)));
    for _ in 0..30 {
        v.advance(1.0 / 30.0);
    }
    v.build_frame(W as f32 / H as f32);
    // Figures that depend on the machine's speed are fixed for the picture.
    v.figures = super::state::Figures {
        fps: 30.0,
        frame_ms: 33.3,
        sim_ms: 1.0,
        build_ms: 0.1,
        render_ms: 20.0,
        passes: Some([0.72, 1.5, 9.33, 2.81, 0.23]),
        substeps: 2,
    };
    v.gpu_passes = true;
    let ctx = egui::Context::default();
    let raw = egui::RawInput {
        screen_rect: Some(egui::Rect::from_min_size(
            egui::Pos2::ZERO,
            egui::vec2(W as f32, H as f32),
        )),
        ..Default::default()
    };
    let mut draft = Draft::of(&v);
    let mut actions = Vec::new();
    // Two passes: the first lays out, the second draws settled sizes.
    let first = ctx.run_ui(raw.clone(), |ui| {
        panel::show(ui, &v, &mut draft, &mut actions);
    });
    let full = ctx.run_ui(raw, |ui| {
        panel::show(ui, &v, &mut draft, &mut actions);
    });
    assert!(actions.is_empty(), "drawing alone changes nothing: {actions:?}");
    let mut textures = first.textures_delta;
    textures.append(full.textures_delta);
    let mut pf = sylva_render::PanelFrame {
        primitives: ctx.tessellate(full.shapes, full.pixels_per_point),
        textures,
        pixels_per_point: full.pixels_per_point,
    };
    let mut headless = sylva_render::Headless::new(&v.forest, W, H).expect("lavapipe");
    let format = headless.format();
    let img = headless
        .render_with(&v.frame, &v.orbit.camera(), |gpu, view| {
            sylva_render::PanelPass::new(gpu, format).draw(gpu, view, [W, H], &mut pf);
        })
        .expect("render");
    let bare = headless.render(&v.frame, &v.orbit.camera()).expect("render");
    // The panel covers the left of the image, and nothing else changes.
    let differs = |x: u32, y: u32| {
        let i = ((y * W + x) * 4) as usize;
        (0..3).any(|c| img[i + c].abs_diff(bare[i + c]) > 8)
    };
    let left = (0..H).filter(|&y| (0..200).any(|x| differs(x, y))).count();
    let right = (0..H).filter(|&y| (420..W).any(|x| differs(x, y))).count();
    assert!(left as u32 > H / 2 && right == 0, "panel rows {left}, rows changed right {right}");
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/panel.png");
    if std::env::var_os("SYLVA_BLESS").is_some() {
        sylva_frames::render::write_png(&path, W, H, &img).expect("bless");
    }
    let want = read_png(&path).expect("tests/golden/panel.png (SYLVA_BLESS=1 writes it)");
    let mean =
        img.iter().zip(&want).map(|(a, b)| a.abs_diff(*b) as f64).sum::<f64>() / img.len() as f64;
    let far = img
        .chunks(4)
        .zip(want.chunks(4))
        .filter(|(a, b)| (0..3).any(|c| a[c].abs_diff(b[c]) > 48))
        .count();
    if mean > 3.0 || far as f64 > 0.02 * (W * H) as f64 {
        let _ =
            sylva_frames::render::write_png(&path.with_file_name("panel-actual.png"), W, H, &img);
        panic!(
            "panel image off its golden: mean |Δ| {mean:.2}, {far} pixels far off (panel-actual.png)"
        );
    }
}

fn read_png(path: &std::path::Path) -> Option<Vec<u8>> {
    let d = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).ok()?));
    let mut r = d.read_info().ok()?;
    let mut buf = vec![0; r.output_buffer_size()];
    r.next_frame(&mut buf).ok()?;
    Some(buf)
}

#[test]
fn a_recorded_camera_path_is_written_read_back_and_replayed() {
    let dir = sylva_testkit::TempDir::new("sylva-view-path");
    let mut v = viewer(3);
    v.path_file = dir.join("path.toml");
    let mut c = Controls::default();
    for i in key(KeyCode::KeyR) {
        c.handle(&mut v, i, 800.0, 600.0);
    }
    assert!(v.recording.is_some());
    // Two seconds of orbiting, a quarter turn, at 20 frames a second.
    let start = v.orbit.camera();
    for _ in 0..40 {
        v.orbit.yaw += std::f32::consts::FRAC_PI_2 / 40.0;
        v.advance(0.05);
    }
    let end = v.orbit.camera();
    for i in key(KeyCode::KeyR) {
        c.handle(&mut v, i, 800.0, 600.0);
    }
    assert!(v.recording.is_none());
    let text = std::fs::read_to_string(&v.path_file).expect("path written");
    let keys = sylva_forest::camera_path_from_toml("path.toml", &text).expect("a valid path");
    assert_eq!(keys, v.path);
    assert!((keys.len() as i32 - 9).abs() <= 1, "a key every 0.25 s over 2 s: {}", keys.len());
    assert_eq!(keys[0].eye, start.eye);
    // Replay: the camera starts where the recording did and ends where it ended.
    for i in key(KeyCode::KeyP) {
        c.handle(&mut v, i, 800.0, 600.0);
    }
    v.advance(0.0);
    let near = |a: [f32; 3], b: [f32; 3], tol: f32| (0..3).all(|i| (a[i] - b[i]).abs() < tol);
    assert!(
        near(v.orbit.camera().eye, start.eye, 1e-2),
        "{:?} vs {:?}",
        v.orbit.camera().eye,
        start.eye
    );
    for _ in 0..60 {
        v.advance(0.05);
    }
    assert!(v.replaying.is_none(), "the replay stops at the path's end");
    let last = keys.last().expect("keys");
    assert!(near(v.orbit.camera().eye, last.eye, 1e-2));
    assert!(near(last.eye, end.eye, 0.5 * v.orbit.distance), "the last key is near the end pose");
    // A path file with times going backwards is refused, naming the key.
    let bad = text.replacen("t = 0.25", "t = -1.0", 1);
    let err = sylva_forest::camera_path_from_toml("bad.toml", &bad).expect_err("refused");
    assert!(err.to_string().contains("camera_path.t"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The U* slider ended at 3 m/s: picking the storm (U* = 6) showed 3.00, and dragging to the
/// end halved the storm. It now reaches past every preset.
#[test]
fn the_u_star_slider_covers_every_preset() {
    for p in sylva_wind::Preset::ALL {
        assert!(p.u_star() <= crate::panel::U_STAR_MAX, "{}: {}", p.name(), p.u_star());
    }
}
