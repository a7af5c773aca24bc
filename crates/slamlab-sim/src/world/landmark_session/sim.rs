//! The landmark-SLAM lesson's simulation, as the generic stepper runs it
//! ([`crate::stepper::Simulation`]).
//!
//! Its state is everything a checkpoint must hold: the scenario and the true
//! world, the sensor, who drives, the true and dead-reckoning poses, the noise
//! streams, every estimator with its own random stream, the phases still to run
//! in this tick and this tick's measurements. What only grows (paths, metrics,
//! commands) goes to its [`LandmarkRecords`]. The changes a student makes while
//! the run goes on are [`LandmarkEvent`]s, recorded by the stepper and met again
//! at the same phase when a step back replays the run.
//!
//! One tick is: the controller gives a command; the true robot moves with that
//! command plus noise; the sensor measures the landmarks in view, with noise
//! (`begin_tick`); then every estimator runs its phases on the same command and
//! measurements: first `predict`, then one `update` per observed landmark, in id
//! order, and, when a particle filter (FastSLAM) runs, `resample` last
//! (`run_phase`); the last phase records the paths and metrics (`end_tick`).

use super::records::{LandmarkRecords, NeffSample, NisSample, TickMetrics};
use super::records::{nearest_landmark_rmse, tick_metrics};
use crate::noise::{Stream, gaussian, stream_rng};
use crate::params;
use crate::stepper::Simulation;
use crate::world::landmark_scenario::{
    Association, ControllerKind, EstimatorKind, LandmarkScenario, MapMode,
};
use crate::world::landmark_session::ideal_ekf::IdealEkf;
use crate::world::landmark_session::particle_estimator::{FastSlamEstimator, OWN_LABELS};
use crate::world::landmarks::LandmarkWorld;
use crate::world::recorded::{RecordedWorld, Sighting, StepMotion};
use nalgebra::{Matrix2, Vector2};
use rand_chacha::ChaCha8Rng;
use slamlab_core::association::{
    AssociationMode, GaussianLandmark, GaussianMap, NearestNeighbour, landmark_distance,
    nearest_neighbour,
};
use slamlab_core::kalman::{
    EkfSlam, LandmarkSlam, Linearization, PredictReport, UkfSlam, UpdateReport,
};
use slamlab_core::math;
use slamlab_core::motion::RecordedMotion;
use slamlab_core::particle::fastslam::{FastSlamNoise, ResamplePolicy, ResampleReport};
use slamlab_core::particle::{FastSlamConfig, FastSlamVersion};
use slamlab_core::range_bearing::{self, RangeBearing, RangeBearingSensor};
use slamlab_core::{Control, MotionModel, Pose2};
use std::collections::{BTreeSet, VecDeque};
use std::sync::Arc;

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

/// A live change to the run, applied between two phases. Invalid values change
/// nothing (so a replay meets exactly what the live run did).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LandmarkEvent {
    /// The manual-driving command (used while the controller is manual).
    Teleop(Control),
    /// Who drives, from the next tick on. A circle needs finite speeds.
    Controller(ControllerKind),
    /// The sensor's field of view (radians) and maximum range (metres) from the
    /// next tick on, clamped to the parameters' ranges.
    SensorReach {
        /// Field of view, radians.
        fov: f64,
        /// Maximum range, metres.
        max_range: f64,
    },
    /// The sensor gives one observation of tick `tick` the id of another landmark.
    Mislabel {
        /// The tick whose first observation is mislabelled.
        tick: u64,
    },
}

/// An estimator of the landmark lesson: `LandmarkSlam` plus `Debug` and
/// cloning, so sessions can be printed and checkpointed, and an ear for the truth.
pub trait LandmarkSlamDebug: LandmarkSlam + std::fmt::Debug + CloneEstimator {
    /// The simulator offers every estimator the true state of the tick that is
    /// starting (the robot before and after its move, and every landmark). Real
    /// estimators ignore it (the default); the ideal EKF linearizes at it.
    fn observe_truth(
        &mut self,
        _robot_before: Pose2,
        _robot: Pose2,
        _landmarks: &mut dyn Iterator<Item = (usize, Vector2<f64>)>,
    ) {
    }
}

