//! The popping measurements of `sylva bench table3`: how much a frame where trees change
//! level (or instance group) differs from the frames around it, with the cross-fade and
//! with instant switches.

use std::fmt::Write as _;

use anyhow::Context;
use sylva_forest::{Camera, Forest, FrameData, FrameStats, SceneSpec};
use sylva_render::Headless;

use super::Table3Bench;
use sylva_frames::render::median;

/// Median and maximum of `v` (NaN when empty).
fn median_max(v: &mut [f64]) -> (f64, f64) {
    let max = v.iter().copied().fold(f64::NAN, f64::max);
    (median(v), max)
}

/// Popping: the small scene in calm air seen from a fixed camera while the LOD threshold
/// h₀ sweeps from 0.3 to 3 (so every tree walks down the chain as in a fly-out, with no
/// camera motion to hide a jump): how much each frame differs from the one before (mean
/// |Δ| over RGB, 0–255), split into frames where some tree changed level, frames where
/// some tree was cross-fading but none changed, and the rest; with the cross-fade and with
/// instant switches.
pub(super) fn popping(a: &Table3Bench) -> anyhow::Result<String> {
    let (w, h) = (512, 384);
    let mut spec = SceneSpec::builtin("small")?;
    spec.wind = "calm".into();
    let n = a.popping_frames;
    let mut md = String::new();
    table_head(
        &mut md,
        &format!(
            "Popping — scene `small` in calm air, fixed camera, {n} frames while h₀ sweeps 0.3 → 3 (trees coarsen as if the camera backed off ×10), {w}×{h}; mean |Δ| (0–255) between consecutive frames:"
        ),
        "| level switch | frames with no tree fading or changing level: median / max | fading, no change: median / max | with a level change: median / max | a frame with a level change over the nearest frames either side without one, their mean: median / max | over the larger of the two: median / max |",
    );
    let mut gpu: Option<Headless> = None;
    for (label, band, hysteresis) in
        [("cross-faded (default)", 0.3, 0.1), ("instant (band 0)", 0.0, 0.0)]
    {
        let mut forest = Forest::new(&spec)?;
        forest.set_lod(sylva_forest::LodSettings { band, hysteresis, ..forest.lod() });
        if gpu.is_none() {
            gpu = Some(Headless::new(&forest, w, h)?);
        }
        let gpu = gpu.as_mut().context("renderer")?;
        let camera = forest.default_camera();
        let mut frame = FrameData::with_rows(h);
        let mut diffs = FrameDiffs::default();
        for i in 0..n {
            let h0 = 0.3 * 10f32.powf(i as f32 / (n - 1) as f32);
            forest.set_lod(sylva_forest::LodSettings { fraction: h0, ..forest.lod() });
            forest.step(0.1);
            forest.frame(&camera, w as f32 / h as f32, &mut frame);
            let s = &frame.stats;
            diffs.push(gpu.render(&frame, &camera)?, s.level_changes > 0, s.fading > 0);
        }
        diffs.row(&mut md, label);
    }
    let gpu = gpu.as_mut().context("renderer")?;
    fly_out_popping(a, &mut md, gpu)?;
    regroup_popping(a, &mut md, gpu)?;
    println!("{md}");
    Ok(md)
}

/// How far the fly-out takes the camera from the trees, as a factor on its first distance.
const FLY_OUT: f32 = 10.0;

