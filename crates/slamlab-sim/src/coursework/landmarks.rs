//! Landmark-SLAM assignments: one student's run of the landmark lesson's world,
//! handed out in the formats courses use, and the reference EKF replayed on
//! exactly what was handed out.
//!
//! The run is the landmark lesson's ([`LandmarkSession`]) with the student's
//! seed: the robot drives its circle with noisy wheels, the range-bearing sensor
//! measures the landmarks in view with known ids. Recorded per step `k = 1..n`
//! (time `t = k·dt`): the command `(v, w)` the robot was given for the interval
//! `(t − dt, t]`, and the measurements taken at the pose reached at `t`.
//!
//! - `controls.csv` (`t,v,w`) and `measurements.csv` (`t,id,range,bearing`): the
//!   velocity motion model's input, exactly what the lesson's estimators receive
//!   (numbers printed with the shortest round-trip formatting: read back they are
//!   the same bits, so the reference EKF on the files is the lesson's EKF).
//! - `world.dat` (`id x y`) and `sensor_data.dat` (`ODOMETRY r1 t r2` then
//!   `SENSOR id range bearing` lines, one block per step): the Freiburg Robot
//!   Mapping course's format for the odometry motion model; the odometry reading
//!   is the motion between consecutive dead-reckoning poses (what wheel encoders
//!   integrating the commands would report), decomposed as rotation, translation,
//!   rotation (Probabilistic Robotics, Sec. 5.4).
//!
//! Landmark ids are written from 1 (the course's Octave code indexes with them).

use super::files::{InputFiles, number};
use super::{CourseworkError, InputFormat, Task, TaskKind, TaskRun};
use crate::metrics::Trajectory;
use crate::world::landmark_scenario::LandmarkScenario;
use crate::world::landmark_session::LandmarkSession;
use slamlab_core::belief::PoseBelief;
use slamlab_core::kalman::{EkfSlam, LandmarkSlam};
use slamlab_core::range_bearing::RangeBearing;
use slamlab_core::{Control, Pose2, math, wrap_angle};
use std::fmt::Write as _;

/// One student's landmark run: what the estimators received and the truth.
#[derive(Clone, Debug)]
pub struct LandmarkRun {
    /// The scenario (the student's seed in it).
    pub scenario: LandmarkScenario,
    /// The start pose, known to the student.
    pub start: Pose2,
    /// The command of each step.
    pub controls: Vec<Control>,
    /// The measurements of each step: landmark id (from 0) and reading.
    pub measurements: Vec<Vec<(usize, RangeBearing)>>,
    /// The true pose at the start and after each step.
    pub truth: Vec<Pose2>,
    /// Dead reckoning from the commands, at the start and after each step.
    pub dead_reckoning: Vec<Pose2>,
    /// The true landmarks: id (from 0) and position.
    pub landmarks: Vec<(usize, [f64; 2])>,
}

impl LandmarkRun {
    /// Runs the landmark lesson's world for `steps` steps (no estimator runs).
    pub fn simulate(scenario: &LandmarkScenario, steps: u64) -> LandmarkRun {
        let mut session = LandmarkSession::new(LandmarkScenario {
            estimators: Vec::new(),
            ..scenario.clone()
        });
        let mut controls = Vec::with_capacity(steps as usize);
        let mut measurements = Vec::with_capacity(steps as usize);
        for _ in 0..steps {
            session.step_tick();
            controls.push(session.command());
            measurements.push(
                session
                    .observations()
                    .iter()
                    .map(|o| (o.id, o.measurement))
                    .collect(),
            );
        }
        LandmarkRun {
            scenario: session.scenario().clone(),
            start: session.scenario().start_pose(),
            controls,
            measurements,
            truth: session.truth_path().to_vec(),
            dead_reckoning: session.dead_reckoning_path().to_vec(),
            landmarks: session
                .world()
                .landmarks
                .iter()
                .map(|l| (l.id, [l.position.x, l.position.y]))
                .collect(),
        }
    }

    /// The time step, seconds.
    pub fn dt(&self) -> f64 {
        self.scenario.dt
    }

    /// The stamps of the start and every step: `k·dt`.
    pub fn stamps(&self) -> Vec<f64> {
        (0..=self.controls.len())
            .map(|k| k as f64 * self.dt())
            .collect()
    }

    /// The true trajectory.
    pub fn truth_trajectory(&self) -> Trajectory {
        Trajectory::new(self.stamps(), self.truth.clone())
    }

    /// Dead reckoning, as a trajectory.
    pub fn dead_reckoning_trajectory(&self) -> Trajectory {
        Trajectory::new(self.stamps(), self.dead_reckoning.clone())
    }

