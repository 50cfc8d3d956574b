//! Joint rotations: Rodrigues' formula with series for small angles, the lever's bend,
//! and the 3×4 palettes composed down the skeleton.

use std::f32::consts::PI;

use sylva_core::v3::dot;

use super::Palette;

/// Rotation matrix of the rotation vector φ (axis × angle), Rodrigues' formula. Small
/// angles use Taylor series of sin a/a and (1 − cos a)/a² (error < 1e-9 below 0.5 rad).
#[cfg(test)]
pub(super) fn rotation(phi: [f32; 3]) -> [[f32; 3]; 3] {
    let (s, c) = sin_cos_ratios(dot(phi, phi));
    rodrigues(phi, s, c)
}

/// (sin a / a, (1 − cos a) / a²) from a², by series below a = 0.5 rad.
pub(super) fn sin_cos_ratios(a2: f32) -> (f32, f32) {
    if a2 < 0.25 { small_angle(a2) } else { large_angle(a2) }
}

/// A joint's palette for the rotation vector `phi` about its rest position `o` (one joint
/// at a time, off the step's lanes: `CrownLean`'s settled crowns).
pub(crate) fn joint_palette(phi: [f32; 3], o: [f32; 3]) -> Palette {
    let (s, c) = sin_cos_ratios(dot(phi, phi));
    local_palette(phi, o, s, c)
}

/// Below this e² (e = 0.1 rad) `lever_bend`'s factor is taken from its series, 1 − e²/2.
pub(super) const LEVER_SERIES: f32 = 0.01;

/// The bend at which a joint's spring balances the drag's moment on the bent joint, as a
/// factor of the linear equilibrium bend `e` (moment over stiffness), from `e2` = e².
///
/// The loads are summed on the rest pose. As a joint turns by θ into the flow, its load's
/// lever arm shortens as cos θ (a segment across a fixed force), so it settles where
/// θ = e cos θ: θ ≈ e for small loads, 0.74 rad at e = 1, 1.17 at e = 3, and never past a
/// quarter turn however strong the wind — where a linear spring would fold the twig over.
/// Solved by one Newton step from e / √(1 + (2e/π)²) (within 0.6 % of the root for every
/// e), with short polynomials for cos and sin on [0, π/2] so the lane loop vectorises.
#[inline(always)]
pub(crate) fn lever_bend(e2: f32) -> f32 {
    // Floored so that no load divides by zero (the factor tends to 1 there).
    let e = e2.sqrt().max(1e-6);
    let t = e / (1.0 + e2 * (4.0 / (PI * PI))).sqrt();
    let t2 = t * t;
    let c = 1.0 + t2 * (-0.5 + t2 * (1.0 / 24.0 + t2 * (-1.0 / 720.0)));
    let s = t * (1.0 + t2 * (-1.0 / 6.0 + t2 * (1.0 / 120.0 + t2 * (-1.0 / 5040.0))));
    let root = t - (t - e * c) / (1.0 + e * s);
    root / e
}

/// Per lane, [`lever_bend`]'s factor from e², or its series 1 − e²/2 below [`LEVER_SERIES`]:
/// the Newton step is taken only where some lane is above it, and each lane's factor is the
/// same whichever way its neighbours go.
#[inline(always)]
pub(super) fn lever_factors<const N: usize>(e2: &[f32; N]) -> [f32; N] {
    let heavy = e2.iter().fold(false, |h, &x| h | (x > LEVER_SERIES));
    let mut f = [0.0f32; N];
    for l in 0..N {
        f[l] = 1.0 - 0.5 * e2[l];
    }
    if heavy {
        for l in 0..N {
            let full = lever_bend(e2[l]);
            f[l] = if e2[l] > LEVER_SERIES { full } else { f[l] };
        }
    }
    f
}

/// (sin a / a, (1 − cos a) / a²) from a² by Taylor series, for a² < 0.25.
#[inline(always)]
pub(super) fn small_angle(a2: f32) -> (f32, f32) {
    (
        1.0 - a2 / 6.0 * (1.0 - a2 / 20.0 * (1.0 - a2 / 42.0 * (1.0 - a2 / 72.0))),
        0.5 * (1.0 - a2 / 12.0 * (1.0 - a2 / 30.0 * (1.0 - a2 / 56.0 * (1.0 - a2 / 90.0)))),
    )
}

pub(super) fn large_angle(a2: f32) -> (f32, f32) {
    let a = a2.sqrt();
    (a.sin() / a, (1.0 - a.cos()) / a2)
}

/// (sin a / a, (1 − cos a) / a²) from a² for any angle, branch-free so it vectorises: the
/// angle is reduced to r ∈ [−π, π] (same sine and cosine), the Taylor series is taken at
/// r/8 and doubled three times (sin 2h / 2h = (sin h / h) cos h; (1 − cos 2h) / (2h)² =
/// (sin h / h)² / 2; cos h = 1 − h² (1 − cos h)/h²), then rescaled by r/a. Absolute error
/// below 3e-7 (against f64).
#[inline(always)]
pub(super) fn any_angle(a2: f32) -> (f32, f32) {
    let a = a2.sqrt();
    let r = a - std::f32::consts::TAU * (a / std::f32::consts::TAU).round();
    let ratio = if a > 0.0 { r / a } else { 1.0 };
    let mut h2 = r * r / 64.0;
    let (mut s, mut v) = small_angle(h2);
    for _ in 0..3 {
        let c = 1.0 - h2 * v;
        v = 0.5 * s * s;
        s *= c;
        h2 *= 4.0;
    }
    (s * ratio, v * ratio * ratio)
}

