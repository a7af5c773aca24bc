//! Sensor-fusion assignments (`crate::coursework`'s [`Task`] of `fusion`
//! tasks): one student's drive of the fusion lesson's robot, handed out as one
//! CSV per sensor, and the lesson's fusion EKF replayed on the same readings.
//!
//! The run is the lesson's ([`simulate`]) with the student's seed and a drive
//! of `steps / 10` seconds (a step is one 0.1 s pose of the hand-in): the
//! joystick drive of thesis `002` ch. 5 in a 4 m x 3 m room, wheel odometry at
//! 50 Hz (a per-drive wheel-scale error and turn slip make it drift), an IMU at
//! 100 Hz (yaw rate with a drifting bias, accelerations), a SLAM pose at 1 Hz
//! (white noise, map drift, relocalization jumps). The files print every number
//! with the shortest text that reads back as the same `f64`, so a program that
//! reads them gets, to the bit, the readings the reference filter fused
//! (tested).
//!
//! References: the lesson's [`FusionEkf`](slamlab_core::kalman::fusion::FusionEkf)
//! in the assignment's first mode (the lesson's default: `_differential`, thesis
//! Table 5.3) sampled every 0.1 s, the reference solution; and dead reckoning
//! from the wheel odometry ([`dead_reckoning`], what `starter.py` writes).

use super::log::{IMU, ODOMETRY, SLAM, SensorLog};
use super::params::FusionLessonScenario;
use super::runner::{FusionMode, ModeRun};
use super::scenario::SlamSource;
use super::sensors::simulate;
use crate::coursework::files::{InputFiles, number};
use crate::coursework::{
    Assignment, CourseworkError, InputFormat, Task, TaskKind, TaskRun, Variant, steps_refusal,
};
use crate::io::trajectory::write_tum;
use crate::metrics::Trajectory;
use slamlab_core::Pose2;
use slamlab_core::kalman::fusion::Reading;
use slamlab_core::motion::{Control, MotionModel};
use std::fmt::Write as _;

/// The hand-in's rate: one pose every 0.1 s (a step of the assignment).
pub const POSES_PER_SECOND: f64 = 10.0;

/// The fewest steps (poses at 10 Hz) of a fusion assignment's drive: 10 s,
/// the lesson's shortest drive is 5 s.
pub const MIN_STEPS: u64 = 100;

/// The most steps: 1,200 s, the lesson's longest drive.
pub const MAX_STEPS: u64 = 12_000;

/// The lesson's parameters an assignment may not set: the drive's length comes
/// from the steps, and the files carry stamps, not arrival times, nor a
/// covariance per reading.
const REFUSED: &[(&str, &str)] = &[
    (
        "duration",
        "the drive's length is scenario.steps / 10 seconds (the steps are the hand-in's 0.1 s poses)",
    ),
    (
        "slam-latency",
        "the files give each SLAM pose's stamp; an assignment's poses arrive on time",
    ),
    (
        "filter-delay",
        "the files give each reading's stamp; an assignment's readings arrive on time",
    ),
    (
        "output-rate",
        "the hand-in and the reference are sampled every 0.1 s",
    ),
];

/// One sensor's readings as the CSV hands them out: `(t, values)`.
pub type Rows = Vec<(f64, Vec<f64>)>;

/// One student's drive: the lesson's log, the files made from it and the truth.
#[derive(Clone, Debug)]
pub struct FusionRun {
    /// The lesson's parameters (the student's seed and the drive's length in them).
    pub lesson: FusionLessonScenario,
    /// The drive: the truth and every reading.
    pub log: SensorLog,
    /// The true pose every 0.1 s, from 0 to the end of the drive.
    pub truth: Trajectory,
}

impl FusionRun {
    /// Simulates the lesson's drive for `steps` poses of 0.1 s.
    pub fn simulate(
        lesson: &FusionLessonScenario,
        steps: u64,
    ) -> Result<FusionRun, CourseworkError> {
        let mut lesson = lesson.clone();
        lesson.scenario.drive.duration = duration_of(steps);
        lesson.scenario.slam.latency = 0.0;
        lesson.scenario.filter_delay = 0.0;
        let log = simulate(&lesson.scenario)
            .map_err(|e| CourseworkError::Generate(format!("the drive: {e}")))?;
        let mut truth = Trajectory::default();
        for t in sample_times(steps) {
            truth.push(t, log.truth_at(t), None);
        }
        Ok(FusionRun { lesson, log, truth })
    }

