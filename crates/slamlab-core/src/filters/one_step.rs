//! One Gaussian through one nonlinear function, three ways (thesis `000` Sec.
//! 2.2): linearization at the mean (the EKF's step, Eq. 2.23-2.25), the
//! unscented transform (the UKF's step, Eq. 2.26-2.28) and samples (the particle
//! filter's step, Sec. 2.3). Each method gives a Gaussian; [`compare`] measures
//! how far it is from a reference (the moments of many samples).
//!
//! Every function maps the plane to the plane, so the prior is a 2-D Gaussian
//! the student can drag and the output can be drawn beside it.

use crate::kalman::unscented::{SigmaWeights, UnscentedParams, sigma_points, unscented_transform};
use crate::math;
use crate::motion::{Control, MotionModel};
use crate::random::standard_normal;
use crate::range_bearing;
use crate::{Pose2, geometry::CHI2_2DOF_95};
use nalgebra::{DMatrix, DVector, Matrix2, Vector2};
use rand::Rng;
use serde::{Deserialize, Serialize};

/// Why a step could not be taken. The caller keeps its last valid result.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum OneStepError {
    /// The prior has a NaN or infinite entry.
    #[error("the prior belief has a NaN or infinite entry")]
    NotFinite,
    /// The prior covariance is singular or not positive definite.
    #[error(
        "the prior covariance is not positive definite (variances {var_x:.3e} and {var_y:.3e}, \
         determinant {determinant:.3e}): keep both standard deviations above zero and the \
         correlation inside (-1, 1)"
    )]
    NotPositiveDefinite {
        /// First variance.
        var_x: f64,
        /// Second variance.
        var_y: f64,
        /// Determinant.
        determinant: f64,
    },
    /// The unscented parameters give `α²(n + κ) ≤ 0` or are not finite.
    #[error("unscented transform: {0}")]
    Unscented(String),
    /// Too few samples or particles for a covariance.
    #[error("{count} {what}: at least 2 are needed for a mean and a covariance")]
    TooFewSamples {
        /// "samples" or "particles".
        what: &'static str,
        /// The count asked for.
        count: usize,
    },
    /// Some samples overflowed or could not be evaluated.
    #[error(
        "{bad} of {count} {what} gave NaN or infinite values through {function} \
         (the function overflows there)"
    )]
    SamplesOverflow {
        /// "samples" or "particles".
        what: &'static str,
        /// How many were bad.
        bad: usize,
        /// How many were drawn.
        count: usize,
        /// The function's name.
        function: &'static str,
    },
    /// The function or its Jacobian cannot be evaluated at the mean.
    #[error("{0}")]
    AtMean(String),
    /// A result has a NaN or infinite entry.
    #[error("the {0} is NaN or infinite (the function overflows)")]
    NonFiniteResult(&'static str),
}

/// A Gaussian in the plane: mean and 2x2 covariance.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Gaussian2 {
    /// Mean.
    pub mean: Vector2<f64>,
    /// Covariance (symmetric).
    pub covariance: Matrix2<f64>,
}

impl Gaussian2 {
    /// The Gaussian with `mean` and `covariance` (symmetrized).
    pub fn new(mean: Vector2<f64>, covariance: Matrix2<f64>) -> Self {
        Self {
            mean,
            covariance: 0.5 * (covariance + covariance.transpose()),
        }
    }

    /// The Gaussian with standard deviations `std` and correlation coefficient `rho`.
    pub fn from_std(mean: [f64; 2], std: [f64; 2], rho: f64) -> Self {
        let c = rho * std[0] * std[1];
        Self::new(
            Vector2::new(mean[0], mean[1]),
            Matrix2::new(std[0] * std[0], c, c, std[1] * std[1]),
        )
    }

    /// True when every entry is finite.
    pub fn is_finite(&self) -> bool {
        self.mean
            .iter()
            .chain(self.covariance.iter())
            .all(|v| v.is_finite())
    }

