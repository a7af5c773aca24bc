//! A running landmark-SLAM lesson: the true world, the estimators, and time
//! advanced one phase or one tick at a time.
//!
//! One tick is: the controller gives a command; the true robot moves with that
//! command plus noise; the sensor measures the landmarks in view, with noise;
//! then every estimator runs its phases on the same command and measurements:
//! first `predict`, then one `update` per observed landmark, in id order, and,
//! when a particle filter (FastSLAM) runs, `resample` last. For FastSLAM the
//! three phases are: sample (a new pose per particle), weight (per observation),
//! resample.
//!
//! With `association=unknown` the estimators do not get the sensor's ids: FastSLAM
//! associates per particle by maximum likelihood, the Gaussian filters by nearest
//! neighbour with a Mahalanobis gate ([`slamlab_core::association`]). A "wrong
//! association" ([`LandmarkSession::mislabel_next_observation`]) makes the sensor
//! give one observation of the next tick the id of another landmark.

use crate::noise::{Stream, gaussian, stream_rng};
use crate::params::{self, ParamIssue};
use crate::particle_estimator::{FastSlamEstimator, OWN_LABELS};
use crate::scenario::{Association, ControllerKind, EstimatorKind, LandmarkScenario};
use crate::world::LandmarkWorld;
use nalgebra::{DMatrix, DVector, Vector2};
use rand_chacha::ChaCha8Rng;
use slamlab_core::association::{
    AssociationMode, GaussianMap, NearestNeighbour, nearest_neighbour,
};
use slamlab_core::kalman::{
    EkfSlam, LandmarkSlam, Linearization, PredictReport, UkfSlam, UpdateReport,
};
use slamlab_core::math;
use slamlab_core::particle::fastslam::{FastSlamNoise, ResamplePolicy, ResampleReport};
use slamlab_core::particle::{FastSlamConfig, FastSlamVersion};
use slamlab_core::range_bearing::{self, RangeBearing, RangeBearingSensor};
use slamlab_core::stats::normalized_squared_error;
use slamlab_core::{Control, MotionModel, Pose2, wrap_angle};
use std::collections::{BTreeSet, VecDeque};

/// One step of an estimator within a tick.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// Motion prediction with the tick's command.
    Predict,
    /// Update with the measurement of one landmark.
    Update {
        /// The landmark's id.
        id: usize,
        /// Position of this update within the tick, from 1.
        index: usize,
        /// Number of updates in the tick.
        count: usize,
    },
    /// Resampling of the particle filters (only in sessions that run one).
    Resample,
}

impl Phase {
    /// The phase's name as shown on screen, e.g. "update landmark 7 (2 of 5)".
    pub fn label(&self) -> String {
        match self {
            Phase::Predict => "predict".to_owned(),
            Phase::Update { id, index, count } => {
                format!("update landmark {id} ({index} of {count})")
            }
            Phase::Resample => "resample".to_owned(),
        }
    }
}

/// A measurement made this tick, with the truth behind it (for drawing only).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Observation {
    /// The landmark's id.
    pub id: usize,
    /// What the sensor reported.
    pub measurement: RangeBearing,
    /// Where the measurement puts the landmark, seen from the true robot pose.
    pub measured_point: Vector2<f64>,
}

/// Errors and uncertainty of one estimator after one tick.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TickMetrics {
    /// Tick number, from 1.
    pub tick: u64,
    /// Simulated time, seconds.
    pub time: f64,
    /// True minus estimated robot pose: `[x m, y m, θ rad]`, heading wrapped.
    pub error: [f64; 3],
    /// The filter's standard deviations of `[x, y, θ]`.
    pub sigma: [f64; 3],
    /// Robot position error `‖(e_x, e_y)‖`, metres.
    pub position_error: f64,
    /// The filter's 2-sigma bound on that error: `2 √(σ_x² + σ_y²)`, metres.
    pub position_bound_2sigma: f64,
    /// Robot-pose NEES `eᵀ P_RR⁻¹ e` (3 degrees of freedom); `None` while `P_RR` is singular.
    pub nees: Option<f64>,
    /// RMS position error over the landmarks initialized so far, metres.
    pub landmark_rmse: Option<f64>,
    /// Landmarks in the state.
    pub landmarks_initialized: usize,
}

/// One update's normalized innovation squared (2 degrees of freedom).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NisSample {
    /// Tick of the update.
    pub tick: u64,
    /// The landmark.
    pub id: usize,
    /// `νᵀ S⁻¹ ν`.
    pub nis: f64,
}

/// A particle filter's effective sample size at one tick, before resampling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NeffSample {
    /// The tick.
    pub tick: u64,
    /// `N_eff = 1 / Σ wᵢ²` before the resampling phase.
    pub n_eff: f64,
    /// The particle count `M`.
    pub particles: usize,
    /// Whether the set was resampled.
    pub resampled: bool,
}

/// The wrong association the sensor made this tick.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Mislabel {
    /// The observation's position in this tick's list.
    pub index: usize,
    /// The landmark really measured.
    pub true_id: usize,
    /// The id the sensor reported.
    pub reported_id: usize,
}

/// One estimator and its history in a session.
#[derive(Debug)]
pub struct FilterRun {
    /// Which estimator this is.
    pub kind: EstimatorKind,
    filter: Box<dyn LandmarkSlamDebug>,
    /// The estimated robot pose after every completed tick, starting with the start pose.
    pub path: Vec<Pose2>,
    /// Metrics after every completed tick.
    pub history: Vec<TickMetrics>,
    /// NIS of every correcting update.
    pub nis: Vec<NisSample>,
    /// A particle filter's `N_eff` at every resampling phase (empty for the others).
    pub n_eff: Vec<NeffSample>,
    /// The latest resampling (particle filters).
    pub last_resample: Option<ResampleReport>,
    /// The next label for a landmark this filter starts itself (nearest-neighbour
    /// association), from [`OWN_LABELS`].
    next_label: usize,
    /// The latest prediction.
    pub last_predict: Option<PredictReport>,
    /// The latest landmark update.
    pub last_update: Option<UpdateReport>,
    /// The latest error, if the latest phase failed (the state is then unchanged).
    pub last_error: Option<String>,
}

/// `LandmarkSlam` plus `Debug` and cloning, so sessions can be printed and
/// checkpointed.
pub trait LandmarkSlamDebug: LandmarkSlam + std::fmt::Debug {
    /// A boxed copy.
    fn clone_box(&self) -> Box<dyn LandmarkSlamDebug>;
}
impl<T: LandmarkSlam + std::fmt::Debug + Clone + 'static> LandmarkSlamDebug for T {
    fn clone_box(&self) -> Box<dyn LandmarkSlamDebug> {
        Box::new(self.clone())
    }
}

