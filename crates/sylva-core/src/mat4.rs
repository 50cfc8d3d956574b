//! Column-major 4×4 matrices (`m[column][row]`, as WGSL reads them): product and inverse.

/// A 4×4 matrix, column-major.
pub type Mat4 = [[f32; 4]; 4];

/// a · b.
pub fn mul(a: &Mat4, b: &Mat4) -> Mat4 {
    let mut m = [[0.0; 4]; 4];
    for c in 0..4 {
        for r in 0..4 {
            m[c][r] = (0..4).map(|k| a[k][r] * b[c][k]).sum();
        }
    }
    m
}

/// Inverse of a column-major 4×4 matrix (Gauss–Jordan with partial pivoting, in f64);
/// the identity for a singular one.
pub fn invert(m: &Mat4) -> Mat4 {
    // a[row][col], augmented with the identity.
    let mut a = [[0.0f64; 8]; 4];
    for r in 0..4 {
        for c in 0..4 {
            a[r][c] = m[c][r] as f64;
        }
        a[r][4 + r] = 1.0;
    }
    let mut out = [[0.0f32; 4]; 4];
    for col in 0..4 {
        let pivot =
            (col..4).max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs())).unwrap_or(col);
        if a[pivot][col].abs() < 1e-30 {
            for (i, row) in out.iter_mut().enumerate() {
                row[i] = 1.0;
            }
            return out;
        }
        a.swap(col, pivot);
        let p = a[col][col];
        for v in &mut a[col] {
            *v /= p;
        }
        for r in 0..4 {
            if r != col {
                let f = a[r][col];
                let pivot_row = a[col];
                for (v, pv) in a[r].iter_mut().zip(pivot_row) {
                    *v -= f * pv;
                }
            }
        }
    }
    for r in 0..4 {
        for c in 0..4 {
            out[c][r] = a[r][4 + c] as f32;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_times_matrix_is_identity() {
        // A perspective view-projection, the hardest case the renderer inverts.
        let m: Mat4 = [
            [1.2, 0.1, -0.3, -0.3],
            [0.05, 1.7, 0.2, 0.2],
            [0.3, -0.2, 1.001, 1.0],
            [2.0, -3.0, 18.5, 19.0],
        ];
        let p = mul(&invert(&m), &m);
        for c in 0..4 {
            for r in 0..4 {
                let want = if c == r { 1.0 } else { 0.0 };
                assert!((p[c][r] - want).abs() < 1e-4, "({c},{r}) = {}", p[c][r]);
            }
        }
        // A singular matrix gives the identity rather than infinities.
        assert_eq!(invert(&[[0.0; 4]; 4])[2], [0.0, 0.0, 1.0, 0.0]);
    }
}
