//! The spring model against its physics: free decay at the analytic frequency and damping,
//! static deflection τ/k growing as the drag law says, the same statistics at 5 and 240
//! steps per second, no NaN in a storm, smooth animation-LOD switching, determinism.

use sylva_sway::{LANES, SwayBatch, SwayParams, SwaySpecies, transform};
use sylva_tree::{Joint, NO_PARENT, Skeleton, Species};
use sylva_wind::{Grid, Method, Preset, SynthParams, WindField};

/// A vertical pole of `n` segments (base radius `r0`, tapering) with `leaf` m² of leaves on
/// the top segment.
fn pole(n: usize, height: f32, r0: f32, leaf: f32) -> Skeleton {
    let l = height / n as f32;
    let joints = (0..n)
        .map(|i| {
            let r = r0 * (1.0 - 0.6 * i as f32 / n as f32);
            Joint {
                parent: if i == 0 { NO_PARENT } else { (i - 1) as u32 },
                origin: [0.0, 0.0, i as f32 * l],
                axis: [0.0, 0.0, 1.0],
                length: l,
                radius: r,
                own_mass: 800.0 * std::f32::consts::PI * r * r * l,
                leaf_area: if i + 1 == n { leaf } else { 0.0 },
                leaf_mass: if i + 1 == n { 0.3 * leaf } else { 0.0 },
                continues: i > 0,
            }
        })
        .collect();
    Skeleton::new(joints).expect("valid pole")
}

fn tip(b: &SwayBatch, sk: &Skeleton) -> [f32; 3] {
    let last = sk.len() - 1;
    transform(&b.palette(0, last), sk.joints()[last].tip())
}

#[test]
fn free_decay_has_the_analytic_frequency_and_damping_ratio() {
    // No drag: the joint is the linear oscillator alone.
    let params =
        SwayParams { wood_drag: 0.0, leaf_drag: 0.0, damping_ratio: 0.05, ..SwayParams::default() };
    let sk = pole(1, 2.0, 0.025, 0.0); // a bare 5 cm × 2 m branch
    let sp = SwaySpecies::new(&sk, params).expect("valid params");
    let spring = sp.spring(0);
    let mut b = SwayBatch::new(sp, 1);
    b.set_state(0, 0, [0.05, 0.0], [0.0, 0.0]);
    let dt = 1.0 / 2000.0;
    let mut series = vec![0.05f64];
    for _ in 0..8000 {
        b.step(dt, &[[0.0; 3]]);
        series.push(b.angles(0, 0)[0] as f64);
    }
    // Upward zero crossings (interpolated) give the damped period; successive peaks the
    // logarithmic decrement.
    let ups: Vec<f64> = (1..series.len())
        .filter(|&k| series[k - 1] < 0.0 && series[k] >= 0.0)
        .map(|k| (k - 1) as f64 + series[k - 1] / (series[k - 1] - series[k]))
        .map(|k| k * dt as f64)
        .collect();
    let periods = ups.len() - 1;
    let fd = periods as f64 / (ups[periods] - ups[0]);
    let zeta = 0.05f64;
    let f_expect = spring.frequency as f64 * (1.0 - zeta * zeta).sqrt();
    assert!((fd / f_expect - 1.0).abs() < 0.01, "damped frequency {fd} Hz, expected {f_expect}");
    let peaks: Vec<f64> = (1..series.len() - 1)
        .filter(|&k| series[k] > series[k - 1] && series[k] >= series[k + 1] && series[k] > 0.0)
        .map(|k| series[k])
        .collect();
    let cycles = (peaks.len() - 1) as f64;
    let delta = (peaks[0] / peaks[peaks.len() - 1]).ln() / cycles;
    let zeta_meas = delta / (4.0 * std::f64::consts::PI.powi(2) + delta * delta).sqrt();
    assert!((zeta_meas / zeta - 1.0).abs() < 0.01, "damping ratio {zeta_meas}, expected {zeta}");
    // A bare 5 cm × 2 m branch swings at 5–7 Hz, as measured.
    assert!(spring.frequency > 5.0 && spring.frequency < 7.0, "{} Hz", spring.frequency);
}