    /// The lower Cholesky factor `L` with `L Lᵀ = Σ`, or why there is none.
    ///
    /// A determinant below `10⁻¹²` of the variances' product (a correlation
    /// within about `5·10⁻¹³` of ±1) counts as singular.
    pub fn factor(&self) -> Result<Matrix2<f64>, OneStepError> {
        if !self.is_finite() {
            return Err(OneStepError::NotFinite);
        }
        let (a, b, d) = (
            self.covariance[(0, 0)],
            self.covariance[(0, 1)],
            self.covariance[(1, 1)],
        );
        let determinant = a * d - b * b;
        if !(a > 0.0 && d > 0.0 && determinant > 1e-12 * a * d) {
            return Err(OneStepError::NotPositiveDefinite {
                var_x: a,
                var_y: d,
                determinant,
            });
        }
        let l11 = a.sqrt();
        let l21 = b / l11;
        let l22 = (d - l21 * l21).sqrt();
        Ok(Matrix2::new(l11, 0.0, l21, l22))
    }

    /// `KL(reference ‖ self)`, the information lost when `self` stands for
    /// `reference`: `½ [tr(Σ⁻¹Σ_r) + (μ − μ_r)ᵀ Σ⁻¹ (μ − μ_r) − 2 + ln(det Σ / det Σ_r)]`.
    /// `None` when either covariance is not positive definite.
    pub fn kl_from(&self, reference: &Gaussian2) -> Option<f64> {
        self.factor().ok()?;
        reference.factor().ok()?;
        let inverse = self.covariance.try_inverse()?;
        let d = self.mean - reference.mean;
        let value = 0.5
            * ((inverse * reference.covariance).trace() + (d.transpose() * inverse * d)[(0, 0)]
                - 2.0
                + math::ln(self.covariance.determinant() / reference.covariance.determinant()));
        value.is_finite().then_some(value.max(0.0))
    }

    /// The 95% ellipse (chi-square, 2 dof).
    pub fn ellipse_95(&self) -> crate::CovarianceEllipse {
        crate::CovarianceEllipse::from_covariance(self.mean, &self.covariance, CHI2_2DOF_95)
    }
}

/// The nonlinear function a belief is pushed through. Each maps the plane to the
/// plane.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StepFunction {
    /// Polar to Cartesian: `(r, b) ↦ (r cos b, r sin b)`, the classic banana.
    Polar,
    /// A landmark at `(x, y)` in the robot's frame to its range and bearing:
    /// `(x, y) ↦ (√(x² + y²), atan2(y, x))` (thesis `000` Eq. 3.37 with the
    /// robot at the origin).
    RangeBearing,
    /// The robot's control `(v, w)` to its position after `dt` seconds along the
    /// exact arc from the origin, heading 0 (thesis `000` Eq. 2.70).
    Motion {
        /// Time step, s.
        dt: f64,
    },
    /// `y = A x + b`.
    Linear {
        /// `A`.
        a: Matrix2<f64>,
        /// `b`.
        b: Vector2<f64>,
    },
    /// `y = (x₁, x₂ + c x₁²)`.
    Quadratic {
        /// `c`.
        c: f64,
    },
    /// `y = (x₁, e^(c x₂))`; overflows for large `c x₂`.
    Exponential {
        /// `c`.
        c: f64,
    },
}