/// Popping along a camera path: the small scene in calm air, the camera backing away from
/// the point it looks at, its distance growing by the same factor each frame up to
/// [`FLY_OUT`] times the first (the trees shrink on screen and walk down the chain as they
/// would in a fly-out); frames split as in [`popping`], with the cross-fade and with
/// instant switches, and at full detail throughout (how much the path alone changes each
/// frame). Two comparisons per frame: with the frame before, as a user sees them (the
/// switch against the motion it comes with), and with the frame before drawn from this
/// frame's camera (the switch alone, the path's motion taken out).
fn fly_out_popping(a: &Table3Bench, md: &mut String, gpu: &mut Headless) -> anyhow::Result<()> {
    let (w, h) = (512, 384);
    let mut spec = SceneSpec::builtin("small")?;
    spec.wind = "calm".into();
    let n = a.popping_frames;
    table_head(
        md,
        &format!(
            "Along a camera path — scene `small` in calm air, the camera backing away from its target to {FLY_OUT}× its distance over {n} frames (the same factor each frame), {w}×{h}; mean |Δ| (0–255) between a frame and the frame before (as shown), or the frame before drawn from this frame's camera (the switch alone):"
        ),
        "| level switch, compared with | frames with no tree fading or changing level: median / max | fading, no change: median / max | with a level change: median / max | a frame with a level change over the nearest frames either side without one, their mean: median / max | over the larger of the two: median / max |",
    );
    for (label, geometry, instant, error_budget) in [
        ("cross-faded (default)", true, false, 0.0),
        ("instant (band 0)", true, true, 0.0),
        ("by error, 1 px, every mesh level, cross-faded", true, false, 1.0),
        ("full detail throughout", false, false, 0.0),
    ] {
        let mut forest = Forest::new(&spec)?;
        let lod = forest.lod();
        // Switched at once: no cross-fade band, and no hysteresis to hold a level.
        let (band, hysteresis) = if instant { (0.0, 0.0) } else { (lod.band, lod.hysteresis) };
        let far_level =
            if error_budget > 0.0 { sylva_tree::mesh::LOD_LEVELS as u32 } else { lod.far_level };
        forest.set_lod(sylva_forest::LodSettings {
            geometry,
            band,
            hysteresis,
            error_budget,
            far_level,
            ..lod
        });
        let start = forest.default_camera();
        let back: [f32; 3] = std::array::from_fn(|k| start.eye[k] - start.target[k]);
        let mut frame = FrameData::with_rows(h);
        let mut diffs = TwoWays::default();
        for i in 0..n {
            let k = FLY_OUT.powf(i as f32 / (n - 1) as f32);
            let camera = Camera {
                eye: std::array::from_fn(|c| start.target[c] + k * back[c]),
                far: start.far * k,
                ..start
            };
            diffs.next(gpu, &mut forest, &mut frame, &camera, w as f32 / h as f32, |s| {
                (s.level_changes > 0, s.fading > 0)
            })?;
        }
        diffs.rows(md, label);
    }
    Ok(())
}

/// Each frame compared two ways: with the frame before as shown (a switch against the
/// camera's motion that comes with it), and with the frame before drawn from this frame's
/// camera (the switch alone, the camera's motion taken out).
#[derive(Default)]
struct TwoWays {
    shown: FrameDiffs,
    alone: FrameDiffs,
    before: FrameData,
}

impl TwoWays {
    /// Step `forest` 0.1 s and build its next frame over `frame` from `camera`, then draw it
    /// and the frame before from `camera` and count both differences; `switch` reads from
    /// the frame's figures whether something switched in it and whether something is fading.
    fn next(
        &mut self,
        gpu: &mut Headless,
        forest: &mut Forest,
        frame: &mut FrameData,
        camera: &Camera,
        aspect: f32,
        switch: impl Fn(&FrameStats) -> (bool, bool),
    ) -> anyhow::Result<()> {
        // A copy: a frame carries each tree's LOD state on to the next.
        self.before.clone_from(frame);
        forest.step(0.1);
        forest.frame(camera, aspect, frame);
        let (switched, fading) = switch(&frame.stats);
        let img = gpu.render(frame, camera)?;
        if self.shown.prev.is_some() {
            let then = gpu.render(&self.before, camera)?;
            self.alone.add(mean_abs_difference(&then, &img), switched, fading);
        }
        self.shown.push(img, switched, fading);
        Ok(())
    }

    /// Two Markdown rows, one for each comparison.
    fn rows(&mut self, md: &mut String, label: &str) {
        self.shown.row(md, &format!("{label}, the frame before"));
        self.alone.row(md, &format!("{label}, the frame before from this camera"));
    }
}

/// A popping table's title (a paragraph of its own) and its header row: `head`'s columns
/// and a rule under them.
fn table_head(md: &mut String, title: &str, head: &str) {
    let _ =
        writeln!(md, "\n{title}\n\n{head}\n{}|", "|---".repeat(head.matches(" | ").count() + 1));
}

/// Mean |Δ| over the channels of two images of the same size (0–255).
fn mean_abs_difference(a: &[u8], b: &[u8]) -> f64 {
    let sum: f64 =
        a.iter().zip(b).map(|(x, y)| (*x as i32 - *y as i32).unsigned_abs() as f64).sum();
    sum / a.len().max(1) as f64
}

/// What [`FrameDiffs::spikes`] sets a switching frame's difference against: the nearest
/// frames either side without a switch, their mean or the larger of them.
#[derive(Debug, Clone, Copy)]
enum Against {
    Mean,
    Larger,
}