/// A boxed copy of an estimator behind `dyn` ([`LandmarkSlamDebug`]): every
/// estimator that is `Clone` has one.
pub trait CloneEstimator {
    /// A boxed copy.
    fn clone_box(&self) -> Box<dyn LandmarkSlamDebug>;
}

impl<T: LandmarkSlamDebug + Clone + 'static> CloneEstimator for T {
    fn clone_box(&self) -> Box<dyn LandmarkSlamDebug> {
        Box::new(self.clone())
    }
}

impl LandmarkSlamDebug for EkfSlam {}

impl LandmarkSlamDebug for UkfSlam {}

impl LandmarkSlamDebug for FastSlamEstimator {}

impl LandmarkSlamDebug for IdealEkf {
    fn observe_truth(
        &mut self,
        robot_before: Pose2,
        robot: Pose2,
        landmarks: &mut dyn Iterator<Item = (usize, Vector2<f64>)>,
    ) {
        IdealEkf::observe_truth(self, robot_before, robot, landmarks);
    }
}

/// One estimator in the run: the filter and what its latest phase reported.
/// Its growing records are in [`LandmarkRecords::filters`].
#[derive(Debug)]
pub struct FilterState {
    /// Which estimator this is.
    pub kind: EstimatorKind,
    pub(super) filter: Box<dyn LandmarkSlamDebug>,
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
    /// Measurements the outlier gate refused so far.
    pub rejected: u64,
    /// The latest measurement the outlier gate refused.
    pub last_rejection: Option<Rejection>,
    /// Measurements dropped as ambiguous (unknown association, between the gate
    /// and the new-landmark threshold).
    pub ambiguous: u64,
}

/// A measurement of a known landmark that the outlier gate refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rejection {
    /// The tick.
    pub tick: u64,
    /// The landmark the measurement claimed.
    pub id: usize,
    /// Its squared Mahalanobis distance `νᵀ S⁻¹ ν`, beyond the gate.
    pub mahalanobis_squared: f64,
}

impl Clone for FilterState {
    fn clone(&self) -> Self {
        Self {
            kind: self.kind,
            filter: self.filter.clone_box(),
            last_resample: self.last_resample,
            next_label: self.next_label,
            last_predict: self.last_predict,
            last_update: self.last_update,
            last_error: self.last_error.clone(),
            rejected: self.rejected,
            last_rejection: self.last_rejection,
            ambiguous: self.ambiguous,
        }
    }
}

impl FilterState {
    /// The estimator's read-only view.
    pub fn filter(&self) -> &dyn LandmarkSlam {
        &*self.filter
    }
}

/// The landmark-SLAM run's state (a clone of it is a checkpoint).
#[derive(Clone, Debug)]
pub struct LandmarkSim {
    /// The scenario the run started with (after checking).
    pub(super) scenario: LandmarkScenario,
    pub(super) world: LandmarkWorld,
    pub(super) sensor: RangeBearingSensor,
    control_rng: ChaCha8Rng,
    measurement_rng: ChaCha8Rng,
    pub(super) truth: Pose2,
    pub(super) dead_reckoning: Pose2,
    pub(super) tick: u64,
    /// Who drives now; starts as the scenario's controller and can be switched mid-run.
    pub(super) controller: ControllerKind,
    pub(super) teleop: Control,
    pub(super) command: Control,
    pub(super) observations: Vec<Observation>,
    pub(super) pending: VecDeque<Phase>,
    pub(super) last_phase: Option<Phase>,
    pub(super) filters: Vec<FilterState>,
    /// The sensor's field of view and range from the next tick on, if changed.
    pub(super) next_reach: Option<(f64, f64)>,
    /// The tick whose first observation the sensor mislabels, if one is asked for.
    pub(super) mislabel_tick: Option<u64>,
    /// This tick's wrong association, if any.
    pub(super) mislabel: Option<Mislabel>,
    /// Landmarks measured in earlier ticks (the mislabel picks one of them).
    seen: BTreeSet<usize>,
    /// The recorded world being replayed; `None` in the simulated world.
    pub(super) replay: Option<Replay>,
}

