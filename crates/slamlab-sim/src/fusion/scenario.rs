//! The fusion lesson's scenario: the drive, the three simulated sensors and the
//! filter's own parameters, as plain serde data with defaults.
//!
//! The defaults describe the thesis's robot (thesis `002` ch. 3 and 5): a Clearpath
//! Jackal driven by joystick at 0.05 m/s on average and at most 0.1 m/s inside a
//! motion-capture room, wheel odometry from 1024-CPR encoders on a skid-steered
//! base, an MPU-9250 IMU (gyroscope noise 0.1 °/s RMS, accelerometer 8 mg RMS,
//! thesis Table 3.1), and RTAB-Map's pose at about 1 Hz.

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// How the robot drives.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DriveKind {
    /// A tour of seeded random waypoints inside the room, with speed and turn-rate
    /// limits and smooth acceleration (a joystick drive).
    Waypoints,
    /// Forward speed and yaw rate are independent random walks with the given
    /// spectral densities (m²/s³ and rad²/s³): exactly the filter's
    /// constant-velocity model with white-noise acceleration, for consistency tests.
    RandomWalk {
        /// Spectral density of the forward acceleration, m²/s³.
        speed_density: f64,
        /// Spectral density of the yaw acceleration, rad²/s³.
        turn_density: f64,
    },
}

/// The drive.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct DriveParams {
    /// What kind of drive.
    pub kind: DriveKind,
    /// Length of the drive, seconds.
    pub duration: f64,
    /// Rate of the ground-truth integration, Hz (every sensor samples the truth at
    /// the nearest tick at or after its sample time).
    pub truth_rate: f64,
    /// Standstill at the start, seconds (as a trial starts).
    pub standstill: f64,
    /// The room's size `[along x, along y]`, metres, centred on the start.
    pub room: [f64; 2],
    /// Top forward speed, m/s (thesis: 0.1).
    pub max_speed: f64,
    /// Top yaw rate, rad/s.
    pub max_turn_rate: f64,
    /// Largest change of forward speed, m/s².
    pub max_acceleration: f64,
    /// Largest change of yaw rate, rad/s².
    pub max_turn_acceleration: f64,
}

impl Default for DriveParams {
    fn default() -> Self {
        Self {
            kind: DriveKind::Waypoints,
            duration: 300.0,
            truth_rate: 200.0,
            standstill: 2.0,
            room: [4.0, 3.0],
            max_speed: 0.1,
            max_turn_rate: 0.3,
            max_acceleration: 0.1,
            max_turn_acceleration: 0.5,
        }
    }
}

/// Wheel odometry (`diff_drive_controller`'s twist).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct OdometryParams {
    /// Whether the sensor is used.
    pub enabled: bool,
    /// Rate, Hz.
    pub rate: f64,
    /// Track width between the left and right wheels, metres (Jackal: 0.37).
    pub wheel_base: f64,
    /// Standard deviation of each wheel's scale error (a wrong wheel radius),
    /// drawn once per drive: it makes the distance and the heading drift.
    pub scale_error_std: f64,
    /// Skid while turning: the wheels report a yaw rate `(1 + turn_slip)` times the
    /// body's (a skid-steered base turns less than its wheels say).
    pub turn_slip: f64,
    /// White noise on the reported forward speed, m/s.
    pub speed_noise_std: f64,
    /// White noise on the reported yaw rate, rad/s.
    pub turn_noise_std: f64,
    /// The standard deviation the twist message reports for the sideways
    /// velocity (a differential drive cannot move sideways: robot_localization's
    /// advice is to fuse `v_y = 0`), m/s.
    pub lateral_std: f64,
}

impl Default for OdometryParams {
    fn default() -> Self {
        Self {
            enabled: true,
            rate: 50.0,
            wheel_base: 0.37,
            scale_error_std: 0.02,
            turn_slip: 0.05,
            speed_noise_std: 0.005,
            turn_noise_std: 0.01,
            lateral_std: 0.005,
        }
    }
}

