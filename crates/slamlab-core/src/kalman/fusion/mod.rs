//! Sensor fusion in the manner of ROS robot_localization's EKF (thesis `002`
//! Sec. 3.5 and ch. 5): a planar state `[x, y, ψ, v_x, v_y, ψ̇, a_x, a_y]`
//! predicted with an omnidirectional constant-velocity (or constant-acceleration)
//! model and corrected by any number of sensors, each fusing its own selection of
//! state variables.
//!
//! * Every measurement is linear in the state once prepared (robot_localization
//!   measures state variables directly): `H` picks the selected rows of the
//!   identity, the innovation of the heading is wrapped.
//! * Measurements are applied in time order: [`FusionEkf::enqueue`] keeps a queue
//!   sorted by stamp, and each one is applied after a prediction to its stamp.
//! * An absolute pose is taken in one of three [`PoseMode`]s: as it is, relative
//!   to the sensor's first reading (`_relative`), or differenced with the previous
//!   reading into a body-frame velocity (`_differential`).
//! * Optional Mahalanobis rejection per sensor, as robot_localization's
//!   `*_rejection_threshold` (in standard deviations).
//! * Bad input (NaN readings, noise that is not positive, a stamp before the
//!   filter's start or older than its current time) is skipped with a typed
//!   [`FusionError`] and counted in [`FusionStats`]; nothing panics.

mod filter;
pub mod model;
#[cfg(test)]
mod tests;

pub use filter::{FusionEkf, Outcome, StepReport, UpdateReport};
pub use model::{STATE_SIZE, StateIndex, StateMatrix, StateVector};

use crate::geometry::Pose2;
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// How a pose sensor's readings are taken in (robot_localization's `*_relative`
/// and `*_differential` parameters; thesis `002` Sec. 3.5 and 5.3.1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PoseMode {
    /// The pose as it is, in the filter's world frame.
    #[default]
    Absolute,
    /// The pose relative to the sensor's first reading, `P₀⁻¹ ∘ P` (`_relative`).
    /// The first reading fuses as the identity pose.
    Relative,
    /// Consecutive poses differenced into a body-frame velocity,
    /// `(P_{k−1}⁻¹ ∘ P_k) / Δt` (`_differential`). The pose's selection moves to
    /// the velocities: fusing x, y, ψ becomes fusing v_x, v_y, ψ̇. The first
    /// reading is only stored.
    Differential,
}

impl PoseMode {
    /// Every mode.
    pub const ALL: [PoseMode; 3] = [
        PoseMode::Absolute,
        PoseMode::Relative,
        PoseMode::Differential,
    ];

    /// The mode's name as robot_localization spells the parameter ("absolute",
    /// "relative", "differential").
    pub fn name(self) -> &'static str {
        match self {
            PoseMode::Absolute => "absolute",
            PoseMode::Relative => "relative",
            PoseMode::Differential => "differential",
        }
    }
}

/// Which state variables a sensor fuses: robot_localization's 15-bool
/// `*_config`, restricted to the planar state (in [`StateIndex`] order).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct StateMask(pub [bool; STATE_SIZE]);

impl StateMask {
    /// A mask selecting exactly `variables`.
    pub fn of(variables: &[StateIndex]) -> Self {
        let mut mask = [false; STATE_SIZE];
        for &v in variables {
            mask[v as usize] = true;
        }
        Self(mask)
    }

    /// Whether `variable` is selected.
    pub fn contains(&self, variable: StateIndex) -> bool {
        self.0[variable as usize]
    }
}

/// One sensor of the filter.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SensorConfig {
    /// Its name in reports ("wheel odometry", "IMU", "SLAM pose").
    pub name: String,
    /// Which state variables it fuses. Variables its readings do not carry are
    /// ignored (a pose reading carries x, y, ψ; a twist v_x, v_y, ψ̇; an IMU
    /// reading ψ̇, a_x, a_y). In differential mode the pose selection applies to
    /// the velocities.
    pub fuse: StateMask,
    /// How pose readings are taken in; ignored for other readings.
    pub pose_mode: PoseMode,
    /// Mahalanobis rejection threshold in standard deviations: a reading with
    /// `νᵀ S⁻¹ ν ≥ threshold²` is rejected (robot_localization
    /// `FilterBase::checkMahalanobisThreshold`). `None` fuses everything.
    pub rejection_threshold: Option<f64>,
}

impl SensorConfig {
    /// A sensor named `name` that fuses the variables `fuse`, its pose readings
    /// taken as absolute, none rejected.
    pub fn new(name: &str, fuse: &[StateIndex]) -> Self {
        Self {
            name: name.to_owned(),
            fuse: StateMask::of(fuse),
            pose_mode: PoseMode::Absolute,
            rejection_threshold: None,
        }
    }

