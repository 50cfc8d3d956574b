//! Sway as glTF animation: rotation channels per joint with keys dropped within an error
//! bound, and leaf flutter as two morph targets driven by a `weights` channel.

use sylva_core::v3::{V3, scale};

use super::*;

pub(super) fn norm_of(v: V3) -> f64 {
    v.iter().map(|&x| x as f64 * x as f64).sum::<f64>().sqrt()
}

/// Angle between two rotations given as quaternions, rad: 2·atan2(|a − b|, |a + b|) after
/// normalising and taking b in a's hemisphere (accurate at small angles, where the acos of
/// a dot product loses everything below about 1e-3 rad to rounding).
pub(super) fn rotation_angle(a: [f64; 4], b: [f64; 4]) -> f64 {
    let unit = |q: [f64; 4]| {
        let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
        q.map(|v| v / n)
    };
    let (a, mut b) = (unit(a), unit(b));
    if (0..4).map(|i| a[i] * b[i]).sum::<f64>() < 0.0 {
        b = b.map(|v| -v);
    }
    let diff = (0..4).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt();
    let sum = (0..4).map(|i| (a[i] + b[i]).powi(2)).sum::<f64>().sqrt();
    2.0 * diff.atan2(sum)
}

/// Samples to keep as keys so that slerp between kept neighbours stays within `eps` rad of
/// every dropped sample (greedy, from the first sample; the last is always kept). `eps` ≤ 0
/// keeps all.
pub(super) fn reduce_keys(times: &[f32], q: &[[f64; 4]], eps: f64) -> Vec<usize> {
    let n = q.len();
    if eps <= 0.0 || n <= 2 {
        return (0..n).collect();
    }
    let fits = |a: usize, b: usize| {
        let span = (times[b] - times[a]) as f64;
        (a + 1..b).all(|k| {
            let u = (times[k] - times[a]) as f64 / span;
            rotation_angle(sylva_core::quat::slerp(q[a], q[b], u), q[k]) <= eps
        })
    };
    let mut keep = vec![0];
    let mut a = 0;
    while a + 1 < n {
        let mut b = a + 1;
        while b + 1 < n && fits(a, b + 1) {
            b += 1;
        }
        keep.push(b);
        a = b;
    }
    keep
}

