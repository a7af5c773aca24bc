//! FastSLAM as one more estimator of the landmark lesson, beside EKF- and
//! UKF-SLAM: an adapter that runs a [`FastSlam`] filter behind the
//! [`LandmarkSlam`] trait.
//!
//! The lesson compares estimators by what they show
//! ([`slamlab_core::belief`]): FastSLAM's robot pose is the weighted mean and
//! covariance of its particles, its landmarks are the best (heaviest)
//! particle's map, each landmark with its own 2x2 EKF. It keeps no joint
//! Gaussian: given the path, FastSLAM's landmarks are independent, and the
//! particles are what it has ([`LandmarkSlam::particle_set`]).

use nalgebra::{Matrix2, Matrix3, Vector2};
use slamlab_core::belief::{LandmarkBelief, LandmarkEstimate, PoseBelief};
use slamlab_core::kalman::{FilterError, LandmarkSlam, PredictReport, UpdateReport};
use slamlab_core::motion::RecordedMotion;
use slamlab_core::particle::fastslam::{FastSlam, FastSlamError, ResampleReport};
use slamlab_core::particle::{FastSlamConfig, LandmarkObservation};
use slamlab_core::range_bearing::RangeBearing;
use slamlab_core::{Control, Pose2};

/// The ids a filter gives the landmarks it starts itself when the sensor's ids are
/// withheld start here, so that they never look like a true landmark's id.
pub const OWN_LABELS: usize = 1_000_000;

/// A FastSLAM filter seen as a landmark SLAM estimator.
#[derive(Clone, Debug)]
pub struct FastSlamEstimator {
    inner: FastSlam,
    /// True when the filter labels landmarks itself (maximum likelihood).
    own_labels: bool,
    /// The best particle's landmarks, as the lesson labels them.
    landmarks: Vec<LandmarkEstimate>,
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
        FastSlamError::InvalidMotion(message) => FilterError::InvalidMotion(message),
        FastSlamError::InvalidLandmark { id, why } => FilterError::InvalidLandmark { id, why },
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
            landmarks: Vec::new(),
            ids: Vec::new(),
        };
        estimator.summarize();
        Ok(estimator)
    }

    /// The FastSLAM filter inside.
    pub fn inner(&self) -> &FastSlam {
        &self.inner
    }

    /// Reads the best particle's map after every phase (it may be another
    /// particle than before).
    fn summarize(&mut self) {
        self.landmarks.clear();
        self.ids.clear();
        for l in self.inner.best_landmarks() {
            let id = if self.own_labels {
                OWN_LABELS + l.id
            } else {
                l.id
            };
            self.ids.push(id);
            self.landmarks.push(LandmarkEstimate {
                id,
                mean: l.mean,
                covariance: l.covariance,
            });
        }
    }
}

impl PoseBelief for FastSlamEstimator {
    fn robot_pose(&self) -> Pose2 {
        self.inner.robot_pose()
    }

    fn robot_covariance(&self) -> Matrix3<f64> {
        self.inner.robot_covariance()
    }
}

impl LandmarkBelief for FastSlamEstimator {
    fn landmark_ids(&self) -> &[usize] {
        &self.ids
    }

    fn landmarks(&self) -> Vec<LandmarkEstimate> {
        self.landmarks.clone()
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

    fn predict_recorded(&mut self, motion: &RecordedMotion) -> Result<PredictReport, FilterError> {
        let before = self.robot_covariance().determinant();
        let report = self.inner.predict_recorded(motion).map_err(filter_error)?;
        self.summarize();
        Ok(PredictReport {
            control: report.control,
            robot_det_before: before,
            robot_det_after: self.robot_covariance().determinant(),
        })
    }

    fn insert_landmark(
        &mut self,
        id: usize,
        position: Vector2<f64>,
        covariance: Matrix2<f64>,
    ) -> Result<(), FilterError> {
        self.inner
            .insert_landmark(id, position, covariance)
            .map_err(filter_error)?;
        self.summarize();
        Ok(())
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
