//! Small dense linear-algebra helpers the estimators share.

use nalgebra::DMatrix;
use thiserror::Error;

/// The matrix is indefinite beyond round-off.
#[derive(Clone, Copy, Debug, PartialEq, Error)]
#[error("matrix is not positive semi-definite at pivot {pivot} ({value:.3e})")]
pub struct NotPositiveSemidefinite {
    /// Index of the failing pivot.
    pub pivot: usize,
    /// The pivot's value if it is negative; beside a zero pivot, the largest entry
    /// left in its column (a positive semi-definite matrix leaves none).
    pub value: f64,
}

/// Beside a zero pivot, entries of its column up to `ZERO_COLUMN · max(diag)` are
/// round-off: for a PSD matrix they are bounded by √(pivot · other pivot), and a
/// pivot counts as zero below `1e-12 · max(diag)`.
const ZERO_COLUMN: f64 = 1e-6;

/// The lower Cholesky factor `L` with `L Lᵀ = A` of a symmetric positive
/// *semi*-definite matrix.
///
/// A pivot at or below `1e-12 · max(diag)` is taken as zero and its column left
/// zero, so a singular covariance (the robot's at the start of a run, or a robot
/// that has not moved) still factors. A pivot clearly negative is an error, and so
/// is a zero pivot whose column still holds more than round-off (`[[0, 1], [1, 1]]`).
pub fn psd_cholesky(a: &DMatrix<f64>) -> Result<DMatrix<f64>, NotPositiveSemidefinite> {
    let n = a.nrows();
    let scale = (0..n)
        .map(|i| a[(i, i)].abs())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let tol = 1e-12 * scale;
    let mut l = DMatrix::<f64>::zeros(n, n);
    for j in 0..n {
        let mut d = a[(j, j)];
        for k in 0..j {
            d -= l[(j, k)] * l[(j, k)];
        }
        if !d.is_finite() || d < -1e-9 * scale {
            return Err(NotPositiveSemidefinite { pivot: j, value: d });
        }
        let ljj = if d <= tol { 0.0 } else { d.sqrt() };
        l[(j, j)] = ljj;
        for i in (j + 1)..n {
            let mut s = a[(i, j)];
            for k in 0..j {
                s -= l[(i, k)] * l[(j, k)];
            }
            if ljj > 0.0 {
                l[(i, j)] = s / ljj;
            } else if !(s.abs() <= ZERO_COLUMN * scale) {
                return Err(NotPositiveSemidefinite { pivot: j, value: s });
            }
        }
    }
    Ok(l)
}

/// `L_oa = P_oa L_aa⁻ᵀ`: the rows that extend the factor `L_aa` of `P_aa` to the
/// factor of the joint covariance `[[P_aa, P_oa]ᵀ, [P_oa, ·]]`, so that
/// `L_oa L_aaᵀ = P_oa`. A zero pivot of `L_aa` leaves its column zero; if `P_oa`
/// still has more than round-off there (relative to the largest of `P_aa`'s pivots
/// and `P_oa`'s entries), the joint covariance is not PSD.
pub fn psd_cross_factor(
    l_aa: &DMatrix<f64>,
    p_oa: &DMatrix<f64>,
) -> Result<DMatrix<f64>, NotPositiveSemidefinite> {
    let k = l_aa.ncols();
    let scale = (0..k)
        .map(|j| l_aa[(j, j)] * l_aa[(j, j)])
        .chain(p_oa.iter().map(|v| v.abs()))
        .fold(f64::MIN_POSITIVE, f64::max);
    let mut l_oa = DMatrix::<f64>::zeros(p_oa.nrows(), k);
    for j in 0..k {
        let mut col = p_oa.column(j).into_owned();
        for t in 0..j {
            col -= l_oa.column(t) * l_aa[(j, t)];
        }
        let pivot = l_aa[(j, j)];
        if pivot > 0.0 {
            l_oa.set_column(j, &(col / pivot));
        } else if let Some(worst) = col
            .iter()
            .copied()
            .find(|v| !(v.abs() <= ZERO_COLUMN * scale))
        {
            return Err(NotPositiveSemidefinite {
                pivot: j,
                value: worst,
            });
        }
    }
    Ok(l_oa)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn factors_definite_and_semidefinite_matrices() {
        let a = DMatrix::from_row_slice(3, 3, &[4.0, 2.0, 0.4, 2.0, 5.0, 1.0, 0.4, 1.0, 3.0]);
        let l = psd_cholesky(&a).unwrap_or_else(|e| panic!("{e}"));
        assert!((&l * l.transpose() - &a).norm() < 1e-12);
        // Rank 1: v vᵀ.
        let v = DMatrix::from_column_slice(3, 1, &[1.0, -2.0, 0.5]);
        let a = &v * v.transpose();
        let l = psd_cholesky(&a).unwrap_or_else(|e| panic!("{e}"));
        assert!((&l * l.transpose() - &a).norm() < 1e-12);
        // All zero.
        let z = psd_cholesky(&DMatrix::zeros(4, 4)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(z, DMatrix::zeros(4, 4));
    }

    #[test]
    fn rejects_indefinite_and_nan() {
        let a = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        assert!(psd_cholesky(&a).is_err());
        // A zero pivot beside a non-zero entry: eigenvalues (1 ± √5)/2, one negative.
        let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 1.0, 1.0]);
        assert_eq!(psd_cholesky(&a).map_err(|e| e.pivot), Err(0));
        // The same after a first, regular pivot.
        let a = DMatrix::from_row_slice(3, 3, &[4.0, 2.0, 0.0, 2.0, 1.0, 0.5, 0.0, 0.5, 1.0]);
        assert_eq!(psd_cholesky(&a).map_err(|e| e.pivot), Err(1));
        let a = DMatrix::from_row_slice(2, 2, &[f64::NAN, 0.0, 0.0, 1.0]);
        assert!(psd_cholesky(&a).is_err());
    }

    #[test]
    fn cross_factor_extends_the_factor_and_refuses_an_indefinite_joint() {
        let joint = DMatrix::from_row_slice(
            4,
            4,
            &[
                4.0, 2.0, 0.4, 1.0, //
                2.0, 5.0, 1.0, -0.5, //
                0.4, 1.0, 3.0, 0.2, //
                1.0, -0.5, 0.2, 2.0,
            ],
        );
        let p_aa = joint.view((0, 0), (2, 2)).into_owned();
        let p_oa = joint.view((2, 0), (2, 2)).into_owned();
        let l_aa = psd_cholesky(&p_aa).unwrap_or_else(|e| panic!("{e}"));
        let l_oa = psd_cross_factor(&l_aa, &p_oa).unwrap_or_else(|e| panic!("{e}"));
        assert!((&l_oa * l_aa.transpose() - &p_oa).norm() < 1e-12);
        // A zero-variance active state correlated with another: not a covariance.
        let l_aa = psd_cholesky(&DMatrix::from_row_slice(2, 2, &[0.0, 0.0, 0.0, 1.0]))
            .unwrap_or_else(|e| panic!("{e}"));
        let p_oa = DMatrix::from_row_slice(1, 2, &[0.3, 0.1]);
        assert_eq!(psd_cross_factor(&l_aa, &p_oa).map_err(|e| e.pivot), Err(0));
        // Zero beside the zero pivot is fine (a robot that has not moved yet).
        let p_oa = DMatrix::from_row_slice(1, 2, &[0.0, 0.1]);
        let l_oa = psd_cross_factor(&l_aa, &p_oa).unwrap_or_else(|e| panic!("{e}"));
        assert!((&l_oa * l_aa.transpose() - &p_oa).norm() < 1e-12);
    }
}