/// The IMU.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ImuParams {
    /// Whether the sensor is used.
    pub enabled: bool,
    /// Rate, Hz.
    pub rate: f64,
    /// White noise on the yaw rate, rad/s (MPU-9250: 0.1 °/s RMS).
    pub gyro_noise_std: f64,
    /// Standard deviation of the gyroscope bias at the start, rad/s.
    pub gyro_bias_std: f64,
    /// Random walk of the gyroscope bias, rad/s per √s.
    pub gyro_bias_walk: f64,
    /// Whether the linear acceleration is fused too (then the filter estimates
    /// accelerations: the constant-acceleration model).
    pub fuse_acceleration: bool,
    /// White noise on each acceleration, m/s² (MPU-9250: 8 mg RMS).
    pub accel_noise_std: f64,
}

impl Default for ImuParams {
    fn default() -> Self {
        Self {
            enabled: true,
            rate: 100.0,
            gyro_noise_std: 0.1_f64.to_radians(),
            gyro_bias_std: 0.001,
            gyro_bias_walk: 2e-5,
            fuse_acceleration: false,
            accel_noise_std: 0.008 * 9.80665,
        }
    }
}

/// Where the SLAM pose comes from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SlamSource {
    /// The truth plus white noise, map drift and relocalization jumps (the
    /// parameters below).
    #[default]
    Simulated,
    /// The landmark lesson's EKF-SLAM on the same drive (its estimate and
    /// covariance; the noise, drift and outlier parameters below are then unused).
    LandmarkEkf,
}

/// The SLAM pose (RTAB-Map's `PoseWithCovarianceStamped`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SlamParams {
    /// Whether the sensor is used (the odometry-only baseline never uses it).
    pub enabled: bool,
    /// Rate, Hz.
    pub rate: f64,
    /// Where the poses come from.
    pub source: SlamSource,
    /// White noise on x and y, metres.
    pub position_noise_std: f64,
    /// White noise on the heading, radians.
    pub yaw_noise_std: f64,
    /// Whether the heading is fused (thesis Sec. 5.2.1: full pose and position only
    /// performed alike).
    pub fuse_yaw: bool,
    /// Drift of the map between relocalizations: a random walk of the pose's
    /// offset, metres per √s (the heading drifts by this per metre, in radians).
    pub drift_per_sqrt_s: f64,
    /// Mean time between relocalizations (loop closures) that reset the drift,
    /// seconds; 0 for never. Each reset is a jump in the reported pose.
    pub relocalization_interval: f64,
    /// Probability that a reading is a wrong relocalization (an outlier).
    pub outlier_probability: f64,
    /// Size of an outlier's position error, metres (standard deviation).
    pub outlier_std: f64,
    /// Delay between a pose's stamp and its arrival at the filter, seconds.
    pub latency: f64,
    /// Mahalanobis rejection threshold in standard deviations; `None` fuses every pose.
    pub rejection_threshold: Option<f64>,
}

impl Default for SlamParams {
    fn default() -> Self {
        Self {
            enabled: true,
            rate: 1.0,
            source: SlamSource::Simulated,
            position_noise_std: 0.05,
            yaw_noise_std: 0.05,
            fuse_yaw: true,
            drift_per_sqrt_s: 0.005,
            relocalization_interval: 60.0,
            outlier_probability: 0.0,
            outlier_std: 0.3,
            latency: 0.0,
            rejection_threshold: None,
        }
    }
}

/// Everything a fusion run needs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FusionScenario {
    /// The seed of every random stream (drive, each sensor).
    pub seed: u64,
    /// The drive.
    pub drive: DriveParams,
    /// Wheel odometry.
    pub odometry: OdometryParams,
    /// The IMU.
    pub imu: ImuParams,
    /// The SLAM pose.
    pub slam: SlamParams,
    /// The filter's process-noise densities (robot_localization's diagonal of
    /// `process_noise_covariance`, in state order x, y, ψ, v_x, v_y, ψ̇, a_x, a_y).
    pub process_noise: [f64; 8],
    /// The filter's initial variance of every state variable (the robot starts at
    /// the origin at rest, which the simulator knows exactly). robot_localization's
    /// `initial_estimate_covariance` defaults to 1e-9.
    pub initial_variance: f64,
    /// Rate at which the fused estimate is sampled for plots and RMSE, Hz
    /// (robot_localization's `frequency`; the thesis's 30 Hz).
    pub output_rate: f64,
    /// How long the filter waits for late measurements before it processes a
    /// stamp, seconds (a pose arriving later than this is skipped as out of order).
    pub filter_delay: f64,
}