/// A change of the sensor's field of view and range made while the run goes on,
/// in effect from tick `from_tick` (the measurements of earlier ticks stay).
#[derive(Clone, Copy, Debug, PartialEq)]
struct SensorChange {
    from_tick: u64,
    fov: f64,
    max_range: f64,
}

/// Ticks between two checkpoints.
const CHECKPOINT_EVERY: u64 = 50;
/// At most this many checkpoints are kept...
const MAX_CHECKPOINTS: usize = 20;
/// ...and they hold at most about this many bytes of filter state.
const CHECKPOINT_BUDGET_BYTES: usize = 64 << 20;

/// The session at the end of a tick, so that stepping back replays from here
/// rather than from the start. It keeps everything but the records that only grow
/// (paths, metrics, commands), of which it notes the lengths.
#[derive(Debug)]
struct Checkpoint {
    /// A copy with empty records and no checkpoints of its own.
    state: Box<LandmarkSession>,
    records: RecordLengths,
}

/// The lengths of a session's growing records.
#[derive(Clone, Debug, PartialEq)]
struct RecordLengths {
    truth_path: usize,
    dead_reckoning_path: usize,
    commands: usize,
    /// Per filter: path, history, NIS samples, N_eff samples.
    filters: Vec<(usize, usize, usize, usize)>,
}

impl FilterRun {
    /// A copy of everything but the records (path, history, NIS).
    fn without_records(&self) -> FilterRun {
        FilterRun {
            kind: self.kind,
            filter: self.filter.clone_box(),
            path: Vec::new(),
            history: Vec::new(),
            nis: Vec::new(),
            n_eff: Vec::new(),
            last_resample: self.last_resample,
            next_label: self.next_label,
            last_predict: self.last_predict,
            last_update: self.last_update,
            last_error: self.last_error.clone(),
        }
    }

    /// The estimator's read-only view.
    pub fn filter(&self) -> &dyn LandmarkSlam {
        &*self.filter
    }

    /// Metrics after the latest completed tick.
    pub fn latest(&self) -> Option<&TickMetrics> {
        self.history.last()
    }
}

/// A landmark-SLAM run in progress.
#[derive(Debug)]
pub struct LandmarkSession {
    scenario: LandmarkScenario,
    world: LandmarkWorld,
    sensor: RangeBearingSensor,
    control_rng: ChaCha8Rng,
    measurement_rng: ChaCha8Rng,
    truth: Pose2,
    truth_path: Vec<Pose2>,
    dead_reckoning: Pose2,
    dead_reckoning_path: Vec<Pose2>,
    tick: u64,
    /// Who drives now; starts as the scenario's controller and can be switched mid-run.
    controller: ControllerKind,
    teleop: Control,
    /// A replay's command for the next tick, overriding the controller.
    replayed_command: Option<Control>,
    command: Control,
    observations: Vec<Observation>,
    pending: VecDeque<Phase>,
    last_phase: Option<Phase>,
    filters: Vec<FilterRun>,
    notices: Vec<String>,
    /// The command of every tick started so far: with the seed and the sensor
    /// changes, all a replay needs.
    commands: Vec<Control>,
    /// Live changes of the sensor's reach, in tick order.
    sensor_changes: Vec<SensorChange>,
    /// Ticks at which the sensor mislabels one observation, in order.
    mislabel_ticks: Vec<u64>,
    /// This tick's wrong association, if any.
    mislabel: Option<Mislabel>,
    /// Landmarks measured in earlier ticks (the mislabel picks one of them).
    seen: BTreeSet<usize>,
    phases_run: u64,
    /// Checkpoints every [`CHECKPOINT_EVERY`] ticks, oldest first.
    checkpoints: VecDeque<Checkpoint>,
}

impl LandmarkSession {
    /// Starts a session. The scenario is checked first; whatever had to be changed
    /// is listed in [`notices`](Self::notices).
    pub fn new(mut scenario: LandmarkScenario) -> Self {
        let mut notices: Vec<String> = params::sanitize(&mut scenario)
            .iter()
            .map(ParamIssue::to_string)
            .collect();
        let world = LandmarkWorld::generate(
            scenario.layout,
            scenario.landmarks,
            scenario.world_size,
            scenario.circle_radius(),
            scenario.seed,
        );
        let start = scenario.start_pose();
        let mut filters = Vec::new();
        for &kind in &scenario.estimators {
            let built: Result<Box<dyn LandmarkSlamDebug>, String> = match kind {
                EstimatorKind::Ekf => EkfSlam::new(scenario.filter_config(), start)
                    .map(|f| Box::new(f) as _)
                    .map_err(|e| e.to_string()),
                EstimatorKind::Ukf => UkfSlam::new(scenario.filter_config(), scenario.ukf, start)
                    .map(|f| Box::new(f) as _)
                    .map_err(|e| e.to_string()),
                EstimatorKind::FejEkf => EkfSlam::with_linearization(
                    scenario.filter_config(),
                    start,
                    Linearization::FirstEstimates,
                )
                .map(|f| Box::new(f) as _)
                .map_err(|e| e.to_string()),
                EstimatorKind::IdealEkf => EkfSlam::with_linearization(
                    scenario.filter_config(),
                    start,
                    Linearization::TrueState,
                )
                .map(|f| Box::new(f) as _)
                .map_err(|e| e.to_string()),
                EstimatorKind::FastSlam1 | EstimatorKind::FastSlam2 => {
                    FastSlamEstimator::new(fastslam_config(&scenario, kind), start)
                        .map(|f| Box::new(f) as _)
                        .map_err(|e| e.to_string())
                }
            };
            match built {
                Ok(filter) => filters.push(FilterRun {
                    kind,
                    filter,
                    path: vec![start],
                    history: Vec::new(),
                    nis: Vec::new(),
                    n_eff: Vec::new(),
                    last_resample: None,
                    next_label: OWN_LABELS,
                    last_predict: None,
                    last_update: None,
                    last_error: None,
                }),
                Err(e) => notices.push(format!(
                    "{} could not start: {e}; change the parameter and reset",
                    kind.name()
                )),
            }
        }
        if world
            .landmarks
            .iter()
            .any(|l| (l.position - start.translation()).norm() < range_bearing::MIN_RANGE)
        {
            notices.push("a landmark sits on the robot's start position; it is not measured while the robot is on it".to_owned());
        }
        Self {
            sensor: scenario.sensor(),
            control_rng: stream_rng(scenario.seed, Stream::Control),
            measurement_rng: stream_rng(scenario.seed, Stream::Measurement),
            truth: start,
            truth_path: vec![start],
            dead_reckoning: start,
            dead_reckoning_path: vec![start],
            tick: 0,
            controller: scenario.controller,
            teleop: Control::default(),
            replayed_command: None,
            command: Control::default(),
            observations: Vec::new(),
            pending: VecDeque::new(),
            last_phase: None,
            filters,
            notices,
            world,
            scenario,
            commands: Vec::new(),
            sensor_changes: Vec::new(),
            mislabel_ticks: Vec::new(),
            mislabel: None,
            seen: BTreeSet::new(),
            phases_run: 0,
            checkpoints: VecDeque::new(),
        }
    }

