//! The Kalman filter in one dimension (thesis `002` Sec. 2.1.1; thesis `000`
//! Algorithm 2): the gain as the balance between the prediction and the
//! measurement. With `Φ = H = 1`:
//!
//! - predict: `x̄ = x + u` (Eq. 2.10 with a control), `P̄ = P + Q` (Eq. 2.18);
//! - gain: `K = P̄ / (P̄ + R)` (Eq. 2.8);
//! - update: `x = x̄ + K (z − x̄)` (Eq. 2.5), `P = (1 − K) P̄` (Eq. 2.9).
//!
//! `K → 1` trusts the measurement (`R ≪ P̄`), `K → 0` the prediction (`R ≫ P̄`).

use serde::{Deserialize, Serialize};

/// Why a Kalman step was refused (the estimate is kept).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Kalman1Error {
    /// A value is NaN, infinite, or a variance negative.
    #[error("Kalman filter: {name} = {value} must be finite (and not negative for a variance)")]
    Parameter {
        /// Its name.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// `P̄ + R` is zero: the gain is undefined.
    #[error("Kalman filter: P̄ + R = 0, the gain is undefined (give the measurement some noise)")]
    ZeroInnovationVariance,
}

/// A 1-D Gaussian estimate.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Kalman1 {
    /// Mean, metres.
    pub mean: f64,
    /// Variance, m².
    pub variance: f64,
}

/// What one update did, with every intermediate named as in the derivation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct KalmanUpdate {
    /// `x̄`.
    pub prior_mean: f64,
    /// `P̄`.
    pub prior_variance: f64,
    /// `z`.
    pub measurement: f64,
    /// `R`.
    pub measurement_variance: f64,
    /// `z − x̄`.
    pub innovation: f64,
    /// `K = P̄ / (P̄ + R)` (Eq. 2.8).
    pub gain: f64,
    /// `x = x̄ + K (z − x̄)` (Eq. 2.5).
    pub posterior_mean: f64,
    /// `P = (1 − K) P̄` (Eq. 2.9).
    pub posterior_variance: f64,
}

fn check(name: &'static str, value: f64, variance: bool) -> Result<(), Kalman1Error> {
    if value.is_finite() && (!variance || value >= 0.0) {
        Ok(())
    } else {
        Err(Kalman1Error::Parameter { name, value })
    }
}

impl Kalman1 {
    /// The estimate `N(mean, variance)`.
    pub fn new(mean: f64, variance: f64) -> Self {
        Self { mean, variance }
    }

    /// The prediction: moved by `u` with motion variance `q` (Eq. 2.10, 2.18).
    pub fn predict(&mut self, u: f64, q: f64) -> Result<(), Kalman1Error> {
        check("motion", u, false)?;
        check("motion variance Q", q, true)?;
        self.mean += u;
        self.variance += q;
        Ok(())
    }

    /// What [`Kalman1::update`] would do, without doing it.
    pub fn preview(&self, z: f64, r: f64) -> Result<KalmanUpdate, Kalman1Error> {
        check("measurement z", z, false)?;
        check("measurement variance R", r, true)?;
        let s = self.variance + r;
        if !(s > 0.0) {
            return Err(Kalman1Error::ZeroInnovationVariance);
        }
        let gain = self.variance / s;
        let innovation = z - self.mean;
        Ok(KalmanUpdate {
            prior_mean: self.mean,
            prior_variance: self.variance,
            measurement: z,
            measurement_variance: r,
            innovation,
            gain,
            posterior_mean: self.mean + gain * innovation,
            posterior_variance: (1.0 - gain) * self.variance,
        })
    }

    /// The update with measurement `z` of variance `r` (Eq. 2.5, 2.8, 2.9).
    pub fn update(&mut self, z: f64, r: f64) -> Result<KalmanUpdate, Kalman1Error> {
        let report = self.preview(z, r)?;
        self.mean = report.posterior_mean;
        self.variance = report.posterior_variance;
        Ok(report)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gain_balances_prediction_and_measurement() {
        let mut kf = Kalman1::new(0.0, 1.0);
        kf.predict(2.0, 3.0).unwrap();
        assert_eq!((kf.mean, kf.variance), (2.0, 4.0));
        // P̄ = 4, R = 1: K = 0.8, x = 2 + 0.8 (3 − 2) = 2.8, P = 0.2 · 4 = 0.8.
        let r = kf.update(3.0, 1.0).unwrap();
        assert_eq!(r.gain, 0.8);
        assert!((kf.mean - 2.8).abs() < 1e-15 && (kf.variance - 0.8).abs() < 1e-15);
        // Equal variances: halfway, half the variance.
        let r = Kalman1::new(0.0, 2.0).preview(1.0, 2.0).unwrap();
        assert_eq!(
            (r.gain, r.posterior_mean, r.posterior_variance),
            (0.5, 0.5, 1.0)
        );
        // A perfect measurement: K = 1; no prior knowledge of the measurement: K → 0.
        assert_eq!(Kalman1::new(0.0, 2.0).preview(1.0, 0.0).unwrap().gain, 1.0);
        assert!(Kalman1::new(0.0, 1e-9).preview(1.0, 1.0).unwrap().gain < 1e-8);
    }

    #[test]
    fn bad_values_are_refused_and_the_estimate_kept() {
        let mut kf = Kalman1::new(1.0, 0.0);
        assert_eq!(
            kf.update(2.0, 0.0),
            Err(Kalman1Error::ZeroInnovationVariance)
        );
        assert!(kf.update(f64::NAN, 1.0).is_err());
        assert!(kf.predict(1.0, -1.0).is_err());
        assert_eq!(kf, Kalman1::new(1.0, 0.0));
    }
}