    /// The reference filter's mode: the assignment's first mode (the lesson's
    /// default `_differential`), or the baseline when none is given.
    pub fn reference_mode(&self) -> FusionMode {
        self.lesson
            .modes
            .first()
            .copied()
            .unwrap_or(FusionMode::Differential)
    }

    /// The wheel odometry's readings: `t, v, w` (forward speed m/s, yaw rate rad/s).
    pub fn odometry_rows(&self) -> Rows {
        self.rows(ODOMETRY, |r| match r {
            Reading::Twist { twist, .. } => Some(vec![twist[0], twist[2]]),
            _ => None,
        })
    }

    /// The IMU's readings: `t, yaw rate, a_x, a_y` (rad/s, m/s²).
    pub fn imu_rows(&self) -> Rows {
        self.rows(IMU, |r| match r {
            Reading::Imu { values, .. } => Some(vec![values[0], values[1], values[2]]),
            _ => None,
        })
    }

    /// The SLAM poses: `t, x, y, theta` (m, m, rad, in the world frame).
    pub fn slam_rows(&self) -> Rows {
        self.rows(SLAM, |r| match r {
            Reading::Pose { pose, .. } => Some(vec![pose.x, pose.y, pose.theta]),
            _ => None,
        })
    }

    fn rows(&self, sensor: usize, values: impl Fn(&Reading) -> Option<Vec<f64>>) -> Rows {
        self.log
            .measurements
            .iter()
            .filter(|a| a.measurement.sensor == sensor)
            .filter_map(|a| Some((a.measurement.stamp, values(&a.measurement.reading)?)))
            .collect()
    }

    /// The lesson's fusion EKF in [`Self::reference_mode`] on the drive's
    /// readings, sampled every 0.1 s (the same filter the lesson steps; only
    /// the sampling differs from the lesson's 30 Hz plots).
    pub fn reference_ekf(&self) -> Result<Trajectory, CourseworkError> {
        let mut scenario = self.lesson.scenario.clone();
        scenario.output_rate = POSES_PER_SECOND;
        let mut run = ModeRun::new(&scenario, self.reference_mode())
            .map_err(|e| CourseworkError::Generate(format!("the reference filter: {e}")))?;
        run.run_to_end(&self.log);
        let mut path = Trajectory::default();
        for (k, &t) in self.truth.stamps().iter().enumerate() {
            // The drive's last truth tick may fall a hair before the last
            // 0.1 s: that pose is the filter's prediction to it.
            let pose = match run.samples().get(k) {
                Some(sample) => sample.estimate,
                None => match run.filter().predicted_at(t) {
                    Some((mean, _)) => Pose2::new(mean[0], mean[1], mean[2]),
                    None => continue,
                },
            };
            path.push(t, pose, None);
        }
        Ok(path)
    }

    /// Dead reckoning from `odometry.csv` at the truth's times.
    pub fn dead_reckoning(&self) -> Trajectory {
        dead_reckoning(&self.odometry_rows(), self.truth.stamps())
    }
}

/// The drive's length for `steps` poses of 0.1 s, seconds.
pub fn duration_of(steps: u64) -> f64 {
    steps as f64 / POSES_PER_SECOND
}

/// The hand-in's times: `k / 10` s for `k = 0 ..= steps`.
pub fn sample_times(steps: u64) -> Vec<f64> {
    (0..=steps).map(|k| k as f64 / POSES_PER_SECOND).collect()
}

/// A CSV file: the header, then each row's time and values.
fn csv(header: &str, rows: &Rows) -> String {
    let mut out = String::with_capacity(rows.len() * 48);
    out.push_str(header);
    out.push('\n');
    for (t, values) in rows {
        out.push_str(&number(*t));
        for v in values {
            out.push(',');
            out.push_str(&number(*v));
        }
        out.push('\n');
    }
    out
}