/// A recorded world being replayed (see [`crate::world::recorded`]): the step
/// the run has reached, and what the current tick brought.
#[derive(Clone, Debug)]
pub struct Replay {
    /// The world, shared by the run's checkpoints.
    pub(super) world: Arc<RecordedWorld>,
    /// The next step to play.
    pub(super) next: usize,
    /// The time of the current tick, seconds since the world's start.
    pub(super) time: f64,
    /// The current tick's motion as the filters predict with it.
    pub(super) motion: TickMotion,
    /// Whether the truth is known at the current tick.
    pub(super) truth_known: bool,
    /// Other robots the current tick's measurements saw (shown, not used).
    pub(super) other_sightings: Vec<OtherSighting>,
}

/// How a recorded tick moves the robot in the filters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TickMotion {
    /// A velocity held for `dt` seconds, through the scenario's motion model.
    Velocity {
        /// The command.
        control: Control,
        /// Seconds.
        dt: f64,
    },
    /// An odometry reading or the car's input, with the scenario's noise.
    Recorded(RecordedMotion),
}

/// A measurement of another robot (MRCLAM): shown greyed and named, never used.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OtherSighting {
    /// The robot seen.
    pub robot: u32,
    /// What the camera reported.
    pub measurement: RangeBearing,
    /// Where it puts the robot, from the true pose (or the first estimate's when
    /// the truth is unknown).
    pub measured_point: Vector2<f64>,
}

impl LandmarkSim {
    /// The run at its start. The scenario is checked first; whatever had to be
    /// changed, and every estimator that could not start, is listed in the notices
    /// returned.
    pub fn start(mut scenario: LandmarkScenario) -> (Self, Vec<String>) {
        let mut notices = params::sanitize_notices(&mut scenario);
        let world = scenario.world();
        let start = scenario.start_pose();
        let map: Vec<(usize, Vector2<f64>, Matrix2<f64>)> = match scenario.mode {
            MapMode::Slam => Vec::new(),
            MapMode::Localization => world
                .landmarks
                .iter()
                .map(|l| (l.id, l.position, Matrix2::zeros()))
                .collect(),
        };
        let filters = build_filters(&scenario, start, &map, &mut notices);
        if world
            .landmarks
            .iter()
            .any(|l| (l.position - start.translation()).norm() < range_bearing::MIN_RANGE)
        {
            notices.push("a landmark sits on the robot's start position; it is not measured while the robot is on it".to_owned());
        }
        (
            Self::at_start(scenario, world, start, filters, None),
            notices,
        )
    }