impl Default for FusionScenario {
    fn default() -> Self {
        Self {
            seed: 1,
            drive: DriveParams::default(),
            odometry: OdometryParams::default(),
            imu: ImuParams::default(),
            slam: SlamParams::default(),
            // robot_localization's defaults for the planar variables.
            process_noise: [0.05, 0.05, 0.06, 0.025, 0.025, 0.02, 0.01, 0.01],
            initial_variance: 1e-9,
            output_rate: 30.0,
            filter_delay: 0.0,
        }
    }
}

/// A scenario parameter that cannot be used.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum ScenarioError {
    /// A parameter is NaN, infinite or out of its range.
    #[error("fusion parameter {name} = {value} is not allowed: {expected}")]
    Invalid {
        /// The parameter's name (dotted path).
        name: &'static str,
        /// The value given.
        value: f64,
        /// What is allowed.
        expected: &'static str,
    },
    /// The drive is too long (the truth would take too much memory).
    #[error(
        "the drive has {ticks} truth ticks; at most {max} are allowed (shorten the drive or lower the truth rate)"
    )]
    TooLong {
        /// Ticks asked for.
        ticks: f64,
        /// The limit.
        max: usize,
    },
}

/// Most truth ticks a drive may have (an hour at 1 kHz).
pub const MAX_TRUTH_TICKS: usize = 3_600_000;

