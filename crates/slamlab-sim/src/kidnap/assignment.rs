//! Localization assignments (`crate::coursework`'s [`Task`] of localization
//! tasks): one student's run of the Monte Carlo localization
//! lesson's robot, handed out as a ROS map and a CARMEN log, and the reference
//! MCL replayed on exactly what was handed out.
//!
//! The run is the lesson's ([`MclRun`]) with the student's seed: the explorer
//! drives the round robot through the built-in map, wheel odometry drifts, the
//! lidar scans from the true pose. The log's numbers are CARMEN's printed
//! precision (ranges to 1 mm, poses to 1 µm), so the reference MCL reads the
//! written log back and runs on that: what the student's program reads is, to
//! the bit, what the reference got.

use super::{InitMode, LocalizationEstimator, MclRun, MclScenario};
use crate::coursework::files::{InputFiles, number};
use crate::coursework::{
    Assignment, CourseworkError, InputFormat, Task, TaskKind, TaskRun, builtin_map_refusal,
    load_builtin_map,
};
use crate::io::laser_log::{LaserKind, LaserLog, LogOdometry, LogScan, write_carmen};
use crate::io::ros_map::{ImageFormat, export_map, load_map};
use crate::io::trajectory::write_tum;
use crate::metrics::Trajectory;
use slamlab_core::grid::{Costmap, OccupancyGrid};
use slamlab_core::particle::LocalizationMap;
use slamlab_core::{Pose2, math, wrap_angle};
use std::fmt::Write as _;
use std::sync::Arc;

/// One student's localization run: the map and log as handed out, and the truth.
#[derive(Clone, Debug)]
pub struct LocalizationRun {
    /// The scenario (the student's seed in it).
    pub scenario: MclScenario,
    /// The true start pose, given to the student.
    pub start: Pose2,
    /// `map.yaml`.
    pub map_yaml: String,
    /// `map.pgm`.
    pub map_pgm: Vec<u8>,
    /// `robot.log`, the CARMEN log.
    pub log_text: String,
    /// The log as read back from `log_text`.
    pub log: LaserLog,
    /// The map as read back from `map.yaml` and `map.pgm`.
    pub grid: OccupancyGrid,
    /// The true pose at each scan's time.
    pub truth: Trajectory,
}

impl LocalizationRun {
    /// Runs the lesson's robot for `steps` steps (no filter runs) and writes its
    /// map and log.
    pub fn simulate(
        scenario: &MclScenario,
        grid: OccupancyGrid,
        steps: u64,
    ) -> Result<LocalizationRun, CourseworkError> {
        let scenario = MclScenario {
            estimators: Vec::new(),
            init: InitMode::Tracking,
            kidnap_at: None,
            ..scenario.clone()
        };
        let (map_yaml, map_pgm) = export_map(&grid, "map.pgm", ImageFormat::Pgm)
            .map_err(|e| CourseworkError::Generate(format!("the map: {e}")))?;
        let mut run = MclRun::new(scenario.clone(), grid)
            .map_err(|e| CourseworkError::Generate(format!("the robot's run: {e}")))?;
        let start = run.path().first().copied().unwrap_or_default();
        let dt = scenario.dt;
        let mut log = LaserLog::default();
        log.params
            .insert("slamlab_dt".to_owned(), number(scenario.dt));
        let mut truth = Trajectory::default();
        let mut previous = start;
        for k in 1..=steps {
            run.tick();
            let t = k as f64 * dt;
            let odometry = run.odometry();
            let step = previous.between(&odometry);
            previous = odometry;
            log.odometry.push(LogOdometry {
                timestamp: t,
                pose: odometry,
                tv: math::hypot(step.x, step.y) / dt,
                rv: wrap_angle(step.theta) / dt,
            });
            if let Some(scan) = run.scan() {
                log.scans.push(LogScan {
                    timestamp: t,
                    kind: LaserKind::Front,
                    scan: scan.clone(),
                    odometry,
                    laser_pose: None,
                    line: 0,
                });
            }
            if let Some(pose) = run.truth_ticks().last() {
                truth.push(t, *pose, None);
            }
        }
        let log_text =
            write_carmen(&log).map_err(|e| CourseworkError::Generate(format!("the log: {e}")))?;
        let log = LaserLog::from_bytes(log_text.as_bytes())
            .map_err(|e| CourseworkError::Generate(format!("the log read back: {e}")))?;
        let (grid, _) = load_map(&map_yaml, &map_pgm)
            .map_err(|e| CourseworkError::Generate(format!("the map read back: {e}")))?;
        Ok(LocalizationRun {
            scenario,
            start,
            map_yaml,
            map_pgm,
            log_text,
            log,
            grid,
            truth,
        })
    }

