//! The little linear algebra the filters need: symmetric 2x2 inverse and eigen-decomposition,
//! and for any small D a Cholesky factor, the SPD inverse (plain, or scaled to unit diagonal
//! for entries of very different sizes) and a matrix-vector product. Everything returns `None`
//! instead of NaN.

/// Inverse of a symmetric 2x2 matrix; `None` when it is singular or ill-conditioned.
pub fn inverse2(m: &[[f32; 2]; 2]) -> Option<[[f32; 2]; 2]> {
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let scale = libm::fabsf(m[0][0] * m[1][1]) + libm::fabsf(m[0][1] * m[1][0]);
    if !det.is_finite() || !(scale > 0.0) || libm::fabsf(det) <= 1e-6 * scale {
        return None;
    }
    let inv = [
        [m[1][1] / det, -m[0][1] / det],
        [-m[1][0] / det, m[0][0] / det],
    ];
    all_finite2(&inv).then_some(inv)
}

/// Solve a 2x2 system `m x = b`.
pub fn solve2(m: &[[f32; 2]; 2], b: &[f32; 2]) -> Option<[f32; 2]> {
    let inv = inverse2(m)?;
    let x = [
        inv[0][0] * b[0] + inv[0][1] * b[1],
        inv[1][0] * b[0] + inv[1][1] * b[1],
    ];
    (x[0].is_finite() && x[1].is_finite()).then_some(x)
}

/// Eigenvalues (descending) and the orientation of the major axis (radians from +x) of a
/// symmetric 2x2 matrix.
pub fn eigen2(m: &[[f32; 2]; 2]) -> Option<(f32, f32, f32)> {
    let a = m[0][0];
    let b = 0.5 * (m[0][1] + m[1][0]);
    let c = m[1][1];
    let half_trace = 0.5 * (a + c);
    // hypot(h, b) in f32 alone (libm's hypotf computes in f64, which the MCU emulates in
    // software): scaled by the larger so the squares cannot overflow.
    let h = 0.5 * (a - c);
    let (ah, ab) = (libm::fabsf(h), libm::fabsf(b));
    let big = if ah > ab { ah } else { ab };
    let radius = if big > 0.0 {
        let (x, y) = (h / big, b / big);
        big * libm::sqrtf(x * x + y * y)
    } else {
        0.0
    };
    let l1 = half_trace + radius;
    let l2 = half_trace - radius;
    let angle = 0.5 * crate::fastmath::atan2(2.0 * b, a - c);
    (l1.is_finite() && l2.is_finite() && angle.is_finite()).then_some((l1, l2, angle))
}

/// Lower Cholesky factor of a symmetric positive semi-definite matrix. Near-zero pivots are
/// clamped to zero (a degenerate direction gets no spread) rather than producing NaN.
pub fn cholesky<const D: usize>(m: &[[f32; D]; D]) -> Option<[[f32; D]; D]> {
    let mut l = [[0.0f32; D]; D];
    for i in 0..D {
        for j in 0..=i {
            let mut sum = 0.5 * (m[i][j] + m[j][i]);
            for k in 0..j {
                sum -= l[i][k] * l[j][k];
            }
            if i == j {
                l[i][i] = if sum > 0.0 { libm::sqrtf(sum) } else { 0.0 };
            } else if l[j][j] > 0.0 {
                l[i][j] = sum / l[j][j];
            }
        }
    }
    l.iter().flatten().all(|v| v.is_finite()).then_some(l)
}

/// Inverse of a symmetric positive definite matrix through its Cholesky factor; `None` when
/// the matrix is not positive definite (a zero or negative pivot) or the result is not finite.
pub fn inverse_spd<const D: usize>(m: &[[f32; D]; D]) -> Option<[[f32; D]; D]> {
    let l = cholesky(m)?;
    let max_pivot = (0..D).map(|i| l[i][i]).fold(0.0f32, f32::max);
    if (0..D).any(|i| !(l[i][i] > 1e-6 * max_pivot)) {
        return None;
    }
    // Solve L L^T X = I column by column.
    let mut inv = [[0.0f32; D]; D];
    for c in 0..D {
        let mut y = [0.0f32; D];
        for i in 0..D {
            let mut s = if i == c { 1.0 } else { 0.0 };
            for k in 0..i {
                s -= l[i][k] * y[k];
            }
            y[i] = s / l[i][i];
        }
        for i in (0..D).rev() {
            let mut s = y[i];
            for k in i + 1..D {
                s -= l[k][i] * inv[k][c];
            }
            inv[i][c] = s / l[i][i];
        }
    }
    inv.iter().flatten().all(|v| v.is_finite()).then_some(inv)
}

