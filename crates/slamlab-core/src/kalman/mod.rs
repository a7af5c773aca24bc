//! Kalman-family SLAM on a landmark map (thesis `000` Sec. 3.2-3.3).
//!
//! The state is `M = [x, y, θ, L¹x, L¹y, …]` (thesis Eq. 3.1) with landmarks in
//! order of discovery. Every estimator here exposes its phases separately
//! (predict, then one update per observed landmark) so the app can step through
//! them, and a read-only view for drawing.
//!
//! Every estimator shows a robot pose and landmark estimates
//! ([`PoseBelief`], [`LandmarkBelief`]). The Kalman filters also show their joint
//! Gaussian ([`LandmarkSlam::gaussian`], for the correlation heatmap and gated
//! association); a particle filter has none, shows its particles instead
//! ([`LandmarkSlam::particles`]) and has a third phase, resampling
//! ([`LandmarkSlam::resample`]). See [`crate::belief`].

mod ekf_slam;
pub mod fusion;
#[cfg(test)]
mod recorded_tests;
mod state;
mod ukf_slam;
pub mod unscented;

pub use ekf_slam::{EkfSlam, Linearization};
pub use ukf_slam::UkfSlam;
pub use unscented::UnscentedParams;

pub use crate::belief::LandmarkEstimate;
use crate::belief::{JointGaussian, LandmarkBelief, ParticleBelief, PoseBelief};
use crate::geometry::Pose2;
use crate::motion::{Control, MotionModel, RecordedMotion};
use crate::particle::fastslam::{FastSlam, ResampleReport};
use crate::range_bearing::{MeasurementError, RangeBearing};
use nalgebra::{DMatrix, Matrix2, Vector2};
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// The noise a landmark SLAM filter assumes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FilterNoise {
    /// Standard deviation of the executed forward speed, m/s (thesis `q[0]`).
    pub v_std: f64,
    /// Standard deviation of the executed turn rate, rad/s (thesis `q[1]`).
    pub w_std: f64,
    /// Standard deviation of the range measurement, metres (thesis `v[0]`).
    pub range_std: f64,
    /// Standard deviation of the bearing measurement, radians (thesis `v[1]`).
    pub bearing_std: f64,
}

impl FilterNoise {
    /// The control noise covariance `diag(σ_v², σ_w²)`.
    pub fn control_covariance(&self) -> Matrix2<f64> {
        Matrix2::new(self.v_std.powi(2), 0.0, 0.0, self.w_std.powi(2))
    }

    /// The measurement noise covariance `V = diag(σ_r², σ_b²)`.
    pub fn measurement_covariance(&self) -> Matrix2<f64> {
        Matrix2::new(self.range_std.powi(2), 0.0, 0.0, self.bearing_std.powi(2))
    }

    /// Checks that every standard deviation is finite and positive.
    pub fn validate(&self) -> Result<(), FilterError> {
        for (name, value) in [
            ("v_std", self.v_std),
            ("w_std", self.w_std),
            ("range_std", self.range_std),
            ("bearing_std", self.bearing_std),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(FilterError::InvalidParameter { name, value });
            }
        }
        Ok(())
    }
}

/// Everything a landmark SLAM filter is configured with.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FilterConfig {
    /// The motion model the filter predicts with.
    pub motion_model: MotionModel,
    /// The noise it assumes.
    pub noise: FilterNoise,
}

/// Why a filter phase could not run. The filter's state is unchanged after any error.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum FilterError {
    /// A parameter is NaN, infinite or out of its range.
    #[error("parameter {name} = {value} is not allowed (it must be finite and positive)")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// The rejected value.
        value: f64,
    },
    /// A control is NaN or infinite, or the time step is that or negative.
    #[error(
        "control (v = {v}, w = {w}) must be finite and the time step dt = {dt} finite and not negative"
    )]
    InvalidControl {
        /// Forward speed.
        v: f64,
        /// Turn rate.
        w: f64,
        /// Time step.
        dt: f64,
    },
    /// The measurement model could not be evaluated.
    #[error("landmark {id}: {source}")]
    Measurement {
        /// The landmark's id.
        id: usize,
        /// What went wrong.
        source: MeasurementError,
    },
    /// A matrix that must be positive definite is not.
    #[error("{what} is not positive definite; the update was skipped")]
    NotPositiveDefinite {
        /// Which matrix.
        what: &'static str,
    },
    /// A recorded motion (odometry reading, car input) cannot move the robot.
    #[error("{0}")]
    InvalidMotion(String),
    /// A landmark given with the map is already in the state, or its position or
    /// covariance is not finite (or the covariance not symmetric positive semi-definite).
    #[error("landmark {id} cannot be added to the map: {why}")]
    InvalidLandmark {
        /// The landmark's id.
        id: usize,
        /// Why.
        why: &'static str,
    },
    /// A result came out NaN or infinite (the inputs were finite).
    #[error("{what} came out NaN or infinite; the step was skipped")]
    NonFinite {
        /// Which result.
        what: &'static str,
    },
}

/// What a prediction did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PredictReport {
    /// The control the filter used.
    pub control: Control,
    /// The robot's covariance determinant before and after, a measure of how much
    /// the uncertainty ellipse grew.
    pub robot_det_before: f64,
    /// See `robot_det_before`.
    pub robot_det_after: f64,
}