#[test]
fn static_deflection_is_torque_over_stiffness_and_grows_as_the_drag_law() {
    // Eq. 8 with reconfiguring leaves: F = ½ρ (C_w A_w + C_l A_l / (1 + u/U_r)) u², so the
    // wood's share grows as u² and the leaves' towards u (Vogel exponent −1).
    let sk = pole(1, 3.0, 0.04, 2.0);
    // The elements' own drag law (the whole-crown calibration, which scales it, off).
    let params = SwayParams { crown_drag: 0.0, ..SwayParams::default() };
    let j = sk.joints()[0];
    let force = |u: f32| {
        let wood = params.wood_drag * 2.0 * j.radius * j.length;
        let leaves = params.leaf_drag * j.leaf_area / (1.0 + u / params.leaf_reconfiguration_speed);
        0.5 * params.air_density * (wood + leaves) * u * u
    };
    let deflect = |u: f32| {
        let sp = SwaySpecies::new(&sk, params).expect("valid params");
        let k = sp.spring(0).stiffness;
        let mut b = SwayBatch::new(sp, 1);
        for _ in 0..20_000 {
            b.step(1.0 / 100.0, &[[u, 0.0, 0.0]]);
        }
        let tau = force(u) * 0.5 * j.length;
        // The bend (about the axis across the wind) has magnitude |θ| = τ/k.
        let [x, y] = b.angles(0, 0);
        (x.hypot(y), tau / k)
    };
    let (a1, want1) = deflect(5.0);
    let (a2, want2) = deflect(20.0);
    assert!((a1 / want1 - 1.0).abs() < 1e-3, "deflection {a1} vs τ/k {want1}");
    assert!((a2 / want2 - 1.0).abs() < 1e-3, "deflection {a2} vs τ/k {want2}");
    // Four times the wind: less than 16× the load (the leaves reconfigure), more than 4×.
    let ratio = a2 / a1;
    assert!(ratio > 4.0 && ratio < 12.0, "four times the wind gives {ratio}× the deflection");
}

fn turbulent_wind(preset: Preset, seconds: f64, dt: f64) -> Vec<[f32; 3]> {
    let grid = Grid::regular(4, 4, 4.0, &[12.0], 4096, 0.1);
    let f = WindField::generate(
        &preset.params(),
        &grid,
        SynthParams { seed: 3, method: Method::Separable },
        &|_| {},
    )
    .expect("wind field");
    let v = f.view();
    (0..(seconds / dt) as usize)
        .map(|k| {
            let s = v.sample([6.0, 6.0, 12.0], k as f64 * dt);
            [s[0] as f32, s[1] as f32, s[2] as f32]
        })
        .collect()
}

fn tip_sigma(dt: f64, preset: Preset) -> (f64, bool) {
    let sk = pole(6, 12.0, 0.15, 30.0);
    let sp = SwaySpecies::new(&sk, SwayParams::default()).expect("valid params");
    let mut b = SwayBatch::new(sp, 1);
    let wind = turbulent_wind(preset, 400.0, dt);
    let mut xs = Vec::new();
    let mut finite = true;
    for (k, w) in wind.iter().enumerate() {
        b.step(dt as f32, &[*w]);
        let t = tip(&b, &sk);
        finite &= t.iter().all(|c| c.is_finite());
        if k as f64 * dt > 50.0 {
            xs.push(t[0] as f64);
        }
    }
    let m = xs.iter().sum::<f64>() / xs.len() as f64;
    ((xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / xs.len() as f64).sqrt(), finite)
}

#[test]
fn five_and_240_steps_per_second_agree_and_a_storm_stays_finite() {
    let (fast, ok_fast) = tip_sigma(1.0 / 240.0, Preset::Strong);
    let (slow, ok_slow) = tip_sigma(1.0 / 5.0, Preset::Strong);
    assert!(ok_fast && ok_slow);
    assert!(fast > 0.01, "the tree must move: σ = {fast} m");
    assert!((slow / fast - 1.0).abs() < 0.05, "tip σ {slow} m at 5 fps vs {fast} m at 240 fps");
    // Storm: U* = 6 m/s, gusts near 40 m/s at the crown.
    let (storm, ok) = tip_sigma(1.0 / 5.0, Preset::Storm);
    assert!(ok && storm.is_finite() && storm > fast);
}

#[test]
fn switching_joints_off_and_on_moves_points_smoothly() {
    // Documented bound: a switch moves a point, per frame, by at most its deflection
    // × dt / blend_time beyond the motion the springs themselves make.
    let sk = pole(6, 12.0, 0.15, 30.0);
    let params = SwayParams::default();
    let dt = 1.0 / 60.0;
    let run = |switch: bool| {
        let sp = SwaySpecies::new(&sk, params).expect("valid params");
        let mut b = SwayBatch::new(sp, 1);
        let mut steps = Vec::new();
        let mut last = tip(&b, &sk);
        let mut max_defl = 0.0f32;
        for k in 0..1200 {
            if switch && k == 400 {
                b.set_budget(0, 1);
            }
            if switch && k == 800 {
                b.set_budget(0, 6);
            }
            b.step(dt, &[[12.0, 0.0, 0.0]]);
            let t = tip(&b, &sk);
            max_defl = max_defl.max(t[0].abs());
            steps.push(((t[0] - last[0]).powi(2) + (t[2] - last[2]).powi(2)).sqrt());
            last = t;
        }
        (steps, max_defl)
    };
    let (free, _) = run(false);
    let (switched, defl) = run(true);
    let natural = free[300..].iter().cloned().fold(0.0f32, f32::max);
    let bound = natural + defl * dt / params.blend_time;
    let worst = switched[300..].iter().cloned().fold(0.0f32, f32::max);
    assert!(worst <= bound * 1.05, "a switch moved the tip {worst} m in a frame (bound {bound})");
    // And the switch does something: the top joints blend to rest and the tip moves.
    assert!(switched[400..].iter().sum::<f32>() > free[400..].iter().sum::<f32>() * 1.01);
}

