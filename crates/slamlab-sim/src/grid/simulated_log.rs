//! Simulated laser logs with ground truth: the explorer drives the round robot
//! through a map, wheel odometry drifts, the lidar scans; the result is a
//! [`LaserLog`] (what a real robot would have recorded) and, apart, the true
//! poses (which reach only metrics).
//!
//! The same pieces and random streams as the Monte Carlo localization run
//! (`localization::run`): the start pose from stream 1, lidar noise from
//! stream 2, odometry noise from stream 3, the explorer's goals from stream 4,
//! each derived from the seed.

use crate::grid::explorer::{Explorer, ExplorerConfig};
use crate::grid::lidar::Lidar;
use crate::grid::robot::{GridRobot, OdometrySensor, ROBOT_ODOMETRY_NOISE};
use crate::io::laser_log::{LaserKind, LaserLog, LogOdometry, LogScan, TruePose};
use crate::noise::stream_seed;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use slamlab_core::Pose2;
use slamlab_core::grid::{Costmap, FreeCells, OccupancyGrid};
use slamlab_core::odometry::OdometryNoise;
use std::f64::consts::TAU;

/// The most steps one simulated log may have (360-beam scans take about
/// 6 kB each in memory).
pub const MAX_SIMULATED_STEPS: usize = 50_000;

/// How a simulated log is recorded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimulatedLogConfig {
    /// Time between scans, seconds (default 0.1 s: a 10 Hz lidar).
    pub dt: f64,
    /// The lidar (default: 360 beams over 360°, 1° apart starting at -180°,
    /// 12 m maximum range, 3 cm range noise, no outliers).
    pub lidar: Lidar,
    /// Odometry noise (default: the Monte Carlo localization lesson's,
    /// α = 0.05, 0.01, 0.05, 0.01).
    pub odom_noise: OdometryNoise,
    /// The explorer (default: 0.5 m/s, 1.5 rad/s).
    pub explorer: ExplorerConfig,
    /// Robot radius, metres (default 0.2).
    pub robot_radius: f64,
}

impl Default for SimulatedLogConfig {
    fn default() -> Self {
        Self {
            dt: 0.1,
            lidar: Lidar {
                beams: 360,
                fov: TAU,
                max_range: 12.0,
                range_std: 0.03,
                outlier_prob: 0.0,
            },
            odom_noise: ROBOT_ODOMETRY_NOISE,
            explorer: ExplorerConfig::default(),
            robot_radius: 0.2,
        }
    }
}

/// Why a log cannot be simulated.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SimLogError {
    /// No free place in the map holds the robot.
    #[error("the robot (radius {0} m) fits nowhere in the map")]
    RobotDoesNotFit(f64),
    /// Too many steps.
    #[error("{0} steps is over the limit of {MAX_SIMULATED_STEPS}")]
    TooManySteps(usize),
    /// A parameter that makes no sense.
    #[error("{0}")]
    BadConfig(String),
}

/// Drives the explorer through `map` for `steps` steps of `config.dt` seconds
/// and records, at each step `k = 1..=steps` (time `k·dt`), an `ODOM` record
/// (the odometry pose and the commanded `(v, ω)`) and a `FLASER` scan taken
/// from the true pose, with the odometry pose in its odometry fields. Returns
/// the log and the true pose at each scan.
pub fn simulate_log(
    map: &OccupancyGrid,
    steps: usize,
    seed: u64,
    config: &SimulatedLogConfig,
) -> Result<(LaserLog, Vec<TruePose>), SimLogError> {
    if steps > MAX_SIMULATED_STEPS {
        return Err(SimLogError::TooManySteps(steps));
    }
    if !(config.dt > 0.0 && config.dt.is_finite()) {
        return Err(SimLogError::BadConfig(format!(
            "dt = {} s: the time step must be a positive number",
            config.dt
        )));
    }
    let lidar = config.lidar;
    if lidar.beams == 0 || lidar.beams > crate::io::laser_log::MAX_BEAMS {
        return Err(SimLogError::BadConfig(format!(
            "{} beams: the lidar needs 1 to {} beams",
            lidar.beams,
            crate::io::laser_log::MAX_BEAMS
        )));
    }
    if !(lidar.max_range > 0.0 && lidar.max_range.is_finite()) {
        return Err(SimLogError::BadConfig(format!(
            "maximum range {} m: must be a positive number",
            lidar.max_range
        )));
    }
    let radius = if config.robot_radius >= 0.0 && config.robot_radius.is_finite() {
        config.robot_radius
    } else {
        return Err(SimLogError::BadConfig(format!(
            "robot radius {} m: must be a non-negative number",
            config.robot_radius
        )));
    };
    let mut drive = ExploringRobot::place(map, Costmap::inflate(map, radius), radius, config, seed)
        .ok_or(SimLogError::RobotDoesNotFit(radius))?;
    let mut lidar_rng = ChaCha8Rng::seed_from_u64(stream_seed(seed, 2));

    let mut log = LaserLog::default();
    log.scans.reserve(steps);
    log.odometry.reserve(steps);
    let mut truth = Vec::with_capacity(steps);
    log.params
        .insert("slamlab_seed".to_string(), seed.to_string());
    log.params
        .insert("slamlab_dt".to_string(), config.dt.to_string());
    for k in 1..=steps {
        let (v, w) = drive.step(config.dt);
        let after = drive.robot.pose;
        let scan = lidar.scan(map, &after, &mut lidar_rng);
        let timestamp = k as f64 * config.dt;
        log.odometry.push(LogOdometry {
            timestamp,
            pose: drive.odometry.pose,
            tv: v,
            rv: w,
        });
        log.scans.push(LogScan {
            timestamp,
            kind: LaserKind::Front,
            scan,
            odometry: drive.odometry.pose,
            laser_pose: None,
            line: 0,
        });
        truth.push(TruePose {
            timestamp,
            pose: after,
        });
    }
    Ok((log, truth))
}