    /// A copy of the session without its growing records and checkpoints.
    fn without_records(&self) -> LandmarkSession {
        LandmarkSession {
            scenario: self.scenario.clone(),
            world: self.world.clone(),
            sensor: self.sensor,
            control_rng: self.control_rng.clone(),
            measurement_rng: self.measurement_rng.clone(),
            truth: self.truth,
            truth_path: Vec::new(),
            dead_reckoning: self.dead_reckoning,
            dead_reckoning_path: Vec::new(),
            tick: self.tick,
            controller: self.controller,
            teleop: self.teleop,
            replayed_command: self.replayed_command,
            command: self.command,
            observations: self.observations.clone(),
            pending: self.pending.clone(),
            last_phase: self.last_phase,
            filters: self
                .filters
                .iter()
                .map(FilterRun::without_records)
                .collect(),
            notices: Vec::new(),
            commands: Vec::new(),
            sensor_changes: Vec::new(),
            mislabel_ticks: Vec::new(),
            mislabel: self.mislabel,
            seen: self.seen.clone(),
            phases_run: self.phases_run,
            checkpoints: VecDeque::new(),
        }
    }

    fn record_lengths(&self) -> RecordLengths {
        RecordLengths {
            truth_path: self.truth_path.len(),
            dead_reckoning_path: self.dead_reckoning_path.len(),
            commands: self.commands.len(),
            filters: self
                .filters
                .iter()
                .map(|r| (r.path.len(), r.history.len(), r.nis.len(), r.n_eff.len()))
                .collect(),
        }
    }

    /// How many checkpoints fit the memory budget with this state size.
    fn checkpoint_capacity(&self) -> usize {
        let bytes_per_checkpoint: usize = self
            .filters
            .iter()
            .map(|r| r.filter.mean().len().pow(2) * std::mem::size_of::<f64>())
            .sum::<usize>()
            .max(1);
        (CHECKPOINT_BUDGET_BYTES / bytes_per_checkpoint).clamp(2, MAX_CHECKPOINTS)
    }

    /// The phases a [`step_back`](Self::step_back) would replay now: from the latest
    /// checkpoint before the previous phase, or from the start.
    pub fn step_back_replay_length(&self) -> u64 {
        let Some(target) = self.phases_run.checked_sub(1) else {
            return 0;
        };
        let from = self
            .checkpoints
            .iter()
            .rev()
            .find(|c| c.state.phases_run <= target)
            .map_or(0, |c| c.state.phases_run);
        target - from
    }

    /// The scenario as it runs (after checking).
    pub fn scenario(&self) -> &LandmarkScenario {
        &self.scenario
    }

    /// The true world.
    pub fn world(&self) -> &LandmarkWorld {
        &self.world
    }

    /// The simulated sensor.
    pub fn sensor(&self) -> &RangeBearingSensor {
        &self.sensor
    }

    /// The true robot pose.
    pub fn truth(&self) -> Pose2 {
        self.truth
    }

    /// The true path, one pose per tick.
    pub fn truth_path(&self) -> &[Pose2] {
        &self.truth_path
    }

    /// Where the robot would think it is from the commands alone (no measurements).
    pub fn dead_reckoning(&self) -> Pose2 {
        self.dead_reckoning
    }

    /// The dead-reckoning path, one pose per tick.
    pub fn dead_reckoning_path(&self) -> &[Pose2] {
        &self.dead_reckoning_path
    }

    /// Ticks started so far.
    pub fn tick(&self) -> u64 {
        self.tick
    }

    /// Simulated time of the latest tick, seconds.
    pub fn time(&self) -> f64 {
        self.tick as f64 * self.scenario.dt
    }

    /// The command of the current tick.
    pub fn command(&self) -> Control {
        self.command
    }

    /// The measurements of the current tick.
    pub fn observations(&self) -> &[Observation] {
        &self.observations
    }

    /// The estimators.
    pub fn filters(&self) -> &[FilterRun] {
        &self.filters
    }

    /// Messages for the user: parameters that were changed, estimators that could not start.
    pub fn notices(&self) -> &[String] {
        &self.notices
    }

    /// The phase that ran last.
    pub fn last_phase(&self) -> Option<Phase> {
        self.last_phase
    }

    /// The phase that runs next, if the current tick is not finished.
    pub fn next_phase(&self) -> Option<Phase> {
        self.pending.front().copied()
    }

    /// True between the first and the last phase of a tick.
    pub fn is_mid_tick(&self) -> bool {
        !self.pending.is_empty()
    }

    /// Sets the command used by manual driving (keyboard, on-screen buttons).
    /// Non-finite values are ignored.
    pub fn set_teleop(&mut self, control: Control) {
        if control.is_finite() {
            self.teleop = control;
        }
    }

    /// Who drives the robot now.
    pub fn controller(&self) -> ControllerKind {
        self.controller
    }

    /// Hands the robot to `controller` from the next tick on. Nothing else changes:
    /// the world, the filters and the noise streams carry on, and
    /// [`step_back`](Self::step_back) still replays exactly (it replays the commands).
    /// A circle without finite speeds is ignored.
    pub fn set_controller(&mut self, controller: ControllerKind) {
        if let ControllerKind::Circle { v, w } = controller
            && !(v.is_finite() && w.is_finite())
        {
            return;
        }
        self.controller = controller;
    }

    /// Changes the sensor's field of view (radians) and maximum range (metres) from
    /// the next tick on, while the run goes on: neither enters the filters, which
    /// only see the measurements. Values outside the parameters' ranges are
    /// clamped; non-finite ones change nothing. A change made after stepping back
    /// replaces the recorded changes that came later.
    pub fn set_sensor_reach(&mut self, fov: f64, max_range: f64) {
        if !(fov.is_finite() && max_range.is_finite()) {
            return;
        }
        let mut checked = self.scenario_now();
        checked.fov = fov;
        checked.max_range = max_range;
        let _clamped = params::sanitize(&mut checked);
        let from_tick = self.tick + 1;
        self.sensor_changes.retain(|c| c.from_tick < from_tick);
        self.sensor_changes.push(SensorChange {
            from_tick,
            fov: checked.fov,
            max_range: checked.max_range,
        });
    }

    /// The scenario as it stands now: the one the run started with, with the
    /// controller that drives now and the sensor's reach of the next tick.
    pub fn scenario_now(&self) -> LandmarkScenario {
        let (fov, max_range) = self
            .sensor_changes
            .iter()
            .rev()
            .find(|c| c.from_tick <= self.tick + 1)
            .map_or((self.sensor.fov, self.sensor.max_range), |c| {
                (c.fov, c.max_range)
            });
        LandmarkScenario {
            controller: self.controller,
            fov,
            max_range,
            ..self.scenario.clone()
        }
    }

