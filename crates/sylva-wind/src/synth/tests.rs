//! The methods against each other and the phases against their definition.

use super::*;

#[test]
fn phasors_are_unit_and_uniform_in_angle() {
    let key = line_key(7, Component::U, 3);
    let n = 200_000;
    let mut hist = [0usize; 16];
    for k in 0..n {
        let p = phasor(key, k as u64);
        // The remainder's sine and cosine are f32 polynomials: unit to f32 precision.
        assert!((p.norm() - 1.0).abs() < 1e-7);
        let a = p.im.atan2(p.re) + PI;
        hist[((a / (2.0 * PI) * 16.0) as usize).min(15)] += 1;
    }
    // Each bin expects n/16 = 12500 with σ ≈ 108: 6σ bounds.
    for h in hist {
        assert!((h as f64 - 12_500.0).abs() < 650.0, "{hist:?}");
    }
}

#[test]
fn vectorised_kernels_give_the_scalar_bits() {
    // The widest kernel the CPU has must agree bit for bit with the scalar phasor, so
    // the field does not depend on the machine's vector units.
    let keys: Vec<u64> = (0..301).map(|j| line_key(3, Component::V, j)).collect();
    let rho: Vec<f64> = (0..301).map(|j| (-(j as f64) * 0.01).exp()).collect();
    let s: Vec<f64> = rho.iter().map(|r| (1.0 - r * r).sqrt()).collect();
    for k in [0u64, 7, 123_456] {
        let mut v: Vec<C64> = (0..301).map(|j| C64::new(j as f64, -1.0)).collect();
        let want: Vec<C64> = v
            .iter()
            .zip(&keys)
            .zip(rho.iter().zip(&s))
            .map(|((o, key), (r, s))| {
                let e = phasor(*key, k);
                C64::new(o.re * r + e.re * s, o.im * r + e.im * s)
            })
            .collect();
        phasor_row(&keys, k, &mut v, Some((&rho, &s)));
        for (a, b) in v.iter().zip(&want) {
            assert_eq!((a.re.to_bits(), a.im.to_bits()), (b.re.to_bits(), b.im.to_bits()));
        }
    }
}

#[test]
fn cholesky_factor_reproduces_the_matrix() {
    let n = 5;
    let full: Vec<f64> = (0..n * n)
        .map(|k| {
            let (i, j) = (k / n, k % n);
            0.7f64.powi((i as i32 - j as i32).abs()) + if i == j { 0.1 } else { 0.0 }
        })
        .collect();
    let mut l = full.clone();
    cholesky_lower(&mut l, n).expect("positive definite");
    for i in 0..n {
        for j in 0..=i {
            let s: f64 = (0..=j).map(|k| l[i * n + k] * l[j * n + k]).sum();
            assert!((s - full[i * n + j]).abs() < 1e-12);
        }
    }
    let mut bad = vec![1.0, 0.0, 2.0, 1.0];
    assert_eq!(cholesky_lower(&mut bad, 2), Err(1));
}

/// The embedding's stream takes two phases from each hash: each must still be unit and
/// uniform in angle, the two halves of one hash uncorrelated, and a span starting or ending
/// on either half the same phasors, bit for bit, as those indices taken one at a time.
#[test]
fn paired_phasors_are_unit_uniform_and_independent_halves() {
    let key = line_key(11, Component::W, 5);
    let n = 200_000;
    let mut span = vec![C64::default(); n];
    phasor_span(key, 0, &mut span);
    let mut hist = [0usize; 16];
    let mut cross = C64::default();
    for (k, p) in span.iter().enumerate() {
        assert!((p.norm() - 1.0).abs() < 1e-7);
        let a = p.im.atan2(p.re) + PI;
        hist[((a / (2.0 * PI) * 16.0) as usize).min(15)] += 1;
        if k % 2 == 1 {
            cross += span[k - 1] * p.conj();
        }
    }
    for h in hist {
        assert!((h as f64 - 12_500.0).abs() < 650.0, "{hist:?}");
    }
    // |mean of n/2 unit products| has σ ≈ 1/√(n/2) = 0.0032 when the halves are independent.
    let r = cross.norm() / (n / 2) as f64;
    assert!(r < 0.015, "halves of one hash correlate: {r}");
    // Spans shorter than a block of 16 pairs, whole blocks, and blocks with a remainder, each
    // starting on either half; the f32 span holds the same values before widening.
    for (k0, len) in
        [(0u64, 7usize), (1, 7), (1, 8), (5, 1), (40_000, 33), (0, 64), (1, 64), (3, 101), (2, 250)]
    {
        let mut got = vec![C64::default(); len];
        phasor_span(key, k0, &mut got);
        let mut got32 = vec![Complex::<f32>::default(); len];
        phasor_span_f32(key, k0, &mut got32);
        for (i, (g, g32)) in got.iter().zip(&got32).enumerate() {
            let want = paired_phasor(key, k0 + i as u64);
            assert_eq!((g.re.to_bits(), g.im.to_bits()), (want.re.to_bits(), want.im.to_bits()));
            assert_eq!((f64::from(g32.re), f64::from(g32.im)), (want.re, want.im));
        }
    }
}