    /// The odometry of the log, at its scans' times (in the map's frame: the
    /// odometry starts at the true start pose).
    pub fn odometry_trajectory(&self) -> Trajectory {
        let mut t = Trajectory::default();
        for s in &self.log.scans {
            t.push(s.timestamp, s.odometry, None);
        }
        t
    }

    /// The reference MCL (the lesson's, with its parameters) on the map and
    /// log as read back from the files: initialized around the start pose with
    /// the lesson's tracking spread, then at every scan an update when the
    /// odometry has moved enough, and the estimate (the last update's, moved
    /// by the odometry since) at the scan's time.
    pub fn reference_mcl(&self) -> Result<Trajectory, CourseworkError> {
        reference_mcl(&self.scenario, self.grid.clone(), &self.log, self.start)
    }
}

/// Monte Carlo localization on a map and a log, as the lesson runs it (see
/// [`LocalizationRun::reference_mcl`]).
pub fn reference_mcl(
    scenario: &MclScenario,
    grid: OccupancyGrid,
    log: &LaserLog,
    start: Pose2,
) -> Result<Trajectory, CourseworkError> {
    let radius = scenario.robot_radius;
    let collision = Arc::new(Costmap::inflate(&grid, radius));
    let map = Arc::new(
        LocalizationMap::new(grid, scenario.laser_likelihood_max_dist)
            .map_err(|e| CourseworkError::Generate(format!("the reference MCL's map: {e}")))?,
    );
    let mut filter = scenario.filter(LocalizationEstimator::Mcl, map, collision, 100);
    scenario.init_tracking(&mut filter, start);
    let mut path = Trajectory::default();
    for s in &log.scans {
        let odom = s.odometry;
        if filter.update_due(odom) {
            filter.predict(odom);
            filter.weight(&s.scan);
            filter.resample();
        }
        let Some(estimate) = filter.mcl().estimate().map(|e| e.pose) else {
            continue;
        };
        let now = match filter.mcl().last_odometry() {
            Some(at_update) => estimate.compose(&at_update.between(&odom)),
            None => estimate,
        };
        path.push(s.timestamp, now, None);
    }
    Ok(path)
}

/// The starter code of localization assignments.
pub const LOCALIZATION_STARTER: &str = include_str!("assignment_starter.py");

/// Localization tasks: the lesson's parameter table checks the assignment's
/// parameters (the map must be a built-in one), and a variant is the lesson's
/// robot run with the student's seed.
impl Task for LocalizationRun {
    const KIND: TaskKind = TaskKind::Localization;
    type Scenario = MclScenario;

    fn refusals(_assignment: &Assignment, scenario: &MclScenario) -> Vec<String> {
        builtin_map_refusal(&scenario.map).into_iter().collect()
    }

    fn run(mut scenario: MclScenario, seed: u64, steps: u64) -> Result<Self, CourseworkError> {
        scenario.seed = seed;
        let grid = load_builtin_map(&scenario.map)?;
        LocalizationRun::simulate(&scenario, grid, steps)
    }
}

