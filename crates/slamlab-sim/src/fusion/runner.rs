//! Fusing one drive's sensor data in each mode, and the metrics against the truth.

use super::log::{IMU, ODOMETRY, SLAM, SensorLog};
use super::scenario::{FusionScenario, ScenarioError};
use nalgebra::{Matrix3, Vector3};
use serde::Serialize;
use slamlab_core::geometry::{Pose2, wrap_angle};
use slamlab_core::kalman::fusion::{
    FusionConfig, FusionEkf, FusionError, Outcome, PoseMode, SensorConfig, StateIndex, StateMatrix,
    StateVector, StepReport,
};

/// How a run uses the sensors: the odometry-only baseline (wheel odometry and
/// IMU, the thesis's local EKF) or the global EKF with the SLAM pose in one of
/// robot_localization's three modes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FusionMode {
    /// Wheel odometry and IMU only.
    Odometry,
    /// Plus the SLAM pose as it is.
    Absolute,
    /// Plus the SLAM pose relative to its first reading (`_relative`).
    Relative,
    /// Plus the SLAM pose differenced into a velocity (`_differential`).
    Differential,
}

impl FusionMode {
    /// Every mode.
    pub const ALL: [FusionMode; 4] = [
        FusionMode::Differential,
        FusionMode::Relative,
        FusionMode::Absolute,
        FusionMode::Odometry,
    ];
    /// The modes of thesis Table 5.3 and the baseline, in the experiment's order.
    pub const TABLE: [FusionMode; 3] = [
        FusionMode::Differential,
        FusionMode::Relative,
        FusionMode::Odometry,
    ];

    /// The mode's name ("differential", "relative", "absolute", "odometry").
    pub fn name(self) -> &'static str {
        match self {
            FusionMode::Odometry => "odometry",
            FusionMode::Absolute => "absolute",
            FusionMode::Relative => "relative",
            FusionMode::Differential => "differential",
        }
    }

    /// The SLAM pose's mode, or `None` for the odometry-only baseline.
    pub fn pose_mode(self) -> Option<PoseMode> {
        match self {
            FusionMode::Odometry => None,
            FusionMode::Absolute => Some(PoseMode::Absolute),
            FusionMode::Relative => Some(PoseMode::Relative),
            FusionMode::Differential => Some(PoseMode::Differential),
        }
    }
}

/// The filter configured for `mode`: sensors at the fixed indices [`ODOMETRY`],
/// [`IMU`], [`SLAM`]; wheel odometry fuses v_x, v_y (= 0) and the yaw rate; the IMU
/// the yaw rate (and a_x with `fuse_acceleration`); the SLAM pose x, y (and ψ with
/// `fuse_yaw`). The robot starts at the origin at rest, with the scenario's
/// `initial_variance` on every variable (robot_localization's default 1e-9).
pub fn filter_for(scenario: &FusionScenario, mode: FusionMode) -> Result<FusionEkf, FusionError> {
    let mut imu = vec![StateIndex::YawRate];
    if scenario.imu.fuse_acceleration {
        imu.push(StateIndex::AX);
    }
    let mut slam = vec![StateIndex::X, StateIndex::Y];
    if scenario.slam.fuse_yaw {
        slam.push(StateIndex::Yaw);
    }
    let sensors = vec![
        SensorConfig::new(
            "wheel odometry",
            &[StateIndex::VX, StateIndex::VY, StateIndex::YawRate],
        ),
        SensorConfig::new("IMU", &imu),
        SensorConfig::new("SLAM pose", &slam).with_pose_mode(
            mode.pose_mode().unwrap_or_default(),
            scenario.slam.rejection_threshold,
        ),
    ];
    let config = FusionConfig {
        process_noise: scenario.process_noise,
        use_acceleration: scenario.imu.fuse_acceleration,
    };
    FusionEkf::new(
        config,
        sensors,
        0.0,
        StateVector::zeros(),
        StateMatrix::identity() * scenario.initial_variance,
    )
}

/// The estimate against the truth at one output time.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Sample {
    /// Time, seconds.
    pub t: f64,
    /// The true pose.
    pub truth: Pose2,
    /// The fused pose.
    pub estimate: Pose2,
    /// Estimate minus truth `[x m, y m, ψ rad]`, heading wrapped.
    pub error: [f64; 3],
    /// The filter's standard deviations of x, y, ψ (plots show ±2σ).
    pub sigma: [f64; 3],
    /// The pose NEES `eᵀ P⁻¹ e` (3 dof), when the pose covariance is positive definite.
    pub nees: Option<f64>,
    /// The 2x2 position covariance, for ellipses (row-major).
    pub position_covariance: [f64; 4],
}

/// How much one SLAM update moved the position estimate.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SlamJump {
    /// The update's stamp, seconds.
    pub t: f64,
    /// `|x_after − x_before|` of the position, metres.
    pub jump: f64,
}