impl StepFunction {
    /// The function's name in URLs and the CLI.
    pub fn name(&self) -> &'static str {
        match self {
            StepFunction::Polar => "polar",
            StepFunction::RangeBearing => "range-bearing",
            StepFunction::Motion { .. } => "motion",
            StepFunction::Linear { .. } => "linear",
            StepFunction::Quadratic { .. } => "quadratic",
            StepFunction::Exponential { .. } => "exp",
        }
    }

    /// The formula, for the screen.
    pub fn formula(&self) -> String {
        match self {
            StepFunction::Polar => "(x, y) = (r cos b, r sin b)".to_owned(),
            StepFunction::RangeBearing => "(range, bearing) = (√(x² + y²), atan2(y, x))".to_owned(),
            StepFunction::Motion { dt } => format!(
                "(x, y) after {dt} s along the arc: ((v/w) sin(w Δt), (v/w)(1 − cos(w Δt)))"
            ),
            StepFunction::Linear { a, b } => format!(
                "y = [[{}, {}], [{}, {}]] x + ({}, {})",
                a[(0, 0)],
                a[(0, 1)],
                a[(1, 0)],
                a[(1, 1)],
                b[0],
                b[1]
            ),
            StepFunction::Quadratic { c } => format!("y = (x₁, x₂ + {c} x₁²)"),
            StepFunction::Exponential { c } => format!("y = (x₁, exp({c} x₂))"),
        }
    }

    /// Names and units of the input's two components.
    pub fn input_axes(&self) -> [&'static str; 2] {
        match self {
            StepFunction::Polar => ["range r (m)", "bearing b (rad)"],
            StepFunction::RangeBearing => ["x (m)", "y (m)"],
            StepFunction::Motion { .. } => ["speed v (m/s)", "turn rate w (rad/s)"],
            _ => ["x₁", "x₂"],
        }
    }

    /// Names and units of the output's two components.
    pub fn output_axes(&self) -> [&'static str; 2] {
        match self {
            StepFunction::Polar | StepFunction::Motion { .. } => ["x (m)", "y (m)"],
            StepFunction::RangeBearing => ["range (m)", "bearing (rad)"],
            _ => ["y₁", "y₂"],
        }
    }

    /// `f(x)`. NaN or infinite where the function overflows.
    pub fn eval(&self, x: &Vector2<f64>) -> Vector2<f64> {
        match *self {
            StepFunction::Polar => {
                let (s, c) = math::sin_cos(x[1]);
                Vector2::new(x[0] * c, x[0] * s)
            }
            StepFunction::RangeBearing => {
                Vector2::new(math::hypot(x[0], x[1]), math::atan2(x[1], x[0]))
            }
            StepFunction::Motion { dt } => {
                let pose = MotionModel::ExactArc.predict(
                    &Pose2::new(0.0, 0.0, 0.0),
                    &Control::new(x[0], x[1]),
                    dt,
                );
                Vector2::new(pose.x, pose.y)
            }
            StepFunction::Linear { a, b } => a * x + b,
            StepFunction::Quadratic { c } => Vector2::new(x[0], x[1] + c * x[0] * x[0]),
            StepFunction::Exponential { c } => Vector2::new(x[0], math::exp(c * x[1])),
        }
    }

    /// The Jacobian `∂f/∂x` at `x` (the EKF's tangent plane).
    pub fn jacobian(&self, x: &Vector2<f64>) -> Result<Matrix2<f64>, OneStepError> {
        let j = match *self {
            StepFunction::Polar => {
                let (s, c) = math::sin_cos(x[1]);
                Matrix2::new(c, -x[0] * s, s, x[0] * c)
            }
            StepFunction::RangeBearing => {
                range_bearing::predict(&Pose2::new(0.0, 0.0, 0.0), x)
                    .map_err(|e| {
                        OneStepError::AtMean(format!(
                            "range-bearing at the mean ({:.3}, {:.3}): {e}",
                            x[0], x[1]
                        ))
                    })?
                    .jacobian_landmark
            }
            StepFunction::Motion { dt } => {
                let step = MotionModel::ExactArc.step(
                    &Pose2::new(0.0, 0.0, 0.0),
                    &Control::new(x[0], x[1]),
                    dt,
                );
                let g = step.jacobian_control;
                Matrix2::new(g[(0, 0)], g[(0, 1)], g[(1, 0)], g[(1, 1)])
            }
            StepFunction::Linear { a, .. } => a,
            StepFunction::Quadratic { c } => Matrix2::new(1.0, 0.0, 2.0 * c * x[0], 1.0),
            StepFunction::Exponential { c } => Matrix2::new(1.0, 0.0, 0.0, c * math::exp(c * x[1])),
        };
        if j.iter().all(|v| v.is_finite()) {
            Ok(j)
        } else {
            Err(OneStepError::NonFiniteResult("Jacobian at the mean"))
        }
    }
}

/// The EKF's step: the Gaussian `N(f(x̄), J Σ Jᵀ)` with `J = ∂f/∂x` at `x̄`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Linearized {
    /// The linearized Gaussian.
    pub gaussian: Gaussian2,
    /// The Jacobian at the prior mean.
    pub jacobian: Matrix2<f64>,
}

/// Linearizes `f` at the prior mean (thesis `000` Eq. 2.23 and 2.25; thesis `002`
/// Eq. 2.15 and 2.18).
pub fn linearize(prior: &Gaussian2, f: &StepFunction) -> Result<Linearized, OneStepError> {
    prior.factor()?;
    let jacobian = f.jacobian(&prior.mean)?;
    let gaussian = Gaussian2::new(
        f.eval(&prior.mean),
        jacobian * prior.covariance * jacobian.transpose(),
    );
    if !gaussian.is_finite() {
        return Err(OneStepError::NonFiniteResult("linearized Gaussian"));
    }
    Ok(Linearized { gaussian, jacobian })
}

