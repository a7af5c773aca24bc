//! The Monte Carlo localization runner: a robot explores a grid map, its lidar
//! and wheel odometry feed one or more particle filters, and every update's
//! error is recorded against the truth.
//!
//! A tick is four phases, each callable on its own ([`MclRun::step_phase`]) so a
//! lesson can show them one at a time: *move* (the explorer's command, the
//! robot, its odometry and a lidar scan), then, if any filter's update
//! thresholds are met, *predict*, *weight* and *resample*.
//!
//! Random streams (each derived from the scenario's seed, so changing one part
//! never changes another's numbers): the start pose, lidar noise, odometry
//! noise, the explorer's goals, and one per filter.
//!
//! A run can also replay a recorded robot ([`MclRun::from_log`]): the *move*
//! phase then takes the log's next scan and its odometry pose instead of
//! driving the simulated robot, and the filters run exactly as they do on the
//! simulated robot. A log has no truth unless it carries one (a bag SLAM Lab
//! simulated has `/ground_truth`); without it every error is `NaN`, the
//! statuses say so, and the summaries leave the errors out.

use super::scenario::{InitMode, MclScenario};
use crate::grid::explorer::Explorer;
use crate::grid::robot::{GridRobot, OdometrySensor};
use crate::grid::scans::MappingInput;
use crate::noise::stream_seed;
use nalgebra::Matrix3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use slamlab_core::grid::{Costmap, OccupancyGrid};
use slamlab_core::particle::{
    LocalizationMap, Mcl, PredictReport, RecoveringMcl, RecoveryReport, ResampleReport, Scan,
    WeightReport,
};
use slamlab_core::{Pose2, math, wrap_angle};
use std::sync::Arc;
use thiserror::Error;

/// Convergence: within this distance of the truth, metres.
pub const CONVERGED_POSITION: f64 = 0.5;
/// Convergence: within this heading of the truth, radians.
pub const CONVERGED_HEADING: f64 = 0.3;
/// Convergence: for this many consecutive filter updates.
pub const CONVERGED_UPDATES: usize = 10;

/// Why a run cannot start.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum MclRunError {
    /// No free cell at all.
    #[error("the map has no free cell: there is nowhere for the robot to be")]
    NoFreeCell,
    /// Free cells, but none where the robot's disc fits.
    #[error("no free place on the map is farther than the robot radius {0} m from every wall")]
    RobotDoesNotFit(f64),
    /// A log to replay without a single scan.
    #[error("the log has no laser scan to localize with")]
    EmptyLog,
}

/// The phase a run will execute next.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MclPhase {
    /// Command, robot motion, odometry and lidar scan.
    #[default]
    Move,
    /// Motion update of the filters due for an update.
    Predict,
    /// Measurement update.
    Weight,
    /// Resampling, then the tick's records.
    Resample,
}

/// One filter update's record.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct UpdateRecord {
    /// The tick of the update.
    pub tick: u64,
    /// Distance of the estimate from the truth, metres.
    pub position_error: f64,
    /// Heading error, radians (absolute, wrapped).
    pub heading_error: f64,
    /// Twice the standard deviation of the estimate along its longest axis,
    /// metres.
    pub position_2sigma: f64,
    /// Twice the heading standard deviation, radians.
    pub heading_2sigma: f64,
    /// Effective sample size after weighting.
    pub n_eff: f64,
    /// Particle count.
    pub particles: usize,
    /// Whether the filter resampled.
    pub resampled: bool,
    /// Fraction of the particles injected or regenerated in this update.
    pub randomized: f64,
    /// Augmented MCL's injection probability `max(0, 1 − w_fast/w_slow)`.
    pub injection_probability: f64,
    /// `ln w_slow` after this update (AMCL and ACMCL; `None` for the others).
    pub log_w_slow: Option<f64>,
    /// `ln w_fast` after this update (AMCL and ACMCL; `None` for the others).
    pub log_w_fast: Option<f64>,
}

/// The error of a filter's estimate at one tick (moved along with the odometry
/// since the filter's last update, as amcl's published pose is).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TickError {
    /// Metres.
    pub position: f64,
    /// Radians, absolute.
    pub heading: f64,
}