    /// The same sensor with its pose readings taken in `pose_mode`, and those
    /// `rejection_threshold` standard deviations or more from the prediction
    /// rejected (`None`: none).
    pub fn with_pose_mode(self, pose_mode: PoseMode, rejection_threshold: Option<f64>) -> Self {
        Self {
            pose_mode,
            rejection_threshold,
            ..self
        }
    }
}

/// What a sensor reports. Each kind carries three values and their 3x3 covariance.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Reading {
    /// A pose `[x, y, ψ]` (SLAM, `geometry_msgs/PoseWithCovarianceStamped`).
    Pose {
        /// The pose in the sensor's world frame.
        pose: Pose2,
        /// Its covariance.
        covariance: Matrix3<f64>,
    },
    /// A body-frame velocity `[v_x, v_y, ψ̇]` (wheel odometry's twist,
    /// `geometry_msgs/TwistWithCovarianceStamped`).
    Twist {
        /// `[v_x, v_y, ψ̇]`, m/s and rad/s.
        twist: nalgebra::Vector3<f64>,
        /// Its covariance.
        covariance: Matrix3<f64>,
    },
    /// An IMU: yaw rate and body-frame linear acceleration `[ψ̇, a_x, a_y]`.
    Imu {
        /// `[ψ̇, a_x, a_y]`, rad/s and m/s².
        values: nalgebra::Vector3<f64>,
        /// Their covariance.
        covariance: Matrix3<f64>,
    },
}

impl Reading {
    /// The state variables the reading's three values measure.
    pub fn variables(&self) -> [StateIndex; 3] {
        match self {
            Reading::Pose { .. } => [StateIndex::X, StateIndex::Y, StateIndex::Yaw],
            Reading::Twist { .. } => [StateIndex::VX, StateIndex::VY, StateIndex::YawRate],
            Reading::Imu { .. } => [StateIndex::YawRate, StateIndex::AX, StateIndex::AY],
        }
    }

    /// A short name of the kind ("pose", "twist", "IMU").
    pub fn kind(&self) -> &'static str {
        match self {
            Reading::Pose { .. } => "pose",
            Reading::Twist { .. } => "twist",
            Reading::Imu { .. } => "IMU",
        }
    }

    /// The three values.
    pub fn values(&self) -> nalgebra::Vector3<f64> {
        match self {
            Reading::Pose { pose, .. } => pose.to_vector(),
            Reading::Twist { twist, .. } => *twist,
            Reading::Imu { values, .. } => *values,
        }
    }

    /// The covariance of the three values.
    pub fn covariance(&self) -> &Matrix3<f64> {
        match self {
            Reading::Pose { covariance, .. }
            | Reading::Twist { covariance, .. }
            | Reading::Imu { covariance, .. } => covariance,
        }
    }
}

/// A stamped reading of one sensor (an index into the filter's sensors).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Measurement {
    /// The sensor's index in [`FusionEkf::sensors`].
    pub sensor: usize,
    /// When the reading was taken, seconds.
    pub stamp: f64,
    /// What it says.
    pub reading: Reading,
}

/// The filter's own parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FusionConfig {
    /// Process noise spectral densities, one per state variable (diagonal of
    /// robot_localization's `process_noise_covariance`; the prediction adds
    /// `Q Δt`). Units: the variable's unit squared per second.
    pub process_noise: [f64; STATE_SIZE],
    /// Whether the accelerations are estimated (constant-acceleration model).
    /// Without them they stay zero with zero variance: the constant-velocity model.
    pub use_acceleration: bool,
}

impl Default for FusionConfig {
    /// robot_localization's default process noise for the planar variables
    /// (`ekf.yaml`: x 0.05, y 0.05, yaw 0.06, v_x 0.025, v_y 0.025, yaw rate 0.02,
    /// a_x 0.01, a_y 0.01), constant-velocity model.
    fn default() -> Self {
        Self {
            process_noise: [0.05, 0.05, 0.06, 0.025, 0.025, 0.02, 0.01, 0.01],
            use_acceleration: false,
        }
    }
}

impl FusionConfig {
    /// Checks every process-noise density is finite and not negative.
    pub fn validate(&self) -> Result<(), FusionError> {
        for (variable, &q) in StateIndex::ALL.iter().zip(&self.process_noise) {
            if !(q.is_finite() && q >= 0.0) {
                return Err(FusionError::InvalidProcessNoise {
                    variable: variable.label(),
                    value: q,
                });
            }
        }
        Ok(())
    }
}

