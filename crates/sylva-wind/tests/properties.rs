//! Property: any wind model with every parameter inside its documented range (see
//! `WindParams::validate`), on any small grid, synthesises a finite field, by the method
//! `Method::fastest` picks, with a finite coherence-error bound; the same seed gives the
//! same bits. Where a range is open-ended the draw spans several decades (log-uniform).
//!
//! proptest draws the cases from a fixed seed and shrinks a failure. `PROPTEST_CASES` sets
//! the number of cases (default 16).

use proptest::prelude::*;
use sylva_testkit::runner;
use sylva_wind::params::{CoherenceConstants, PAPER_COHERENCE, PAPER_SPECTRUM, SpectrumConstants};
use sylva_wind::{
    CoherenceSpeed, Grid, Method, Profile, SpectrumModel, SynthParams, WindField, WindParams,
};

/// log-uniform in [10^lo, 10^hi].
fn decades(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo..=hi).prop_map(|e| 10f64.powf(e))
}

fn profile() -> impl Strategy<Value = Profile> {
    prop_oneof![
        (decades(-3.0, 1.0), 0.0f64..=100.0).prop_map(|(z0, d)| Profile::Log { z0, d }),
        (decades(-3.0, 2.0), decades(-2.0, 4.0), 0.0f64..=1.0)
            .prop_map(|(u_ref, z_ref, alpha)| Profile::Power { u_ref, z_ref, alpha }),
    ]
}

fn spectrum_constants() -> impl Strategy<Value = [SpectrumConstants; 3]> {
    prop_oneof![
        Just(PAPER_SPECTRUM),
        proptest::array::uniform3(
            (decades(-3.0, 4.0), decades(-3.0, 4.0)).prop_map(|(a, b)| SpectrumConstants { a, b })
        ),
    ]
}

fn coherence() -> impl Strategy<Value = [CoherenceConstants; 3]> {
    prop_oneof![
        Just(PAPER_COHERENCE),
        proptest::array::uniform3(
            (0.0f64..=1e3, 0.0f64..=1e3, 0.0f64..=1e3)
                .prop_map(|(cx, cy, cz)| CoherenceConstants { cx, cy, cz })
        ),
    ]
}

fn params() -> impl Strategy<Value = WindParams> {
    (
        (decades(-3.0, 0.0), 0.0f64..=1.0).prop_map(|(lo, f)| (lo + f * 20.0).min(20.0)),
        profile(),
        prop_oneof![
            Just(SpectrumModel::Paper),
            Just(SpectrumModel::Kaimal),
            Just(SpectrumModel::VonKarman)
        ],
        spectrum_constants(),
        coherence(),
        prop_oneof![Just(CoherenceSpeed::Reference), Just(CoherenceSpeed::PairMean)],
        -720.0f64..=720.0,
        any::<bool>(),
    )
        .prop_map(
            |(u_star, profile, spectrum, spectrum_constants, coherence, speed, dir, advection)| {
                WindParams {
                    u_star,
                    profile,
                    spectrum,
                    spectrum_constants,
                    coherence,
                    coherence_speed: speed,
                    direction_deg: dir,
                    advection,
                    convection_speed: None,
                }
            },
        )
}

/// Small grids: 2–6 × 2–5 points, one to three heights, 8–64 frames.
fn grid() -> impl Strategy<Value = Grid> {
    (
        2usize..=6,
        2usize..=5,
        decades(-1.0, 2.0),
        decades(-1.0, 2.0),
        proptest::collection::vec(decades(-1.0, 1.5), 0..=2),
        (4usize..=32).prop_map(|h| 2 * h),
        decades(-2.0, 0.5),
    )
        .prop_map(|(nx, ny, spacing, z0, steps, frames, dt)| {
            let mut zs = vec![z0];
            for s in steps {
                let last = *zs.last().expect("one height");
                zs.push(last + s);
            }
            Grid::regular(nx, ny, spacing, &zs, frames, dt)
        })
}

#[test]
fn any_wind_parameters_inside_the_ranges_give_finite_fields() {
    let mut runner = runner(16, 0x5eed_0002);
    let outcome = runner.run(&(params(), grid(), any::<u64>()), |(p, grid, seed)| {
        p.validate().map_err(|e| TestCaseError::fail(format!("drawn outside the ranges: {e}")))?;
        grid.validate().map_err(|e| TestCaseError::fail(format!("grid: {e}")))?;
        let sp = SynthParams { seed, method: Method::fastest(&p, &grid) };
        // Ranges each parameter keeps can still combine into a mean wind over 100 m/s on
        // the grid: such a profile is refused, naming a parameter, before any synthesis.
        let fastest = grid.zs.iter().map(|&z| p.mean_speed(z)).fold(0.0, f64::max);
        if fastest > sylva_wind::field::MAX_MEAN_SPEED {
            let e = WindField::generate(&p, &grid, sp, &|_| {}).expect_err("refused");
            prop_assert!(e.to_string().contains("at most 100 m/s"), "{}", e);
            return Ok(());
        }
        let f = WindField::generate(&p, &grid, sp, &|_| {})
            .map_err(|e| TestCaseError::fail(format!("{e}")))?;
        prop_assert_eq!(f.data.len(), grid.points() * 3 * grid.frames);
        sylva_wind::field::check_samples(&f).map_err(|e| {
            TestCaseError::fail(format!("a synthesised field a reader refuses: {e}"))
        })?;
        prop_assert!(f.data.iter().all(|v| v.is_finite()), "a non-finite sample");
        prop_assert!(f.coherence_error.is_finite() && f.coherence_error >= 0.0);
        let again = WindField::generate(&p, &grid, sp, &|_| {})
            .map_err(|e| TestCaseError::fail(format!("{e}")))?;
        prop_assert!(again.data == f.data, "same seed, other bits");
        Ok(())
    });
    if let Err(e) = outcome {
        panic!("{e}");
    }
}