    /// The command of every tick started so far, in order.
    pub fn commands(&self) -> &[Control] {
        &self.commands
    }

    /// The manual-driving command.
    pub fn teleop(&self) -> Control {
        self.teleop
    }

    /// Runs the next phase (starting a new tick when the last one is finished) and
    /// returns it.
    pub fn step_phase(&mut self) -> Phase {
        if self.pending.is_empty() {
            self.begin_tick();
        }
        let phase = self.pending.pop_front().unwrap_or(Phase::Predict);
        self.run_phase(phase);
        self.phases_run += 1;
        if self.pending.is_empty() {
            self.end_tick();
        }
        phase
    }

    /// Phases run since the start.
    pub fn phases_run(&self) -> u64 {
        self.phases_run
    }

    /// Goes back one phase: the session becomes exactly what it was before the
    /// last phase ran. Returns `false` at the start.
    ///
    /// The run is deterministic given the scenario (with its seed) and the tick
    /// commands, so this replays them from the latest checkpoint before that phase
    /// (one every 50 ticks, the latest 20 or as many as 64 MB hold), or from the start.
    pub fn step_back(&mut self) -> bool {
        let Some(target) = self.phases_run.checked_sub(1) else {
            return false;
        };
        let checkpoint = self
            .checkpoints
            .iter()
            .rev()
            .find(|c| c.state.phases_run <= target);
        let mut replay = match checkpoint {
            Some(checkpoint) => {
                let mut replay = checkpoint.state.without_records();
                let lengths = &checkpoint.records;
                replay.truth_path = self.truth_path[..lengths.truth_path].to_vec();
                replay.dead_reckoning_path =
                    self.dead_reckoning_path[..lengths.dead_reckoning_path].to_vec();
                replay.commands = self.commands[..lengths.commands].to_vec();
                for (run, (from, &(path, history, nis, n_eff))) in replay
                    .filters
                    .iter_mut()
                    .zip(self.filters.iter().zip(&lengths.filters))
                {
                    run.path = from.path[..path].to_vec();
                    run.history = from.history[..history].to_vec();
                    run.nis = from.nis[..nis].to_vec();
                    run.n_eff = from.n_eff[..n_eff].to_vec();
                }
                replay
            }
            None => LandmarkSession::new(self.scenario.clone()),
        };
        // Every change, the later ones too: stepping forward again replays them.
        replay.sensor_changes = self.sensor_changes.clone();
        replay.mislabel_ticks = self.mislabel_ticks.clone();
        replay.checkpoints = std::mem::take(&mut self.checkpoints);
        replay.checkpoints.retain(|c| c.state.phases_run <= target);
        while replay.phases_run < target {
            if replay.pending.is_empty() {
                replay.replayed_command = self.commands.get(replay.commands.len()).copied();
            }
            replay.step_phase();
        }
        replay.replayed_command = None;
        replay.controller = self.controller;
        replay.teleop = self.teleop;
        replay.notices = std::mem::take(&mut self.notices);
        *self = replay;
        true
    }

    /// Finishes the current tick, or runs a whole new one.
    pub fn step_tick(&mut self) {
        loop {
            self.step_phase();
            if self.pending.is_empty() {
                break;
            }
        }
    }

    /// Runs `count` whole ticks.
    pub fn run_ticks(&mut self, count: u64) {
        for _ in 0..count {
            self.step_tick();
        }
    }

    fn begin_tick(&mut self) {
        self.tick += 1;
        if let Some(change) = self
            .sensor_changes
            .iter()
            .find(|c| c.from_tick == self.tick)
        {
            self.sensor.fov = change.fov;
            self.sensor.max_range = change.max_range;
        }
        let dt = self.scenario.dt;
        self.command = match (self.replayed_command.take(), self.controller) {
            (Some(command), _) => command,
            (None, ControllerKind::Circle { v, w }) => Control::new(v, w),
            (None, ControllerKind::Manual) => self.teleop,
        };
        self.commands.push(self.command);
        // Noise is on the executed wheel speeds of a moving robot; a robot told to
        // stop stays put (and the estimators add no process noise for it).
        let executed = if self.command == Control::default() {
            self.command
        } else {
            Control::new(
                self.command.v + gaussian(&mut self.control_rng, self.scenario.v_std),
                self.command.w + gaussian(&mut self.control_rng, self.scenario.w_std),
            )
        };
        let robot_before = self.truth;
        self.truth = MotionModel::ExactArc.predict(&self.truth, &executed, dt);
        for run in &mut self.filters {
            run.filter.observe_truth(
                robot_before,
                self.truth,
                &mut self.world.landmarks.iter().map(|l| (l.id, l.position)),
            );
        }
        self.dead_reckoning = self
            .scenario
            .motion
            .predict(&self.dead_reckoning, &self.command, dt);

        self.observations.clear();
        for landmark in &self.world.landmarks {
            if !self.sensor.sees(&self.truth, &landmark.position) {
                continue;
            }
            let Ok(exact) = range_bearing::predict(&self.truth, &landmark.position) else {
                // The landmark is under the robot: no bearing to measure.
                continue;
            };
            let measurement = RangeBearing::new(
                exact.measurement.range
                    + gaussian(&mut self.measurement_rng, self.sensor.range_std),
                exact.measurement.bearing
                    + gaussian(&mut self.measurement_rng, self.sensor.bearing_std),
            );
            let angle = self.truth.theta + measurement.bearing;
            let measured_point = self.truth.translation()
                + measurement.range * Vector2::new(math::cos(angle), math::sin(angle));
            self.observations.push(Observation {
                id: landmark.id,
                measurement,
                measured_point,
            });
        }
        self.mislabel = None;
        if self.mislabel_ticks.contains(&self.tick) {
            self.mislabel_one_observation();
        }
        self.seen.extend(
            self.observations
                .iter()
                .enumerate()
                .map(|(i, o)| match self.mislabel {
                    Some(m) if m.index == i => m.true_id,
                    _ => o.id,
                }),
        );
        let count = self.observations.len();
        self.pending.push_back(Phase::Predict);
        for (i, o) in self.observations.iter().enumerate() {
            self.pending.push_back(Phase::Update {
                id: o.id,
                index: i + 1,
                count,
            });
        }
        if self.filters.iter().any(|r| r.kind.is_particle_filter()) {
            self.pending.push_back(Phase::Resample);
        }
    }

