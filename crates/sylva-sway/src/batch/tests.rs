//! The rotations, the lever's bend and the group formula checked against their definitions.

#[test]
fn the_lever_bend_balances_spring_and_shortened_arm() {
    // θ = e cos θ, solved in f64 by Newton to convergence, against lever_bend's one step.
    let mut last = 0.0;
    for k in 0..=400 {
        let e = 0.001 * 1.03f64.powi(k); // 0.001 … 1.4e2
        let mut t = e.min(1.0);
        for _ in 0..60 {
            t -= (t - e * t.cos()) / (1.0 + e * t.sin());
        }
        // The step's rule: the series below LEVER_SERIES, the Newton step above.
        let e2 = (e * e) as f32;
        let factor = if e2 > super::LEVER_SERIES { super::lever_bend(e2) } else { 1.0 - 0.5 * e2 };
        let got = factor as f64 * e;
        assert!((got / t - 1.0).abs() < 0.007, "e {e}: {got} against {t}");
        assert!(got < std::f64::consts::FRAC_PI_2, "e {e}: past a quarter turn");
        assert!(got > last, "the bend grows with the load (e {e})");
        last = got;
    }
}

/// The group's one choice of rotation formula is made by the lanes whose values are
/// read: a lane nothing reads (stepped alone on its row), however far it is bent, leaves
/// the others' palettes exactly as they are with it at rest; taking part, it would
/// switch the whole group to the full formula.
#[test]
fn lanes_nothing_reads_take_no_part_in_the_group_formula() {
    use crate::SwayParams;
    let model = sylva_tree::Species::preset("quaking_aspen").expect("preset").model(5, 6);
    let sp = crate::SwaySpecies::new(&model.expect("model").tree.skeleton, SwayParams::default())
        .expect("species");
    // Joint 0 (the root, no parent) bent by a small angle in lanes 0–2; lane 3 far bent.
    let palettes = |bent: f32, ignored: bool| {
        let mut lanes = vec![[[0.0f32; 4]; 12]; 1];
        let mut phi = [[0.0f32; 4]; 3];
        for l in 0..3 {
            phi[0][l] = 0.013 * (l + 1) as f32;
            phi[1][l] = -0.007 * (l + 1) as f32;
        }
        phi[0][3] = bent;
        let mut skip = [false; LANES];
        skip[3] = ignored;
        palette_of::<4>(&sp, &mut lanes, 0, &phi, &skip);
        (0..3)
            .map(|l| (0..12).map(|e| lanes[0][e][l].to_bits()).collect())
            .collect::<Vec<Vec<u32>>>()
    };
    let at_rest = palettes(0.0, false);
    assert_eq!(palettes(1.1, true), at_rest, "ignored: as if at rest");
    assert_ne!(palettes(1.1, false), at_rest, "taking part, it switches the formula");
}

#[test]
fn any_angle_matches_f64_within_3e_7() {
    for k in 0..=40000 {
        let a = k as f32 * 1e-3;
        let (s, v) = any_angle(a * a);
        // Reference in f64 (f32's 1 − cos a cancels at small a).
        let x = a as f64;
        let (ls, lv) = if k > 0 {
            ((x.sin() / x) as f32, ((1.0 - x.cos()) / (x * x)) as f32)
        } else {
            (1.0, 0.5)
        };
        assert!((s - ls).abs() <= 3e-7, "sin a / a at {a}: {s} vs {ls}");
        assert!((v - lv).abs() <= 3e-7, "(1 − cos a)/a² at {a}: {v} vs {lv}");
    }
}

use super::kernel::*;
use super::*;

#[test]
fn rotation_matches_rodrigues_across_the_series_switch() {
    for a in [1e-4f32, 0.1, 0.49, 0.51, 1.0] {
        let r = rotation([0.0, 0.0, a]);
        assert!((r[0][0] - a.cos()).abs() < 1e-6 && (r[1][0] - a.sin()).abs() < 1e-6, "{a}: {r:?}");
    }
}

#[test]
fn compose_is_matrix_product() {
    let a = [0.0, -1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 2.0, 0.0, 0.0, 1.0, 3.0];
    let b = [1.0, 0.0, 0.0, 5.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let x = [0.3, 0.7, -0.2];
    let ab = transform(&compose(&a, &b), x);
    let want = transform(&a, transform(&b, x));
    for c in 0..3 {
        assert!((ab[c] - want[c]).abs() < 1e-6);
    }
}