/// The round robot driven by the explorer, with its wheel odometry: what a
/// simulated log (and the kidnap run of `cartographer::input`) drives.
pub(crate) struct ExploringRobot {
    /// Where the robot truly is.
    pub robot: GridRobot,
    /// What its wheels say.
    pub odometry: OdometrySensor,
    /// Where it may start (and be carried to): the free cells with 10 cm to
    /// spare, or all those it fits in when none has.
    pub cells: FreeCells,
    /// The robot inflated by its radius: where it may stand.
    collision: Costmap,
    explorer: Explorer,
    odom_rng: ChaCha8Rng,
}

impl ExploringRobot {
    /// The robot at a random start (stream 1 of `seed`), the explorer's goals
    /// from stream 4 and the odometry noise from stream 3; None when it fits
    /// nowhere.
    pub(crate) fn place(
        map: &OccupancyGrid,
        collision: Costmap,
        radius: f64,
        config: &SimulatedLogConfig,
        seed: u64,
    ) -> Option<Self> {
        let roomy = Costmap::inflate(map, radius + 0.1).valid_cells();
        let cells = if roomy.is_empty() {
            collision.valid_cells()
        } else {
            roomy
        };
        let mut start_rng = ChaCha8Rng::seed_from_u64(stream_seed(seed, 1));
        let start = cells.sample(&mut start_rng)?;
        Some(Self {
            robot: GridRobot {
                pose: start,
                radius,
            },
            odometry: OdometrySensor::new(start, config.odom_noise),
            cells,
            collision,
            explorer: Explorer::new(map, radius, config.explorer, stream_seed(seed, 4)),
            odom_rng: ChaCha8Rng::seed_from_u64(stream_seed(seed, 3)),
        })
    }

    /// One step of `dt` seconds: the explorer's command `(v, w)`, driven (a
    /// new plan after a bump) and read by the odometry.
    pub(crate) fn step(&mut self, dt: f64) -> (f64, f64) {
        let (v, w) = self.explorer.command(&self.robot.pose);
        let before = self.robot.pose;
        if self.robot.drive(&self.collision, v, w, dt).is_some() {
            self.explorer.replan();
        }
        self.odometry
            .record(&before, &self.robot.pose, &mut self.odom_rng);
        (v, w)
    }

    /// Carries the robot to `pose` (the odometry does not see it) and plans anew.
    pub(crate) fn carry_to(&mut self, pose: Pose2) {
        self.robot.pose = pose;
        self.explorer.replan();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::laser_log::tests::{assert_same_to_printed_precision, read};
    use crate::io::laser_log::{read_truth, write_carmen, write_truth};
    use std::f64::consts::PI;

    #[test]
    fn a_simulated_log_reads_back_as_recorded() {
        let map = crate::grid::BuiltinMap::Maze.load().unwrap();
        let config = SimulatedLogConfig::default();
        let (log, truth) = simulate_log(&map, 150, 3, &config).unwrap();
        assert_eq!(log.scans.len(), 150);
        assert_eq!(truth.len(), 150);
        assert_eq!(log.beams(), Some(360));
        let s = &log.scans[0].scan;
        assert_eq!(s.range_max, 12.0);
        assert!(
            (s.angles[0] + PI).abs() < 1e-15 && (s.angles[359] - PI * 179.0 / 180.0).abs() < 1e-12
        );
        assert_eq!(log.time_span(), Some((0.1, 15.0)));
        // The same seed gives the same log; another seed does not.
        let (again, truth_again) = simulate_log(&map, 150, 3, &config).unwrap();
        assert_eq!(again, log);
        assert_eq!(truth_again, truth);
        let (other, _) = simulate_log(&map, 150, 4, &config).unwrap();
        assert_ne!(other.scans[0].scan.ranges, log.scans[0].scan.ranges);
        // The robot moved (about 0.5 m/s for 15 s) and the odometry drifted from
        // the truth, but not wildly.
        let first = truth[0].pose;
        let last = truth[149].pose;
        let moved: f64 = truth
            .windows(2)
            .map(|w| {
                slamlab_core::math::hypot(w[1].pose.x - w[0].pose.x, w[1].pose.y - w[0].pose.y)
            })
            .sum();
        assert!(moved > 2.0 && moved < 7.6, "{moved}");
        let odom_last = log.scans[149].odometry;
        let drift = slamlab_core::math::hypot(odom_last.x - last.x, odom_last.y - last.y);
        assert!(drift > 1e-4 && drift < 1.0, "drift {drift}");
        assert!(first != last);
        // Through the file and back.
        let text = write_carmen(&log).unwrap();
        let back = read(&text).unwrap();
        assert_same_to_printed_precision(&log, &back);
        let truth_back = read_truth(&write_truth(&truth)).unwrap();
        for (a, b) in truth.iter().zip(&truth_back) {
            assert!((a.timestamp - b.timestamp).abs() <= 5e-7);
            assert!((a.pose.x - b.pose.x).abs() <= 5e-7 && (a.pose.y - b.pose.y).abs() <= 5e-7);
        }
        // Bad configurations are refused with a message.
        assert!(simulate_log(&map, MAX_SIMULATED_STEPS_PLUS_ONE, 1, &config).is_err());
        let bad = SimulatedLogConfig {
            dt: f64::NAN,
            ..config
        };
        assert!(matches!(
            simulate_log(&map, 10, 1, &bad),
            Err(SimLogError::BadConfig(_))
        ));
    }

    const MAX_SIMULATED_STEPS_PLUS_ONE: usize = MAX_SIMULATED_STEPS + 1;
}
