//! The scaled unscented transform (thesis `000` Sec. 2.2.4, Eq. 2.27-2.32).
//!
//! The transform here works on an *active* part of a larger Gaussian state: the
//! sigma points vary only the `k` active components (for SLAM: the robot and the
//! landmark being measured, or the robot and the control noise), and the
//! covariance between the output and every other state component follows from
//! the same sigma points through the factor `L_oa = P_oa L_aa⁻ᵀ`. For a Gaussian
//! state this equals running the transform on the whole state, at `O(n k²)` cost
//! instead of `O(n³)`.

use super::FilterError;
use crate::geometry::wrap_angle;
use crate::linalg::{psd_cholesky, psd_cross_factor};
use crate::math;
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// The scaling parameters `α`, `β`, `κ` of the unscented transform.
///
/// With `k` active dimensions, `λ = α²(k + κ) − k`, the sigma points are
/// `x̄ ± √(k + λ) L e_j`, and the weights are `W₀ᵐ = λ / (k + λ)`,
/// `W₀ᶜ = W₀ᵐ + 1 − α² + β`, `Wᵢ = 1 / (2 (k + λ))` (thesis Eq. 2.28).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct UnscentedParams {
    /// Spread of the sigma points (`0 < α ≤ 1`).
    pub alpha: f64,
    /// Prior knowledge of the distribution (2 is optimal for a Gaussian).
    pub beta: f64,
    /// Secondary scaling.
    pub kappa: f64,
}

impl Default for UnscentedParams {
    /// `α = 1`, `β = 2`, `κ = 0`: `λ = 0`, so every weight is non-negative and the
    /// sigma points sit at `±√k σ`. (The popular `α = 10⁻³` gives a large negative
    /// `W₀` that can make a covariance indefinite.)
    fn default() -> Self {
        Self {
            alpha: 1.0,
            beta: 2.0,
            kappa: 0.0,
        }
    }
}

/// The weights for `k` active dimensions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SigmaWeights {
    /// `λ`.
    pub lambda: f64,
    /// `√(k + λ)`, the sigma points' distance in units of the factor's columns.
    pub spread: f64,
    /// `W₀ᵐ`.
    pub mean0: f64,
    /// `W₀ᶜ`.
    pub cov0: f64,
    /// `Wᵢ`, `i = 1 … 2k`.
    pub other: f64,
}

impl UnscentedParams {
    /// The weights for `k` active dimensions, or an error when `k + λ ≤ 0`.
    pub fn weights(&self, k: usize) -> Result<SigmaWeights, FilterError> {
        for (name, value) in [
            ("ukf alpha", self.alpha),
            ("ukf beta", self.beta),
            ("ukf kappa", self.kappa),
        ] {
            if !value.is_finite() {
                return Err(FilterError::InvalidParameter { name, value });
            }
        }
        let k = k as f64;
        let lambda = self.alpha * self.alpha * (k + self.kappa) - k;
        if !(k + lambda > 1e-9) {
            return Err(FilterError::InvalidParameter {
                name: "ukf k + lambda = alpha^2 (k + kappa)",
                value: k + lambda,
            });
        }
        let mean0 = lambda / (k + lambda);
        Ok(SigmaWeights {
            lambda,
            spread: (k + lambda).sqrt(),
            mean0,
            cov0: mean0 + 1.0 - self.alpha * self.alpha + self.beta,
            other: 0.5 / (k + lambda),
        })
    }
}

/// The result of [`unscented_transform`].
#[derive(Clone, Debug, PartialEq)]
pub struct UnscentedOutput {
    /// The output mean `ȳ` (angle components by circular mean).
    pub mean: DVector<f64>,
    /// The output covariance `P_yy` (no noise added).
    pub covariance: DMatrix<f64>,
    /// The cross-covariance `P_ay` of the active components with the output (k x m).
    pub cross_active: DMatrix<f64>,
    /// The cross-covariance `P_oy` of the other components with the output.
    pub cross_other: DMatrix<f64>,
    /// The output of every sigma point, centre first.
    pub sigma_outputs: Vec<DVector<f64>>,
}

impl UnscentedOutput {
    /// True when the output mean and covariance are finite (a sigma point the
    /// model could not evaluate makes them NaN).
    pub fn is_finite(&self) -> bool {
        self.mean
            .iter()
            .chain(self.covariance.iter())
            .all(|v| v.is_finite())
    }
}

/// `y - mean` with the components listed in `angles` wrapped to (-π, π].
fn difference(y: &DVector<f64>, mean: &DVector<f64>, angles: &[usize]) -> DVector<f64> {
    let mut d = y - mean;
    for &i in angles {
        d[i] = wrap_angle(d[i]);
    }
    d
}