/// Root-mean-square error of x, y (metres) and yaw (radians): one row of thesis
/// Table 5.3.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Rmse {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// yaw, radians.
    pub yaw: f64,
}

/// One mode's filter fed one drive's data, advanced in time; the lesson steps it,
/// the experiment runs it to the end.
#[derive(Clone, Debug)]
pub struct ModeRun {
    mode: FusionMode,
    filter: FusionEkf,
    output_period: f64,
    filter_delay: f64,
    uses: [bool; 3],
    next_arrival: usize,
    next_output: usize,
    now: f64,
    samples: Vec<Sample>,
    slam_jumps: Vec<SlamJump>,
}

impl ModeRun {
    /// A run of `mode` on `scenario`'s sensors.
    pub fn new(scenario: &FusionScenario, mode: FusionMode) -> Result<Self, ScenarioError> {
        scenario.validate()?;
        let filter = filter_for(scenario, mode).map_err(|e| ScenarioError::Invalid {
            name: "filter",
            value: f64::NAN,
            expected: match e {
                FusionError::InvalidProcessNoise { .. } => "process noise finite and not negative",
                _ => "a valid filter configuration",
            },
        })?;
        Ok(Self {
            mode,
            filter,
            output_period: 1.0 / scenario.output_rate,
            filter_delay: scenario.filter_delay,
            uses: [
                scenario.odometry.enabled,
                scenario.imu.enabled,
                scenario.slam.enabled && mode != FusionMode::Odometry,
            ],
            next_arrival: 0,
            next_output: 0,
            now: 0.0,
            samples: Vec::new(),
            slam_jumps: Vec::new(),
        })
    }

    /// The mode.
    pub fn mode(&self) -> FusionMode {
        self.mode
    }

    /// The filter (mean, covariance, queue, counts).
    pub fn filter(&self) -> &FusionEkf {
        &self.filter
    }

    /// The run's time, seconds.
    pub fn now(&self) -> f64 {
        self.now
    }

    /// The estimate against the truth at every output time so far.
    pub fn samples(&self) -> &[Sample] {
        &self.samples
    }

    /// Every fused SLAM update's position jump.
    pub fn slam_jumps(&self) -> &[SlamJump] {
        &self.slam_jumps
    }

    /// The largest position jump at a SLAM update, metres.
    pub fn max_slam_jump(&self) -> f64 {
        self.slam_jumps.iter().map(|j| j.jump).fold(0.0, f64::max)
    }

    /// Whether this run feeds the filter `sensor`'s readings.
    pub fn uses(&self, sensor: usize) -> bool {
        self.uses.get(sensor).copied().unwrap_or(false)
    }

    /// Switches a sensor on or off from now on (the lesson's toggles).
    pub fn set_uses(&mut self, sensor: usize, on: bool) {
        if let Some(u) = self.uses.get_mut(sensor) {
            *u = on && !(sensor == SLAM && self.mode == FusionMode::Odometry);
        }
    }

    /// Advances the run to time `t`: hands the filter every reading that has
    /// arrived by then, applies those stamped up to `t − filter_delay` one at a time
    /// (calling `on_step` with each report), and samples the estimate at every
    /// output time up to `t` (and up to the end of the drive; `t` may be infinite).
    pub fn advance_to(&mut self, log: &SensorLog, t: f64, mut on_step: impl FnMut(&StepReport)) {
        let end = log.duration();
        loop {
            let output_t = self.next_output as f64 * self.output_period;
            if !(output_t <= t && output_t <= end) {
                break;
            }
            self.feed(log, output_t, &mut on_step);
            self.sample(log, output_t);
            self.next_output += 1;
        }
        self.feed(log, t, &mut on_step);
        self.now = self.now.max(if t.is_finite() { t } else { end });
    }

    /// Runs to the end of the drive.
    pub fn run_to_end(&mut self, log: &SensorLog) {
        self.advance_to(log, log.duration(), |_| {});
    }

    /// The RMSE of x, y and yaw over every output sample.
    pub fn rmse(&self) -> Rmse {
        let n = self.samples.len().max(1) as f64;
        let ms =
            |k: usize| (self.samples.iter().map(|s| s.error[k].powi(2)).sum::<f64>() / n).sqrt();
        Rmse {
            x: ms(0),
            y: ms(1),
            yaw: ms(2),
        }
    }

