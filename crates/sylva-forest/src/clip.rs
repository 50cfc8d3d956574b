//! One tree swaying in a wind, sampled at a fixed rate: the motion `sylva tree animate`
//! exports as a glTF animation, and the wind series `sylva sway probe` drives its tree with.
//!
//! The wind is read at one point, the crown (0.7 of the tree's height above its base), as
//! the forest reads it for a tree: a preset is synthesised on a small grid around that
//! point (the loop of the synthesis sets the clip's period with `looped`), a steady speed
//! blows along +x, and a wind file is sampled where the point falls in it.
//!
//! A clip starts after a warm-up in the same wind (the tree already bent and swaying, not
//! leaving rest). A looping clip lasts one period of its wind, after a warm-up of at least
//! three periods. A damped tree driven by a periodic wind settles into that period only
//! where its response is linear; light twigs in strong wind do not (their motion depends on
//! where they were), so the end of the period is blended into the start over its last
//! [`LOOP_BLEND`] (each joint's rotation towards the pose one period earlier, which meets
//! the start exactly): the clip's last sample is its first, and [`SwayClip::seam_deg`] says
//! how far the simulation itself was from closing the loop.

use sylva_core::quat;
use sylva_sway::{LeafParams, LeafSway, Palette, SwayBatch, SwayParams, SwaySpecies};
use sylva_tree::Skeleton;
use sylva_wind::{Grid, Preset, SynthParams, WindField};

use crate::driver::ForestError;
use crate::scene::WindSource;

/// The wind at one point over time.
#[derive(Debug)]
pub enum PointWind {
    /// A steady uniform wind, m/s (world axes).
    Steady([f32; 3]),
    /// A field sampled at `point`; it repeats every `period` s.
    Field {
        /// The field.
        field: Box<WindField>,
        /// Where it is read, world m.
        point: [f64; 3],
        /// Its loop, s.
        period: f64,
    },
}

impl PointWind {
    /// The wind of `source` at `point` (world m; the tree at the origin, `point` on its
    /// crown). A preset is synthesised (seed `seed`) for at least `seconds` s — exactly
    /// `seconds` rounded to the synthesis step of 0.1 s when `looped`.
    pub fn new(
        source: &WindSource,
        point: [f64; 3],
        seconds: f64,
        seed: u64,
        looped: bool,
    ) -> Result<PointWind, ForestError> {
        Ok(match source {
            WindSource::Steady(speed) => PointWind::Steady([*speed as f32, 0.0, 0.0]),
            WindSource::Preset(preset) => {
                PointWind::from_preset(*preset, point, seconds, seed, looped)?
            }
            WindSource::File(path) => {
                let field = sylva_wind::io::read_field(path)
                    .map_err(|e| ForestError::Wind(format!("{}: {e}", path.display())))?;
                let period = field.grid.frames as f64 * field.grid.dt;
                PointWind::Field { field: Box::new(field), point, period }
            }
        })
    }

    fn from_preset(
        preset: Preset,
        point: [f64; 3],
        seconds: f64,
        seed: u64,
        looped: bool,
    ) -> Result<PointWind, ForestError> {
        const DT: f64 = 0.1;
        if !(seconds > 0.0 && seconds <= 86_400.0) {
            return Err(ForestError::Wind(format!(
                "{seconds} s of wind: more than 0 and at most 86 400 s (a day)"
            )));
        }
        let frames = if looped {
            ((seconds / DT).round() as usize).next_multiple_of(2).max(16)
        } else {
            ((seconds / DT).ceil() as usize + 4).next_multiple_of(2).max(64)
        };
        let mut grid = Grid::regular(4, 4, 4.0, &[point[2].max(1.0)], frames, DT);
        grid.xs = vec![point[0] - 6.0, point[0] - 2.0, point[0] + 2.0, point[0] + 6.0];
        grid.ys = vec![point[1] - 6.0, point[1] - 2.0, point[1] + 2.0, point[1] + 6.0];
        let field = WindField::generate(
            &preset.params(),
            &grid,
            SynthParams { seed, ..Default::default() },
            &|_| {},
        )
        .map_err(|e| ForestError::Wind(e.to_string()))?;
        Ok(PointWind::Field { field: Box::new(field), point, period: frames as f64 * DT })
    }