/// The UKF's step: sigma points before and after, their weights and the
/// recovered Gaussian.
#[derive(Clone, Debug, PartialEq)]
pub struct Unscented {
    /// The recovered Gaussian (Eq. 2.26, 2.27 on the transformed points).
    pub gaussian: Gaussian2,
    /// The weights (Eq. 2.28).
    pub weights: SigmaWeights,
    /// The `2n + 1 = 5` sigma points in the input, centre first.
    pub sigma_in: Vec<Vector2<f64>>,
    /// The same points through `f`.
    pub sigma_out: Vec<Vector2<f64>>,
}

impl Unscented {
    /// True when the recovered covariance is positive definite (a negative `W₀ᶜ`
    /// can make it indefinite).
    pub fn is_positive_definite(&self) -> bool {
        self.gaussian.factor().is_ok()
    }
}

/// Passes the prior through `f` with the scaled unscented transform (thesis
/// `000` Eq. 2.26-2.28), using [`crate::kalman::unscented`].
pub fn unscented(
    prior: &Gaussian2,
    f: &StepFunction,
    params: &UnscentedParams,
) -> Result<Unscented, OneStepError> {
    let factor = prior.factor()?;
    let weights = params
        .weights(2)
        .map_err(|e| OneStepError::Unscented(e.to_string()))?;
    let mean = DVector::from_column_slice(prior.mean.as_slice());
    let cov = DMatrix::from_column_slice(2, 2, prior.covariance.as_slice());
    let out = unscented_transform(params, &mean, &cov, &DMatrix::zeros(0, 2), &[], |x| {
        let y = f.eval(&Vector2::new(x[0], x[1]));
        DVector::from_column_slice(y.as_slice())
    })
    .map_err(|e| OneStepError::Unscented(e.to_string()))?;
    if !out.is_finite() {
        return Err(OneStepError::NonFiniteResult("unscented Gaussian"));
    }
    let l = DMatrix::from_column_slice(2, 2, factor.as_slice());
    let sigma_in = sigma_points(&mean, &l, weights.spread)
        .iter()
        .map(|p| Vector2::new(p[0], p[1]))
        .collect();
    let sigma_out = out
        .sigma_outputs
        .iter()
        .map(|p| Vector2::new(p[0], p[1]))
        .collect();
    Ok(Unscented {
        gaussian: Gaussian2::new(
            Vector2::new(out.mean[0], out.mean[1]),
            Matrix2::new(
                out.covariance[(0, 0)],
                out.covariance[(0, 1)],
                out.covariance[(1, 0)],
                out.covariance[(1, 1)],
            ),
        ),
        weights,
        sigma_in,
        sigma_out,
    })
}

/// Samples pushed through `f` and their moments.
#[derive(Clone, Debug, PartialEq)]
pub struct Cloud {
    /// The transformed samples.
    pub points: Vec<Vector2<f64>>,
    /// Their mean and (unbiased, `N − 1`) covariance.
    pub moments: Gaussian2,
}

/// The mean and unbiased covariance of `points` (at least two).
pub fn moments(points: &[Vector2<f64>]) -> Option<Gaussian2> {
    if points.len() < 2 {
        return None;
    }
    let n = points.len() as f64;
    let mean = points.iter().fold(Vector2::zeros(), |acc, p| acc + p) / n;
    let mut cov = Matrix2::zeros();
    for p in points {
        let d = p - mean;
        cov += d * d.transpose();
    }
    let g = Gaussian2::new(mean, cov / (n - 1.0));
    g.is_finite().then_some(g)
}

/// Draws `count` samples from the prior (`x = x̄ + L n`, `n ~ N(0, I)`), pushes
/// them through `f` and takes their moments: the particle filter's prediction
/// (thesis `000` Sec. 2.3, Algorithm 5 line 4) and, with many samples, the
/// reference the Gaussians are measured against. `what` names them in errors.
///
/// The same as [`standard_normals`] followed by [`sample_from_normals`], which
/// is how it is written: a caller that keeps the draws (they depend only on the
/// rng and the count, not on the prior or `f`) moves the prior without drawing
/// again and gets the same cloud, bit for bit.
pub fn sample<R: Rng + ?Sized>(
    prior: &Gaussian2,
    f: &StepFunction,
    count: usize,
    what: &'static str,
    rng: &mut R,
) -> Result<Cloud, OneStepError> {
    // Refused before anything is drawn, so the rng is untouched.
    prior.factor()?;
    if count < 2 {
        return Err(OneStepError::TooFewSamples { what, count });
    }
    sample_from_normals(prior, f, &standard_normals(count, rng), what)
}