    /// The reference EKF-SLAM on the run's controls and measurements, with the
    /// noise the README tells the student to assume: predict with each step's
    /// command, then update with each measurement in file order. A phase the
    /// filter refuses leaves its state as it was, as in the lesson.
    pub fn reference_ekf(&self) -> Option<Trajectory> {
        let mut ekf = EkfSlam::new(self.scenario.filter_config(), self.start).ok()?;
        let dt = self.dt();
        let mut path = vec![ekf.robot_pose()];
        for (control, seen) in self.controls.iter().zip(&self.measurements) {
            let _ = ekf.predict(control, dt);
            for (id, z) in seen {
                let _ = ekf.update(*id, z);
            }
            path.push(ekf.robot_pose());
        }
        Some(Trajectory::new(self.stamps(), path))
    }

    /// The odometry reading of each step in the course's form `(rot1, trans,
    /// rot2)`: the motion between consecutive dead-reckoning poses.
    pub fn odometry_readings(&self) -> Vec<[f64; 3]> {
        self.dead_reckoning
            .windows(2)
            .map(|w| {
                let (a, b) = (w[0], w[1]);
                let (dx, dy) = (b.x - a.x, b.y - a.y);
                let trans = math::hypot(dx, dy);
                let rot1 = if trans > 1e-12 {
                    wrap_angle(math::atan2(dy, dx) - a.theta)
                } else {
                    0.0
                };
                let rot2 = wrap_angle(b.theta - a.theta - rot1);
                [rot1, trans, rot2]
            })
            .collect()
    }

    /// `controls.csv`: `t,v,w`.
    pub fn controls_csv(&self) -> String {
        let mut out = String::from("t,v,w\n");
        for (k, c) in self.controls.iter().enumerate() {
            let t = (k + 1) as f64 * self.dt();
            let _ = writeln!(out, "{},{},{}", number(t), number(c.v), number(c.w));
        }
        out
    }

    /// `measurements.csv`: `t,id,range,bearing`, ids from 1.
    pub fn measurements_csv(&self) -> String {
        let mut out = String::from("t,id,range,bearing\n");
        for (k, seen) in self.measurements.iter().enumerate() {
            let t = (k + 1) as f64 * self.dt();
            for (id, z) in seen {
                let _ = writeln!(
                    out,
                    "{},{},{},{}",
                    number(t),
                    id + 1,
                    number(z.range),
                    number(z.bearing)
                );
            }
        }
        out
    }

    /// The Freiburg course's `world.dat`: `id x y`, ids from 1.
    pub fn world_dat(&self) -> String {
        let mut out = String::new();
        for (id, p) in &self.landmarks {
            let _ = writeln!(out, "{} {} {}", id + 1, number(p[0]), number(p[1]));
        }
        out
    }

    /// The Freiburg course's `sensor_data.dat`: per step an `ODOMETRY rot1 trans
    /// rot2` line, then a `SENSOR id range bearing` line per measurement.
    pub fn sensor_data_dat(&self) -> String {
        let mut out = String::new();
        for (odometry, seen) in self.odometry_readings().iter().zip(&self.measurements) {
            let _ = writeln!(
                out,
                "ODOMETRY {} {} {}",
                number(odometry[0]),
                number(odometry[1]),
                number(odometry[2])
            );
            for (id, z) in seen {
                let _ = writeln!(
                    out,
                    "SENSOR {} {} {}",
                    id + 1,
                    number(z.range),
                    number(z.bearing)
                );
            }
        }
        out
    }

    /// `landmarks.csv` of the answers: `id,x,y`, ids from 1.
    pub fn landmarks_csv(&self) -> String {
        let mut out = String::from("id,x,y\n");
        for (id, p) in &self.landmarks {
            let _ = writeln!(out, "{},{},{}", id + 1, number(p[0]), number(p[1]));
        }
        out
    }

    /// The files handed out: the formats asked for, the start pose, the README
    /// and the starter code; with `answers`, `answers/truth.tum` and
    /// `answers/landmarks.csv`.
    pub fn files(&self, freiburg: bool, velocity: bool, readme: &str, answers: bool) -> InputFiles {
        let mut files = InputFiles::with_readme(readme);
        files.add_start_pose(&self.start);
        files.add(
            "run.txt",
            format!("dt {}\nsteps {}\n", number(self.dt()), self.controls.len()),
        );
        if velocity {
            files.add("controls.csv", self.controls_csv());
            files.add("measurements.csv", self.measurements_csv());
        }
        if freiburg {
            files.add("world.dat", self.world_dat());
            files.add("sensor_data.dat", self.sensor_data_dat());
        }
        files.add("starter.py", LANDMARK_STARTER);
        if answers {
            files.add(
                "answers/truth.tum",
                crate::io::trajectory::write_tum(&self.truth_trajectory()),
            );
            files.add("answers/landmarks.csv", self.landmarks_csv());
        }
        files
    }