#[test]
fn batches_are_bit_identical_for_one_and_two_threads() {
    let sk = pole(8, 15.0, 0.2, 40.0);
    let winds: Vec<[f32; 3]> =
        (0..64).map(|i| [4.0 + (i % 7) as f32, (i % 3) as f32 - 1.0, 0.0]).collect();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
        pool.install(|| {
            let sp = SwaySpecies::new(&sk, SwayParams::default()).expect("valid params");
            let mut b = SwayBatch::new(sp, 64);
            for i in 0..64 {
                b.set_budget(i, i % 9);
            }
            for _ in 0..200 {
                b.step(1.0 / 30.0, &winds);
            }
            (0..b.groups())
                .flat_map(|g| b.group_palettes(g).iter().map(|x| x.to_bits()))
                .collect::<Vec<u32>>()
        })
    };
    assert_eq!(run(1), run(2));
}

/// A crown of thousands of joints (a near tree) stepped alone has its joints'
/// independent work split into runs on several threads, and its sweeps along the skeleton
/// into bins of whole subtrees. Each joint's arithmetic, and the order of its sums, is the
/// same wherever it runs: the palettes are the same bits on one thread and on two, and the
/// same as those of a full group of 16 such instances in the same wind (stepped together,
/// nothing split).
#[test]
fn a_large_crown_stepped_alone_is_the_same_on_any_threads_and_in_a_group() {
    let model = Species::preset("black_tupelo").expect("preset").model(5, 4).expect("model");
    let sp = SwaySpecies::new(&model.tree.skeleton, SwayParams::default()).expect("species");
    let n = sp.len();
    assert!(n >= 8192, "{n} joints: too few to be split twice");
    let bits = |b: &SwayBatch, i: usize| -> Vec<u32> {
        (0..n).flat_map(|j| b.palette(i, j)).map(f32::to_bits).collect()
    };
    let run = |threads: usize, instances: usize, wind: [f32; 3]| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
        pool.install(|| {
            let mut b = SwayBatch::new(sp.clone(), instances);
            for _ in 0..30 {
                b.step(1.0 / 30.0, &vec![wind; instances]);
            }
            bits(&b, instances - 1)
        })
    };
    let mut last = Vec::new();
    for wind in [[6.0, 1.0, 0.0], [18.0, -3.0, 0.5]] {
        let one = run(1, 1, wind);
        assert!(one == run(2, 1, wind), "{wind:?}: one thread and two differ");
        assert!(one == run(1, LANES, wind), "{wind:?}: alone and in a group differ");
        // The comparison can fail: the two winds bend the crown differently.
        assert!(one != last, "{wind:?}: the crown moved as in the other wind");
        last = one;
    }
}

/// Groups are stepped in parallel, and a large crown stepped alone within one splits its
/// own work across threads too: a thread waiting on that split may take up another
/// group's step meanwhile. Each group's scratch loads must then be its own, not the
/// thread's borrowed twice (which panicked with 16 threads). Sixty-four groups, each with
/// one near tree (every joint, in its lane alone) among fifteen far ones (their trunks),
/// step on eight threads to the same bits as on one.
#[test]
fn groups_with_crowns_stepped_alone_step_on_many_threads_as_on_one() {
    let model = Species::preset("black_tupelo").expect("preset").model(5, 4).expect("model");
    let order = sylva_tree::lod_order(&model);
    let model = model.reordered(&order.order).expect("reorder");
    let sp = SwaySpecies::new(&model.tree.skeleton, SwayParams::default()).expect("species");
    let n = sp.len();
    assert!(n >= 4096, "{n} joints: too few to be split into runs");
    let instances = 64 * LANES;
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
        pool.install(|| {
            let mut b = SwayBatch::new(sp.clone(), instances);
            b.set_prefixes(&[order.prefix.as_slice(), &[order.trunk]].concat());
            for i in (0..instances).filter(|i| i % LANES != 0) {
                b.set_lane_active(i, order.trunk);
            }
            let winds: Vec<[f32; 3]> =
                (0..instances).map(|i| [6.0 + (i % 5) as f32, 1.0, 0.0]).collect();
            // The far crowns fade out over the blend time (0.5 s), then go.
            for _ in 0..20 {
                b.step(1.0 / 30.0, &winds);
            }
            let trunk = b.prefix_for(order.trunk);
            assert_eq!(b.simulated(0), n, "the near tree is simulated in full");
            assert_eq!(b.simulated(1), trunk, "a far tree simulates its trunk");
            let mut bits = Vec::new();
            for i in (0..instances).step_by(LANES) {
                bits.extend((0..n).flat_map(|j| b.palette(i, j)).map(f32::to_bits));
            }
            bits
        })
    };
    assert!(run(1) == run(8), "eight threads step the near crowns differently from one");
}