/// One filter in a run, with its records.
#[derive(Clone, Debug)]
pub struct FilterRun {
    /// Its name.
    pub name: &'static str,
    /// The filter.
    pub filter: RecoveringMcl,
    /// Whether the current tick updates it.
    pub due: bool,
    /// Its records, one per update.
    pub updates: Vec<UpdateRecord>,
    /// Its error at every tick.
    pub ticks: Vec<TickError>,
    /// Its estimate at the end of every tick (the last update's, moved by the
    /// odometry since, as the error above uses it) with the last update's
    /// covariance; `None` before it has one.
    pub estimates: Vec<Option<(Pose2, Matrix3<f64>)>>,
    /// The last phase reports (for the explanation panel).
    pub last_predict: Option<PredictReport>,
    /// The last weighting report.
    pub last_weight: Option<WeightReport>,
    /// The last resampling report.
    pub last_resample: Option<ResampleReport>,
}

impl FilterRun {
    /// The inner MCL (particles, estimate, N_eff).
    pub fn mcl(&self) -> &Mcl {
        self.filter.mcl()
    }

    /// What the recovery did in the latest update.
    pub fn recovery(&self) -> &RecoveryReport {
        self.filter.report()
    }

    /// The estimate now: the filter's estimate at its last update moved by the
    /// odometry since then.
    pub fn current_estimate(&self, odom_now: &Pose2) -> Option<Pose2> {
        let e = self.mcl().estimate()?.pose;
        Some(match self.mcl().last_odometry() {
            Some(at_update) => e.compose(&at_update.between(odom_now)),
            None => e,
        })
    }

    /// What the filter is doing, as a student should read it: tracking, lost,
    /// recovering, or recovered after a kidnap (and how long it took), judged by
    /// the experiments' convergence criterion. `now` is the estimate's error against
    /// the truth as it is now ([`MclRun::error_now`]): right after a kidnap the
    /// records still hold the error from before it. [`MclRun::status_of`] gives both.
    pub fn status(&self, kidnap_tick: Option<u64>, dt: f64, now: Option<TickError>) -> String {
        let f = self;
        let good = |u: &UpdateRecord| {
            u.position_error <= CONVERGED_POSITION && u.heading_error <= CONVERGED_HEADING
        };
        let Some(last) = f.updates.last() else {
            return "waiting for the robot to move".to_owned();
        };
        // Between updates the estimate moves with the odometry; this is how far off it is now.
        let off = now
            .or_else(|| f.ticks.last().copied())
            .map_or(last.position_error, |e| e.position);
        let Some(kidnap) = kidnap_tick else {
            return if good(last) {
                format!("tracking ({off:.2} m off)")
            } else {
                format!("localizing ({off:.2} m off)")
            };
        };
        let since: Vec<&UpdateRecord> = f.updates.iter().filter(|u| u.tick >= kidnap).collect();
        if since.is_empty() {
            return format!("lost: {off:.2} m off, no update since the kidnap yet");
        }
        let recovered = (0..since.len()).find(|&k| {
            since.len() - k >= CONVERGED_UPDATES
                && since[k..k + CONVERGED_UPDATES].iter().all(|u| good(u))
        });
        match recovered {
            Some(k) => format!(
                "recovered after {k} updates ({:.1} s after the kidnap)",
                (since[k].tick - kidnap) as f64 * dt
            ),
            None if good(last) => {
                "recovering: on the truth again, not yet for 10 updates".to_owned()
            }
            None if last.randomized > 0.0 => format!(
                "recovering: {:.1}% of its particles drawn anew in the last update",
                100.0 * last.randomized
            ),
            None => format!(
                "lost: {off:.2} m off, {} updates since the kidnap",
                since.len()
            ),
        }
    }

    /// The metrics the CLI prints.
    pub fn summary(&self) -> FilterSummary {
        let converged_at = (0..self.updates.len()).find(|&u| {
            self.updates.len() - u >= CONVERGED_UPDATES
                && self.updates[u..u + CONVERGED_UPDATES].iter().all(|r| {
                    r.position_error <= CONVERGED_POSITION && r.heading_error <= CONVERGED_HEADING
                })
        });
        let converged_tick = converged_at.map(|u| self.updates[u].tick);
        let position_rmse_converged = converged_tick.and_then(|t| {
            let after: Vec<f64> = self
                .ticks
                .iter()
                .skip(t as usize)
                .map(|e| e.position * e.position)
                .collect();
            (!after.is_empty()).then(|| (after.iter().sum::<f64>() / after.len() as f64).sqrt())
        });
        let last = self.ticks.last();
        // A run without truth has NaN errors: no number to report.
        let known = |v: f64| (!v.is_nan()).then_some(v);
        FilterSummary {
            name: self.name.to_owned(),
            particles: self.mcl().count(),
            converged_tick,
            position_error_final: last.and_then(|e| known(e.position)),
            heading_error_final: last.and_then(|e| known(e.heading)),
            position_rmse_converged,
        }
    }
}