impl FusionScenario {
    /// Checks every parameter; a rate of 0, a negative noise or a NaN anywhere is
    /// refused with the parameter's name.
    pub fn validate(&self) -> Result<(), ScenarioError> {
        let positive = "a finite number above 0";
        let non_negative = "a finite number, 0 or more";
        let probability = "a probability in [0, 1]";
        let checks: [(&'static str, f64, &'static str, bool); 30] = {
            let d = &self.drive;
            let o = &self.odometry;
            let i = &self.imu;
            let s = &self.slam;
            let pos = |v: f64| v.is_finite() && v > 0.0;
            let nn = |v: f64| v.is_finite() && v >= 0.0;
            [
                ("drive.duration", d.duration, positive, pos(d.duration)),
                (
                    "drive.truth_rate",
                    d.truth_rate,
                    positive,
                    pos(d.truth_rate),
                ),
                (
                    "drive.standstill",
                    d.standstill,
                    non_negative,
                    nn(d.standstill),
                ),
                ("drive.room[0]", d.room[0], positive, pos(d.room[0])),
                ("drive.room[1]", d.room[1], positive, pos(d.room[1])),
                ("drive.max_speed", d.max_speed, positive, pos(d.max_speed)),
                (
                    "drive.max_turn_rate",
                    d.max_turn_rate,
                    positive,
                    pos(d.max_turn_rate),
                ),
                (
                    "drive.max_acceleration",
                    d.max_acceleration,
                    positive,
                    pos(d.max_acceleration),
                ),
                (
                    "drive.max_turn_acceleration",
                    d.max_turn_acceleration,
                    positive,
                    pos(d.max_turn_acceleration),
                ),
                ("odometry.rate", o.rate, positive, pos(o.rate)),
                (
                    "odometry.wheel_base",
                    o.wheel_base,
                    positive,
                    pos(o.wheel_base),
                ),
                (
                    "odometry.scale_error_std",
                    o.scale_error_std,
                    non_negative,
                    nn(o.scale_error_std),
                ),
                (
                    "odometry.turn_slip",
                    o.turn_slip,
                    "a finite number above -1",
                    o.turn_slip.is_finite() && o.turn_slip > -1.0,
                ),
                (
                    "odometry.speed_noise_std",
                    o.speed_noise_std,
                    positive,
                    pos(o.speed_noise_std),
                ),
                (
                    "odometry.turn_noise_std",
                    o.turn_noise_std,
                    positive,
                    pos(o.turn_noise_std),
                ),
                (
                    "odometry.lateral_std",
                    o.lateral_std,
                    positive,
                    pos(o.lateral_std),
                ),
                ("imu.rate", i.rate, positive, pos(i.rate)),
                (
                    "imu.gyro_noise_std",
                    i.gyro_noise_std,
                    positive,
                    pos(i.gyro_noise_std),
                ),
                (
                    "imu.gyro_bias_std",
                    i.gyro_bias_std,
                    non_negative,
                    nn(i.gyro_bias_std),
                ),
                (
                    "imu.gyro_bias_walk",
                    i.gyro_bias_walk,
                    non_negative,
                    nn(i.gyro_bias_walk),
                ),
                (
                    "imu.accel_noise_std",
                    i.accel_noise_std,
                    positive,
                    pos(i.accel_noise_std),
                ),
                ("slam.rate", s.rate, positive, pos(s.rate)),
                (
                    "slam.position_noise_std",
                    s.position_noise_std,
                    positive,
                    pos(s.position_noise_std),
                ),
                (
                    "slam.yaw_noise_std",
                    s.yaw_noise_std,
                    positive,
                    pos(s.yaw_noise_std),
                ),
                (
                    "slam.drift_per_sqrt_s",
                    s.drift_per_sqrt_s,
                    non_negative,
                    nn(s.drift_per_sqrt_s),
                ),
                (
                    "slam.relocalization_interval",
                    s.relocalization_interval,
                    non_negative,
                    nn(s.relocalization_interval),
                ),
                (
                    "slam.outlier_probability",
                    s.outlier_probability,
                    probability,
                    (0.0..=1.0).contains(&s.outlier_probability),
                ),
                (
                    "slam.outlier_std",
                    s.outlier_std,
                    non_negative,
                    nn(s.outlier_std),
                ),
                ("slam.latency", s.latency, non_negative, nn(s.latency)),
                (
                    "output_rate",
                    self.output_rate,
                    positive,
                    pos(self.output_rate),
                ),
            ]
        };
        for (name, value, expected, ok) in checks {
            if !ok {
                return Err(ScenarioError::Invalid {
                    name,
                    value,
                    expected,
                });
            }
        }
        if !(self.initial_variance.is_finite() && self.initial_variance >= 0.0) {
            return Err(ScenarioError::Invalid {
                name: "initial_variance",
                value: self.initial_variance,
                expected: non_negative,
            });
        }
        if !(self.filter_delay.is_finite() && self.filter_delay >= 0.0) {
            return Err(ScenarioError::Invalid {
                name: "filter_delay",
                value: self.filter_delay,
                expected: non_negative,
            });
        }
        if let Some(t) = self.slam.rejection_threshold
            && !(t.is_finite() && t > 0.0)
        {
            return Err(ScenarioError::Invalid {
                name: "slam.rejection_threshold",
                value: t,
                expected: positive,
            });
        }
        if let DriveKind::RandomWalk {
            speed_density,
            turn_density,
        } = self.drive.kind
        {
            for (name, v) in [
                ("drive.kind.speed_density", speed_density),
                ("drive.kind.turn_density", turn_density),
            ] {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(ScenarioError::Invalid {
                        name,
                        value: v,
                        expected: non_negative,
                    });
                }
            }
        }
        for (k, &q) in self.process_noise.iter().enumerate() {
            if !(q.is_finite() && q >= 0.0) {
                const NAMES: [&str; 8] = [
                    "process_noise[0] (x)",
                    "process_noise[1] (y)",
                    "process_noise[2] (yaw)",
                    "process_noise[3] (v_x)",
                    "process_noise[4] (v_y)",
                    "process_noise[5] (yaw rate)",
                    "process_noise[6] (a_x)",
                    "process_noise[7] (a_y)",
                ];
                return Err(ScenarioError::Invalid {
                    name: NAMES[k],
                    value: q,
                    expected: non_negative,
                });
            }
        }
        let ticks = self.drive.duration * self.drive.truth_rate;
        if !(ticks <= MAX_TRUTH_TICKS as f64) {
            return Err(ScenarioError::TooLong {
                ticks,
                max: MAX_TRUTH_TICKS,
            });
        }
        Ok(())
    }
}
