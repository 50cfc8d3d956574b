//! Unit quaternions (x, y, z, w), the form glTF stores rotations in: from a rotation matrix
//! (Shepperd's method: the largest of the four candidate components is taken from the
//! diagonal, the others from off-diagonal sums, so no branch divides by a small number),
//! back to a matrix, and spherical interpolation the short way round (glTF's `LINEAR`
//! rotation channels). In f64: callers convert at the edges.

/// Unit quaternion of the rotation matrix whose element (row r, column c) is `m(r, c)`.
pub fn from_matrix(m: impl Fn(usize, usize) -> f64) -> [f64; 4] {
    let trace = m(0, 0) + m(1, 1) + m(2, 2);
    let q = if trace > 0.0 {
        let s = (trace + 1.0).sqrt() * 2.0;
        [(m(2, 1) - m(1, 2)) / s, (m(0, 2) - m(2, 0)) / s, (m(1, 0) - m(0, 1)) / s, 0.25 * s]
    } else if m(0, 0) > m(1, 1) && m(0, 0) > m(2, 2) {
        let s = (1.0 + m(0, 0) - m(1, 1) - m(2, 2)).sqrt() * 2.0;
        [0.25 * s, (m(0, 1) + m(1, 0)) / s, (m(0, 2) + m(2, 0)) / s, (m(2, 1) - m(1, 2)) / s]
    } else if m(1, 1) > m(2, 2) {
        let s = (1.0 + m(1, 1) - m(0, 0) - m(2, 2)).sqrt() * 2.0;
        [(m(0, 1) + m(1, 0)) / s, 0.25 * s, (m(1, 2) + m(2, 1)) / s, (m(0, 2) - m(2, 0)) / s]
    } else {
        let s = (1.0 + m(2, 2) - m(0, 0) - m(1, 1)).sqrt() * 2.0;
        [(m(0, 2) + m(2, 0)) / s, (m(1, 2) + m(2, 1)) / s, 0.25 * s, (m(1, 0) - m(0, 1)) / s]
    };
    normalize(q)
}

/// The rotation matrix of unit quaternion `q`, row-major.
pub fn to_rows(q: [f64; 4]) -> [[f64; 3]; 3] {
    let [x, y, z, w] = q;
    [
        [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)],
        [2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)],
        [2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)],
    ]
}

/// Spherical interpolation from `a` (u = 0) to `b` (u = 1), the short way round; linear
/// (then normalised) where the two are within about 0.1° of each other.
pub fn slerp(a: [f64; 4], b: [f64; 4], u: f64) -> [f64; 4] {
    let mut d: f64 = (0..4).map(|i| a[i] * b[i]).sum();
    let b = if d < 0.0 {
        d = -d;
        b.map(|v| -v)
    } else {
        b
    };
    let (wa, wb) = if d > 0.999_999 {
        (1.0 - u, u)
    } else {
        let th = d.min(1.0).acos();
        let s = th.sin();
        (((1.0 - u) * th).sin() / s, (u * th).sin() / s)
    };
    normalize(std::array::from_fn(|i| wa * a[i] + wb * b[i]))
}

fn normalize(q: [f64; 4]) -> [f64; 4] {
    let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    q.map(|v| v / n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matrix_round_trip_and_halfway_slerp() {
        // 90° about z: x → y.
        let q = from_matrix(|r, c| [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]][r][c]);
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!((q[2] - h).abs() < 1e-12 && (q[3] - h).abs() < 1e-12, "{q:?}");
        let m = to_rows(q);
        assert!((m[1][0] - 1.0).abs() < 1e-12 && m[0][0].abs() < 1e-12);
        // Halfway between identity and 90° about z is 45° about z.
        let s = slerp([0.0, 0.0, 0.0, 1.0], q, 0.5);
        let a = std::f64::consts::FRAC_PI_8;
        assert!((s[2] - a.sin()).abs() < 1e-12 && (s[3] - a.cos()).abs() < 1e-12, "{s:?}");
        // The short way: −q is the same rotation.
        assert!((slerp([0.0, 0.0, 0.0, 1.0], q.map(|v| -v), 0.5)[2] - a.sin()).abs() < 1e-12);
    }
}