/// A filter's result (the JSON keys of `slamlab run kidnap`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FilterSummary {
    /// Estimator name.
    pub name: String,
    /// Particle count at the end.
    pub particles: usize,
    /// The first tick after which the estimate stays within 0.5 m and 0.3 rad
    /// of the truth for 10 consecutive updates (the tick of the first of them),
    /// or `None`.
    pub converged_tick: Option<u64>,
    /// Position error at the last tick, metres.
    pub position_error_final: Option<f64>,
    /// Heading error at the last tick, radians.
    pub heading_error_final: Option<f64>,
    /// Root mean square position error over the ticks from `converged_tick` on.
    pub position_rmse_converged: Option<f64>,
}

/// A running Monte Carlo localization scenario. Cloning it is a checkpoint.
#[derive(Clone, Debug)]
pub struct MclRun {
    scenario: MclScenario,
    map: Arc<LocalizationMap>,
    collision: Arc<Costmap>,
    robot: GridRobot,
    odometry: OdometrySensor,
    explorer: Explorer,
    lidar_rng: ChaCha8Rng,
    odom_rng: ChaCha8Rng,
    filters: Vec<FilterRun>,
    tick: u64,
    phase: MclPhase,
    scan: Option<Scan>,
    /// Where the latest scan was taken (the robot may have been kidnapped since).
    scan_pose: Option<Pose2>,
    path: Vec<Pose2>,
    /// The true pose at the end of every tick.
    truth_ticks: Vec<Pose2>,
    /// Indices of `path` where a kidnap starts a new stretch (a teleport, not a drive).
    path_breaks: Vec<usize>,
    notes: Vec<String>,
    kidnap_rng: ChaCha8Rng,
    kidnap_tick: Option<u64>,
    /// The student's command `(v, w)` while driving by hand; `None`: the explorer drives.
    manual: Option<(f64, f64)>,
    /// A recorded robot replayed instead of the simulated one (its truth, when
    /// it has one, has one pose per scan).
    replay: Option<Arc<MappingInput>>,
    /// The log's next scan.
    replay_next: usize,
}

impl MclRun {
    /// Starts a run on `grid`: the robot at a seeded random pose where its disc
    /// fits (with 0.1 m to spare), the filters initialized as the scenario says.
    pub fn new(scenario: MclScenario, grid: OccupancyGrid) -> Result<Self, MclRunError> {
        let seed = scenario.seed;
        let radius = robot_radius(&scenario);
        let collision = Arc::new(Costmap::inflate(&grid, radius));
        let start_cells = Costmap::inflate(&grid, radius + 0.1).valid_cells();
        let start_cells = if start_cells.is_empty() {
            collision.valid_cells()
        } else {
            start_cells
        };
        let map = LocalizationMap::new(grid, scenario.laser_likelihood_max_dist)
            .map_err(|_| MclRunError::NoFreeCell)?;
        let mut start_rng = ChaCha8Rng::seed_from_u64(stream_seed(seed, 1));
        let start = start_cells
            .sample(&mut start_rng)
            .ok_or(MclRunError::RobotDoesNotFit(radius))?;
        Ok(Self::assemble(scenario, Arc::new(map), collision, start))
    }