/// Mean |Δ| between consecutive frames, split three ways: frames where nothing is fading or
/// switching, frames where a cross-fade is under way but nothing switched, and frames where
/// something switched (a switch ends a fade, so it is to be compared with the second kind
/// as much as with the first).
#[derive(Default)]
struct FrameDiffs {
    prev: Option<Vec<u8>>,
    calm: Vec<f64>,
    fading: Vec<f64>,
    switching: Vec<f64>,
    /// Every frame's difference in frame order, and whether something switched in it.
    sequence: Vec<(f64, bool)>,
}

impl FrameDiffs {
    fn push(&mut self, img: Vec<u8>, switched: bool, fading: bool) {
        if let Some(p) = &self.prev {
            self.add(mean_abs_difference(p, &img), switched, fading);
        }
        self.prev = Some(img);
    }

    /// Count a frame's difference `d` from what it is compared with.
    fn add(&mut self, d: f64, switched: bool, fading: bool) {
        self.sequence.push((d, switched));
        match (switched, fading) {
            (true, _) => self.switching.push(d),
            (false, true) => self.fading.push(d),
            (false, false) => self.calm.push(d),
        }
    }

    /// Each frame where something switched, its difference over the differences of the
    /// nearest frames either side where nothing did (one side at the ends of the sequence),
    /// taken `against` their mean or the larger of them: whether the switch stands out
    /// from the frames around it, as a pop does, whatever those frames hold. Against the
    /// mean, a switch that ends a fade beside a still frame reads up to twice its change
    /// over the fade's steps, as the still side halves the mean; against the larger, a
    /// frame reads above 1 only where it changes more than both sides, a spike.
    fn spikes(&self, against: Against) -> Vec<f64> {
        let q = &self.sequence;
        let calm = |mut i: usize, back: bool| loop {
            i = if back { i.checked_sub(1)? } else { i + 1 };
            match q.get(i) {
                Some(&(d, false)) => return Some(d),
                Some(_) => continue,
                None => return None,
            }
        };
        (0..q.len())
            .filter(|&i| q[i].1)
            .filter_map(|i| {
                let around: Vec<f64> =
                    [calm(i, true), calm(i, false)].into_iter().flatten().collect();
                if around.is_empty() {
                    return None;
                }
                let base = match against {
                    Against::Mean => around.iter().sum::<f64>() / around.len() as f64,
                    Against::Larger => around.iter().copied().fold(0.0, f64::max),
                };
                // A switch among frames that do not change at all stands out without bound.
                Some(match (base > 0.0, q[i].0 > 0.0) {
                    (true, _) => q[i].0 / base,
                    (false, true) => f64::INFINITY,
                    (false, false) => 1.0,
                })
            })
            .collect()
    }

    /// A Markdown row: median / max of each kind of frame, and the frame counts; then
    /// median / max of [`FrameDiffs::spikes`], against the mean and the larger neighbour.
    fn row(&mut self, md: &mut String, label: &str) {
        let cell = |v: &mut Vec<f64>| {
            if v.is_empty() {
                "— (0 frames)".to_string()
            } else {
                let (m, x) = median_max(v);
                format!("{m:.2} / {x:.2} ({} frames)", v.len())
            }
        };
        let spike = |against| {
            let mut spikes = self.spikes(against);
            if spikes.is_empty() {
                "—".to_string()
            } else {
                let (m, x) = median_max(&mut spikes);
                format!("×{m:.2} / ×{x:.2}")
            }
        };
        let (mean, larger) = (spike(Against::Mean), spike(Against::Larger));
        let (c, f, s) = (cell(&mut self.calm), cell(&mut self.fading), cell(&mut self.switching));
        let _ = writeln!(md, "| {label} | {c} | {f} | {s} | {mean} | {larger} |");
    }
}

