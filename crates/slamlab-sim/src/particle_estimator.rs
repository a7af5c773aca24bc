//! FastSLAM as one more estimator of the landmark lesson, beside EKF- and
//! UKF-SLAM: an adapter that runs a [`FastSlam`] filter behind the
//! [`LandmarkSlam`] trait.
//!
//! The lesson compares estimators by their robot pose, landmark estimates and
//! uncertainty, so the adapter summarizes the particles as a Gaussian after every
//! phase:
//!
//! - robot: the weighted mean pose and the weighted covariance of the particle
//!   poses around it (heading differences wrapped);
//! - landmarks: the best (heaviest) particle's map, each landmark with its own 2x2
//!   EKF; cross covariances are zero (given the path, FastSLAM's landmarks are
//!   independent).
//!
//! The particles themselves are available through [`LandmarkSlam::particle_set`].

use nalgebra::{DMatrix, DVector, Vector3};
use slamlab_core::kalman::{FilterError, LandmarkSlam, PredictReport, UpdateReport};
use slamlab_core::particle::fastslam::{FastSlam, FastSlamError, ResampleReport};
use slamlab_core::particle::{FastSlamConfig, LandmarkObservation};
use slamlab_core::range_bearing::RangeBearing;
use slamlab_core::{Control, Pose2, wrap_angle};

/// The ids a filter gives the landmarks it starts itself when the sensor's ids are
/// withheld start here, so that they never look like a true landmark's id.
pub const OWN_LABELS: usize = 1_000_000;

/// A FastSLAM filter seen as a landmark SLAM estimator.
#[derive(Clone, Debug)]
pub struct FastSlamEstimator {
    inner: FastSlam,
    /// True when the filter labels landmarks itself (maximum likelihood).
    own_labels: bool,
    mean: DVector<f64>,
    covariance: DMatrix<f64>,
    ids: Vec<usize>,
}

fn filter_error(e: FastSlamError) -> FilterError {
    match e {
        FastSlamError::InvalidControl { v, w, dt } => FilterError::InvalidControl { v, w, dt },
        FastSlamError::InvalidMeasurement { .. } => FilterError::NonFinite {
            what: "the measurement",
        },
        FastSlamError::InvalidParameter { name, value } => {
            FilterError::InvalidParameter { name, value }
        }
        FastSlamError::ThresholdOutOfRange { value } => FilterError::InvalidParameter {
            name: "resample threshold",
            value,
        },
        FastSlamError::NoParticles | FastSlamError::TooManyParticles { .. } => {
            FilterError::InvalidParameter {
                name: "particles",
                value: f64::NAN,
            }
        }
    }
}

impl FastSlamEstimator {
    /// A filter whose particles all start at `start`.
    pub fn new(config: FastSlamConfig, start: Pose2) -> Result<Self, FastSlamError> {
        let own_labels = !matches!(
            config.association,
            slamlab_core::association::AssociationMode::KnownIds
        );
        let mut estimator = Self {
            inner: FastSlam::new(config, start)?,
            own_labels,
            mean: DVector::zeros(3),
            covariance: DMatrix::zeros(3, 3),
            ids: Vec::new(),
        };
        estimator.summarize();
        Ok(estimator)
    }

    /// The FastSLAM filter inside.
    pub fn inner(&self) -> &FastSlam {
        &self.inner
    }

    /// Recomputes the Gaussian summary from the particles.
    fn summarize(&mut self) {
        let f = &self.inner;
        let mean_pose = f.mean_pose();
        let mut robot = nalgebra::Matrix3::zeros();
        for (p, &w) in f.particles().map(|p| p.pose).zip(f.weights()) {
            let d = Vector3::new(
                p.x - mean_pose.x,
                p.y - mean_pose.y,
                wrap_angle(p.theta - mean_pose.theta),
            );
            robot += w * d * d.transpose();
        }
        let landmarks = f.best_landmarks();
        let n = 3 + 2 * landmarks.len();
        let mut mean = DVector::zeros(n);
        let mut covariance = DMatrix::zeros(n, n);
        mean[0] = mean_pose.x;
        mean[1] = mean_pose.y;
        mean[2] = mean_pose.theta;
        covariance.fixed_view_mut::<3, 3>(0, 0).copy_from(&robot);
        self.ids.clear();
        for (slot, l) in landmarks.iter().enumerate() {
            let j = 3 + 2 * slot;
            mean[j] = l.mean.x;
            mean[j + 1] = l.mean.y;
            covariance
                .fixed_view_mut::<2, 2>(j, j)
                .copy_from(&l.covariance);
            self.ids.push(if self.own_labels {
                OWN_LABELS + l.id
            } else {
                l.id
            });
        }
        self.mean = mean;
        self.covariance = covariance;
    }
}

impl LandmarkSlam for FastSlamEstimator {
    fn name(&self) -> &'static str {
        self.inner.name()
    }

    fn predict(&mut self, control: &Control, dt: f64) -> Result<PredictReport, FilterError> {
        let before = self.robot_covariance().determinant();
        let report = self.inner.predict(control, dt).map_err(filter_error)?;
        self.summarize();
        Ok(PredictReport {
            control: report.control,
            robot_det_before: before,
            robot_det_after: self.robot_covariance().determinant(),
        })
    }

    fn update(&mut self, id: usize, z: &RangeBearing) -> Result<UpdateReport, FilterError> {
        let report = self
            .inner
            .update(&LandmarkObservation { id, z: *z })
            .map_err(filter_error)?;
        self.summarize();
        Ok(UpdateReport::Weighted {
            id,
            n_eff: report.n_eff,
            new_landmark_particles: report.new_landmark_particles,
            best_log_likelihood: report.best_log_weight_change,
        })
    }

    fn mean(&self) -> &DVector<f64> {
        &self.mean
    }

    fn covariance(&self) -> &DMatrix<f64> {
        &self.covariance
    }

    fn landmark_ids(&self) -> &[usize] {
        &self.ids
    }

    fn particle_set(&self) -> Option<&FastSlam> {
        Some(&self.inner)
    }

    fn resample(&mut self) -> Option<ResampleReport> {
        let report = self.inner.resample();
        self.summarize();
        Some(report)
    }
}
