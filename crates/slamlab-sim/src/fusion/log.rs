//! One drive's record: the truth and every sensor reading of one seeded drive
//! ([`SensorLog`]), so that every fusion mode runs on exactly the same data.

use slamlab_core::geometry::{Pose2, wrap_angle};
use slamlab_core::kalman::fusion::{Measurement, Reading};

/// The wheel odometry's sensor index in every fusion filter.
pub const ODOMETRY: usize = 0;
/// The IMU's sensor index.
pub const IMU: usize = 1;
/// The SLAM pose's sensor index.
pub const SLAM: usize = 2;

/// The true state at one tick.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TruthSample {
    /// Time, seconds.
    pub t: f64,
    /// The robot's pose.
    pub pose: Pose2,
    /// Forward speed, m/s.
    pub v: f64,
    /// Yaw rate, rad/s.
    pub w: f64,
}

/// A reading with the time it reaches the filter (its stamp plus any latency).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Arrival {
    /// When the filter receives it, seconds.
    pub arrival: f64,
    /// The stamped reading.
    pub measurement: Measurement,
}

impl Arrival {
    /// `reading` of `sensor`, taken at `stamp` and received at `arrival`.
    pub fn new(sensor: usize, stamp: f64, arrival: f64, reading: Reading) -> Self {
        Arrival {
            arrival,
            measurement: Measurement {
                sensor,
                stamp,
                reading,
            },
        }
    }
}

/// The truth and every sensor reading of one drive.
#[derive(Clone, Debug, PartialEq)]
pub struct SensorLog {
    /// The truth at every tick, `truth[k].t = k · truth_dt`.
    pub truth: Vec<TruthSample>,
    /// The truth's tick, seconds.
    pub truth_dt: f64,
    /// Every reading of every sensor, in order of arrival (equal arrivals in
    /// stamp order).
    pub measurements: Vec<Arrival>,
    /// The raw odometry integrated alone (dead reckoning), at each odometry reading.
    pub odometry_path: Vec<(f64, Pose2)>,
    /// The SLAM poses as reported, with their stamps.
    pub slam_poses: Vec<(f64, Pose2)>,
    /// When the SLAM map relocalized (its drift reset: a jump).
    pub relocalizations: Vec<f64>,
    /// The gyroscope bias at each IMU reading, rad/s (for plots).
    pub gyro_bias: Vec<(f64, f64)>,
}

impl SensorLog {
    /// The true pose at time `t`, interpolated between ticks (clamped to the drive).
    pub fn truth_at(&self, t: f64) -> Pose2 {
        let Some(last) = self.truth.last() else {
            return Pose2::IDENTITY;
        };
        let u = (t / self.truth_dt).max(0.0);
        let k = u.floor() as usize;
        if k + 1 >= self.truth.len() {
            return last.pose;
        }
        let (a, b) = (self.truth[k].pose, self.truth[k + 1].pose);
        let f = u - k as f64;
        Pose2::new(
            a.x + f * (b.x - a.x),
            a.y + f * (b.y - a.y),
            a.theta + f * wrap_angle(b.theta - a.theta),
        )
    }

    /// The drive's length, seconds.
    pub fn duration(&self) -> f64 {
        self.truth.last().map_or(0.0, |s| s.t)
    }
}