    /// Replays a recorded robot in `grid`: every tick's *move* takes the log's
    /// next scan and the odometry pose at it ([`MappingInput`], from a CARMEN
    /// log or a ROS 2 bag through [`crate::grid::LaserFile`]); the filters are
    /// seeded, initialized and stepped as on the simulated robot. The truth is
    /// the input's, when it has one pose per scan (a bag SLAM Lab simulated);
    /// else the run has none ([`MclRun::has_truth`]). `init = tracking` starts
    /// the particles around the first true pose, or without truth around the
    /// log's first odometry pose (the map's frame only where the robot's
    /// odometry started at its place in the map, as in a simulated log; a
    /// recorded robot wants `init = global`). The notes say where the log does
    /// not fit the map ([`log_notes`]).
    pub fn from_log(
        scenario: MclScenario,
        grid: OccupancyGrid,
        mut input: MappingInput,
    ) -> Result<Self, MclRunError> {
        let mut notes = Vec::new();
        if let Some(truth) = &input.truth
            && truth.len() != input.scans.len()
        {
            notes.push(format!(
                "the log's truth has {} poses for {} scans; it is left out",
                truth.len(),
                input.scans.len()
            ));
            input.truth = None;
        }
        // An odometry pose that is not a number would spread NaN through every
        // particle: those scans are dropped (with their truth), and counted.
        let finite: Vec<bool> = input.scans.iter().map(|s| s.odometry.is_finite()).collect();
        let dropped = finite.iter().filter(|&&ok| !ok).count();
        if dropped > 0 {
            let mut keep = finite.iter();
            input
                .scans
                .retain(|_| keep.next().copied().unwrap_or(false));
            if let Some(truth) = &mut input.truth {
                let mut keep = finite.iter();
                truth.retain(|_| keep.next().copied().unwrap_or(false));
            }
            notes.push(format!(
                "{dropped} scans whose odometry pose is not a number were left out"
            ));
        }
        let Some(first) = input.scans.first().map(|s| s.odometry) else {
            return Err(MclRunError::EmptyLog);
        };
        notes.extend(log_notes(&grid, &input));
        let radius = robot_radius(&scenario);
        let collision = Arc::new(Costmap::inflate(&grid, radius));
        let map = LocalizationMap::new(grid, scenario.laser_likelihood_max_dist)
            .map_err(|_| MclRunError::NoFreeCell)?;
        let truth_start = input.truth.as_ref().and_then(|t| t.first().copied());
        if truth_start.is_none() && scenario.init == InitMode::Tracking {
            notes.push(format!(
                "the log has no truth: tracking starts around its first odometry pose ({:.2}, {:.2}) m, {:.0}°, which is a place in the map only if the odometry started there; init global localizes a recorded robot from nothing",
                first.x,
                first.y,
                first.theta.to_degrees()
            ));
        }
        let mut run = Self::assemble(
            scenario,
            Arc::new(map),
            collision,
            truth_start.unwrap_or(first),
        );
        run.notes.extend(notes);
        run.odometry.pose = first;
        if truth_start.is_none() {
            run.path.clear();
        }
        run.replay = Some(Arc::new(input));
        Ok(run)
    }

    /// A run's pieces around the robot's start pose.
    fn assemble(
        scenario: MclScenario,
        map: Arc<LocalizationMap>,
        collision: Arc<Costmap>,
        start: Pose2,
    ) -> Self {
        let seed = scenario.seed;
        let radius = robot_radius(&scenario);
        let mut notes = Vec::new();
        let filters = scenario
            .estimators
            .iter()
            .enumerate()
            .map(|(k, est)| {
                let name = est.name();
                let mut filter = scenario.filter(
                    *est,
                    Arc::clone(&map),
                    Arc::clone(&collision),
                    100 + k as u64,
                );
                notes.extend(filter.notices().iter().map(|n| format!("{name}: {n}")));
                if scenario.init == InitMode::Tracking {
                    scenario.init_tracking(&mut filter, start);
                }
                FilterRun {
                    name,
                    filter,
                    due: false,
                    updates: Vec::new(),
                    ticks: Vec::new(),
                    estimates: Vec::new(),
                    last_predict: None,
                    last_weight: None,
                    last_resample: None,
                }
            })
            .collect();
        let explorer = Explorer::new(map.grid(), radius, scenario.explorer, stream_seed(seed, 4));
        Self {
            robot: GridRobot {
                pose: start,
                radius,
            },
            odometry: OdometrySensor::new(start, scenario.odom_noise),
            explorer,
            lidar_rng: ChaCha8Rng::seed_from_u64(stream_seed(seed, 2)),
            odom_rng: ChaCha8Rng::seed_from_u64(stream_seed(seed, 3)),
            collision,
            map,
            filters,
            tick: 0,
            phase: MclPhase::Move,
            scan: None,
            scan_pose: None,
            path: vec![start],
            truth_ticks: Vec::new(),
            path_breaks: Vec::new(),
            notes,
            kidnap_rng: ChaCha8Rng::seed_from_u64(stream_seed(seed, 5)),
            kidnap_tick: None,
            manual: None,
            replay: None,
            replay_next: 0,
            scenario,
        }
    }