    /// Velocity at time `t`, s, world m/s.
    pub fn at(&self, t: f64) -> [f32; 3] {
        match self {
            PointWind::Steady(v) => *v,
            PointWind::Field { field, point, .. } => {
                let s = field.view().sample(*point, t);
                [s[0] as f32, s[1] as f32, s[2] as f32]
            }
        }
    }

    /// Time after which the wind repeats, s (`None`: steady, any time).
    pub fn period(&self) -> Option<f64> {
        match self {
            PointWind::Steady(_) => None,
            PointWind::Field { period, .. } => Some(*period),
        }
    }
}

/// How a clip is sampled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClipSettings {
    /// Length, s (> 0). A looping clip lasts its wind's period instead.
    pub seconds: f64,
    /// Samples per second (> 0, ≤ 1000).
    pub fps: f64,
    /// Simulated time before the first sample, s (≥ 0).
    pub warmup: f64,
    /// Loop seamlessly: the clip is one period of the wind (a steady wind: `seconds`).
    pub looped: bool,
    /// The leaf-flutter model, driven by the wind speed at the same point.
    pub leaves: LeafParams,
}

impl Default for ClipSettings {
    fn default() -> Self {
        ClipSettings {
            seconds: 10.0,
            fps: 30.0,
            warmup: 10.0,
            looped: false,
            leaves: LeafParams::default(),
        }
    }
}

/// A recorded sway clip.
#[derive(Debug, Clone, PartialEq)]
pub struct SwayClip {
    /// Sample times from 0, s.
    pub times: Vec<f32>,
    /// The skeleton joints recorded.
    pub joints: Vec<usize>,
    /// Per sample, per recorded joint: its palette (rest → animated, tree space).
    pub palettes: Vec<Vec<Palette>>,
    /// Looping clips: the largest angle, degrees, between a recorded joint's rotation at
    /// the end of the period and at its start, before the last sample was set to the first.
    pub seam_deg: f32,
    /// Per sample: the leaves' flutter (amplitude and phase, rad), as the renderer reads it
    /// per tree. A looping clip's flutter runs a whole number of cycles in the period (its
    /// rate scaled by at most half a cycle over the clip), so its last sample is its first.
    pub flutter: Vec<LeafSway>,
}

impl SwayClip {
    /// Per sample, per recorded joint: the rotation part of its palette, row-major 3×3.
    pub fn rotations(&self) -> Vec<Vec<[f32; 9]>> {
        self.palettes.iter().map(|s| s.iter().map(sylva_sway::rotation_of).collect()).collect()
    }

    /// Per sample: the flutter as (amplitude, phase), rad — `JointAnimation::flutter`.
    pub fn flutter_track(&self) -> Vec<[f32; 2]> {
        self.flutter.iter().map(|l| [l.amplitude, l.phase]).collect()
    }
}