    /// Applies exactly one measurement, the next one due (in arrival order, each
    /// applied once the filter's delay has passed), sampling the outputs on the
    /// way: the lesson's "step one measurement". `None` when every reading of the
    /// drive has been applied (the remaining outputs are then sampled). Stepping
    /// to the end gives the same samples as [`ModeRun::run_to_end`].
    pub fn step_one(&mut self, log: &SensorLog) -> Option<StepReport> {
        let end = log.duration();
        loop {
            self.receive(log, self.now);
            if let Some(report) = self.apply_ready_one(self.now) {
                return Some(report);
            }
            let next_arrival = log.measurements.get(self.next_arrival).map(|a| a.arrival);
            let next_release = self
                .filter
                .pending()
                .next()
                .map(|m| m.stamp + self.filter_delay);
            let t = match (next_arrival, next_release) {
                (Some(a), Some(r)) => a.min(r),
                (Some(a), None) => a,
                (None, Some(r)) => r,
                (None, None) => {
                    self.sample_until(log, end, true);
                    self.now = self.now.max(end);
                    return None;
                }
            };
            let t = t.max(self.now);
            self.sample_until(log, t.min(end), t > end);
            self.now = t;
        }
    }

    /// Samples every output time before `t` (and at `t` when `inclusive`).
    fn sample_until(&mut self, log: &SensorLog, t: f64, inclusive: bool) {
        loop {
            let output_t = self.next_output as f64 * self.output_period;
            if output_t < t || (inclusive && output_t <= t) {
                self.sample(log, output_t);
                self.next_output += 1;
            } else {
                break;
            }
        }
    }

    /// Hands the filter every reading (of a sensor in use) that has arrived by `t`.
    fn receive(&mut self, log: &SensorLog, t: f64) {
        while let Some(a) = log.measurements.get(self.next_arrival) {
            if a.arrival > t {
                break;
            }
            if self.uses(a.measurement.sensor) {
                self.filter.enqueue(a.measurement);
            }
            self.next_arrival += 1;
        }
    }

    /// Applies the earliest queued measurement if its delay has passed by `now`.
    fn apply_ready_one(&mut self, now: f64) -> Option<StepReport> {
        let front = self.filter.pending().next().copied()?;
        if front.stamp.is_finite() && front.stamp + self.filter_delay > now {
            return None;
        }
        // The SLAM updates' jumps: the position predicted to the stamp, before.
        let before = if front.sensor == SLAM {
            self.filter.predicted_at(front.stamp).map(|(m, _)| m)
        } else {
            None
        };
        let report = self.filter.step()?;
        if front.sensor == SLAM
            && let (Outcome::Updated(u), Some(before)) = (&report.outcome, before)
            && !u.rejected
        {
            let after = self.filter.mean();
            self.slam_jumps.push(SlamJump {
                t: front.stamp,
                jump: ((after[0] - before[0]).powi(2) + (after[1] - before[1]).powi(2)).sqrt(),
            });
        }
        Some(report)
    }

    fn feed(&mut self, log: &SensorLog, t: f64, on_step: &mut impl FnMut(&StepReport)) {
        self.receive(log, t);
        while let Some(report) = self.apply_ready_one(t) {
            on_step(&report);
        }
    }

    fn sample(&mut self, log: &SensorLog, t: f64) {
        let (mean, cov) = self
            .filter
            .predicted_at(t)
            .unwrap_or((*self.filter.mean(), *self.filter.covariance()));
        let truth = log.truth_at(t);
        let estimate = Pose2::new(mean[0], mean[1], mean[2]);
        let error = [
            estimate.x - truth.x,
            estimate.y - truth.y,
            wrap_angle(estimate.theta - truth.theta),
        ];
        let pose_cov: Matrix3<f64> = cov.fixed_view::<3, 3>(0, 0).into_owned();
        let e = Vector3::from(error);
        let nees = pose_cov
            .cholesky()
            .map(|c| e.dot(&c.solve(&e)))
            .filter(|v| v.is_finite());
        self.samples.push(Sample {
            t,
            truth,
            estimate,
            error,
            sigma: [
                pose_cov[(0, 0)].max(0.0).sqrt(),
                pose_cov[(1, 1)].max(0.0).sqrt(),
                pose_cov[(2, 2)].max(0.0).sqrt(),
            ],
            nees,
            position_covariance: [
                pose_cov[(0, 0)],
                pose_cov[(0, 1)],
                pose_cov[(1, 0)],
                pose_cov[(1, 1)],
            ],
        });
    }
}

/// Runs every mode in `modes` on the same sensor data to the end.
pub fn run_modes(
    scenario: &FusionScenario,
    log: &SensorLog,
    modes: &[FusionMode],
) -> Result<Vec<ModeRun>, ScenarioError> {
    modes
        .iter()
        .map(|&mode| {
            let mut run = ModeRun::new(scenario, mode)?;
            run.run_to_end(log);
            Ok(run)
        })
        .collect()
}

/// The sensor indices, for readers of [`ModeRun::uses`].
pub const SENSORS: [(usize, &str); 3] = [
    (ODOMETRY, "wheel odometry"),
    (IMU, "IMU"),
    (SLAM, "SLAM pose"),
];
