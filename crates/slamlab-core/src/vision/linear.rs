//! Fixed-size linear algebra for the minimal solvers inside RANSAC's loop,
//! where a general-purpose decomposition per sample would cost more than the
//! rest of the sample together: the null space of the 8x9 (eight-point,
//! Eq. 4.21) or 5x9 (five-point, Eq. 4.24) constraint matrix by a Householder
//! QR factorization, and the right singular vector of the smallest singular
//! value of a 3x3 matrix (the rank-2 projection of F) in closed form. Nothing
//! here allocates.

use nalgebra::{Matrix3, Vector3};

/// The null space of an `R x 9` matrix `A` of rank R (its rows given), as
/// `K = 9 - R` orthonormal 9-vectors, and a rank measure: the smallest
/// `|r_kk|` of the QR factorization divided by the largest row norm of `A`
/// (0 for a rank-deficient A).
///
/// Householder QR of `Aᵀ` (Golub and Van Loan, Sec. 5.2): `Aᵀ = Q [R; 0]` with
/// Q an orthogonal 9x9 matrix. The first R columns of Q span the rows of A,
/// so the last K columns are orthogonal to every row: `A q = 0`. Q is the
/// product of R reflections `H_k = I - 2 v_k v_kᵀ / (v_kᵀ v_k)`, and its
/// column j is `H_0 H_1 ... H_{R-1} e_j`. Nistér (2004, Sec. 3.2) recommends
/// this QR in place of an SVD: it is exact for a minimal sample (A has a null
/// space of exactly K dimensions), where the SVD's ordering of singular values
/// buys nothing. About 600 multiplications for the eight-point sample.
pub(crate) fn null_space<const R: usize, const K: usize>(
    rows: &[[f64; 9]; R],
) -> ([[f64; 9]; K], f64) {
    const { assert!(R + K == 9) };
    // Columns of Aᵀ = rows of A; each step zeroes column k below the diagonal.
    let mut a = *rows;
    let mut reflections = [[0.0f64; 9]; R];
    let largest_row = rows
        .iter()
        .map(|r| r.iter().map(|v| v * v).sum::<f64>().sqrt())
        .fold(0.0f64, f64::max);
    let mut smallest_diagonal = f64::INFINITY;
    for k in 0..R {
        // v = x - alpha e_0 with alpha = -sign(x_0) ‖x‖ (no cancellation), so
        // that H x = alpha e_0. v is kept as a full 9-vector, zero above entry
        // k, and the loops run over all nine entries (fixed bounds the
        // compiler unrolls): the zeros add exact zeros in front of each sum
        // and subtract exact zeros from the entries above k, so the result has
        // the bits of loops over k..9.
        let mut v = [0.0f64; 9];
        for (i, slot) in v.iter_mut().enumerate() {
            if i >= k {
                *slot = a[k][i];
            }
        }
        let norm = dot9(&v, &v).sqrt();
        smallest_diagonal = smallest_diagonal.min(norm);
        if !(norm > 0.0) {
            // A zero column: nothing to reflect (A has rank below R).
            continue;
        }
        let alpha = if a[k][k] >= 0.0 { -norm } else { norm };
        v[k] -= alpha;
        let v_norm2 = dot9(&v, &v);
        if !(v_norm2 > 0.0) {
            continue;
        }
        // Apply H_k to the remaining columns of Aᵀ.
        for column in a.iter_mut().skip(k + 1) {
            let s = 2.0 * dot9(&v, column) / v_norm2;
            for (c, vi) in column.iter_mut().zip(&v) {
                *c -= s * vi;
            }
        }
        // Kept scaled so that H_k = I - v vᵀ.
        let scale = (2.0 / v_norm2).sqrt();
        for (r, vi) in reflections[k].iter_mut().zip(&v) {
            *r = vi * scale;
        }
    }
    let null = std::array::from_fn(|j| {
        // Column R + j of Q: H_0 (H_1 (... H_{R-1} e_{R+j})).
        let mut q = [0.0f64; 9];
        q[R + j] = 1.0;
        for v in reflections.iter().rev() {
            let dot = dot9(v, &q);
            for (qi, vi) in q.iter_mut().zip(v) {
                *qi -= dot * vi;
            }
        }
        q
    });
    let rank_measure = if largest_row > 0.0 && largest_row.is_finite() {
        smallest_diagonal / largest_row
    } else {
        0.0
    };
    (null, rank_measure)
}