/// Popping when instance groups are re-formed: scene `small` grown to 60 trees in a breeze
/// (about a dozen simulations per species), the camera outside it sliding sideways 1 m a
/// frame (0.1 s), so groups are formed again each second; how much
/// each frame differs from the one before, split into frames where trees changed group,
/// frames where trees were fading between groups but none changed, and the rest; with the
/// cross-fade and with instant switches.
fn regroup_popping(a: &Table3Bench, md: &mut String, gpu: &mut Headless) -> anyhow::Result<()> {
    const STEP: f32 = 1.0;
    let (w, h) = (512, 384);
    let mut spec = SceneSpec::builtin("small")?;
    spec.wind = "breeze".into();
    spec.trees = 60;
    spec.sim_joint_budget = 150_000;
    let n = a.popping_frames;
    table_head(
        md,
        &format!(
            "Regrouping — scene `small` with 60 trees sharing about a dozen simulations per species, a breeze, camera outside the forest sliding {STEP} m a frame (0.1 s), {n} frames, {w}×{h}; mean |Δ| (0–255) between a frame and the frame before (as shown), or the frame before drawn from this frame's camera (the switch and a step of sway, the slide taken out):"
        ),
        "| group switch, compared with | frames with no tree regrouping: median / max | fading between groups, no change: median / max | with a group change: median / max | a frame with a group change over the nearest frames either side without one, their mean: median / max | over the larger of the two: median / max |",
    );
    for (label, fade) in
        [("cross-faded over 1 s (default)", sylva_forest::REGROUP_FADE), ("instant", 0.0)]
    {
        let mut forest = Forest::new(&spec)?;
        forest.set_regroup_fade(fade);
        // From outside the forest: the default viewpoint pulled back to 2.5 × the radius.
        let mut camera = forest.default_camera();
        let r = forest.radius.max(1.0);
        let back = [camera.eye[0] - camera.target[0], camera.eye[1] - camera.target[1]];
        let k = 2.5 * r / (back[0] * back[0] + back[1] * back[1]).sqrt().max(1e-6);
        (camera.eye[0], camera.eye[1]) =
            (camera.target[0] + k * back[0], camera.target[1] + k * back[1]);
        camera.eye[2] = camera.target[2] + 0.6 * r;
        let mut frame = FrameData::with_rows(h);
        let mut diffs = TwoWays::default();
        // Sideways: across the line of sight, horizontally.
        let f = [camera.target[0] - camera.eye[0], camera.target[1] - camera.eye[1]];
        let norm = (f[0] * f[0] + f[1] * f[1]).sqrt().max(1e-6);
        let side = [-f[1] / norm * STEP, f[0] / norm * STEP];
        for _ in 0..n {
            for k in 0..2 {
                camera.eye[k] += side[k];
                camera.target[k] += side[k];
            }
            diffs.next(gpu, &mut forest, &mut frame, &camera, w as f32 / h as f32, |s| {
                (s.group_changes > 0, s.regrouping > 0)
            })?;
        }
        diffs.rows(md, label);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{Against, FrameDiffs};

    /// Frames as (mean |Δ| from the frame before, whether something switched in it).
    fn diffs(frames: &[(f64, bool)]) -> FrameDiffs {
        let mut d = FrameDiffs::default();
        for &(x, switched) in frames {
            d.add(x, switched, false);
        }
        d
    }

    /// A switch that jumps out of the frames around it reads as the ratio of its change to
    /// theirs, the neighbours taken past other switching frames; a switch within a fade
    /// that moves every frame alike reads about 1; a switch among frames that do not change
    /// at all has no bound.
    #[test]
    fn a_switch_is_measured_against_the_nearest_frames_without_one() {
        let pop = diffs(&[(0.1, false), (0.1, false), (4.0, true), (3.0, true), (0.3, false)]);
        assert_eq!(pop.spikes(Against::Mean), vec![4.0 / 0.2, 3.0 / 0.2]);
        assert_eq!(pop.spikes(Against::Larger), vec![4.0 / 0.3, 3.0 / 0.3]);
        let fade = diffs(&[(0.5, false), (0.5, false), (0.5, true), (0.5, false)]);
        assert_eq!(fade.spikes(Against::Mean), vec![1.0]);
        assert_eq!(fade.spikes(Against::Larger), vec![1.0]);
        // At the end of the sequence, the one side there is.
        let last = diffs(&[(0.25, false), (0.5, false), (0.75, true)]);
        assert_eq!(last.spikes(Against::Mean), vec![1.5]);
        assert_eq!(last.spikes(Against::Larger), vec![1.5]);
        let still = diffs(&[(0.0, false), (1.0, true), (0.0, false)]);
        assert_eq!(still.spikes(Against::Mean), vec![f64::INFINITY]);
        assert_eq!(still.spikes(Against::Larger), vec![f64::INFINITY]);
        // Nothing to compare with: no figure rather than a made-up one.
        assert!(diffs(&[(1.0, true)]).spikes(Against::Mean).is_empty());
    }

    /// A fade that ends next to a still frame: its last step is no larger than the steps
    /// before it, so it is no spike, and reads at most 1 against the larger neighbour;
    /// against the mean it reads about twice its share, as the still side halves the mean.
    #[test]
    fn a_fade_that_ends_beside_a_still_frame_is_no_spike_against_the_larger_side() {
        let end = diffs(&[(1.3, false), (1.3, false), (1.1, true), (0.0, false), (0.0, false)]);
        assert_eq!(end.spikes(Against::Larger), vec![1.1 / 1.3]);
        assert_eq!(end.spikes(Against::Mean), vec![1.1 / 0.65]);
    }
}