/// Inverse of a symmetric positive definite matrix scaled to unit diagonal first, so entries
/// of very different sizes (metres and radians) keep their digits. `None` if not SPD.
pub fn inverse_scaled<const D: usize>(m: &[[f32; D]; D]) -> Option<[[f32; D]; D]> {
    let mut d = [0.0f32; D];
    for i in 0..D {
        if !(m[i][i] > 0.0) || !m[i][i].is_finite() {
            return None;
        }
        d[i] = 1.0 / libm::sqrtf(m[i][i]);
    }
    let mut s = [[0.0f32; D]; D];
    for i in 0..D {
        for j in 0..D {
            s[i][j] = 0.5 * (m[i][j] + m[j][i]) * d[i] * d[j];
        }
    }
    let mut inv = inverse_spd(&s)?;
    for i in 0..D {
        for j in 0..D {
            inv[i][j] *= d[i] * d[j];
        }
    }
    inv.iter().flatten().all(|v| v.is_finite()).then_some(inv)
}

/// The largest eigenvalue of a symmetric positive semi-definite matrix, by power iteration
/// (the matrices here are 4 x 4 and well separated enough that 64 steps settle to f32).
pub fn largest_eigenvalue<const D: usize>(m: &[[f32; D]; D]) -> f32 {
    // A start no symmetry of the matrix makes orthogonal to its leading eigenvector.
    let mut v: [f32; D] = core::array::from_fn(|i| 1.0 + 0.37 * i as f32);
    let mut lambda = 0.0f32;
    for _ in 0..64 {
        let w = mat_vec(m, &v);
        let norm = libm::sqrtf(dot(&w, &w));
        if !(norm > 0.0) || !norm.is_finite() {
            return norm;
        }
        lambda = dot(&v, &w) / dot(&v, &v);
        v = w.map(|x| x / norm);
    }
    lambda
}

/// The dot product of two vectors, summed in index order.
pub fn dot<const D: usize>(a: &[f32; D], b: &[f32; D]) -> f32 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The product of a D x D matrix and a vector.
pub fn mat_vec<const D: usize>(m: &[[f32; D]; D], v: &[f32; D]) -> [f32; D] {
    core::array::from_fn(|i| (0..D).map(|j| m[i][j] * v[j]).sum())
}

fn all_finite2(m: &[[f32; 2]; 2]) -> bool {
    m.iter().flatten().all(|v| v.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_and_singular() {
        let m = [[4.0, 1.0], [1.0, 3.0]];
        let inv = inverse2(&m).unwrap();
        assert!((inv[0][0] - 3.0 / 11.0).abs() < 1e-6);
        assert!(inverse2(&[[1.0, 2.0], [2.0, 4.0]]).is_none());
        assert!(inverse2(&[[f32::NAN, 0.0], [0.0, 1.0]]).is_none());
    }

    #[test]
    fn eigen_of_rotated_ellipse() {
        let (l1, l2, a) = eigen2(&[[2.0, 1.0], [1.0, 2.0]]).unwrap();
        assert!((l1 - 3.0).abs() < 1e-6 && (l2 - 1.0).abs() < 1e-6);
        assert!((a - core::f32::consts::FRAC_PI_4).abs() < 1e-6);
    }

    #[test]
    fn spd_inverse() {
        let m = [[4.0, 2.0, 0.0], [2.0, 5.0, 1.0], [0.0, 1.0, 3.0]];
        let inv = inverse_spd(&m).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                let s: f32 = (0..3).map(|k| m[i][k] * inv[k][j]).sum();
                assert!((s - if i == j { 1.0 } else { 0.0 }).abs() < 1e-5);
            }
        }
        assert!(inverse_spd(&[[1.0, 0.0], [0.0, 0.0]]).is_none());
    }

    #[test]
    fn cholesky_reconstructs() {
        let m = [[4.0, 2.0, 0.0], [2.0, 5.0, 1.0], [0.0, 1.0, 3.0]];
        let l = cholesky(&m).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                let s: f32 = (0..3).map(|k| l[i][k] * l[j][k]).sum();
                assert!((s - m[i][j]).abs() < 1e-5);
            }
        }
    }
}
