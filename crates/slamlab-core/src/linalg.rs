//! Small dense linear-algebra helpers the estimators share.

use nalgebra::DMatrix;
use thiserror::Error;

/// The matrix is indefinite beyond round-off.
#[derive(Clone, Copy, Debug, PartialEq, Error)]
#[error("matrix is not positive semi-definite (pivot {pivot} is {value:.3e})")]
pub struct NotPositiveSemidefinite {
    /// Index of the failing pivot.
    pub pivot: usize,
    /// Its value.
    pub value: f64,
}

/// The lower Cholesky factor `L` with `L Lᵀ = A` of a symmetric positive
/// *semi*-definite matrix.
///
/// A pivot at or below `1e-12 · max(diag)` is taken as zero and its column left
/// zero, so a singular covariance (the robot's at the start of a run, or a robot
/// that has not moved) still factors. A pivot clearly negative is an error.
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
        if d <= tol {
            continue;
        }
        let ljj = d.sqrt();
        l[(j, j)] = ljj;
        for i in (j + 1)..n {
            let mut s = a[(i, j)];
            for k in 0..j {
                s -= l[(i, k)] * l[(j, k)];
            }
            l[(i, j)] = s / ljj;
        }
    }
    Ok(l)
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
        let a = DMatrix::from_row_slice(2, 2, &[f64::NAN, 0.0, 0.0, 1.0]);
        assert!(psd_cholesky(&a).is_err());
    }
}