/// Why a measurement (or the filter's set-up) was refused. The filter's state is
/// unchanged after any error; a refused measurement is counted in [`FusionStats`].
#[derive(Clone, Debug, PartialEq, Error)]
pub enum FusionError {
    /// A process-noise density is NaN, infinite or negative.
    #[error("process noise for {variable} = {value} must be finite and not negative")]
    InvalidProcessNoise {
        /// The state variable.
        variable: &'static str,
        /// The rejected value.
        value: f64,
    },
    /// The initial state or covariance has a NaN, an infinity or a negative variance.
    #[error("the initial state must be finite with variances finite and not negative")]
    InvalidInitialState,
    /// A sensor's rejection threshold is not a positive number.
    #[error("sensor {sensor}: rejection threshold {value} must be finite and positive")]
    InvalidThreshold {
        /// The sensor's name.
        sensor: String,
        /// The rejected value.
        value: f64,
    },
    /// The measurement names a sensor the filter does not have.
    #[error("measurement at {stamp} s names sensor {sensor}, but the filter has {count}")]
    UnknownSensor {
        /// The index given.
        sensor: usize,
        /// The measurement's stamp.
        stamp: f64,
        /// How many sensors the filter has.
        count: usize,
    },
    /// The stamp is NaN or infinite.
    #[error("{sensor}: the stamp {stamp} is not a finite time")]
    NonFiniteStamp {
        /// The sensor's name.
        sensor: String,
        /// The stamp.
        stamp: f64,
    },
    /// A fused value or covariance entry is NaN or infinite.
    #[error("{sensor} at {stamp:.3} s: the reading has a NaN or infinite value; skipped")]
    NonFiniteReading {
        /// The sensor's name.
        sensor: String,
        /// The stamp.
        stamp: f64,
    },
    /// A fused variable's variance is zero or negative.
    #[error(
        "{sensor} at {stamp:.3} s: the variance of {variable} is {value}; noise must be positive; skipped"
    )]
    NonPositiveNoise {
        /// The sensor's name.
        sensor: String,
        /// The stamp.
        stamp: f64,
        /// The measured variable.
        variable: &'static str,
        /// The variance given.
        value: f64,
    },
    /// The stamp is before the filter's start (its first prediction).
    #[error("{sensor} at {stamp:.3} s: before the filter's start at {start:.3} s; skipped")]
    BeforeStart {
        /// The sensor's name.
        sensor: String,
        /// The stamp.
        stamp: f64,
        /// The filter's start time.
        start: f64,
    },
    /// The stamp is older than the filter's current time: a later measurement has
    /// already been applied (time went backwards).
    #[error(
        "{sensor} at {stamp:.3} s: older than the filter's time {now:.3} s (time went backwards); skipped"
    )]
    TimeWentBackwards {
        /// The sensor's name.
        sensor: String,
        /// The stamp.
        stamp: f64,
        /// The filter's time.
        now: f64,
    },
    /// Two differential readings with the same stamp cannot make a velocity.
    #[error("{sensor} at {stamp:.3} s: no time since the previous pose; skipped")]
    ZeroInterval {
        /// The sensor's name.
        sensor: String,
        /// The stamp.
        stamp: f64,
    },
    /// The sensor's selection picks nothing its readings carry.
    #[error("{sensor}: its selection fuses nothing of a {kind} reading")]
    NothingToFuse {
        /// The sensor's name.
        sensor: String,
        /// The reading's kind.
        kind: &'static str,
    },
    /// The innovation covariance is not positive definite, or a result came out
    /// NaN or infinite.
    #[error("{sensor} at {stamp:.3} s: {what}; the update was skipped")]
    Numerical {
        /// The sensor's name.
        sensor: String,
        /// The stamp.
        stamp: f64,
        /// What failed.
        what: &'static str,
    },
}

/// How many measurements the filter applied, rejected and skipped.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct FusionStats {
    /// Measurements fused into the state.
    pub fused: usize,
    /// Pose readings only stored (the first reading in differential mode).
    pub stored: usize,
    /// Measurements rejected by the Mahalanobis test.
    pub rejected: usize,
    /// Skipped: NaN or infinite readings or stamps.
    pub non_finite: usize,
    /// Skipped: zero or negative noise.
    pub bad_noise: usize,
    /// Skipped: stamped before the filter's start.
    pub before_start: usize,
    /// Skipped: older than the filter's time (time went backwards).
    pub out_of_order: usize,
    /// Skipped: unknown sensor or nothing to fuse.
    pub unusable: usize,
    /// Skipped: numerical failure (innovation covariance not positive definite,
    /// zero interval between differential poses).
    pub numerical: usize,
}

impl FusionStats {
    /// Total number of skipped measurements.
    pub fn skipped(&self) -> usize {
        self.non_finite
            + self.bad_noise
            + self.before_start
            + self.out_of_order
            + self.unusable
            + self.numerical
    }

    /// Counts a skipped measurement under its reason.
    fn count(&mut self, error: &FusionError) {
        match error {
            FusionError::NonFiniteStamp { .. } | FusionError::NonFiniteReading { .. } => {
                self.non_finite += 1;
            }
            FusionError::NonPositiveNoise { .. } => self.bad_noise += 1,
            FusionError::BeforeStart { .. } => self.before_start += 1,
            FusionError::TimeWentBackwards { .. } => self.out_of_order += 1,
            FusionError::UnknownSensor { .. } | FusionError::NothingToFuse { .. } => {
                self.unusable += 1;
            }
            _ => self.numerical += 1,
        }
    }
}
