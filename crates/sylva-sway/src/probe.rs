//! Measuring a sway record the way a field test does: bend a tree under a steady wind, let
//! go ([`bend_and_release`]), and read the frequency and damping ratio of the free decay
//! ([`free_decay`]).

use sylva_tree::Skeleton;

use crate::batch::{SwayBatch, transform};

/// A bend-and-release test on instance 0 of `batch` (a tree with skeleton `sk`): `hold`
/// steps of `dt` under the steady wind `load` (world m/s), then `free` steps in still air.
/// `each` sees every step after it is taken: its index, the wind it had, and the batch
/// (to record more than the trunk). Returns the trunk top's horizontal displacement from
/// rest, (x, y) in m, over the free steps: the record [`free_decay`] reads.
pub fn bend_and_release(
    batch: &mut SwayBatch,
    sk: &Skeleton,
    load: [f32; 3],
    hold: usize,
    free: usize,
    dt: f32,
    each: &mut dyn FnMut(usize, [f32; 3], &SwayBatch),
) -> (Vec<f64>, Vec<f64>) {
    let tip = sk.joints()[sk.trunk_top()].tip();
    let (mut xs, mut ys) = (Vec::with_capacity(free), Vec::with_capacity(free));
    for k in 0..hold + free {
        let wind = if k < hold { load } else { [0.0; 3] };
        batch.step(dt, &[wind]);
        each(k, wind, batch);
        if k >= hold {
            let p = transform(&batch.palette(0, sk.trunk_top()), tip);
            xs.push((p[0] - tip[0]) as f64);
            ys.push((p[1] - tip[1]) as f64);
        }
    }
    (xs, ys)
}

/// Frequency (Hz) and damping ratio of a free decay sampled every `dt` seconds as the
/// horizontal displacements `xs`, `ys` of a point (the trunk top).
///
/// Frequency: the peak of the spectrum between 0.05 and 5 Hz after a slow trend is removed:
/// swaying branches load the trunk through their drag, and heavy hanging parts (a willow's
/// curtains) settle slowly, adding a drift that would otherwise outweigh the sway. The trend
/// is the best least-squares fit of `a + b·t` or `a + b·exp(−t/τ)` (τ from 1 to 64 s).
/// Damping: the logarithmic decrement δ over up to four periods of the detrended motion along
/// its main direction, ζ = δ/√(4π² + δ²); NaN when fewer than three peaks show.
pub fn free_decay(xs: &[f64], ys: &[f64], dt: f64) -> (f64, f64) {
    let n = xs.len() as f64;
    let detrend = |v: &[f64]| {
        // Fit v ≈ a + b·g(t) by least squares for a trend shape g; keep the best residual.
        let fit = |g: &dyn Fn(f64) -> f64| {
            let gs: Vec<f64> = (0..v.len()).map(|k| g(k as f64 * dt)).collect();
            let (gm, vm) = (gs.iter().sum::<f64>() / n, v.iter().sum::<f64>() / n);
            let sgg: f64 = gs.iter().map(|g| (g - gm).powi(2)).sum();
            let sgv: f64 = gs.iter().zip(v).map(|(g, x)| (g - gm) * (x - vm)).sum();
            let b = if sgg > 0.0 { sgv / sgg } else { 0.0 };
            let r: Vec<f64> = gs.iter().zip(v).map(|(g, x)| x - vm - b * (g - gm)).collect();
            (r.iter().map(|e| e * e).sum::<f64>(), r)
        };
        let mut best = fit(&|t| t);
        for k in 0..=12 {
            let tau = 2f64.powf(k as f64 / 2.0);
            let candidate = fit(&|t| (-t / tau).exp());
            if candidate.0 < best.0 {
                best = candidate;
            }
        }
        best.1
    };
    let (x, y) = (detrend(xs), detrend(ys));
    let power = |f: f64| {
        let w = 2.0 * std::f64::consts::PI * f * dt;
        let (mut a, mut b) = ([0.0; 2], [0.0; 2]);
        for k in 0..x.len() {
            let (s, c) = (w * k as f64).sin_cos();
            a = [a[0] + x[k] * c, a[1] + y[k] * c];
            b = [b[0] + x[k] * s, b[1] + y[k] * s];
        }
        a[0] * a[0] + a[1] * a[1] + b[0] * b[0] + b[1] * b[1]
    };
    let f = (0..=990)
        .map(|k| 0.05 + 0.005 * k as f64)
        .max_by(|a, b| power(*a).total_cmp(&power(*b)))
        .unwrap_or(0.0);
    let (sxx, syy) = (x.iter().map(|v| v * v).sum::<f64>(), y.iter().map(|v| v * v).sum::<f64>());
    let d = if sxx >= syy { x } else { y };
    let peaks: Vec<f64> = (1..d.len().saturating_sub(1))
        .filter(|&k| d[k] > d[k - 1] && d[k] >= d[k + 1] && d[k] > 0.0)
        .map(|k| d[k])
        .collect();
    let zeta = if peaks.len() >= 3 {
        let m = (peaks.len() - 1).min(4);
        let delta = (peaks[0] / peaks[m]).ln() / m as f64;
        delta / (4.0 * std::f64::consts::PI.powi(2) + delta * delta).sqrt()
    } else {
        f64::NAN
    };
    (f, zeta)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_damped_sine_gives_back_its_frequency_and_damping() {
        let (f0, zeta) = (0.5f64, 0.05f64);
        let w = 2.0 * std::f64::consts::PI * f0;
        let wd = w * (1.0 - zeta * zeta).sqrt();
        let dt = 0.02;
        let xs: Vec<f64> = (0..2000)
            .map(|k| k as f64 * dt)
            .map(|t| (-zeta * w * t).exp() * (wd * t).cos() + 0.01 * t)
            .collect();
        let ys = vec![0.0; xs.len()];
        let (f, z) = free_decay(&xs, &ys, dt);
        assert!((f - f0 * (1.0 - zeta * zeta).sqrt()).abs() < 0.01, "{f}");
        assert!((z / zeta - 1.0).abs() < 0.2, "{z}");
    }

    #[test]
    fn a_slow_settling_drift_does_not_hide_the_sway() {
        // A 0.9 Hz decay riding on a part settling with a 6 s time constant, larger than the
        // sway after its first seconds: the frequency is the sway's.
        let (f0, zeta) = (0.9f64, 0.08f64);
        let w = 2.0 * std::f64::consts::PI * f0;
        let dt = 0.04;
        let xs: Vec<f64> = (0..400)
            .map(|k| k as f64 * dt)
            .map(|t| 0.08 * (-zeta * w * t).exp() * (w * t).cos() + 0.05 * (-t / 6.0).exp())
            .collect();
        let ys = vec![0.0; xs.len()];
        let (f, _) = free_decay(&xs, &ys, dt);
        assert!((f - f0).abs() < 0.02, "{f} Hz");
    }
}