    /// Executes the next phase and returns it.
    pub fn step_phase(&mut self) -> MclPhase {
        let phase = self.phase;
        if phase == MclPhase::Move && self.is_finished() {
            // A replayed log has no scan left: nothing moves.
            return phase;
        }
        match phase {
            MclPhase::Move => {
                self.move_robot();
                let odom = self.odometry.pose;
                let mut any = false;
                for f in &mut self.filters {
                    f.due = f.filter.update_due(odom);
                    any |= f.due;
                }
                if any {
                    self.phase = MclPhase::Predict;
                } else {
                    self.finish_tick();
                }
            }
            MclPhase::Predict => {
                let odom = self.odometry.pose;
                for f in self.filters.iter_mut().filter(|f| f.due) {
                    f.last_predict = Some(f.filter.predict(odom));
                }
                self.phase = MclPhase::Weight;
            }
            MclPhase::Weight => {
                if let Some(scan) = &self.scan {
                    for f in self.filters.iter_mut().filter(|f| f.due) {
                        let report = f.filter.weight(scan);
                        if let Some(note) = &report.note {
                            self.notes
                                .push(format!("tick {}: {}: {note}", self.tick, f.name));
                        }
                        f.last_weight = Some(report);
                    }
                }
                self.phase = MclPhase::Resample;
            }
            MclPhase::Resample => {
                let truth = self.truth_now();
                let tick = self.tick;
                for f in self.filters.iter_mut().filter(|f| f.due) {
                    let n_eff = f.filter.mcl().n_eff();
                    let r = f.filter.resample();
                    f.last_resample = Some(r);
                    let (pe, he, p2, h2) = match (f.filter.mcl().estimate(), truth) {
                        (Some(e), None) => {
                            let (p2, h2) = two_sigma(&e.covariance);
                            (f64::NAN, f64::NAN, p2, h2)
                        }
                        (Some(e), Some(truth)) => {
                            let (p2, h2) = two_sigma(&e.covariance);
                            (
                                math::hypot(e.pose.x - truth.x, e.pose.y - truth.y),
                                wrap_angle(e.pose.theta - truth.theta).abs(),
                                p2,
                                h2,
                            )
                        }
                        (None, Some(_)) => (f64::INFINITY, std::f64::consts::PI, 0.0, 0.0),
                        (None, None) => (f64::NAN, f64::NAN, 0.0, 0.0),
                    };
                    f.updates.push(UpdateRecord {
                        tick,
                        position_error: pe,
                        heading_error: he,
                        position_2sigma: p2,
                        heading_2sigma: h2,
                        n_eff,
                        particles: f.filter.mcl().count(),
                        resampled: r.resampled,
                        randomized: f.filter.randomized_fraction(),
                        injection_probability: f.filter.report().injection_probability,
                        log_w_slow: f.filter.report().log_w_slow,
                        log_w_fast: f.filter.report().log_w_fast,
                    });
                }
                self.finish_tick();
            }
        }
        phase
    }

    /// Runs the phases up to the end of the current tick.
    pub fn tick(&mut self) {
        if self.is_finished() {
            return;
        }
        let start = self.tick;
        while self.tick == start {
            self.step_phase();
        }
    }

    /// Runs `n` ticks.
    pub fn run_ticks(&mut self, n: u64) {
        for _ in 0..n {
            self.tick();
        }
    }