    /// What the README says about the files, their units and frames, the noise
    /// and the start.
    pub fn readme_body(&self, freiburg: bool, velocity: bool) -> String {
        let s = &self.scenario;
        let mut out = String::new();
        let _ = writeln!(
            out,
            "The run: {} steps of dt = {} s ({} s), {} landmarks with ids 1 to {}.\n\
             Frames: ROS REP-103 (x forward, y left, angles counter-clockwise), metres,\n\
             radians, seconds. The world frame is the map's; the robot starts at the pose\n\
             in start_pose.txt (x y theta), known exactly: start your filter there\n\
             with zero robot covariance. run.txt gives dt and the number of steps.\n",
            self.controls.len(),
            number(s.dt),
            number(self.controls.len() as f64 * s.dt),
            self.landmarks.len(),
            self.landmarks.len(),
        );
        if velocity {
            let _ = writeln!(
                out,
                "controls.csv  t,v,w: one row per step k = 1..n at t = k*dt; the robot was\n\
                 \x20             commanded forward speed v (m/s) and turn rate w (rad/s) from\n\
                 \x20             t - dt to t. It moves along the exact arc (constant v and w):\n\
                 \x20               x' = x + v/w (sin(th + w dt) - sin th)\n\
                 \x20               y' = y + v/w (cos th - cos(th + w dt))\n\
                 \x20               th' = th + w dt     (straight line when w = 0)\n\
                 \x20             The executed speeds differ from the commands by Gaussian\n\
                 \x20             noise: std {} m/s on v, {} rad/s on w (the control noise\n\
                 \x20             covariance M = diag(sv^2, sw^2), mapped through the motion's\n\
                 \x20             Jacobian with respect to (v, w)).\n\
                 measurements.csv  t,id,range,bearing: the landmarks seen from the pose at\n\
                 \x20             time t (after that step's motion), known ids, range in\n\
                 \x20             metres from the robot's centre, bearing in radians from its\n\
                 \x20             heading, in (-pi, pi]. Noise: std {} m on range, {} rad on\n\
                 \x20             bearing (Q = diag(sr^2, sb^2)), independent. The sensor sees\n\
                 \x20             {} m far over a field of view of {} rad centred on the heading.\n",
                number(s.v_std),
                number(s.w_std),
                number(s.range_std),
                number(s.bearing_std),
                number(s.max_range),
                number(s.fov),
            );
        }
        if freiburg {
            let _ = writeln!(
                out,
                "world.dat     id x y: the landmarks' true positions, as the Freiburg course\n\
                 \x20             gives them (its framework reads the count and draws them).\n\
                 \x20             A SLAM filter must not read the positions: it maps them.\n\
                 sensor_data.dat  the Freiburg course's format: for each step k = 1..n an\n\
                 \x20             'ODOMETRY r1 t r2' line (the odometry motion model: turn r1\n\
                 \x20             rad, drive t m, turn r2 rad, Probabilistic Robotics Sec. 5.4),\n\
                 \x20             the motion between the dead-reckoning poses at (k-1)*dt and\n\
                 \x20             k*dt, then one 'SENSOR id range bearing' line per landmark\n\
                 \x20             seen at k*dt (as in measurements.csv). The readings are the\n\
                 \x20             commands of controls.csv integrated along the exact arc; the\n\
                 \x20             noise lies in the executed motion, as above.\n"
            );
        }
        out
    }
}

/// Landmark-SLAM tasks: the lesson's parameter table checks the assignment's
/// parameters, and a variant is the landmark world run with the student's
/// seed.
impl Task for LandmarkRun {
    const KIND: TaskKind = TaskKind::LandmarkSlam;
    type Scenario = LandmarkScenario;

    fn run(mut scenario: LandmarkScenario, seed: u64, steps: u64) -> Result<Self, CourseworkError> {
        scenario.seed = seed;
        Ok(LandmarkRun::simulate(&scenario, steps))
    }
}

impl TaskRun for LandmarkRun {
    fn truth(&self) -> Trajectory {
        self.truth_trajectory()
    }

    fn references(&self) -> Result<Vec<(String, Trajectory)>, CourseworkError> {
        let ekf = self.reference_ekf().ok_or_else(|| {
            CourseworkError::Generate("the reference EKF could not start".to_owned())
        })?;
        Ok(vec![
            ("ekf".to_owned(), ekf),
            (
                "dead-reckoning".to_owned(),
                self.dead_reckoning_trajectory(),
            ),
        ])
    }

    fn readme_body(&self, inputs: &[InputFormat]) -> String {
        LandmarkRun::readme_body(
            self,
            inputs.contains(&InputFormat::Freiburg),
            inputs.contains(&InputFormat::VelocityCsv),
        )
    }

    fn files(&self, inputs: &[InputFormat], readme: &str, answers: bool) -> InputFiles {
        LandmarkRun::files(
            self,
            inputs.contains(&InputFormat::Freiburg),
            inputs.contains(&InputFormat::VelocityCsv),
            readme,
            answers,
        )
    }
}

/// The starter code of landmark-SLAM assignments.
pub const LANDMARK_STARTER: &str = include_str!("starter/landmarks.py");