impl TaskRun for LocalizationRun {
    fn truth(&self) -> Trajectory {
        self.truth.clone()
    }

    fn references(&self) -> Result<Vec<(String, Trajectory)>, CourseworkError> {
        Ok(vec![
            ("mcl".to_owned(), self.reference_mcl()?),
            ("odometry".to_owned(), self.odometry_trajectory()),
        ])
    }

    /// What the README says about the files.
    fn readme_body(&self, _inputs: &[InputFormat]) -> String {
        let s = &self.scenario;
        let beams = self.log.beams().unwrap_or(0);
        let sd = |v: f64| if v > 0.0 { v.sqrt() } else { 0.0 };
        let mut out = String::new();
        let _ = writeln!(
            out,
            "The run: {} steps of dt = {} s; a round robot of radius {} m explores the map.\n\
             Frames: ROS REP-103 (x forward, y left, angles counter-clockwise), metres,\n\
             radians, seconds; the map's frame is the world's.\n\
             \n\
             map.yaml, map.pgm  a ROS map_server map (resolution {} m per pixel, origin\n\
             \x20             in map.yaml; black occupied, white free, grey unknown).\n\
             robot.log     a CARMEN log. 'ODOM x y theta tv rv accel ts host ts': the wheel\n\
             \x20             odometry's pose, which drifts; it starts at the true start pose,\n\
             \x20             so its frame is the map's at the start. 'FLASER n r1 .. rn x y\n\
             \x20             theta odom_x odom_y odom_theta ts host ts': a scan of n = {}\n\
             \x20             ranges (metres, printed to 1 mm), the first beam at -fov/2 and\n\
             \x20             the others the resolution apart (the PARAM lines give\n\
             \x20             laser_front_laser_fov and _resolution in degrees, and\n\
             \x20             robot_front_laser_max in metres: a reading at the maximum is no\n\
             \x20             return), taken at the robot's centre at the odometry pose\n\
             \x20             printed on the line. One ODOM and one FLASER per step, at\n\
             \x20             t = k*dt.\n\
             start_pose.txt  x y theta: the robot's true pose at t = 0. The reference MCL\n\
             \x20             starts with {} particles spread around it (std {} m in x and\n\
             \x20             y, {} rad in theta).\n\
             \n\
             Noise: range std {} m; the odometry's increments are perturbed as in\n\
             Probabilistic Robotics' odometry motion model with alpha = {}, {}, {}, {}.\n",
            self.truth.len(),
            number(s.dt),
            number(s.robot_radius),
            number(self.grid.resolution()),
            beams,
            s.max_particles,
            number(sd(s.initial_cov_xx)),
            number(sd(s.initial_cov_aa)),
            number(s.lidar.range_std),
            number(s.odom_noise.alpha1),
            number(s.odom_noise.alpha2),
            number(s.odom_noise.alpha3),
            number(s.odom_noise.alpha4),
        );
        out
    }

    /// The files handed out: `map.yaml`, `map.pgm`, `robot.log`,
    /// `start_pose.txt`, the README and the starter code; with `answers`,
    /// `answers/truth.tum`.
    fn files(&self, _inputs: &[InputFormat], readme: &str, answers: bool) -> InputFiles {
        let mut files = InputFiles::with_readme(readme);
        files.add_start_pose(&self.start);
        files.add("map.yaml", &self.map_yaml);
        files.add("map.pgm", &self.map_pgm);
        files.add("robot.log", &self.log_text);
        files.add("starter.py", LOCALIZATION_STARTER);
        if answers {
            files.add("answers/truth.tum", write_tum(&self.truth));
        }
        files
    }

    fn lesson_pairs(&self) -> Vec<(String, String)> {
        // The run starts where the student is told and is never kidnapped
        // (named, so that a link's `kidnap-at=` cannot change the run).
        vec![
            ("init".to_owned(), "tracking".to_owned()),
            ("kidnap-at".to_owned(), "none".to_owned()),
        ]
    }
}