    fn move_robot(&mut self) {
        if let Some(log) = self.replay.clone() {
            let Some(s) = log.scans.get(self.replay_next) else {
                return;
            };
            self.odometry.pose = s.odometry;
            self.scan = Some(s.scan.clone());
            let truth = log
                .truth
                .as_ref()
                .and_then(|t| t.get(self.replay_next).copied());
            if let Some(pose) = truth {
                self.robot.pose = pose;
                self.path.push(pose);
            }
            self.scan_pose = truth;
            self.replay_next += 1;
            return;
        }
        if self.scenario.kidnap_at == Some(self.tick) {
            self.kidnap_random();
        }
        let dt = if self.scenario.dt > 0.0 && self.scenario.dt.is_finite() {
            self.scenario.dt
        } else {
            0.1
        };
        let (v, w) = match self.manual {
            Some(command) => command,
            None => self.explorer.command(&self.robot.pose),
        };
        let before = self.robot.pose;
        if let Some(note) = self.robot.drive(&self.collision, v, w, dt) {
            // A student driving into a wall hears it once, not every tick.
            let repeat = self.manual.is_some()
                && self
                    .notes
                    .last()
                    .is_some_and(|n| n.ends_with(note.as_str()));
            if !repeat {
                self.notes.push(format!("tick {}: {note}", self.tick));
            }
            self.explorer.replan();
        }
        let after = self.robot.pose;
        self.odometry.record(&before, &after, &mut self.odom_rng);
        self.scan = Some(
            self.scenario
                .lidar
                .scan(self.map.grid(), &after, &mut self.lidar_rng),
        );
        self.scan_pose = Some(after);
        self.path.push(after);
    }

    fn finish_tick(&mut self) {
        let truth = self.truth_now();
        let odom = self.odometry.pose;
        if let Some(truth) = truth {
            self.truth_ticks.push(truth);
        }
        for f in &mut self.filters {
            let now = f.current_estimate(&odom);
            f.estimates
                .push(now.zip(f.mcl().estimate().map(|e| e.covariance)));
            let e = match (now, truth) {
                (_, None) => TickError {
                    position: f64::NAN,
                    heading: f64::NAN,
                },
                (None, Some(_)) => TickError {
                    position: f64::INFINITY,
                    heading: std::f64::consts::PI,
                },
                (Some(p), Some(truth)) => TickError {
                    position: math::hypot(p.x - truth.x, p.y - truth.y),
                    heading: wrap_angle(p.theta - truth.theta).abs(),
                },
            };
            f.ticks.push(e);
            f.due = false;
        }
        self.tick += 1;
        self.phase = MclPhase::Move;
    }

    /// Teleports the robot (a kidnap); the filters are not told. Refused (with
    /// the reason) where the robot's disc does not fit.
    pub fn kidnap_to(&mut self, pose: Pose2) -> Result<(), String> {
        if self.replay.is_some() {
            return Err(
                "a recorded robot cannot be kidnapped: the log says where it went".to_owned(),
            );
        }
        if !self.collision.is_valid_at(pose.x, pose.y) {
            return Err(format!(
                "({:.2}, {:.2}) is inside or too close to a wall",
                pose.x, pose.y
            ));
        }
        self.robot.pose = pose;
        self.explorer.replan();
        self.path_breaks.push(self.path.len());
        self.path.push(pose);
        self.kidnap_tick = Some(self.tick);
        Ok(())
    }

    /// Teleports the robot to a random pose where it fits, at least
    /// `kidnap_distance` from where it is (the farthest of 1,000 draws if none
    /// is that far, with a note). The filters are not told.
    pub fn kidnap_random(&mut self) {
        if self.replay.is_some() {
            return;
        }
        let cells = self.collision.valid_cells();
        let here = self.robot.pose;
        let mut best: Option<(f64, Pose2)> = None;
        for _ in 0..1000 {
            let Some(p) = cells.sample(&mut self.kidnap_rng) else {
                break;
            };
            let d = math::hypot(p.x - here.x, p.y - here.y);
            if best.is_none_or(|(bd, _)| d > bd) {
                best = Some((d, p));
            }
            if d >= self.scenario.kidnap_distance {
                break;
            }
        }
        if let Some((d, p)) = best {
            if d < self.scenario.kidnap_distance {
                self.notes.push(format!(
                    "tick {}: no free pose {} m away; kidnapped {d:.2} m",
                    self.tick, self.scenario.kidnap_distance
                ));
            }
            self.robot.pose = p;
            self.explorer.replan();
            self.path_breaks.push(self.path.len());
            self.path.push(p);
            self.kidnap_tick = Some(self.tick);
        }
    }

    /// The tick of the latest kidnap.
    pub fn kidnap_tick(&self) -> Option<u64> {
        self.kidnap_tick
    }

    /// The scenario.
    pub fn scenario(&self) -> &MclScenario {
        &self.scenario
    }

    /// The map with its distance field and free cells.
    pub fn map(&self) -> &Arc<LocalizationMap> {
        &self.map
    }