    /// The run of a recorded world: its steps instead of the simulated robot and
    /// sensor, from its start pose. The scenario gives the estimators and the
    /// noise they assume, and its `max-range` the reach beyond which recorded
    /// measurements are not used; a world whose data names no landmarks (Victoria Park)
    /// runs with unknown association whatever the scenario says, and the ideal
    /// EKF (which needs the true state) does not run.
    pub fn start_recorded(
        mut scenario: LandmarkScenario,
        recorded: Arc<RecordedWorld>,
    ) -> (Self, Vec<String>) {
        let mut notices = params::sanitize_notices(&mut scenario);
        notices.extend(recorded.notices.iter().cloned());
        if !recorded.known_association && scenario.association == Association::Known {
            scenario.association = Association::Unknown;
            notices.push(format!(
                "{} names no landmark: association=unknown (the filters associate each \
                 measurement themselves)",
                recorded.name
            ));
        }
        if scenario.estimators.contains(&EstimatorKind::IdealEkf) {
            scenario
                .estimators
                .retain(|&e| e != EstimatorKind::IdealEkf);
            notices.push(
                "ideal-ekf needs the true state of every landmark and move, which recorded \
                 data does not give: it does not run"
                    .to_owned(),
            );
        }
        let map: Vec<(usize, Vector2<f64>, Matrix2<f64>)> = match scenario.mode {
            MapMode::Slam => Vec::new(),
            MapMode::Localization if recorded.landmarks.is_empty() => {
                notices.push(format!(
                    "{} has no true landmarks to give as the map: mode=slam",
                    recorded.name
                ));
                scenario.mode = MapMode::Slam;
                Vec::new()
            }
            MapMode::Localization => recorded
                .landmarks
                .iter()
                .map(|(l, covariance)| (l.id, l.position, *covariance))
                .collect(),
        };
        let start = recorded.start;
        let filters = build_filters(&scenario, start, &map, &mut notices);
        let world = recorded.landmark_world();
        let replay = Replay {
            truth_known: recorded.truth_at(0.0).is_some(),
            world: recorded,
            next: 0,
            time: 0.0,
            motion: TickMotion::Velocity {
                control: Control::default(),
                dt: 0.0,
            },
            other_sightings: Vec::new(),
        };
        let sim = Self::at_start(scenario, world, start, filters, Some(replay));
        (sim, notices)
    }

    /// A run at tick 0: the robot at `start`, nothing commanded, measured or seen
    /// yet, the random streams seeded from the scenario.
    fn at_start(
        scenario: LandmarkScenario,
        world: LandmarkWorld,
        start: Pose2,
        filters: Vec<FilterState>,
        replay: Option<Replay>,
    ) -> Self {
        Self {
            sensor: scenario.sensor(),
            control_rng: stream_rng(scenario.seed, Stream::Control),
            measurement_rng: stream_rng(scenario.seed, Stream::Measurement),
            truth: start,
            dead_reckoning: start,
            tick: 0,
            controller: scenario.controller,
            teleop: Control::default(),
            command: Control::default(),
            observations: Vec::new(),
            pending: VecDeque::new(),
            last_phase: None,
            filters,
            world,
            scenario,
            next_reach: None,
            mislabel_tick: None,
            mislabel: None,
            seen: BTreeSet::new(),
            replay,
        }
    }

    /// The recorded world being replayed, if any.
    pub fn replay(&self) -> Option<&Replay> {
        self.replay.as_ref()
    }

    /// True when a recorded world has no step left (a simulated world never ends).
    pub fn is_finished(&self) -> bool {
        self.replay
            .as_ref()
            .is_some_and(|r| r.next >= r.world.steps.len())
    }

    /// The records of a run that has not begun: every path holds the start pose.
    pub fn start_records(&self) -> LandmarkRecords {
        // Before the first tick the truth is the start pose (the scenario's, or
        // the recorded world's).
        LandmarkRecords::at_start(self.truth, self.filters.len())
    }

    /// The scenario as it stands now: the one the run started with, with the
    /// controller that drives now and the sensor's reach of the next tick.
    pub fn scenario_now(&self) -> LandmarkScenario {
        let (fov, max_range) = self
            .next_reach
            .unwrap_or((self.sensor.fov, self.sensor.max_range));
        LandmarkScenario {
            controller: self.controller,
            fov,
            max_range,
            ..self.scenario.clone()
        }
    }

    /// Simulated time of the latest tick, seconds.
    pub fn time(&self) -> f64 {
        match &self.replay {
            Some(replay) => replay.time,
            None => self.tick as f64 * self.scenario.dt,
        }
    }