#[inline(always)]
pub(super) fn rodrigues(phi: [f32; 3], s: f32, c: f32) -> [[f32; 3]; 3] {
    let [x, y, z] = phi;
    [
        [1.0 - c * (y * y + z * z), c * x * y - s * z, c * x * z + s * y],
        [c * x * y + s * z, 1.0 - c * (x * x + z * z), c * y * z - s * x],
        [c * x * z - s * y, c * y * z + s * x, 1.0 - c * (x * x + y * y)],
    ]
}

/// Joint palettes of all lanes from their rotation vectors φ, the rest position `o` of the
/// joint and the parent's palettes.
#[cfg(not(feature = "glam"))]
#[inline(always)]
pub(super) fn palette_lanes<const W: usize>(
    phi: &[[f32; W]; 3],
    o: [f32; 3],
    parent: Option<&[[f32; W]; 12]>,
    out: &mut [[f32; W]; 12],
    sc: impl Fn(f32) -> (f32, f32),
) {
    for l in 0..W {
        let ph = [phi[0][l], phi[1][l], phi[2][l]];
        let (s, c) = sc(dot(ph, ph));
        let local = local_palette(ph, o, s, c);
        let m = match parent {
            None => local,
            Some(pm) => compose(&std::array::from_fn(|e| pm[e][l]), &local),
        };
        for e in 0..12 {
            out[e][l] = m[e];
        }
    }
}

/// A joint's rotation about its rest position `o`, T(o) R T(−o), for the rotation vector
/// `ph` with (sin a / a, (1 − cos a) / a²) = (`s`, `c`).
#[inline(always)]
pub(super) fn local_palette(ph: [f32; 3], o: [f32; 3], s: f32, c: f32) -> Palette {
    let r = rodrigues(ph, s, c);
    let t = [
        o[0] - (r[0][0] * o[0] + r[0][1] * o[1] + r[0][2] * o[2]),
        o[1] - (r[1][0] * o[0] + r[1][1] * o[1] + r[1][2] * o[2]),
        o[2] - (r[2][0] * o[0] + r[2][1] * o[1] + r[2][2] * o[2]),
    ];
    [
        r[0][0], r[0][1], r[0][2], t[0], r[1][0], r[1][1], r[1][2], t[1], r[2][0], r[2][1],
        r[2][2], t[2],
    ]
}

/// The same palettes through glam's `Affine3A` (the comparison behind the choice of a small
/// math module over glam: `cargo run --release -p sylva --features sylva-sway/glam -- bench
/// sway`; docs/decisions/0011-vectors-and-simd.md). Same rotation formula; glam builds, composes and
/// stores the matrices, one lane at a time as its types require.
#[cfg(feature = "glam")]
#[inline(always)]
pub(super) fn palette_lanes<const W: usize>(
    phi: &[[f32; W]; 3],
    o: [f32; 3],
    parent: Option<&[[f32; W]; 12]>,
    out: &mut [[f32; W]; 12],
    sc: impl Fn(f32) -> (f32, f32),
) {
    use glam::{Affine3A, Mat3A, Vec3A};
    let origin = Vec3A::from(o);
    let affine = |m: [f32; 12]| Affine3A {
        matrix3: Mat3A::from_cols_array(&[m[0], m[4], m[8], m[1], m[5], m[9], m[2], m[6], m[10]]),
        translation: Vec3A::new(m[3], m[7], m[11]),
    };
    for l in 0..W {
        let ph = Vec3A::new(phi[0][l], phi[1][l], phi[2][l]);
        let (s, c) = sc(ph.length_squared());
        let r = rodrigues(ph.to_array(), s, c);
        let rot = Mat3A::from_cols_array_2d(&r).transpose();
        let local = Affine3A { matrix3: rot, translation: origin - rot * origin };
        let m = match parent {
            None => local,
            Some(pm) => affine(std::array::from_fn(|e| pm[e][l])) * local,
        };
        let (x, y, z, w) = (m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis, m.translation);
        let rows = [x.x, y.x, z.x, w.x, x.y, y.y, z.y, w.y, x.z, y.z, z.z, w.z];
        for e in 0..12 {
            out[e][l] = rows[e];
        }
    }
}

/// a · b for 3×4 affine matrices.
pub(crate) fn compose(a: &Palette, b: &Palette) -> Palette {
    let mut o = [0.0; 12];
    for r in 0..3 {
        for c in 0..4 {
            let mut v = a[r * 4] * b[c] + a[r * 4 + 1] * b[4 + c] + a[r * 4 + 2] * b[8 + c];
            if c == 3 {
                v += a[r * 4 + 3];
            }
            o[r * 4 + c] = v;
        }
    }
    o
}

/// The rotation part of a palette, row-major 3×3.
pub fn rotation_of(p: &Palette) -> [f32; 9] {
    [p[0], p[1], p[2], p[4], p[5], p[6], p[8], p[9], p[10]]
}

/// Apply a palette to a rest-pose point.
pub fn transform(p: &Palette, x: [f32; 3]) -> [f32; 3] {
    [
        p[0] * x[0] + p[1] * x[1] + p[2] * x[2] + p[3],
        p[4] * x[0] + p[5] * x[1] + p[6] * x[2] + p[7],
        p[8] * x[0] + p[9] * x[1] + p[10] * x[2] + p[11],
    ]
}
