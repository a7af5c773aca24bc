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

use super::scenario::{InitMode, MclScenario};
use crate::grid::explorer::Explorer;
use crate::grid::robot::{GridRobot, OdometrySensor};
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
        FilterSummary {
            name: self.name.to_owned(),
            particles: self.mcl().count(),
            converged_tick,
            position_error_final: last.map(|e| e.position),
            heading_error_final: last.map(|e| e.heading),
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
}

impl MclRun {
    /// Starts a run on `grid`: the robot at a seeded random pose where its disc
    /// fits (with 0.1 m to spare), the filters initialized as the scenario says.
    pub fn new(scenario: MclScenario, grid: OccupancyGrid) -> Result<Self, MclRunError> {
        let seed = scenario.seed;
        let radius = if scenario.robot_radius >= 0.0 && scenario.robot_radius.is_finite() {
            scenario.robot_radius
        } else {
            0.2
        };
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
        let map = Arc::new(map);
        let mut notes = Vec::new();
        let filters = scenario
            .estimators
            .iter()
            .enumerate()
            .map(|(k, est)| {
                let name = est.name();
                let mut filter = RecoveringMcl::new(
                    est.recovery(),
                    scenario.mcl_config(),
                    scenario.recovery_alphas(),
                    Arc::clone(&map),
                    Some(Arc::clone(&collision)),
                    stream_seed(seed, 100 + k as u64),
                );
                notes.extend(filter.notices().iter().map(|n| format!("{name}: {n}")));
                if scenario.init == InitMode::Tracking {
                    let sd = |v: f64| if v > 0.0 { v.sqrt() } else { 0.0 };
                    filter.mcl_mut().init_tracking(
                        start,
                        [
                            sd(scenario.initial_cov_xx),
                            sd(scenario.initial_cov_yy),
                            sd(scenario.initial_cov_aa),
                        ],
                    );
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
        Ok(Self {
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
            scenario,
        })
    }

    /// Executes the next phase and returns it.
    pub fn step_phase(&mut self) -> MclPhase {
        let phase = self.phase;
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
                let truth = self.robot.pose;
                let tick = self.tick;
                for f in self.filters.iter_mut().filter(|f| f.due) {
                    let n_eff = f.filter.mcl().n_eff();
                    let r = f.filter.resample();
                    f.last_resample = Some(r);
                    let (pe, he, p2, h2) = match f.filter.mcl().estimate() {
                        Some(e) => {
                            let c = e.covariance;
                            let a = c[(0, 0)];
                            let b = c[(0, 1)];
                            let d = c[(1, 1)];
                            let lmax = 0.5 * (a + d) + (0.25 * (a - d) * (a - d) + b * b).sqrt();
                            (
                                math::hypot(e.pose.x - truth.x, e.pose.y - truth.y),
                                wrap_angle(e.pose.theta - truth.theta).abs(),
                                2.0 * lmax.max(0.0).sqrt(),
                                2.0 * c[(2, 2)].max(0.0).sqrt(),
                            )
                        }
                        None => (f64::INFINITY, std::f64::consts::PI, 0.0, 0.0),
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
        let truth = self.robot.pose;
        let odom = self.odometry.pose;
        self.truth_ticks.push(truth);
        for f in &mut self.filters {
            let now = f.current_estimate(&odom);
            f.estimates
                .push(now.zip(f.mcl().estimate().map(|e| e.covariance)));
            let e = now.map_or(
                TickError {
                    position: f64::INFINITY,
                    heading: std::f64::consts::PI,
                },
                |p| TickError {
                    position: math::hypot(p.x - truth.x, p.y - truth.y),
                    heading: wrap_angle(p.theta - truth.theta).abs(),
                },
            );
            f.ticks.push(e);
            f.due = false;
        }
        self.tick += 1;
        self.phase = MclPhase::Move;
    }

    /// Teleports the robot (a kidnap); the filters are not told. Refused (with
    /// the reason) where the robot's disc does not fit.
    pub fn kidnap_to(&mut self, pose: Pose2) -> Result<(), String> {
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
        let truth = self.robot().pose;
        Some(TickError {
            position: math::hypot(estimate.x - truth.x, estimate.y - truth.y),
            heading: wrap_angle(estimate.theta - truth.theta).abs(),
        })
    }

    /// Filter `k`'s status ([`FilterRun::status`]) with its error now: the one status
    /// line every panel shows.
    pub fn status_of(&self, k: usize) -> String {
        self.filters.get(k).map_or_else(String::new, |f| {
            f.status(self.kidnap_tick(), self.scenario().dt, self.error_now(k))
        })
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