    /// Gives the first observation of this tick the id of another landmark: of
    /// those seen before and not in view now, the one nearest to the landmark
    /// really measured (a plausible confusion); without one, the nearest other
    /// landmark of the world.
    fn mislabel_one_observation(&mut self) {
        let Some(first) = self.observations.first() else {
            return;
        };
        let true_id = first.id;
        let Some(measured) = self.world.landmark(true_id).map(|l| l.position) else {
            return;
        };
        let in_view: BTreeSet<usize> = self.observations.iter().map(|o| o.id).collect();
        let nearest = |seen_only: bool| {
            self.world
                .landmarks
                .iter()
                .filter(|l| !in_view.contains(&l.id) && (!seen_only || self.seen.contains(&l.id)))
                .min_by(|a, b| {
                    (a.position - measured)
                        .norm()
                        .total_cmp(&(b.position - measured).norm())
                })
                .map(|l| l.id)
        };
        let Some(reported_id) = nearest(true).or_else(|| nearest(false)) else {
            return;
        };
        self.observations[0].id = reported_id;
        self.mislabel = Some(Mislabel {
            index: 0,
            true_id,
            reported_id,
        });
    }

    /// The sensor mislabels one observation of the next tick: it reports the id of
    /// another landmark (see [`mislabel`](Self::mislabel)). Recorded with the run,
    /// so stepping back and forward replays it.
    pub fn mislabel_next_observation(&mut self) {
        let tick = self.tick + 1;
        self.mislabel_ticks.retain(|&t| t < tick);
        self.mislabel_ticks.push(tick);
    }

    /// The wrong association of the current tick, if the sensor made one.
    pub fn mislabel(&self) -> Option<Mislabel> {
        self.mislabel
    }

    /// Ticks at which the sensor mislabels (or will mislabel) an observation.
    pub fn mislabel_ticks(&self) -> &[u64] {
        &self.mislabel_ticks
    }

    fn run_phase(&mut self, phase: Phase) {
        let dt = self.scenario.dt;
        let unknown = self.scenario.association == Association::Unknown;
        let measurement_covariance = self.scenario.filter_config().noise.measurement_covariance();
        for run in &mut self.filters {
            let result = match phase {
                Phase::Predict => run
                    .filter
                    .predict(&self.command, dt)
                    .map(|r| run.last_predict = Some(r)),
                Phase::Resample => {
                    if let Some(report) = run.filter.resample() {
                        run.n_eff.push(NeffSample {
                            tick: self.tick,
                            n_eff: report.n_eff_before,
                            particles: run.filter.particle_set().map_or(0, |p| p.particle_count()),
                            resampled: report.resampled,
                        });
                        run.last_resample = Some(report);
                    }
                    Ok(())
                }
                Phase::Update { id, index, .. } => {
                    let z = self.observations[index - 1].measurement;
                    // Without the sensor's ids a Gaussian filter picks the nearest
                    // neighbour inside the gate, or starts a landmark of its own.
                    let id = if unknown && run.filter.particle_set().is_none() {
                        let f = run.filter();
                        let decision =
                            GaussianMap::from_joint(f.mean(), f.covariance(), f.landmark_ids())
                                .map(|map| {
                                    nearest_neighbour(
                                        &map,
                                        &z,
                                        &measurement_covariance,
                                        self.scenario.gate,
                                    )
                                });
                        match decision {
                            Some(NearestNeighbour::Matched { id, .. }) => id,
                            _ => {
                                run.next_label += 1;
                                run.next_label - 1
                            }
                        }
                    } else {
                        id
                    };
                    run.filter.update(id, &z).map(|r| {
                        if let UpdateReport::Corrected { nis, .. } = r {
                            run.nis.push(NisSample {
                                tick: self.tick,
                                id,
                                nis,
                            });
                        }
                        run.last_update = Some(r);
                    })
                }
            };
            run.last_error = result.err().map(|e| format!("{}: {e}", run.kind.name()));
        }
        self.last_phase = Some(phase);
    }

    fn end_tick(&mut self) {
        self.truth_path.push(self.truth);
        self.dead_reckoning_path.push(self.dead_reckoning);
        let time = self.time();
        for run in &mut self.filters {
            let metrics = tick_metrics(self.tick, time, &self.truth, &self.world, run.filter());
            let metrics = if self.scenario.association == Association::Unknown {
                TickMetrics {
                    landmark_rmse: nearest_landmark_rmse(&self.world, run.filter()),
                    ..metrics
                }
            } else {
                metrics
            };
            run.path.push(run.filter.robot_pose());
            run.history.push(metrics);
        }
        if self.tick.is_multiple_of(CHECKPOINT_EVERY)
            && self
                .checkpoints
                .back()
                .is_none_or(|c| c.state.phases_run < self.phases_run)
        {
            let capacity = self.checkpoint_capacity();
            while self.checkpoints.len() >= capacity {
                self.checkpoints.pop_front();
            }
            self.checkpoints.push_back(Checkpoint {
                state: Box::new(self.without_records()),
                records: self.record_lengths(),
            });
        }
    }
}

/// FastSLAM's configuration in a landmark scenario: the scenario's noise and
/// motion model, its particle settings and association.
pub fn fastslam_config(scenario: &LandmarkScenario, kind: EstimatorKind) -> FastSlamConfig {
    let f = &scenario.fastslam;
    let version = if kind == EstimatorKind::FastSlam1 {
        FastSlamVersion::V1
    } else {
        FastSlamVersion::V2
    };
    FastSlamConfig {
        version,
        particles: f.particles,
        motion_model: scenario.motion,
        noise: FastSlamNoise {
            v_std: scenario.v_std,
            w_std: scenario.w_std,
            range_std: scenario.range_std,
            bearing_std: scenario.bearing_std,
        },
        association: match scenario.association {
            Association::Known => AssociationMode::KnownIds,
            Association::Unknown => AssociationMode::MaximumLikelihood {
                gate: f.new_landmark_threshold,
            },
        },
        resampler: f.resampler,
        resample: ResamplePolicy::WhenNeffBelow {
            threshold: f.resample_threshold,
        },
        // The filter's own random stream: from the seed, different for 1.0 and 2.0.
        seed: scenario
            .seed
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add(u64::from(version.number())),
    }
}

/// Landmark RMS error when the estimator labels its landmarks itself: each
/// estimate against the nearest true landmark.
fn nearest_landmark_rmse(world: &LandmarkWorld, filter: &dyn LandmarkSlam) -> Option<f64> {
    let squared: Vec<f64> = filter
        .landmarks()
        .iter()
        .filter_map(|l| {
            world
                .landmarks
                .iter()
                .map(|t| (t.position - l.mean).norm_squared())
                .min_by(f64::total_cmp)
        })
        .collect();
    (!squared.is_empty()).then(|| (squared.iter().sum::<f64>() / squared.len() as f64).sqrt())
}

