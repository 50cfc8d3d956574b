//! Helpers on `[f32; 3]`, the vector type of Sylva's public structs.

/// A 3-vector.
pub type V3 = [f32; 3];

/// a + b.
#[inline]
pub fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// a − b.
#[inline]
pub fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// s·a.
#[inline]
pub fn scale(a: V3, s: f32) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// a · b.
#[inline]
pub fn dot(a: V3, b: V3) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// a × b.
#[inline]
pub fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// |a|.
#[inline]
pub fn length(a: V3) -> f32 {
    dot(a, a).sqrt()
}

/// `a` scaled to unit length (a zero vector stays zero).
#[inline]
pub fn norm(a: V3) -> V3 {
    let n = length(a).max(1e-20);
    [a[0] / n, a[1] / n, a[2] / n]
}

/// Rotate `v` about the unit axis `k` by `angle` radians (Rodrigues).
#[inline]
pub fn rotate(v: V3, k: V3, angle: f32) -> V3 {
    let (s, c) = angle.sin_cos();
    add(add(scale(v, c), scale(cross(k, v), s)), scale(k, dot(k, v) * (1.0 - c)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cross_is_right_handed_and_rotation_keeps_length() {
        assert_eq!(cross([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]), [0.0, 0.0, 1.0]);
        assert_eq!(norm([0.0, 0.0, 0.0]), [0.0, 0.0, 0.0]);
        // A quarter turn about z takes x to y.
        let r = rotate([1.0, 0.0, 0.0], [0.0, 0.0, 1.0], std::f32::consts::FRAC_PI_2);
        assert!(length(sub(r, [0.0, 1.0, 0.0])) < 1e-6, "{r:?}");
        let v = [0.3, -1.2, 2.0];
        let r = rotate(v, norm([1.0, 2.0, 3.0]), 1.1);
        assert!((length(r) - length(v)).abs() < 1e-5);
    }
}