/// Simulate one tree with `skeleton` and sway constants `params` in `wind` and record the
/// palettes of `joints` (skeleton indices) as `settings` ask. The simulation steps at most
/// 1/60 s (several steps per sample when the rate is lower).
pub fn record(
    skeleton: &Skeleton,
    params: SwayParams,
    wind: &PointWind,
    joints: &[usize],
    settings: &ClipSettings,
) -> Result<SwayClip, ForestError> {
    let ClipSettings { seconds, fps, warmup, looped, leaves } = *settings;
    leaves.validate().map_err(|e| ForestError::Wind(format!("leaf flutter: {e}")))?;
    if !(fps > 0.0 && fps <= 1000.0) {
        return Err(ForestError::Wind(format!("{fps} samples per second: 0 < fps ≤ 1000")));
    }
    if !(seconds > 0.0 && seconds <= 3600.0 && (0.0..=36_000.0).contains(&warmup)) {
        return Err(ForestError::Wind(format!(
            "a clip of {seconds} s after {warmup} s of warm-up: 0 < seconds ≤ 3600, 0 ≤ warm-up \
             ≤ 36000"
        )));
    }
    if let Some(&j) = joints.iter().find(|&&j| j >= skeleton.len()) {
        return Err(ForestError::Species {
            name: "clip".into(),
            message: format!("joint {j} is not in the skeleton of {} joints", skeleton.len()),
        });
    }
    let sp = SwaySpecies::new(skeleton, params)
        .map_err(|e| ForestError::Species { name: "clip".into(), message: e.to_string() })?;
    let mut batch = SwayBatch::new(sp, 1);
    let (length, warmup) = match (looped, wind.period()) {
        (true, Some(p)) => (p, warmup.max(3.0 * p)),
        (true, None) => (seconds, warmup.max(30.0)),
        (false, _) => (seconds, warmup),
    };
    let samples = (length * fps).round().max(1.0) as usize;
    let sample_dt = length / samples as f64;
    let sub = (sample_dt * 60.0).ceil().max(1.0) as usize;
    let dt = sample_dt / sub as f64;
    // Warm-up, then the first sample at time `warmup` (rounded to whole steps). A loop also
    // records the period before, to blend its end into its start.
    let before = if looped { length } else { 0.0 };
    let warm_steps = ((warmup - before) / dt).round() as usize;
    let mut t = 0.0;
    // Flutter: its amplitude follows the wind speed; its phase is kept unwrapped (f64) here.
    let mut leaf = LeafSway::default();
    let mut phase = 0.0f64;
    let step = |batch: &mut SwayBatch, leaf: &mut LeafSway, phase: &mut f64, t: f64| {
        let w = wind.at(t);
        batch.step(dt as f32, &[w]);
        let speed = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
        *phase += std::f64::consts::TAU * leaves.frequency(speed) as f64 * dt;
        leaf.amplitude = leaves.amplitude(speed);
    };
    for _ in 0..warm_steps {
        t += dt;
        step(&mut batch, &mut leaf, &mut phase, t);
    }
    let start = t;
    let take = |b: &SwayBatch| joints.iter().map(|&j| b.palette(0, j)).collect::<Vec<_>>();
    let recorded = if looped { 2 * samples } else { samples };
    let mut palettes = vec![take(&batch)];
    let mut flutter = vec![(leaf.amplitude, phase)];
    for k in 1..=recorded {
        for s in 0..sub {
            // Times from the start of the clip, so a looped wind lines up with its period.
            let tk = start + ((k - 1) * sub + s + 1) as f64 * dt;
            step(&mut batch, &mut leaf, &mut phase, tk);
        }
        palettes.push(take(&batch));
        flutter.push((leaf.amplitude, phase));
    }
    if looped {
        // The period's own samples; the flutter's rate scaled to whole cycles in it.
        flutter.drain(..samples);
        let (a0, p0) = flutter[0];
        let advance = flutter[samples].1 - p0;
        let tau = std::f64::consts::TAU;
        let cycles = (advance / tau).round().max(1.0);
        let rate = if advance > 0.0 { cycles * tau / advance } else { 1.0 };
        for f in &mut flutter {
            f.1 = p0 + (f.1 - p0) * rate;
        }
        flutter[samples] = (a0, p0 + cycles * tau);
    }
    let flutter: Vec<LeafSway> = flutter
        .iter()
        .map(|&(amplitude, p)| LeafSway {
            amplitude,
            phase: p.rem_euclid(std::f64::consts::TAU) as f32,
        })
        .collect();
    let times: Vec<f32> = (0..=samples).map(|k| (k as f64 * sample_dt) as f32).collect();
    let mut seam_deg = 0.0;
    if looped {
        // S(t): the recorded poses, the clip's period being [W, W + P]. Its end would jump
        // from S(W + P) back to S(W); over the last LOOP_BLEND of the period each joint's
        // rotation blends (smoothstep in time, slerp in angle) from S(W + t) into S(W + t − P),
        // the same wind one period earlier, which reaches S(W) itself at t = P: the loop
        // closes with no jump in pose or speed.
        let (prev, cur) = palettes.split_at(samples);
        let cur = &cur[..=samples];
        for (a, b) in cur[0].iter().zip(&cur[samples]) {
            seam_deg = f32::max(seam_deg, rotation_between(a, b).to_degrees());
        }
        let mut prev = prev.to_vec();
        prev.push(cur[0].clone());
        palettes = (0..=samples)
            .map(|k| {
                let x =
                    ((k as f64 / samples as f64 - (1.0 - LOOP_BLEND)) / LOOP_BLEND).clamp(0.0, 1.0);
                let w = x * x * (3.0 - 2.0 * x);
                blend_pose(skeleton, joints, &cur[k], &prev[k], w)
            })
            .collect();
    }
    Ok(SwayClip { times, joints: joints.to_vec(), palettes, seam_deg, flutter })
}