    /// The map inflated by the robot radius (where the robot's centre may be).
    pub fn collision_map(&self) -> &Costmap {
        &self.collision
    }

    /// The true robot.
    pub fn robot(&self) -> &GridRobot {
        &self.robot
    }

    /// The true path so far.
    pub fn path(&self) -> &[Pose2] {
        &self.path
    }

    /// The true pose at the end of every tick (`path` also holds the kidnaps'
    /// teleports).
    pub fn truth_ticks(&self) -> &[Pose2] {
        &self.truth_ticks
    }

    /// The true path in stretches: a kidnap teleports the robot, so the path breaks
    /// there instead of joining the two places through the walls.
    pub fn path_stretches(&self) -> Vec<&[Pose2]> {
        let mut out = Vec::with_capacity(self.path_breaks.len() + 1);
        let mut start = 0;
        for &b in &self.path_breaks {
            if b > start && b <= self.path.len() {
                out.push(&self.path[start..b]);
                start = b;
            }
        }
        out.push(&self.path[start..]);
        out
    }

    /// Where the latest scan ([`Self::scan`]) was taken: the robot's pose at its last
    /// move, which a kidnap since then does not change.
    pub fn scan_pose(&self) -> Option<Pose2> {
        self.scan_pose
    }

    /// Filter `k`'s error now: its estimate moved by the odometry since its last
    /// update (as amcl publishes it) against the true pose now, kidnap included.
    /// `None` before the filter has an estimate.
    pub fn error_now(&self, k: usize) -> Option<TickError> {
        let estimate = self.filters.get(k)?.current_estimate(&self.odometry())?;
        let truth = self.truth_now()?;
        Some(TickError {
            position: math::hypot(estimate.x - truth.x, estimate.y - truth.y),
            heading: wrap_angle(estimate.theta - truth.theta).abs(),
        })
    }

    /// Filter `k`'s status ([`FilterRun::status`]) with its error now: the one status
    /// line every panel shows.
    pub fn status_of(&self, k: usize) -> String {
        let Some(f) = self.filters.get(k) else {
            return String::new();
        };
        if self.has_truth() {
            return f.status(self.kidnap_tick(), self.scenario().dt, self.error_now(k));
        }
        let estimate = f.current_estimate(&self.odometry());
        match (estimate, f.mcl().estimate()) {
            (Some(p), Some(e)) => {
                let (p2, _) = two_sigma(&e.covariance);
                format!(
                    "no truth in this log: estimate ({:.2}, {:.2}) m, {:.0}°, 2σ {p2:.2} m",
                    p.x,
                    p.y,
                    p.theta.to_degrees()
                )
            }
            _ => "no truth in this log; waiting for the robot to move".to_owned(),
        }
    }

    /// Whether the run knows where the robot truly is: always for the simulated
    /// robot, for a replayed log only when it carries its truth.
    pub fn has_truth(&self) -> bool {
        self.replay.as_ref().is_none_or(|log| log.truth.is_some())
    }

    /// The true pose now, if the run has a truth.
    pub fn truth_now(&self) -> Option<Pose2> {
        self.has_truth().then_some(self.robot.pose)
    }

    /// The replayed log, if the run replays one.
    pub fn log(&self) -> Option<&MappingInput> {
        self.replay.as_deref()
    }

    /// For a replayed log: scans replayed so far and the log's scan count.
    pub fn log_progress(&self) -> Option<(usize, usize)> {
        self.replay
            .as_ref()
            .map(|log| (self.replay_next, log.scans.len()))
    }

    /// Whether a replayed log has run out of scans (never for the simulated
    /// robot).
    pub fn is_finished(&self) -> bool {
        self.log_progress().is_some_and(|(done, all)| done >= all)
    }

    /// The time at the end of tick `k` (from 0), seconds: `(k + 1) · dt` for the
    /// simulated robot, the scan's time since the log's first scan for a log.
    pub fn tick_time(&self, k: usize) -> f64 {
        match &self.replay {
            Some(log) => log.scans.get(k).map_or(f64::NAN, |s| s.time),
            None => (k + 1) as f64 * self.scenario.dt,
        }
    }

    /// The odometry pose.
    pub fn odometry(&self) -> Pose2 {
        self.odometry.pose
    }