    /// Counts the tick that is starting and gives the sensor the reach set
    /// during the last one.
    fn count_tick(&mut self) {
        self.tick += 1;
        if let Some((fov, max_range)) = self.next_reach.take() {
            self.sensor.fov = fov;
            self.sensor.max_range = max_range;
        }
    }

    /// Starts a tick: the command, the true motion, the measurements, and the
    /// phases the estimators run on them.
    fn begin_tick(&mut self, records: &mut LandmarkRecords) {
        if self.replay.is_some() {
            self.begin_recorded_tick(records);
            return;
        }
        self.count_tick();
        let dt = self.scenario.dt;
        self.command = match self.controller {
            ControllerKind::Circle { v, w } => Control::new(v, w),
            ControllerKind::Manual => self.teleop,
        };
        records.commands.push(self.command);
        let executed = executed_command(
            self.command,
            self.scenario.v_std,
            self.scenario.w_std,
            &mut self.control_rng,
        );
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

        measure_landmarks(
            &self.truth,
            &self.world,
            &self.sensor,
            &mut self.measurement_rng,
            &mut self.observations,
        );
        self.mislabel = None;
        if self.mislabel_tick.is_some_and(|t| t <= self.tick) {
            if self.mislabel_tick == Some(self.tick) {
                self.mislabel_one_observation();
            }
            self.mislabel_tick = None;
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
        self.queue_phases();
    }

    /// Queues the tick's phases: the prediction, an update for each observation,
    /// and a resampling when a particle filter runs.
    fn queue_phases(&mut self) {
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

    /// Starts a tick of a recorded world: its next step's motion, the truth at its
    /// time, its measurements (other robots apart), and the phases they make.
    /// After the last step a tick stands still.
    fn begin_recorded_tick(&mut self, records: &mut LandmarkRecords) {
        if self.replay.is_none() {
            return;
        }
        self.count_tick();
        let Some(replay) = self.replay.as_mut() else {
            return;
        };
        let max_range = self.sensor.max_range;
        let noise = self.scenario.recorded_noise();
        let step = replay.world.steps.get(replay.next).cloned();
        replay.next += 1;
        self.observations.clear();
        replay.other_sightings.clear();
        let Some(step) = step else {
            replay.motion = TickMotion::Velocity {
                control: Control::default(),
                dt: 0.0,
            };
            self.command = Control::default();
            records.commands.push(self.command);
            self.pending.push_back(Phase::Predict);
            return;
        };
        replay.time = step.time;
        (replay.motion, self.command) = match (step.motion, step.motion.recorded(&noise)) {
            (StepMotion::Velocity { control, dt }, _) => {
                (TickMotion::Velocity { control, dt }, control)
            }
            (_, Some(motion)) => (
                TickMotion::Recorded(motion),
                motion.velocity().unwrap_or_default(),
            ),
            (_, None) => (
                TickMotion::Velocity {
                    control: Control::default(),
                    dt: 0.0,
                },
                Control::default(),
            ),
        };
        records.commands.push(self.command);
        let truth = replay.world.truth_at(step.time);
        replay.truth_known = truth.is_some();
        if let Some(truth) = truth {
            self.truth = truth;
        }
        self.dead_reckoning = step
            .motion
            .apply(&self.dead_reckoning, self.scenario.motion, &noise);
        // Rays are drawn from the true pose, or from the first estimate's when the
        // truth is unknown.
        let from = truth
            .or_else(|| self.filters.first().map(|f| f.filter.robot_pose()))
            .unwrap_or(self.dead_reckoning);
        let point = |z: &RangeBearing| {
            let angle = from.theta + z.bearing;
            from.translation() + z.range * Vector2::new(math::cos(angle), math::sin(angle))
        };
        let mut unlabelled = 0;
        for o in &step.observations {
            // Beyond the sensor's reach (the scenario's max-range) a recorded
            // measurement is not used.
            if o.measurement.range > max_range {
                continue;
            }
            let id = match o.sighting {
                Sighting::Landmark(id) => id,
                Sighting::Unlabelled => {
                    unlabelled += 1;
                    unlabelled
                }
                Sighting::Robot(robot) => {
                    replay.other_sightings.push(OtherSighting {
                        robot,
                        measurement: o.measurement,
                        measured_point: point(&o.measurement),
                    });
                    continue;
                }
            };
            self.observations.push(Observation {
                id,
                measurement: o.measurement,
                measured_point: point(&o.measurement),
            });
        }
        self.queue_phases();
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

    /// Runs one phase in every estimator, on the tick's command and measurements.
    fn run_phase(&mut self, phase: Phase, records: &mut LandmarkRecords) {
        let dt = self.scenario.dt;
        let unknown = self.scenario.association == Association::Unknown;
        let measurement_covariance = self.scenario.filter_config().noise.measurement_covariance();
        for (run, rec) in self.filters.iter_mut().zip(&mut records.filters) {
            let result = match phase {
                Phase::Predict => match self.replay.as_ref().map(|r| r.motion) {
                    None => run.filter.predict(&self.command, dt),
                    Some(TickMotion::Velocity { control, dt }) => run.filter.predict(&control, dt),
                    Some(TickMotion::Recorded(motion)) => run.filter.predict_recorded(&motion),
                }
                .map(|r| run.last_predict = Some(r)),
                Phase::Resample => {
                    if let Some(report) = run.filter.resample() {
                        rec.n_eff.push(NeffSample {
                            tick: self.tick,
                            n_eff: report.n_eff_before,
                            particles: run.filter.particles().map_or(0, |p| p.particle_count()),
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
                    // Between the gate and the new-landmark threshold (when that is
                    // the larger) a measurement is too far to match and too near to
                    // be another landmark: it is dropped as ambiguous (the two gates
                    // of Bailey's EKF-SLAM toolbox).
                    let gaussian = run.filter.gaussian();
                    let id = if unknown && let Some(g) = gaussian {
                        let decision = GaussianMap::from_joint(
                            g.mean(),
                            g.covariance(),
                            run.filter.landmark_ids(),
                        )
                        .map(|map| {
                            nearest_neighbour(&map, &z, &measurement_covariance, self.scenario.gate)
                        });
                        match decision {
                            Some(NearestNeighbour::Matched { id, .. }) => id,
                            Some(NearestNeighbour::New {
                                nearest: Some((_, d2)),
                            }) if d2 <= self.scenario.fastslam.new_landmark_threshold => {
                                run.ambiguous += 1;
                                run.last_update = None;
                                run.last_error = None;
                                continue;
                            }
                            _ => {
                                run.next_label += 1;
                                run.next_label - 1
                            }
                        }
                    } else {
                        id
                    };
                    // The outlier gate: a known id whose measurement lies beyond the
                    // gate (a misread barcode) is refused before it can pull the state.
                    if !unknown
                        && self.scenario.outlier_gate > 0.0
                        && let Some(g) = gaussian
                        && let Some(d2) = known_distance(
                            g,
                            run.filter.landmark_ids(),
                            id,
                            &z,
                            &measurement_covariance,
                        )
                        && d2 > self.scenario.outlier_gate
                    {
                        run.rejected += 1;
                        run.last_rejection = Some(Rejection {
                            tick: self.tick,
                            id,
                            mahalanobis_squared: d2,
                        });
                        run.last_update = None;
                        run.last_error = None;
                        continue;
                    }
                    run.filter.update(id, &z).map(|r| {
                        if let UpdateReport::Corrected { nis, .. } = r {
                            rec.nis.push(NisSample {
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

    /// Ends a tick: the paths and every estimator's metrics.
    fn end_tick(&self, records: &mut LandmarkRecords) {
        records.times.push(self.time());
        records.truth_path.push(self.truth);
        records.dead_reckoning_path.push(self.dead_reckoning);
        let time = self.time();
        // A recorded world's truth may be unknown at this tick: then there is
        // nothing to compare with, and the metrics have a gap.
        let truth_known = self.replay.as_ref().is_none_or(|r| r.truth_known);
        for (run, rec) in self.filters.iter().zip(&mut records.filters) {
            rec.path.push(run.filter.robot_pose());
            rec.covariances.push(run.filter.robot_covariance());
            if !truth_known {
                continue;
            }
            let metrics = tick_metrics(self.tick, time, &self.truth, &self.world, run.filter());
            let metrics = if self.scenario.association == Association::Unknown {
                TickMetrics {
                    landmark_rmse: nearest_landmark_rmse(&self.world, run.filter()),
                    ..metrics
                }
            } else {
                metrics
            };
            rec.history.push(metrics);
        }
    }
}

impl Simulation for LandmarkSim {
    type Phase = Phase;
    type Event = LandmarkEvent;
    type Records = LandmarkRecords;

    fn step_phase(&mut self, records: &mut LandmarkRecords) -> Phase {
        if self.pending.is_empty() {
            self.begin_tick(records);
        }
        let phase = self.pending.pop_front().unwrap_or(Phase::Predict);
        self.run_phase(phase, records);
        if self.pending.is_empty() {
            self.end_tick(records);
        }
        phase
    }

    fn is_mid_tick(&self) -> bool {
        !self.pending.is_empty()
    }

    fn tick(&self) -> u64 {
        self.tick
    }

    fn apply_event(&mut self, event: &LandmarkEvent) {
        // A recorded world has no one to drive and no sensor to mislabel; its
        // sensor's reach decides which recorded measurements the filters get.
        if self.replay.is_some() && !matches!(event, LandmarkEvent::SensorReach { .. }) {
            return;
        }
        match *event {
            LandmarkEvent::Teleop(control) => {
                if control.is_finite() {
                    self.teleop = control;
                }
            }
            LandmarkEvent::Controller(controller) => {
                if let ControllerKind::Circle { v, w } = controller
                    && !(v.is_finite() && w.is_finite())
                {
                    return;
                }
                self.controller = controller;
            }
            LandmarkEvent::SensorReach { fov, max_range } => {
                if !(fov.is_finite() && max_range.is_finite()) {
                    return;
                }
                let mut checked = self.scenario_now();
                checked.fov = fov;
                checked.max_range = max_range;
                let _clamped = params::sanitize(&mut checked);
                self.next_reach = Some((checked.fov, checked.max_range));
            }
            LandmarkEvent::Mislabel { tick } => {
                if tick > self.tick {
                    self.mislabel_tick = Some(tick);
                }
            }
        }
    }

    /// The estimators' states (a particle filter's map per particle), the world
    /// and the measurements.
    fn checkpoint_bytes(&self) -> usize {
        let f64s: usize = self
            .filters
            .iter()
            .map(|r| {
                let n = r.filter.gaussian().map_or(0, |g| g.mean().len());
                let particles = r.filter.particles().map_or(0, |p| {
                    p.particle_count() * (4 + 6 * r.filter.landmark_ids().len())
                });
                n * n + n + particles
            })
            .sum();
        let world = self.world.landmarks.len() * 32 + self.seen.len() * 8;
        let observations = self.observations.len() * std::mem::size_of::<Observation>();
        f64s * std::mem::size_of::<f64>() + world + observations + 4096
    }
}

/// The squared Mahalanobis distance of `z` from landmark `id` of a joint
/// Gaussian ([`landmark_distance`]); `None` when `id` is not in it yet.
fn known_distance(
    g: &dyn slamlab_core::belief::JointGaussian,
    ids: &[usize],
    id: usize,
    z: &RangeBearing,
    noise: &nalgebra::Matrix2<f64>,
) -> Option<f64> {
    let slot = ids.iter().position(|&i| i == id)?;
    let (mean, covariance) = (g.mean(), g.covariance());
    let j = 3 + 2 * slot;
    if mean.len() < j + 2 || covariance.nrows() < j + 2 {
        return None;
    }
    let landmark = GaussianLandmark {
        id,
        mean: Vector2::new(mean[j], mean[j + 1]),
        covariance: covariance.fixed_view::<2, 2>(j, j).into_owned(),
        cross_covariance: covariance.fixed_view::<3, 2>(0, j).into_owned(),
    };
    let robot = Pose2::new(mean[0], mean[1], mean[2]);
    landmark_distance(
        &robot,
        &covariance.fixed_view::<3, 3>(0, 0).into_owned(),
        &landmark,
        z,
        noise,
    )
}

/// Every estimator of `scenario`, starting at `start` with the landmarks of
/// `map` (id, position, covariance) given; one that cannot start is left out
/// with a notice saying why.
fn build_filters(
    scenario: &LandmarkScenario,
    start: Pose2,
    map: &[(usize, Vector2<f64>, Matrix2<f64>)],
    notices: &mut Vec<String>,
) -> Vec<FilterState> {
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
            EstimatorKind::IdealEkf => IdealEkf::new(scenario.filter_config(), start)
                .map(|f| Box::new(f) as _)
                .map_err(|e| e.to_string()),
            EstimatorKind::FastSlam1 | EstimatorKind::FastSlam2 => {
                FastSlamEstimator::new(fastslam_config(scenario, kind), start)
                    .map(|f| Box::new(f) as _)
                    .map_err(|e| e.to_string())
            }
        };
        let given = built.and_then(|mut filter| {
            for &(id, position, covariance) in map {
                filter
                    .insert_landmark(id, position, covariance)
                    .map_err(|e| e.to_string())?;
            }
            Ok(filter)
        });
        match given {
            Ok(filter) => filters.push(FilterState {
                kind,
                filter,
                last_resample: None,
                next_label: OWN_LABELS,
                last_predict: None,
                last_update: None,
                last_error: None,
                rejected: 0,
                last_rejection: None,
                ambiguous: 0,
            }),
            Err(e) => notices.push(format!(
                "{} could not start: {e}; change the parameter and reset",
                kind.name()
            )),
        }
    }
    filters
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

/// The command as the robot executes it: Gaussian noise `(v_std, w_std)` on the
/// wheel speeds of a moving robot; a robot told to stop stays put (and the
/// estimators add no process noise for it).
pub(crate) fn executed_command(
    command: Control,
    v_std: f64,
    w_std: f64,
    rng: &mut ChaCha8Rng,
) -> Control {
    if command == Control::default() {
        return command;
    }
    Control::new(
        command.v + gaussian(rng, v_std),
        command.w + gaussian(rng, w_std),
    )
}

/// Every landmark `sensor` sees from `truth`, in id order, measured with Gaussian
/// range and bearing noise from `rng`, into `observations` (cleared first).
pub(crate) fn measure_landmarks(
    truth: &Pose2,
    world: &LandmarkWorld,
    sensor: &RangeBearingSensor,
    rng: &mut ChaCha8Rng,
    observations: &mut Vec<Observation>,
) {
    observations.clear();
    for landmark in &world.landmarks {
        if !sensor.sees(truth, &landmark.position) {
            continue;
        }
        let Ok(exact) = range_bearing::predict(truth, &landmark.position) else {
            // The landmark is under the robot: no bearing to measure.
            continue;
        };
        let measurement = RangeBearing::new(
            exact.measurement.range + gaussian(rng, sensor.range_std),
            exact.measurement.bearing + gaussian(rng, sensor.bearing_std),
        );
        let angle = truth.theta + measurement.bearing;
        let measured_point = truth.translation()
            + measurement.range * Vector2::new(math::cos(angle), math::sin(angle));
        observations.push(Observation {
            id: landmark.id,
            measurement,
            measured_point,
        });
    }
}