/// `Σ aᵢ bᵢ` over nine entries, summed in order from the first (from +0.0:
/// a leading exact zero changes no bit of a sum).
#[inline(always)]
fn dot9(a: &[f64; 9], b: &[f64; 9]) -> f64 {
    let mut sum = 0.0;
    for i in 0..9 {
        sum += a[i] * b[i];
    }
    sum
}

/// The right singular vector `v` of the smallest singular value of a 3x3
/// matrix M, as the eigenvector of the smallest eigenvalue of `S = MᵀM`, both
/// in closed form; `None` when that eigenvalue is not separated from the next
/// (then any vector in a plane would do and the caller should use an SVD).
///
/// The eigenvalues of a symmetric 3x3 matrix are the roots of its
/// characteristic cubic, solved trigonometrically (Smith, "Eigenvalues of a
/// symmetric 3 × 3 matrix", 1961): with `q = tr S / 3`, `p² = ‖S - qI‖²_F / 6`
/// and `B = (S - qI) / p`, they are `q + 2p cos(φ + 2πk/3)` with
/// `φ = acos(det B / 2) / 3`; the smallest is k = 1. Its eigenvector is
/// orthogonal to every row of `S - λI` (rank 2), so it is the longest cross
/// product of two of those rows.
pub(crate) fn smallest_right_singular_vector3(m: &Matrix3<f64>) -> Option<Vector3<f64>> {
    let s = m.tr_mul(m);
    let q = s.trace() / 3.0;
    let off = s[(0, 1)] * s[(0, 1)] + s[(0, 2)] * s[(0, 2)] + s[(1, 2)] * s[(1, 2)];
    let d0 = s[(0, 0)] - q;
    let d1 = s[(1, 1)] - q;
    let d2 = s[(2, 2)] - q;
    let p = ((d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * off) / 6.0).sqrt();
    if !(p > 0.0 && p.is_finite()) {
        return None;
    }
    let b = (s - Matrix3::identity() * q) / p;
    let half_det = (b.determinant() / 2.0).clamp(-1.0, 1.0);
    let phi = crate::math::acos(half_det) / 3.0;
    let smallest = q + 2.0 * p * crate::math::cos(phi + 2.0 * std::f64::consts::FRAC_PI_3);
    let shifted = s - Matrix3::identity() * smallest;
    let (r0, r1, r2) = (
        shifted.row(0).transpose(),
        shifted.row(1).transpose(),
        shifted.row(2).transpose(),
    );
    let candidates = [r0.cross(&r1), r0.cross(&r2), r1.cross(&r2)];
    let (best, norm2) =
        candidates
            .iter()
            .map(|c| (c, c.norm_squared()))
            .fold(
                (&candidates[0], -1.0),
                |acc, c| if c.1 > acc.1 { c } else { acc },
            );
    // Rows of S - λI are of size ‖S‖; a cross product far below ‖S‖² means
    // S - λI has rank below 2 (two eigenvalues nearly equal).
    let scale2 = s.norm_squared();
    if !(norm2 > 1e-20 * scale2 * scale2) {
        return None;
    }
    Some(best / norm2.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::SMatrix;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn random_rows<const R: usize>(rng: &mut ChaCha8Rng) -> [[f64; 9]; R] {
        std::array::from_fn(|_| std::array::from_fn(|_| rng.random_range(-1.0..1.0)))
    }

    /// The SVD's null space of the same rows (zero-padded to 9x9).
    fn svd_null_space<const R: usize>(rows: &[[f64; 9]; R]) -> Vec<SMatrix<f64, 9, 1>> {
        let mut a = SMatrix::<f64, 9, 9>::zeros();
        for (i, row) in rows.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                a[(i, j)] = *v;
            }
        }
        let v_t = a.svd(false, true).v_t.expect("V requested");
        (R..9).map(|r| v_t.row(r).transpose()).collect()
    }

    #[test]
    fn householder_null_space_matches_the_svd_null_space() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..100 {
            // Eight rows: one null vector, equal to the SVD's up to sign.
            let rows: [[f64; 9]; 8] = random_rows(&mut rng);
            let ([q], rank) = null_space::<8, 1>(&rows);
            assert!(rank > 1e-6, "{rank}");
            let q = SMatrix::<f64, 9, 1>::from_row_slice(&q);
            let svd = svd_null_space(&rows)[0];
            assert!((q.norm() - 1.0).abs() < 1e-14);
            assert!((q - svd).amax().min((q + svd).amax()) < 1e-10);
            // Five rows: four orthonormal null vectors spanning the SVD's null
            // space (the projection of each SVD vector onto them keeps its length).
            let rows: [[f64; 9]; 5] = random_rows(&mut rng);
            let (basis, _) = null_space::<5, 4>(&rows);
            let basis: Vec<SMatrix<f64, 9, 1>> = basis
                .iter()
                .map(|q| SMatrix::<f64, 9, 1>::from_row_slice(q))
                .collect();
            for (i, a) in basis.iter().enumerate() {
                for (j, b) in basis.iter().enumerate() {
                    let expected = if i == j { 1.0 } else { 0.0 };
                    assert!((a.dot(b) - expected).abs() < 1e-13);
                }
                for row in &rows {
                    let dot: f64 = row.iter().zip(a.iter()).map(|(x, y)| x * y).sum();
                    assert!(dot.abs() < 1e-13, "{dot}");
                }
            }
            for v in svd_null_space(&rows) {
                let projected: f64 = basis.iter().map(|q| q.dot(&v).powi(2)).sum();
                assert!((projected - 1.0).abs() < 1e-12, "{projected}");
            }
        }
    }

    #[test]
    fn householder_null_space_reports_a_rank_deficient_matrix() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let mut rows: [[f64; 9]; 8] = random_rows(&mut rng);
        // Row 7 = row 0 + row 3: rank 7.
        rows[7] = std::array::from_fn(|j| rows[0][j] + rows[3][j]);
        let (_, rank) = null_space::<8, 1>(&rows);
        assert!(rank < 1e-12, "{rank}");
    }

    #[test]
    fn closed_form_singular_vector_matches_the_svd() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for _ in 0..200 {
            let m = Matrix3::from_fn(|_, _| rng.random_range(-1.0..1.0));
            let svd = m.svd(false, true);
            let v_t = svd.v_t.expect("V requested");
            let (smallest, _) = svd.singular_values.argmin();
            let expected = v_t.row(smallest).transpose();
            let v = smallest_right_singular_vector3(&m).expect("separated");
            assert!(
                (v - expected).amax().min((v + expected).amax()) < 1e-9,
                "{v} {expected}"
            );
        }
        // A nearly rank-2 matrix, as a refit F is: the vector is still found.
        let u = Matrix3::from_fn(|_, _| rng.random_range(-1.0..1.0));
        let m = u * Matrix3::from_diagonal(&Vector3::new(3.0, 1.0, 1e-9));
        let v = smallest_right_singular_vector3(&m).expect("separated");
        assert!((m * v).norm() < 1e-8 * m.norm());
        // A multiple of the identity has no distinguished vector.
        assert!(smallest_right_singular_vector3(&Matrix3::identity()).is_none());
    }
}