/// Compares an estimator's state with the truth.
pub fn tick_metrics(
    tick: u64,
    time: f64,
    truth: &Pose2,
    world: &LandmarkWorld,
    filter: &dyn LandmarkSlam,
) -> TickMetrics {
    let estimate = filter.robot_pose();
    let error = [
        truth.x - estimate.x,
        truth.y - estimate.y,
        wrap_angle(truth.theta - estimate.theta),
    ];
    let p = filter.robot_covariance();
    let sigma = [
        p[(0, 0)].max(0.0).sqrt(),
        p[(1, 1)].max(0.0).sqrt(),
        p[(2, 2)].max(0.0).sqrt(),
    ];
    let nees = normalized_squared_error(
        &DVector::from_column_slice(&error),
        &DMatrix::from_iterator(3, 3, p.iter().copied()),
    );
    let landmarks = filter.landmarks();
    let squared: Vec<f64> = landmarks
        .iter()
        .filter_map(|l| {
            world
                .landmark(l.id)
                .map(|t| (t.position - l.mean).norm_squared())
        })
        .collect();
    let landmark_rmse =
        (!squared.is_empty()).then(|| (squared.iter().sum::<f64>() / squared.len() as f64).sqrt());
    TickMetrics {
        tick,
        time,
        error,
        sigma,
        position_error: (error[0] * error[0] + error[1] * error[1]).sqrt(),
        position_bound_2sigma: 2.0 * (p[(0, 0)] + p[(1, 1)]).max(0.0).sqrt(),
        nees,
        landmark_rmse,
        landmarks_initialized: landmarks.len(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn phases_follow_predict_then_each_update() {
        let mut s = LandmarkSession::new(LandmarkScenario::default());
        let first = s.step_phase();
        assert_eq!(first, Phase::Predict);
        let n = s.observations().len();
        assert!(n > 0, "the teaching layout is in view at the start");
        for k in 1..=n {
            match s.step_phase() {
                Phase::Update { index, count, .. } => assert_eq!((index, count), (k, n)),
                Phase::Predict | Phase::Resample => panic!("expected update {k}"),
            }
        }
        assert!(!s.is_mid_tick());
        assert_eq!(s.filters()[0].history.len(), 1);
        assert_eq!(s.truth_path().len(), 2);
    }

    #[test]
    fn same_seed_same_run_and_the_estimator_does_not_change_the_world() {
        let mut a = LandmarkSession::new(LandmarkScenario {
            seed: 4,
            ..Default::default()
        });
        let mut b = LandmarkSession::new(LandmarkScenario {
            seed: 4,
            ..Default::default()
        });
        a.run_ticks(50);
        b.run_ticks(50);
        assert_eq!(a.truth(), b.truth());
        assert_eq!(
            a.filters()[0].filter().mean(),
            b.filters()[0].filter().mean()
        );
        let mut c = LandmarkSession::new(LandmarkScenario {
            seed: 4,
            estimators: vec![],
            ..Default::default()
        });
        c.run_ticks(50);
        assert_eq!(
            a.truth(),
            c.truth(),
            "the world does not depend on the estimators"
        );
    }

    #[test]
    fn one_phase_advances_every_filter_on_the_same_data() {
        let scenario = LandmarkScenario {
            estimators: vec![EstimatorKind::Ekf, EstimatorKind::Ukf],
            ..Default::default()
        };
        let mut s = LandmarkSession::new(scenario);
        assert_eq!(s.filters().len(), 2);
        let before: Vec<_> = s
            .filters()
            .iter()
            .map(|f| f.filter().robot_covariance())
            .collect();
        assert_eq!(s.step_phase(), Phase::Predict);
        for (f, b) in s.filters().iter().zip(&before) {
            assert_ne!(
                f.filter().robot_covariance(),
                *b,
                "{} did not predict",
                f.kind.name()
            );
            assert!(f.last_predict.is_some());
        }
        s.step_phase();
        for f in s.filters() {
            assert_eq!(
                f.filter().landmark_ids().len(),
                1,
                "{} initialized the first landmark",
                f.kind.name()
            );
        }
        // The world is the same with one filter or two.
        let mut ekf_only = LandmarkSession::new(LandmarkScenario::default());
        s.run_ticks(30);
        ekf_only.run_ticks(30);
        assert_eq!(s.truth(), ekf_only.truth());
        assert_eq!(
            s.filters()[0].filter().mean(),
            ekf_only.filters()[0].filter().mean()
        );
    }

    #[test]
    fn impossible_ukf_parameters_leave_a_notice_and_the_ekf_running() {
        let mut scenario = LandmarkScenario {
            estimators: vec![EstimatorKind::Ekf, EstimatorKind::Ukf],
            ..Default::default()
        };
        scenario.ukf.alpha = 0.5;
        scenario.ukf.kappa = -9.0;
        let mut s = LandmarkSession::new(scenario);
        assert_eq!(s.filters().len(), 1);
        assert!(
            s.notices()
                .iter()
                .any(|n| n.contains("ukf could not start")),
            "{:?}",
            s.notices()
        );
        s.run_ticks(5);
    }

    #[test]
    fn checkpoints_make_stepping_back_cheap_and_exact() {
        let scenario = LandmarkScenario {
            estimators: vec![EstimatorKind::Ekf, EstimatorKind::Ukf],
            ..Default::default()
        };
        let snapshot = |s: &LandmarkSession| {
            (
                (s.tick(), s.phases_run(), s.next_phase(), s.truth()),
                s.truth_path().to_vec(),
                s.filters()
                    .iter()
                    .map(|r| {
                        (
                            r.filter().mean().clone(),
                            r.filter().covariance().clone(),
                            r.history.clone(),
                            r.nis.clone(),
                            r.path.clone(),
                        )
                    })
                    .collect::<Vec<_>>(),
            )
        };
        let mut s = LandmarkSession::new(scenario.clone());
        s.run_ticks(130);
        s.step_phase();
        let phases = s.phases_run();
        // The latest checkpoint is at tick 100: a step back replays about 30 ticks.
        let replay = s.step_back_replay_length();
        assert!(replay > 0 && replay < phases / 3, "{replay} of {phases}");
        // Step back across the checkpoints at ticks 100 and 50, checking the state
        // against a straight run at three points.
        let targets = [phases - 1, phases * 2 / 3, phases / 4];
        for &target in &targets {
            while s.phases_run() > target {
                assert!(s.step_back());
            }
            let mut straight = LandmarkSession::new(scenario.clone());
            while straight.phases_run() < target {
                straight.step_phase();
            }
            assert_eq!(snapshot(&s), snapshot(&straight), "at phase {target}");
        }
        assert!(
            s.tick() < 100,
            "went back past a checkpoint: tick {}",
            s.tick()
        );
        // And forward again from there, exactly as the straight run goes.
        s.run_ticks(60);
        let mut straight = LandmarkSession::new(scenario);
        while straight.phases_run() < targets[2] {
            straight.step_phase();
        }
        straight.run_ticks(60);
        assert_eq!(snapshot(&s), snapshot(&straight));
    }

    #[test]
    fn taking_the_wheel_mid_run_keeps_the_run_and_step_back_replays_it() {
        let scenario = LandmarkScenario {
            estimators: vec![EstimatorKind::Ekf],
            ..Default::default()
        };
        let mut s = LandmarkSession::new(scenario.clone());
        s.run_ticks(30);
        let landmarks = s.filters()[0].filter().landmark_ids().len();
        assert!(landmarks > 0);
        s.set_controller(ControllerKind::Manual);
        s.set_teleop(Control::new(0.4, -0.5));
        s.run_ticks(10);
        assert_eq!(s.tick(), 40, "the run goes on");
        assert_eq!(s.command(), Control::new(0.4, -0.5));
        assert!(s.filters()[0].filter().landmark_ids().len() >= landmarks);
        // Back to the circle: the scripted command again.
        s.set_controller(scenario.controller);
        s.run_ticks(5);
        assert_eq!(s.command(), Control::new(1.0, PI / 10.0));
        // Stepping back across the switches replays the commands exactly.
        let snapshot = |s: &LandmarkSession| {
            (
                s.tick(),
                s.truth(),
                s.filters()[0].filter().mean().clone(),
                s.filters()[0].filter().covariance().clone(),
            )
        };
        let mut straight = LandmarkSession::new(scenario);
        straight.run_ticks(30);
        straight.set_controller(ControllerKind::Manual);
        straight.set_teleop(Control::new(0.4, -0.5));
        straight.run_ticks(10);
        while s.tick() > 40 {
            assert!(s.step_back());
        }
        assert!(!s.is_mid_tick());
        assert_eq!(snapshot(&s), snapshot(&straight));
        assert_eq!(
            s.controller(),
            ControllerKind::Circle {
                v: 1.0,
                w: PI / 10.0
            },
            "stepping back keeps today's driver"
        );
        // A circle without finite speeds is refused.
        s.set_controller(ControllerKind::Circle {
            v: f64::NAN,
            w: 0.0,
        });
        assert_eq!(
            s.controller(),
            ControllerKind::Circle {
                v: 1.0,
                w: PI / 10.0
            }
        );
    }

    #[test]
    fn the_sensor_reach_changes_from_the_next_tick_and_replays_exactly() {
        let mut s = LandmarkSession::new(LandmarkScenario {
            seed: 5,
            ..Default::default()
        });
        let reach = |s: &LandmarkSession| (s.sensor().fov, s.sensor().max_range);
        let start = reach(&s);
        s.run_ticks(10);
        s.set_sensor_reach(2.0 * PI, 8.0);
        assert_eq!(
            reach(&s),
            start,
            "this tick's measurements are already taken"
        );
        assert_eq!(
            (s.scenario_now().fov, s.scenario_now().max_range),
            (2.0 * PI, 8.0)
        );
        assert_eq!(
            s.scenario().fov,
            start.0,
            "the run's scenario is where it started"
        );
        s.step_tick();
        assert_eq!(reach(&s), (2.0 * PI, 8.0));
        let truth = s.truth();
        let in_reach = s
            .world()
            .landmarks
            .iter()
            .filter(|l| (l.position - truth.translation()).norm() <= 8.0)
            .count();
        assert_eq!(s.observations().len(), in_reach, "all around, to 8 m");
        s.run_ticks(19);
        let at_30 = s.filters()[0].filter().mean().clone();

        // Back to tick 8, before the change: the old reach. Forward again: the change
        // replays at tick 11 and the run is the same to the last bit.
        while s.tick() > 8 || s.is_mid_tick() {
            assert!(s.step_back());
        }
        assert_eq!(reach(&s), start);
        s.run_ticks(22);
        assert_eq!(s.tick(), 30);
        assert_eq!(s.filters()[0].filter().mean(), &at_30);

        // Rewound and changed again: the new change replaces the later one.
        while s.tick() > 8 || s.is_mid_tick() {
            assert!(s.step_back());
        }
        s.set_sensor_reach(1.0, 3.0);
        s.run_ticks(12);
        assert_eq!(reach(&s), (1.0, 3.0));

        // Out-of-range values are clamped to the parameters' ranges; NaN changes nothing.
        s.set_sensor_reach(0.0, 1e9);
        s.step_tick();
        assert!((s.sensor().fov - 1_f64.to_radians()).abs() < 1e-12);
        assert_eq!(s.sensor().max_range, 100.0);
        s.set_sensor_reach(f64::NAN, 5.0);
        s.step_tick();
        assert_eq!(s.sensor().max_range, 100.0);
    }

    #[test]
    fn stepping_back_restores_the_state_before_the_last_phase() {
        let scenario = LandmarkScenario {
            controller: crate::scenario::ControllerKind::Manual,
            estimators: vec![EstimatorKind::Ekf, EstimatorKind::Ukf],
            ..Default::default()
        };
        let mut s = LandmarkSession::new(scenario);
        assert!(!s.step_back(), "nothing to undo at the start");
        s.set_teleop(Control::new(1.0, 0.3));
        s.run_ticks(7);
        s.set_teleop(Control::new(0.5, -0.6));
        s.run_ticks(3);
        s.step_phase();
        s.step_phase();
        let phases = s.phases_run();
        let before = (
            s.truth(),
            s.filters()[1].filter().mean().clone(),
            s.filters()[1].filter().covariance().clone(),
            s.next_phase(),
            s.filters()[0].history.len(),
        );
        s.step_phase();
        assert!(s.step_back());
        assert_eq!(s.phases_run(), phases);
        let after = (
            s.truth(),
            s.filters()[1].filter().mean().clone(),
            s.filters()[1].filter().covariance().clone(),
            s.next_phase(),
            s.filters()[0].history.len(),
        );
        assert_eq!(before, after);
        assert_eq!(
            s.teleop(),
            Control::new(0.5, -0.6),
            "the current drive command is kept"
        );
        // Back across a tick boundary, to the very start.
        while s.step_back() {}
        assert_eq!((s.tick(), s.phases_run()), (0, 0));
        assert_eq!(s.truth(), s.scenario().start_pose());
    }

    #[test]
    fn a_stopped_manual_robot_stays_put() {
        let mut s = LandmarkSession::new(LandmarkScenario {
            controller: crate::scenario::ControllerKind::Manual,
            ..Default::default()
        });
        let start = s.truth();
        s.run_ticks(10);
        assert_eq!(s.truth(), start);
        s.set_teleop(Control::new(0.5, 0.0));
        s.set_teleop(Control::new(f64::NAN, 0.0));
        s.run_ticks(10);
        assert!(
            (s.truth().x - start.x - 0.5).abs() < 0.5,
            "moved about 0.5 m: {:?}",
            s.truth()
        );
    }
}

#[cfg(test)]
mod fastslam_tests {
    use super::*;

    fn ekf_and_fastslam(seed: u64) -> LandmarkScenario {
        LandmarkScenario {
            seed,
            estimators: vec![EstimatorKind::Ekf, EstimatorKind::FastSlam2],
            ..Default::default()
        }
    }

    /// Mean robot position error of every filter over ticks `from..to`.
    fn mean_errors(s: &LandmarkSession, from: usize, to: usize) -> Vec<f64> {
        s.filters()
            .iter()
            .map(|r| {
                let e = &r.history[from..to];
                e.iter().map(|m| m.position_error).sum::<f64>() / e.len() as f64
            })
            .collect()
    }

    fn close(a: f64, b: f64, what: &str) {
        assert!((a - b).abs() < 1e-9, "{what}: {a} against {b}");
    }

    #[test]
    fn ekf_beside_fastslam2_golden_and_the_ekf_is_unchanged() {
        let mut s = LandmarkSession::new(ekf_and_fastslam(1));
        // Phases: sample (predict), weight per observation, resample.
        assert_eq!(s.step_phase(), Phase::Predict);
        let n = s.observations().len();
        for _ in 0..n {
            assert!(matches!(s.step_phase(), Phase::Update { .. }));
        }
        assert_eq!(s.step_phase(), Phase::Resample);
        assert!(!s.is_mid_tick());
        assert_eq!(Phase::Resample.label(), "resample");
        s.run_ticks(99);
        let ekf = s.filters()[0].latest().copied().unwrap();
        let fast = s.filters()[1].latest().copied().unwrap();
        close(ekf.position_error, 0.2112864142132007, "EKF position error");
        close(
            fast.position_error,
            0.2792836264881384,
            "FastSLAM 2.0 position error",
        );
        close(
            fast.landmark_rmse.unwrap(),
            0.43476188949744654,
            "FastSLAM landmark RMSE",
        );
        assert_eq!(
            (ekf.landmarks_initialized, fast.landmarks_initialized),
            (15, 15)
        );
        let n_eff = &s.filters()[1].n_eff;
        assert_eq!(n_eff.len(), 100);
        assert_eq!(n_eff.iter().filter(|n| n.resampled).count(), 11);
        close(n_eff[99].n_eff, 49.47614842063085, "N_eff at tick 100");
        assert!(s.filters()[0].n_eff.is_empty(), "the EKF has no particles");
        let particles = s.filters()[1].filter().particle_set().unwrap();
        assert_eq!(particles.particle_count(), 100);
        // The EKF beside FastSLAM is bit for bit the EKF alone.
        let mut alone = LandmarkSession::new(LandmarkScenario {
            seed: 1,
            ..Default::default()
        });
        alone.run_ticks(100);
        assert_eq!(
            alone.filters()[0].filter().mean(),
            s.filters()[0].filter().mean()
        );
        assert_eq!(alone.filters()[0].history, s.filters()[0].history);
    }

    #[test]
    fn a_wrong_association_is_measured_and_replays_exactly() {
        // Over ten seeds: the sensor mislabels one observation at tick 61; the rise
        // of the mean robot position error over ticks 61-101 against the clean run.
        // With known ids every particle takes the same wrong id, so FastSLAM is
        // hurt as much as the EKF (2.0 even more: its proposal uses the measurement).
        for (kind, ekf_rise, fast_rise) in [
            (EstimatorKind::FastSlam1, 0.994, 0.963),
            (EstimatorKind::FastSlam2, 0.994, 1.378),
        ] {
            let (mut de, mut df) = (0.0, 0.0);
            for seed in 1..=10 {
                let sc = LandmarkScenario {
                    estimators: vec![EstimatorKind::Ekf, kind],
                    ..ekf_and_fastslam(seed)
                };
                let mut clean = LandmarkSession::new(sc.clone());
                clean.run_ticks(101);
                let mut wrong = LandmarkSession::new(sc);
                wrong.run_ticks(60);
                wrong.mislabel_next_observation();
                wrong.run_ticks(1);
                let m = wrong.mislabel().unwrap();
                assert_ne!(m.true_id, m.reported_id);
                assert_eq!(wrong.observations()[m.index].id, m.reported_id);
                wrong.run_ticks(40);
                let c = mean_errors(&clean, 60, 101);
                let w = mean_errors(&wrong, 60, 101);
                de += w[0] - c[0];
                df += w[1] - c[1];
            }
            assert!((de - ekf_rise).abs() < 5e-4, "{kind:?}: EKF {de}");
            assert!((df - fast_rise).abs() < 5e-4, "{kind:?}: FastSLAM {df}");
        }
        // Seed 1: landmark 1 is reported as its neighbour 19; stepping back over
        // the tick and forward again replays the mislabel.
        let mut s = LandmarkSession::new(ekf_and_fastslam(1));
        s.run_ticks(60);
        s.mislabel_next_observation();
        s.run_ticks(5);
        let at_65 = s.filters()[1].filter().mean().clone();
        while s.tick() > 59 {
            assert!(s.step_back());
        }
        assert_eq!(s.mislabel_ticks(), &[61]);
        s.run_ticks(2);
        assert_eq!(
            s.mislabel(),
            Some(Mislabel {
                index: 0,
                true_id: 1,
                reported_id: 19
            })
        );
        s.run_ticks(4);
        assert_eq!(s.filters()[1].filter().mean(), &at_65);
    }

    #[test]
    fn unknown_association_runs_nearest_neighbour_and_maximum_likelihood() {
        let mut s = LandmarkSession::new(LandmarkScenario {
            association: Association::Unknown,
            ..ekf_and_fastslam(1)
        });
        s.run_ticks(100);
        let ekf = s.filters()[0].latest().copied().unwrap();
        let fast = s.filters()[1].latest().copied().unwrap();
        // Both found the 15 landmarks the robot saw, under labels of their own.
        assert_eq!(
            (ekf.landmarks_initialized, fast.landmarks_initialized),
            (15, 15)
        );
        assert!(
            s.filters()[0]
                .filter()
                .landmark_ids()
                .iter()
                .all(|&id| id >= OWN_LABELS)
        );
        close(
            ekf.position_error,
            0.3192219318542592,
            "EKF (nearest neighbour)",
        );
        close(
            fast.position_error,
            0.49637817115637156,
            "FastSLAM 2.0 (maximum likelihood)",
        );
        close(
            ekf.landmark_rmse.unwrap(),
            0.5783381344141212,
            "EKF landmark RMSE",
        );
    }

    #[test]
    fn zero_particles_and_a_threshold_outside_0_1_are_repaired_with_a_notice() {
        let mut s = LandmarkSession::new(LandmarkScenario {
            fastslam: crate::scenario::FastSlamSettings {
                particles: 0,
                resample_threshold: 3.0,
                ..Default::default()
            },
            ..ekf_and_fastslam(1)
        });
        assert_eq!(
            s.notices(),
            &[
                "particles = 0 is out of range; using 1".to_owned(),
                "resample-threshold = 3 is out of range; using 1".to_owned()
            ]
        );
        assert_eq!(s.filters().len(), 2);
        s.run_ticks(3);
        assert_eq!(
            s.filters()[1]
                .filter()
                .particle_set()
                .map(|p| p.particle_count()),
            Some(1)
        );
    }
}