/// Dead reckoning: the odometry's twists `(t, [v, w])` integrated along exact
/// arcs (thesis Eq. 2.70), each held until the next reading, from the origin;
/// the pose at each of `times` (what `starter.py` writes).
pub fn dead_reckoning(odometry: &Rows, times: &[f64]) -> Trajectory {
    let mut pose = Pose2::IDENTITY;
    let mut held: Option<(f64, Control)> = None;
    let mut next = 0;
    let mut path = Trajectory::default();
    for &t in times {
        while let Some((stamp, values)) = odometry.get(next) {
            if *stamp > t {
                break;
            }
            if let Some((since, control)) = held {
                pose = MotionModel::ExactArc.predict(&pose, &control, stamp - since);
            }
            let v = values.first().copied().unwrap_or(0.0);
            let w = values.get(1).copied().unwrap_or(0.0);
            held = Some((*stamp, Control::new(v, w)));
            next += 1;
        }
        let now = match held {
            Some((since, control)) => MotionModel::ExactArc.predict(&pose, &control, t - since),
            None => pose,
        };
        path.push(t, now, None);
    }
    path
}

/// The starter code of fusion assignments.
pub const FUSION_STARTER: &str = include_str!("assignment_starter.py");

/// Fusion tasks: the lesson's parameter table checks the assignment's
/// parameters, and a variant is the lesson's drive with the student's seed.
impl Task for FusionRun {
    const KIND: TaskKind = TaskKind::Fusion;
    type Scenario = FusionLessonScenario;

    fn refusals(assignment: &Assignment, lesson: &FusionLessonScenario) -> Vec<String> {
        let mut refused = Vec::new();
        for (name, _) in assignment.param_pairs() {
            if let Some((_, why)) = REFUSED.iter().find(|(n, _)| *n == name) {
                refused.push(format!("{name}: {why}"));
            }
        }
        let s = &lesson.scenario;
        if !s.odometry.enabled {
            refused.push(
                "odom: a fusion assignment hands out the wheel odometry (the starter's dead reckoning)"
                    .to_owned(),
            );
        }
        if s.slam.source != SlamSource::Simulated {
            refused.push(
                "slam-source: an assignment's SLAM poses are the simulated ones (slam-source=simulated)"
                    .to_owned(),
            );
        }
        let limit =
            format!("a fusion assignment's drive has {MIN_STEPS} to {MAX_STEPS} poses of 0.1 s");
        refused.extend(steps_refusal(assignment, MIN_STEPS, MAX_STEPS, &limit));
        refused
    }

    fn run(
        mut lesson: FusionLessonScenario,
        seed: u64,
        steps: u64,
    ) -> Result<Self, CourseworkError> {
        lesson.scenario.seed = seed;
        FusionRun::simulate(&lesson, steps.clamp(MIN_STEPS, MAX_STEPS))
    }
}

impl TaskRun for FusionRun {
    fn truth(&self) -> Trajectory {
        self.truth.clone()
    }

    fn references(&self) -> Result<Vec<(String, Trajectory)>, CourseworkError> {
        Ok(vec![
            (
                format!("ekf-{}", self.reference_mode().name()),
                self.reference_ekf()?,
            ),
            ("dead-reckoning".to_owned(), self.dead_reckoning()),
        ])
    }