/// `count` draws `n ~ N(0, I)` in the plane: two standard normals each, first
/// component first, in the order [`sample`] draws them.
pub fn standard_normals<R: Rng + ?Sized>(count: usize, rng: &mut R) -> Vec<Vector2<f64>> {
    (0..count)
        .map(|_| {
            let n1 = standard_normal(rng);
            Vector2::new(n1, standard_normal(rng))
        })
        .collect()
}

/// [`sample`] on draws already made: each `n` of `normals` becomes
/// `x = x̄ + L n` (`L` the prior's Cholesky factor), pushed through `f`; then the
/// moments of the results.
pub fn sample_from_normals(
    prior: &Gaussian2,
    f: &StepFunction,
    normals: &[Vector2<f64>],
    what: &'static str,
) -> Result<Cloud, OneStepError> {
    let l = prior.factor()?;
    let count = normals.len();
    if count < 2 {
        return Err(OneStepError::TooFewSamples { what, count });
    }
    let mut points = Vec::with_capacity(count);
    let mut bad = 0;
    for n in normals {
        let y = f.eval(&(prior.mean + l * n));
        if y.iter().all(|v| v.is_finite()) {
            points.push(y);
        } else {
            bad += 1;
        }
    }
    if bad > 0 {
        return Err(OneStepError::SamplesOverflow {
            what,
            bad,
            count,
            function: f.name(),
        });
    }
    let moments = moments(&points).ok_or(OneStepError::NonFiniteResult("samples' covariance"))?;
    Ok(Cloud { points, moments })
}

/// How far a Gaussian is from a reference's mean and covariance.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    /// `‖μ − μ_ref‖`, in the output's units.
    pub mean_error: f64,
    /// `‖Σ − Σ_ref‖_F / ‖Σ_ref‖_F`, dimensionless.
    pub covariance_error: f64,
    /// `KL(N_ref ‖ N)`, nats; `None` when a covariance is not positive definite.
    pub kl_divergence: Option<f64>,
}

