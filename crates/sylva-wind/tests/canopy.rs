//! The canopy profile: the log law over the forest, an exponential law inside it,
//! continuous at the canopy top.

use sylva_wind::{Profile, WindParams, canopy_attenuation};

fn canopy(a: f64) -> WindParams {
    WindParams { profile: Profile::Canopy { h: 15.0, a, z0: 1.5, d: 10.0 }, ..Default::default() }
}

#[test]
fn the_canopy_profile_is_the_log_law_above_continuous_at_the_top_and_monotone() {
    let log = WindParams { profile: Profile::Log { z0: 1.5, d: 10.0 }, ..Default::default() };
    for a in [0.5, 2.0, 4.0] {
        let p = canopy(a);
        p.validate().expect("a valid canopy profile");
        // Above the top: the log law itself.
        for z in [15.0, 20.0, 40.0, 100.0] {
            assert_eq!(p.mean_speed(z), log.mean_speed(z), "z {z} m");
        }
        // Continuous at the top, within a millimetre's change of the log law.
        let (below, above) = (p.mean_speed(15.0 - 1e-3), p.mean_speed(15.0 + 1e-3));
        assert!((below - above).abs() < 1e-3 * above, "{below} against {above}");
        // Monotone from the ground up, and falling by e^-a to the ground.
        let us: Vec<f64> = (0..=300).map(|k| p.mean_speed(0.1 * k as f64)).collect();
        assert!(us.windows(2).all(|w| w[1] >= w[0]), "a = {a}");
        let ratio = p.mean_speed(0.0) / p.mean_speed(15.0);
        assert!((ratio - (-a).exp()).abs() < 1e-12, "{ratio}");
        // At half the canopy's height: e^(−a/2) of the top's speed.
        assert!((p.mean_speed(7.5) / p.mean_speed(15.0) - (-a / 2.0).exp()).abs() < 1e-12);
    }
    // Its parameters are checked: the top above the log law's d + z0.
    let low = WindParams {
        profile: Profile::Canopy { h: 11.0, a: 2.0, z0: 1.5, d: 10.0 },
        ..Default::default()
    };
    assert!(low.validate().expect_err("top below d + z0").to_string().contains("profile.h"));
}

#[test]
fn a_denser_canopy_attenuates_more_within_the_range_measured_in_forests() {
    // Leaf area indices of forests, 2 to 6, with c_d = 0.2: attenuations 2.2 … 6.7, rising.
    let a: Vec<f64> = [2.0, 3.0, 4.0, 6.0].iter().map(|&l| canopy_attenuation(l, 0.2)).collect();
    assert!(a.windows(2).all(|w| w[1] > w[0]), "{a:?}");
    assert!((a[0] - 2.22).abs() < 0.01 && a[3] < 10.0, "{a:?}");
}