/// Fraction of a looping clip over which its end blends into its start.
pub const LOOP_BLEND: f64 = 0.3;

/// Poses `a` and `b` of `joints` blended with weight `w` (0: a, 1: b): each joint's rotation
/// slerped, its translation recomposed so that it still turns about its own origin carried
/// by its (blended) parent.
fn blend_pose(
    skeleton: &Skeleton,
    joints: &[usize],
    a: &[Palette],
    b: &[Palette],
    w: f64,
) -> Vec<Palette> {
    if w <= 0.0 {
        return a.to_vec();
    }
    if w >= 1.0 {
        return b.to_vec();
    }
    let js = skeleton.joints();
    let mut slot = std::collections::HashMap::with_capacity(joints.len());
    let mut order: Vec<usize> = (0..joints.len()).collect();
    order.sort_by_key(|&k| joints[k]);
    let mut out = a.to_vec();
    for k in order {
        let j = joints[k];
        let q = |p: &Palette| quat::from_matrix(|r, c| p[4 * r + c] as f64);
        let rows = quat::to_rows(quat::slerp(q(&a[k]), q(&b[k]), w));
        let r: [f32; 9] = std::array::from_fn(|e| rows[e / 3][e % 3] as f32);
        let o = js[j].origin;
        let ro = [0, 1, 2].map(|i| r[3 * i] * o[0] + r[3 * i + 1] * o[1] + r[3 * i + 2] * o[2]);
        // Where the joint's origin goes: carried by the blended parent, or else blended.
        let p = js[j].parent;
        let moved = match (p != sylva_tree::NO_PARENT).then(|| slot.get(&(p as usize))).flatten() {
            Some(&kp) => sylva_sway::transform(&out[kp], o),
            None => {
                let (pa, pb) = (sylva_sway::transform(&a[k], o), sylva_sway::transform(&b[k], o));
                [0, 1, 2].map(|i| pa[i] + (pb[i] - pa[i]) * w as f32)
            }
        };
        out[k] = [
            r[0],
            r[1],
            r[2],
            moved[0] - ro[0],
            r[3],
            r[4],
            r[5],
            moved[1] - ro[1],
            r[6],
            r[7],
            r[8],
            moved[2] - ro[2],
        ];
        slot.insert(j, k);
    }
    out
}

/// Angle of the rotation taking palette `a`'s rotation to `b`'s, rad.
fn rotation_between(a: &Palette, b: &Palette) -> f32 {
    // trace(Aᵀ B) = 1 + 2 cos θ.
    let mut tr = 0.0f64;
    for r in 0..3 {
        for c in 0..3 {
            tr += a[4 * r + c] as f64 * b[4 * r + c] as f64;
        }
    }
    (((tr - 1.0) / 2.0).clamp(-1.0, 1.0)).acos() as f32
}