/// What one landmark update did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum UpdateReport {
    /// The landmark was new: it was added to the state from this measurement.
    Initialized {
        /// The landmark's id.
        id: usize,
        /// Where it was placed.
        position: Vector2<f64>,
    },
    /// The landmark was known: the state was corrected.
    Corrected {
        /// The landmark's id.
        id: usize,
        /// The innovation `z - h(M)`, `[range m, bearing rad]`, bearing wrapped.
        innovation: Vector2<f64>,
        /// The innovation covariance `S`.
        innovation_covariance: Matrix2<f64>,
        /// The normalized innovation squared `νᵀ S⁻¹ ν` (2 degrees of freedom).
        nis: f64,
        /// The Frobenius norm of the Kalman gain's robot rows (3x2), a measure of how
        /// strongly this measurement moves the robot.
        robot_gain_norm: f64,
        /// The Frobenius norm of the whole Kalman gain.
        gain_norm: f64,
    },
    /// A particle filter weighted its particles with the measurement (each
    /// particle updated or started the landmark in its own map).
    Weighted {
        /// The landmark's id as the sensor reported it.
        id: usize,
        /// The effective sample size `1 / Σ wᵢ²` after weighting.
        n_eff: f64,
        /// How many particles started a new landmark with this measurement.
        new_landmark_particles: usize,
        /// The log likelihood of the measurement under the best particle.
        best_log_likelihood: f64,
    },
}

/// A SLAM filter over robot pose and landmark positions, phase by phase. What it
/// can show beyond the pose and the landmarks depends on what it keeps: a joint
/// Gaussian (EKF, UKF) or particles (FastSLAM).
pub trait LandmarkSlam: PoseBelief + LandmarkBelief {
    /// A short name ("ekf", "ukf").
    fn name(&self) -> &'static str;
    /// Prediction: moves the robot by `control` for `dt` seconds and grows its uncertainty.
    fn predict(&mut self, control: &Control, dt: f64) -> Result<PredictReport, FilterError>;
    /// Update with one measurement of landmark `id`; initializes it when new.
    fn update(&mut self, id: usize, z: &RangeBearing) -> Result<UpdateReport, FilterError>;
    /// Prediction with a motion as a data set records it (an odometry reading, the
    /// ACFR car's input; [`RecordedMotion`]) instead of a velocity command: the
    /// same phase, with the motion's own model and input noise.
    fn predict_recorded(&mut self, motion: &RecordedMotion) -> Result<PredictReport, FilterError>;
    /// Adds landmark `id` at `position` with `covariance` and no correlation with
    /// the robot or the other landmarks: a map given before the run (localization
    /// with a known map, where the map enters with its survey's uncertainty).
    /// Refused when `id` is already in the state or the numbers are not a
    /// position and a covariance.
    fn insert_landmark(
        &mut self,
        id: usize,
        position: Vector2<f64>,
        covariance: Matrix2<f64>,
    ) -> Result<(), FilterError>;

    /// The joint Gaussian over robot and landmarks, for filters that keep one
    /// (EKF, UKF); `None` for a particle filter.
    fn gaussian(&self) -> Option<&dyn JointGaussian> {
        None
    }

    /// The particles, for a particle filter; `None` for a Gaussian filter.
    fn particles(&self) -> Option<&dyn ParticleBelief> {
        self.particle_set().map(|f| f as &dyn ParticleBelief)
    }

    /// FastSLAM's particles with their maps (what the lesson draws and explains
    /// beyond poses and weights); `None` for other filters.
    fn particle_set(&self) -> Option<&FastSlam> {
        None
    }

    /// The robot's sigma points (centre first), for filters that use them; empty otherwise.
    fn robot_sigma_points(&self) -> Vec<Pose2> {
        Vec::new()
    }

    /// The resampling phase of a particle filter (run once per tick, after the
    /// updates). Gaussian filters have no such phase: the default does nothing and
    /// returns `None`.
    fn resample(&mut self) -> Option<ResampleReport> {
        None
    }
}

/// Checks a landmark given with the map: a finite position and a finite,
/// symmetric, positive semi-definite covariance.
pub(crate) fn check_known_landmark(
    id: usize,
    position: &Vector2<f64>,
    covariance: &Matrix2<f64>,
) -> Result<(), FilterError> {
    let finite = position
        .iter()
        .chain(covariance.iter())
        .all(|v| v.is_finite());
    let (a, b, c) = (covariance[(0, 0)], covariance[(0, 1)], covariance[(1, 1)]);
    let psd = a >= 0.0 && c >= 0.0 && a * c - b * b >= -1e-12 * (a * c).abs().max(1e-300);
    if !finite {
        return Err(FilterError::InvalidLandmark {
            id,
            why: "its position or covariance is not finite",
        });
    }
    if covariance[(0, 1)] != covariance[(1, 0)] || !psd {
        return Err(FilterError::InvalidLandmark {
            id,
            why: "its covariance is not symmetric positive semi-definite",
        });
    }
    Ok(())
}

/// Makes `p` exactly symmetric by averaging it with its transpose.
pub(crate) fn symmetrize(p: &mut DMatrix<f64>) {
    let n = p.nrows();
    for i in 0..n {
        for j in (i + 1)..n {
            let v = 0.5 * (p[(i, j)] + p[(j, i)]);
            p[(i, j)] = v;
            p[(j, i)] = v;
        }
    }
}