    /// The latest scan.
    pub fn scan(&self) -> Option<&Scan> {
        self.scan.as_ref()
    }

    /// Drives by hand with `(v, w)` (m/s, rad/s; non-finite values count as 0)
    /// from the next move on, or gives the wheel back to the explorer (`None`),
    /// which plans afresh from where the robot is.
    pub fn set_manual(&mut self, command: Option<(f64, f64)>) {
        let finite = |x: f64| if x.is_finite() { x } else { 0.0 };
        self.manual = command.map(|(v, w)| (finite(v), finite(w)));
        if command.is_none() {
            self.explorer.replan();
        }
    }

    /// The student's command while driving by hand.
    pub fn manual(&self) -> Option<(f64, f64)> {
        self.manual
    }

    /// The explorer (its current path, for drawing).
    pub fn explorer(&self) -> &Explorer {
        &self.explorer
    }

    /// The filters with their records.
    pub fn filters(&self) -> &[FilterRun] {
        &self.filters
    }

    /// Mutable filters (for a lesson's buttons: global localization, reset
    /// around the truth).
    pub fn filters_mut(&mut self) -> &mut [FilterRun] {
        &mut self.filters
    }

    /// Ticks completed.
    pub fn tick_count(&self) -> u64 {
        self.tick
    }

    /// The phase that [`step_phase`](Self::step_phase) will run next.
    pub fn next_phase(&self) -> MclPhase {
        self.phase
    }

    /// Notes: clamped parameters, collisions, scans that contradicted every
    /// particle.
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// Every filter's summary.
    pub fn summaries(&self) -> Vec<FilterSummary> {
        self.filters.iter().map(FilterRun::summary).collect()
    }
}

/// The robot's radius from the scenario (0.2 m where it is not a length).
fn robot_radius(scenario: &MclScenario) -> f64 {
    if scenario.robot_radius >= 0.0 && scenario.robot_radius.is_finite() {
        scenario.robot_radius
    } else {
        0.2
    }
}

/// Twice the standard deviations of a pose covariance: along the position
/// ellipse's longest axis (the square root of the larger eigenvalue of the
/// 2 x 2 block, `λ = (a + d)/2 + sqrt(((a − d)/2)² + b²)`), and in heading.
fn two_sigma(c: &Matrix3<f64>) -> (f64, f64) {
    let a = c[(0, 0)];
    let b = c[(0, 1)];
    let d = c[(1, 1)];
    let lmax = 0.5 * (a + d) + (0.25 * (a - d) * (a - d) + b * b).sqrt();
    (2.0 * lmax.max(0.0).sqrt(), 2.0 * c[(2, 2)].max(0.0).sqrt())
}

/// Where a log does not fit the map it is replayed in, one sentence each:
/// true poses (when the log has them) outside the map's free cells, or an
/// odometry path wider or taller than the whole map (then the log was
/// recorded somewhere else: the filters will find nothing).
pub fn log_notes(grid: &OccupancyGrid, input: &MappingInput) -> Vec<String> {
    let mut notes = Vec::new();
    let (w, h) = grid.size_m();
    if let Some(truth) = &input.truth {
        let outside = truth
            .iter()
            .filter(|p| grid.cell_at(p.x, p.y) != Some(slamlab_core::grid::Cell::Free))
            .count();
        if outside > 0 {
            notes.push(format!(
                "{outside} of the log's {} true poses are outside the map's free space: was it recorded in this map?",
                truth.len()
            ));
        }
        return notes;
    }
    let xs = input.scans.iter().map(|s| s.odometry.x);
    let ys = input.scans.iter().map(|s| s.odometry.y);
    let span = |v: &mut dyn Iterator<Item = f64>| {
        let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        });
        if hi >= lo { hi - lo } else { 0.0 }
    };
    let (sx, sy) = (span(&mut xs.into_iter()), span(&mut ys.into_iter()));
    // The odometry drifts, but not by the map's whole size; a path that spans more
    // than the map's diagonal cannot have been driven inside it.
    let diagonal = math::hypot(w, h);
    if math::hypot(sx, sy) > diagonal {
        notes.push(format!(
            "the log's odometry spans {sx:.1} x {sy:.1} m, more than the map ({w:.1} x {h:.1} m) holds: its scans fall outside this map; was it recorded here?"
        ));
    }
    notes
}