/// The sigma points of a `k`-dimensional Gaussian `(mean, L Lᵀ)`: centre first,
/// then `mean + spread L e_j` and `mean − spread L e_j` for `j = 0 … k−1`.
pub fn sigma_points(mean: &DVector<f64>, factor: &DMatrix<f64>, spread: f64) -> Vec<DVector<f64>> {
    let k = mean.len();
    let mut points = Vec::with_capacity(2 * k + 1);
    points.push(mean.clone());
    for j in 0..k {
        points.push(mean + factor.column(j) * spread);
        points.push(mean - factor.column(j) * spread);
    }
    points
}

/// Passes the Gaussian `N(mean_a, P_aa)` of the active components through `f`.
///
/// `p_oa` is the covariance of the other state components with the active ones
/// (`o x k`, possibly with zero rows). Output components whose indices are in
/// `angles` are averaged with the circular mean `atan2(Σ W sin, Σ W cos)` and
/// differenced with wrapping.
pub fn unscented_transform(
    params: &UnscentedParams,
    mean_a: &DVector<f64>,
    p_aa: &DMatrix<f64>,
    p_oa: &DMatrix<f64>,
    angles: &[usize],
    f: impl Fn(&DVector<f64>) -> DVector<f64>,
) -> Result<UnscentedOutput, FilterError> {
    let k = mean_a.len();
    let w = params.weights(k)?;
    let symmetric = 0.5 * (p_aa + p_aa.transpose());
    let l_aa = psd_cholesky(&symmetric).map_err(|_| FilterError::NotPositiveDefinite {
        what: "covariance for the sigma points",
    })?;
    // The other states follow the sigma points through their cross-covariance.
    let l_oa = psd_cross_factor(&l_aa, p_oa).map_err(|_| FilterError::NotPositiveDefinite {
        what: "covariance for the sigma points (cross terms beside a zero variance)",
    })?;

    let outputs: Vec<DVector<f64>> = sigma_points(mean_a, &l_aa, w.spread)
        .iter()
        .map(&f)
        .collect();
    let m = outputs.first().map_or(0, |y| y.len());
    let weight = |i: usize| if i == 0 { w.mean0 } else { w.other };
    let mut mean = DVector::<f64>::zeros(m);
    for (i, y) in outputs.iter().enumerate() {
        mean += y * weight(i);
    }
    for &a in angles {
        let (s, c) = outputs
            .iter()
            .enumerate()
            .fold((0.0, 0.0), |(s, c), (i, y)| {
                (
                    s + weight(i) * math::sin(y[a]),
                    c + weight(i) * math::cos(y[a]),
                )
            });
        mean[a] = math::atan2(s, c);
    }
    let deviations: Vec<DVector<f64>> = outputs
        .iter()
        .map(|y| difference(y, &mean, angles))
        .collect();
    let mut covariance = DMatrix::<f64>::zeros(m, m);
    for (i, d) in deviations.iter().enumerate() {
        let wc = if i == 0 { w.cov0 } else { w.other };
        covariance += d * d.transpose() * wc;
    }
    // Σ Wᵢ (χᵢ − x̄)(yᵢ − ȳ)ᵀ with χ±j − x̄ = ±spread L e_j.
    let mut cross_active = DMatrix::<f64>::zeros(k, m);
    let mut cross_other = DMatrix::<f64>::zeros(p_oa.nrows(), m);
    for j in 0..k {
        let dy =
            (&deviations[1 + 2 * j] - &deviations[2 + 2 * j]).transpose() * (w.other * w.spread);
        cross_active += l_aa.column(j) * &dy;
        cross_other += l_oa.column(j) * &dy;
    }
    Ok(UnscentedOutput {
        mean,
        covariance: 0.5 * (&covariance + covariance.transpose()),
        cross_active,
        cross_other,
        sigma_outputs: outputs,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gaussian(mean: &[f64], cov: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
        let k = mean.len();
        (
            DVector::from_column_slice(mean),
            DMatrix::from_row_slice(k, k, cov),
        )
    }

    #[test]
    fn exact_for_a_linear_map() {
        let (m, p) = gaussian(
            &[1.0, -2.0, 0.5],
            &[2.0, 0.3, 0.1, 0.3, 1.0, -0.2, 0.1, -0.2, 0.5],
        );
        let a = DMatrix::from_row_slice(2, 3, &[1.0, 2.0, -1.0, 0.5, 0.0, 3.0]);
        let b = DVector::from_column_slice(&[0.3, -0.7]);
        // Another component correlated with the active ones.
        let p_oa = DMatrix::from_row_slice(1, 3, &[0.2, -0.1, 0.05]);
        for params in [
            UnscentedParams::default(),
            UnscentedParams {
                alpha: 0.5,
                beta: 2.0,
                kappa: 1.0,
            },
        ] {
            let out = unscented_transform(&params, &m, &p, &p_oa, &[], |x| &a * x + &b)
                .unwrap_or_else(|e| panic!("{e}"));
            assert!((out.mean - (&a * &m + &b)).norm() < 1e-12);
            assert!((out.covariance - &a * &p * a.transpose()).norm() < 1e-12);
            assert!((out.cross_active - &p * a.transpose()).norm() < 1e-12);
            assert!((out.cross_other - &p_oa * a.transpose()).norm() < 1e-12);
        }
    }

    #[test]
    fn singular_input_covariance_still_transforms() {
        let (m, p) = gaussian(&[0.0, 0.0], &[0.0, 0.0, 0.0, 1.0]);
        let out = unscented_transform(
            &UnscentedParams::default(),
            &m,
            &p,
            &DMatrix::zeros(0, 2),
            &[],
            |x| x * 2.0,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert!(
            (out.covariance - DMatrix::from_row_slice(2, 2, &[0.0, 0.0, 0.0, 4.0])).norm() < 1e-12
        );
    }

    #[test]
    fn angles_average_on_the_circle() {
        // Sigma points straddle ±π: the arithmetic mean would be near 0.
        let (m, p) = gaussian(&[std::f64::consts::PI - 0.05], &[0.01]);
        let out = unscented_transform(
            &UnscentedParams::default(),
            &m,
            &p,
            &DMatrix::zeros(0, 1),
            &[0],
            |x| DVector::from_element(1, wrap_angle(x[0])),
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert!(
            wrap_angle(out.mean[0] - (std::f64::consts::PI - 0.05)).abs() < 1e-9,
            "{}",
            out.mean[0]
        );
        assert!((out.covariance[(0, 0)] - 0.01).abs() < 1e-9);
    }

    #[test]
    fn polar_to_cartesian_is_closer_to_monte_carlo_than_linearization() {
        use rand::SeedableRng;
        // A range-bearing measurement with a wide bearing spread: the classic banana.
        let (r, b, sr, sb) = (10.0, 0.3, 0.2, 0.35);
        let (m, p) = gaussian(&[r, b], &[sr * sr, 0.0, 0.0, sb * sb]);
        let polar = |x: &DVector<f64>| {
            DVector::from_column_slice(&[x[0] * math::cos(x[1]), x[0] * math::sin(x[1])])
        };
        let ut = unscented_transform(
            &UnscentedParams::default(),
            &m,
            &p,
            &DMatrix::zeros(0, 2),
            &[],
            polar,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        // Linearization: mean f(x̄), covariance J P Jᵀ.
        let j = DMatrix::from_row_slice(
            2,
            2,
            &[
                math::cos(b),
                -r * math::sin(b),
                math::sin(b),
                r * math::cos(b),
            ],
        );
        let lin_mean = polar(&m);
        let lin_cov = &j * &p * j.transpose();
        // 100k-sample Monte Carlo reference.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(42);
        let samples = 100_000;
        let mut mc_mean = DVector::<f64>::zeros(2);
        let mut pts = Vec::with_capacity(samples);
        for _ in 0..samples {
            let n1: f64 = crate::random::standard_normal(&mut rng);
            let n2: f64 = crate::random::standard_normal(&mut rng);
            let y = polar(&DVector::from_column_slice(&[r + sr * n1, b + sb * n2]));
            mc_mean += &y / samples as f64;
            pts.push(y);
        }
        let mut mc_cov = DMatrix::<f64>::zeros(2, 2);
        for y in &pts {
            let d = y - &mc_mean;
            mc_cov += &d * d.transpose() / (samples - 1) as f64;
        }
        let (ut_mean_err, lin_mean_err) =
            ((&ut.mean - &mc_mean).norm(), (&lin_mean - &mc_mean).norm());
        let (ut_cov_err, lin_cov_err) = (
            (&ut.covariance - &mc_cov).norm(),
            (&lin_cov - &mc_cov).norm(),
        );
        assert!(
            ut_mean_err < 0.5 * lin_mean_err,
            "mean: UT {ut_mean_err} vs linearized {lin_mean_err}"
        );
        assert!(
            ut_cov_err < 0.5 * lin_cov_err,
            "covariance: UT {ut_cov_err} vs linearized {lin_cov_err}"
        );
    }

    #[test]
    fn lambda_plus_k_must_be_positive() {
        let bad = UnscentedParams {
            alpha: 1.0,
            beta: 2.0,
            kappa: -3.0,
        };
        assert!(bad.weights(3).is_err());
        assert!(
            UnscentedParams {
                alpha: f64::NAN,
                ..Default::default()
            }
            .weights(3)
            .is_err()
        );
        let w = UnscentedParams::default()
            .weights(5)
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(
            (w.mean0 + 10.0 * w.other - 1.0).abs() < 1e-15,
            "mean weights sum to one"
        );
    }
}