    /// What the README says about the files: formats, units, frames, noise.
    fn readme_body(&self, _inputs: &[InputFormat]) -> String {
        let s = &self.lesson.scenario;
        let (o, i, p) = (&s.odometry, &s.imu, &s.slam);
        let mut out = String::new();
        let _ = writeln!(
            out,
            "The drive: {} s of a two-wheel robot (track width {} m) driven by joystick\n\
             at up to {} m/s in a {} m x {} m room. Frames: the world frame is the robot's\n\
             pose at t = 0 (x forward, y left, angles counter-clockwise; the robot starts\n\
             at x = y = theta = 0, at rest). Metres, radians, seconds. Every number is\n\
             printed so that it reads back exactly.\n",
            number(s.drive.duration),
            number(o.wheel_base),
            number(s.drive.max_speed),
            number(s.drive.room[0]),
            number(s.drive.room[1]),
        );
        let _ = writeln!(
            out,
            "odometry.csv   t_s,v_m_per_s,w_rad_per_s: the wheel odometry's twist at {} Hz,\n\
             \x20              in the robot's frame: forward speed (m/s) and yaw rate (rad/s).\n\
             \x20              Noise: white, std {} m/s and {} rad/s; besides, each wheel's\n\
             \x20              radius is off by a per-drive error (std {}) and the wheels\n\
             \x20              skid in turns (they report {} times the body's yaw rate), so\n\
             \x20              integrating it drifts.",
            number(o.rate),
            number(o.speed_noise_std),
            number(o.turn_noise_std),
            number(o.scale_error_std),
            number(1.0 + o.turn_slip),
        );
        if i.enabled {
            let _ = writeln!(
                out,
                "imu.csv        t_s,gyro_z_rad_per_s,accel_x_m_per_s2,accel_y_m_per_s2: the\n\
                 \x20              IMU at {} Hz, in the robot's frame: the yaw rate (rad/s; white\n\
                 \x20              noise std {:.3e} rad/s plus a bias: std {} rad/s at the start, a\n\
                 \x20              random walk of {} rad/s per sqrt(s)) and the forward and\n\
                 \x20              sideways accelerations (m/s^2, gravity removed; white noise\n\
                 \x20              std {} m/s^2).",
                number(i.rate),
                i.gyro_noise_std,
                number(i.gyro_bias_std),
                number(i.gyro_bias_walk),
                number(i.accel_noise_std),
            );
        }
        if p.enabled {
            let _ = writeln!(
                out,
                "slam_pose.csv  t_s,x_m,y_m,theta_rad: a SLAM system's pose of the robot at\n\
                 \x20              {} Hz, in the world frame. Noise: white, std {} m in x and y\n\
                 \x20              and {} rad in theta; besides, its map drifts (a random walk of\n\
                 \x20              {} m per sqrt(s)) until a relocalization (about every {} s)\n\
                 \x20              resets it: the pose jumps.{}",
                number(p.rate),
                number(p.position_noise_std),
                number(p.yaw_noise_std),
                number(p.drift_per_sqrt_s),
                number(p.relocalization_interval),
                if p.outlier_probability > 0.0 {
                    format!(
                        " A share {} of the poses are wrong\n\x20              relocalizations (an extra error of std {} m).",
                        number(p.outlier_probability),
                        number(p.outlier_std)
                    )
                } else {
                    String::new()
                },
            );
        }
        let _ = writeln!(
            out,
            "\nEach file has one header line, then one reading a line, by time. The\n\
             readings are stamped when they were taken and all arrive on time.\n\
             The reference solution is an EKF (robot_localization's constant-velocity\n\
             model: x, y, theta, v_x, v_y, yaw rate) that fuses the odometry's v and w,\n\
             the IMU's yaw rate and the SLAM pose ({} mode).",
            self.reference_mode().name()
        );
        out
    }

    /// The files handed out: one CSV per sensor in use, the README and the
    /// starter code; with `answers`, `answers/truth.tum`.
    fn files(&self, _inputs: &[InputFormat], readme: &str, answers: bool) -> InputFiles {
        let s = &self.lesson.scenario;
        let mut files = InputFiles::with_readme(readme);
        files.add(
            "odometry.csv",
            csv("t_s,v_m_per_s,w_rad_per_s", &self.odometry_rows()),
        );
        if s.imu.enabled {
            files.add(
                "imu.csv",
                csv(
                    "t_s,gyro_z_rad_per_s,accel_x_m_per_s2,accel_y_m_per_s2",
                    &self.imu_rows(),
                ),
            );
        }
        if s.slam.enabled {
            files.add(
                "slam_pose.csv",
                csv("t_s,x_m,y_m,theta_rad", &self.slam_rows()),
            );
        }
        files.add("starter.py", FUSION_STARTER);
        if answers {
            files.add("answers/truth.tum", write_tum(&self.truth));
        }
        files
    }

    /// The drive's length (the seed is added by the caller).
    fn lesson_pairs(&self) -> Vec<(String, String)> {
        vec![(
            "duration".to_owned(),
            number(self.lesson.scenario.drive.duration),
        )]
    }

    fn hand_in_text(&self, assignment: &Assignment, variant: &Variant) -> Option<String> {
        Some(format!(
            "{file}: one pose every 0.1 s, from t = 0 to the end of the drive\n\
             (t = {end} s), as TUM ('t x y z qx qy qz qw', z = 0 and a rotation about z:\n\
             qz = sin(theta/2), qw = cos(theta/2)) or CSV ('t,x,y,theta'). Check it with\n\
             \x20 slamlab grade {id} --student '{student}' --estimate {file}\n\n\
             It is scored against the true trajectory in the world frame, without\n\
             alignment (poses paired by time within 0.01 s):",
            file = assignment.output.file,
            end = number(self.lesson.scenario.drive.duration),
            id = assignment.id,
            student = variant.student,
        ))
    }
}