/// Add the rotation channels of `anim` for the joints exported in `keep` (joint nodes from
/// `base`, skeleton joint → exported index in `index`) to `bin` and `channels`.
#[allow(clippy::too_many_arguments)]
pub(super) fn animate(
    anim: &JointAnimation,
    sk: &Skeleton,
    frames: &[[V3; 3]],
    keep: &[bool],
    base: usize,
    index: &[u16],
    bin: &mut Bin,
    channels: &mut Vec<Channel>,
) {
    let js = sk.joints();
    let samples = anim.times.len().min(anim.rotations.len());
    if samples == 0 {
        return;
    }
    let mut slot = vec![usize::MAX; js.len()];
    for (k, &j) in anim.joints.iter().enumerate() {
        if j < slot.len() {
            slot[j] = k;
        }
    }
    const IDENTITY: [f32; 9] = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    let rot = |s: usize, j: usize| -> [f32; 9] {
        anim.rotations[s].get(slot[j]).copied().unwrap_or(IDENTITY)
    };
    let apply = |r: &[f32; 9], v: V3| -> V3 {
        [
            r[0] * v[0] + r[1] * v[1] + r[2] * v[2],
            r[3] * v[0] + r[4] * v[1] + r[5] * v[2],
            r[6] * v[0] + r[7] * v[1] + r[8] * v[2],
        ]
    };
    let apply_t = |r: &[f32; 9], v: V3| -> V3 {
        [
            r[0] * v[0] + r[3] * v[1] + r[6] * v[2],
            r[1] * v[0] + r[4] * v[1] + r[7] * v[2],
            r[2] * v[0] + r[5] * v[1] + r[8] * v[2],
        ]
    };
    let times = &anim.times[..samples];
    let tol = anim.max_error.max(0.0) as f64;
    // Reach of each joint: an upper bound on the distance from its origin to any point it
    // carries (children before parents: joints come parents first).
    let mut reach = vec![0.0f64; js.len()];
    for j in (0..js.len()).rev() {
        let own = norm_of(sub(js[j].tip(), js[j].origin));
        reach[j] = reach[j].max(own);
        let p = js[j].parent;
        if p != NO_PARENT {
            let p = p as usize;
            let arm = norm_of(sub(js[j].origin, js[p].origin));
            reach[p] = reach[p].max(arm + reach[j]);
        }
    }
    let mut all_times: Option<usize> = None;
    let (t0, t1) = (times[0], times[samples - 1]);
    // Animated joints on the longest chain from the root: a point's error is at most the
    // sum over the animated joints above it of (angle error × reach), so an angle bound of
    // tol / (reach × chain) per joint bounds every point's error by tol.
    let mut depth = vec![0usize; js.len()];
    let mut chain = 1;
    for j in 0..js.len() {
        let p = js[j].parent;
        let above = if p == NO_PARENT { 0 } else { depth[p as usize] };
        depth[j] = above + (keep[j] && slot[j] != usize::MAX) as usize;
        chain = chain.max(depth[j]);
    }
    for j in (0..js.len()).filter(|&j| keep[j] && slot[j] != usize::MAX) {
        let f = &frames[j];
        let p = js[j].parent;
        let mut q: Vec<[f64; 4]> = Vec::with_capacity(samples);
        for s in 0..samples {
            let rj = rot(s, j);
            let cols: [V3; 3] = std::array::from_fn(|c| {
                let a = apply(&rj, f[c]);
                if p == NO_PARENT {
                    a
                } else {
                    let pf = &frames[p as usize];
                    to_local(pf, apply_t(&rot(s, p as usize), a))
                }
            });
            let mut k = quaternion(&cols).map(f64::from);
            // Neighbouring keys in one hemisphere, so interpolation takes the short way.
            if let Some(prev) = q.last()
                && (0..4).map(|i| prev[i] * k[i]).sum::<f64>() < 0.0
            {
                k = k.map(|v| -v);
            }
            q.push(k);
        }
        let kept = reduce_keys(times, &q, tol / (reach[j].max(1e-3) * chain as f64));
        let input = if kept.len() == samples {
            *all_times.get_or_insert_with(|| {
                let bytes: Vec<u8> = times.iter().flat_map(|v| v.to_le_bytes()).collect();
                bin.accessor(&bytes, None, FLOAT, samples, "SCALAR", Some((&[t0], &[t1])))
            })
        } else {
            let bytes: Vec<u8> = kept.iter().flat_map(|&k| times[k].to_le_bytes()).collect();
            bin.accessor(&bytes, None, FLOAT, kept.len(), "SCALAR", Some((&[t0], &[t1])))
        };
        let values: Vec<[f32; 4]> = kept.iter().map(|&k| q[k].map(|v| v as f32)).collect();
        let output = bin.accessor(&f32_bytes(&values), None, FLOAT, values.len(), "VEC4", None);
        channels.push(Channel { node: base + index[j] as usize, path: "rotation", input, output });
    }
}

/// Whether `anim` carries leaf flutter for every sample.
pub(super) fn has_flutter(anim: &JointAnimation) -> bool {
    let samples = anim.times.len().min(anim.rotations.len());
    samples > 0 && anim.flutter.len() >= samples
}

/// The `weights` channel of mesh node `node`: per sample the flutter targets' weights
/// (A·sin θ, A·cos θ), every sample kept (two floats each).
pub(super) fn flutter_channel(
    anim: &JointAnimation,
    node: usize,
    bin: &mut Bin,
    channels: &mut Vec<Channel>,
) {
    if !has_flutter(anim) {
        return;
    }
    let samples = anim.times.len().min(anim.rotations.len());
    let times = &anim.times[..samples];
    let bytes: Vec<u8> = times.iter().flat_map(|v| v.to_le_bytes()).collect();
    let range = (&[times[0]][..], &[times[samples - 1]][..]);
    let input = bin.accessor(&bytes, None, FLOAT, samples, "SCALAR", Some(range));
    let weights: Vec<[f32; 2]> = anim.flutter[..samples]
        .iter()
        .map(|&[a, theta]| {
            let (sn, cs) = theta.sin_cos();
            [a * sn, a * cs]
        })
        .collect();
    let output = bin.accessor(&f32_bytes(&weights), None, FLOAT, 2 * samples, "SCALAR", None);
    channels.push(Channel { node, path: "weights", input, output });
}

/// The two flutter targets of a leaf card's four corners (see [`FLUTTER_TARGETS`]), for
/// the corners of [`leaf_quad`].
pub fn flutter_displacements(c: &LeafCluster, corners: &[V3; 4]) -> [[V3; 4]; 2] {
    let o = sub(c.center, c.hang);
    let axis = cross(o, [0.0, 0.0, 1.0]);
    let k = if dot(axis, axis) < 1e-10 { [1.0, 0.0, 0.0] } else { norm(axis) };
    let (sn, cs) = c.phase.sin_cos();
    let swing = corners.map(|p| cross(k, sub(p, c.hang)));
    [swing.map(|d| scale(d, cs)), swing.map(|d| scale(d, sn))]
}