/// Compares `estimate` with `reference` (the samples' moments).
pub fn compare(estimate: &Gaussian2, reference: &Gaussian2) -> Comparison {
    Comparison {
        mean_error: (estimate.mean - reference.mean).norm(),
        covariance_error: (estimate.covariance - reference.covariance).norm()
            / reference.covariance.norm(),
        kl_divergence: estimate.kl_from(reference),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn rng(seed: u64) -> ChaCha8Rng {
        ChaCha8Rng::seed_from_u64(seed)
    }

    #[test]
    fn a_linear_function_gives_the_exact_moments_by_every_gaussian_method() {
        let prior = Gaussian2::from_std([1.0, -2.0], [0.7, 1.3], 0.4);
        let a = Matrix2::new(1.5, -0.3, 0.8, 2.0);
        let b = Vector2::new(0.25, -1.0);
        let f = StepFunction::Linear { a, b };
        let mean = a * prior.mean + b;
        let cov = a * prior.covariance * a.transpose();
        let ekf = linearize(&prior, &f).unwrap();
        assert!((ekf.gaussian.mean - mean).norm() < 1e-12);
        assert!((ekf.gaussian.covariance - cov).norm() < 1e-12);
        for params in [
            UnscentedParams::default(),
            UnscentedParams {
                alpha: 0.3,
                beta: 2.0,
                kappa: 1.0,
            },
        ] {
            let ukf = unscented(&prior, &f, &params).unwrap();
            assert!((ukf.gaussian.mean - mean).norm() < 1e-12);
            assert!((ukf.gaussian.covariance - cov).norm() < 1e-12);
            assert_eq!(ukf.sigma_in.len(), 5);
        }
        // Samples agree within their statistical error (100k: ~0.3% of σ).
        let cloud = sample(&prior, &f, 100_000, "samples", &mut rng(3)).unwrap();
        let c = compare(&ekf.gaussian, &cloud.moments);
        assert!(c.covariance_error < 0.02, "{c:?}");
        assert!(c.kl_divergence.unwrap() < 1e-3, "{c:?}");
    }

    /// Every coordinate of `cloud`'s points and moments, as bits.
    fn bits(cloud: &Cloud) -> Vec<u64> {
        cloud
            .points
            .iter()
            .flat_map(|p| p.iter())
            .chain(cloud.moments.mean.iter())
            .chain(cloud.moments.covariance.iter())
            .map(|v| v.to_bits())
            .collect()
    }

    #[test]
    fn kept_draws_give_the_cloud_of_drawing_afresh_bit_for_bit() {
        let functions = [
            StepFunction::Polar,
            StepFunction::RangeBearing,
            StepFunction::Motion { dt: 1.0 },
            StepFunction::Quadratic { c: 0.5 },
            StepFunction::Exponential { c: 0.5 },
        ];
        let priors = [
            Gaussian2::from_std([1.0, 0.0], [0.1, 30f64.to_radians()], 0.0),
            Gaussian2::from_std([2.0, 0.5], [0.6, 0.6], -0.3),
            Gaussian2::from_std([1.05, 0.01], [0.2, 0.4], 0.7),
        ];
        // Drawn once, used for every prior and function (as the lesson does while
        // the student drags the prior).
        let normals = standard_normals(5_000, &mut rng(9));
        for f in &functions {
            for prior in &priors {
                let fresh = sample(prior, f, 5_000, "samples", &mut rng(9)).unwrap();
                let kept = sample_from_normals(prior, f, &normals, "samples").unwrap();
                assert_eq!(bits(&kept), bits(&fresh), "{f:?} {prior:?}");
                // The first draws of a longer run are the draws of a shorter one.
                let fewer = sample(prior, f, 300, "samples", &mut rng(9)).unwrap();
                let front = sample_from_normals(prior, f, &normals[..300], "samples").unwrap();
                assert_eq!(bits(&front), bits(&fewer), "{f:?} {prior:?}");
            }
        }
        // The same refusals, and a refused prior leaves the rng untouched.
        let singular = Gaussian2::from_std([1.0, 0.0], [0.1, 0.2], 1.0);
        let mut r = rng(9);
        assert!(matches!(
            sample(&singular, &StepFunction::Polar, 10, "samples", &mut r),
            Err(OneStepError::NotPositiveDefinite { .. })
        ));
        assert_eq!(standard_normals(3, &mut r), normals[..3]);
        assert_eq!(
            sample_from_normals(&priors[0], &StepFunction::Polar, &normals[..1], "particles"),
            Err(OneStepError::TooFewSamples {
                what: "particles",
                count: 1
            })
        );
    }

    #[test]
    fn every_jacobian_matches_finite_differences() {
        let cases = [
            (StepFunction::Polar, Vector2::new(3.0, 0.7)),
            (StepFunction::RangeBearing, Vector2::new(2.0, -1.5)),
            (StepFunction::Motion { dt: 1.0 }, Vector2::new(1.0, 0.8)),
            (StepFunction::Motion { dt: 0.5 }, Vector2::new(1.0, 0.0)),
            (StepFunction::Quadratic { c: 0.7 }, Vector2::new(1.2, -0.4)),
            (StepFunction::Exponential { c: 0.5 }, Vector2::new(0.3, 1.1)),
        ];
        let h = 1e-6;
        for (f, x) in cases {
            let j = f.jacobian(&x).unwrap();
            for k in 0..2 {
                let mut e = Vector2::zeros();
                e[k] = h;
                let column = (f.eval(&(x + e)) - f.eval(&(x - e))) / (2.0 * h);
                assert!(
                    (j.column(k) - column).norm() < 1e-7,
                    "{f:?} column {k}: {} vs {column}",
                    j.column(k)
                );
            }
        }
    }

    #[test]
    fn motion_is_the_exact_arc() {
        // v = 1, w = π/2, dt = 1: a quarter circle of radius 2/π.
        let r = 2.0 / std::f64::consts::PI;
        let y =
            StepFunction::Motion { dt: 1.0 }.eval(&Vector2::new(1.0, std::f64::consts::FRAC_PI_2));
        assert!((y - Vector2::new(r, r)).norm() < 1e-12);
        // Straight line at w = 0.
        let y = StepFunction::Motion { dt: 2.0 }.eval(&Vector2::new(1.5, 0.0));
        assert!((y - Vector2::new(3.0, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn polar_banana_at_30_degrees_the_ukf_mean_beats_the_ekf() {
        let prior = Gaussian2::from_std([1.0, 0.0], [0.1, 30f64.to_radians()], 0.0);
        let f = StepFunction::Polar;
        let truth = sample(&prior, &f, 100_000, "samples", &mut rng(1)).unwrap();
        let ekf = compare(&linearize(&prior, &f).unwrap().gaussian, &truth.moments);
        let ukf = compare(
            &unscented(&prior, &f, &UnscentedParams::default())
                .unwrap()
                .gaussian,
            &truth.moments,
        );
        // E[r cos b] = r̄ e^(−σ_b²/2) = 0.8712: the EKF's mean stays at 1.0.
        let exact_x = math::exp(-0.5 * 30f64.to_radians().powi(2));
        assert!((truth.moments.mean[0] - exact_x).abs() < 0.002);
        assert!((ekf.mean_error - (1.0 - exact_x)).abs() < 0.003, "{ekf:?}");
        assert!(ukf.mean_error < 0.25 * ekf.mean_error, "{ukf:?} vs {ekf:?}");
        assert!(
            ukf.covariance_error < ekf.covariance_error,
            "{ukf:?} vs {ekf:?}"
        );
        assert!(ukf.kl_divergence.unwrap() < ekf.kl_divergence.unwrap());
    }

    #[test]
    fn kl_is_zero_for_equal_gaussians_and_matches_a_hand_value() {
        let p = Gaussian2::from_std([0.0, 0.0], [1.0, 1.0], 0.0);
        assert!(p.kl_from(&p).unwrap().abs() < 1e-15);
        // KL(N(0, I) ‖ N((1, 0), 4I)) = ½ (2/4 + 1/4 − 2 + ln 16) = 0.7613.
        let q = Gaussian2::from_std([1.0, 0.0], [2.0, 2.0], 0.0);
        let expected = 0.5 * (0.5 + 0.25 - 2.0 + math::ln(16.0));
        assert!((q.kl_from(&p).unwrap() - expected).abs() < 1e-12);
    }

    #[test]
    fn bad_inputs_are_refused_with_reasons() {
        let f = StepFunction::Polar;
        let singular = Gaussian2::from_std([1.0, 0.0], [0.1, 0.2], 1.0);
        assert!(matches!(
            linearize(&singular, &f),
            Err(OneStepError::NotPositiveDefinite { .. })
        ));
        let negative = Gaussian2::new(Vector2::new(1.0, 0.0), Matrix2::new(-1.0, 0.0, 0.0, 1.0));
        assert!(unscented(&negative, &f, &UnscentedParams::default()).is_err());
        let nan = Gaussian2::from_std([f64::NAN, 0.0], [0.1, 0.2], 0.0);
        assert_eq!(linearize(&nan, &f), Err(OneStepError::NotFinite));
        let ok = Gaussian2::from_std([1.0, 0.0], [0.1, 0.2], 0.0);
        // α²(n + κ) ≤ 0.
        let bad = UnscentedParams {
            alpha: 1.0,
            beta: 2.0,
            kappa: -2.0,
        };
        assert!(matches!(
            unscented(&ok, &f, &bad),
            Err(OneStepError::Unscented(_))
        ));
        assert!(matches!(
            sample(&ok, &f, 0, "particles", &mut rng(1)),
            Err(OneStepError::TooFewSamples { count: 0, .. })
        ));
        // exp(800) overflows.
        let big = Gaussian2::from_std([0.0, 800.0], [0.1, 1.0], 0.0);
        let e = StepFunction::Exponential { c: 1.0 };
        assert!(matches!(
            sample(&big, &e, 100, "samples", &mut rng(1)),
            Err(OneStepError::SamplesOverflow { .. })
        ));
        assert!(linearize(&big, &e).is_err());
        // The range-bearing Jacobian does not exist at the robot.
        let at_robot = Gaussian2::from_std([0.0, 0.0], [0.1, 0.1], 0.0);
        assert!(matches!(
            linearize(&at_robot, &StepFunction::RangeBearing),
            Err(OneStepError::AtMean(_))
        ));
    }
}
