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
//!
//! The run is a [`Simulation`](crate::stepper::Simulation) ([`LandmarkSim`], in
//! `sim.rs`) under the generic [`Stepper`]: its growing records (paths, metrics,
//! NIS, `N_eff`, commands) are in `records.rs`, the live changes (drive command,
//! who drives, the sensor's reach, a wrong association) are [`LandmarkEvent`]s,
//! and stepping back restores a checkpoint and replays them.
//! [`LandmarkSession`] is the lesson's face on it.

#[cfg(test)]
mod fastslam_tests;
pub mod ideal_ekf;
pub mod particle_estimator;
mod records;
pub(crate) mod sim;
#[cfg(test)]
mod tests;

pub use records::{
    FilterRecords, LandmarkRecords, NeffSample, NisSample, RecordLengths, TickMetrics,
    nearest_landmark_rmse, tick_metrics,
};
pub use sim::{
    CloneEstimator, FilterState, LandmarkEvent, LandmarkSim, LandmarkSlamDebug, Mislabel,
    Observation, OtherSighting, Phase, Rejection, Replay, TickMotion, fastslam_config,
};

use crate::stepper::Stepper;
use crate::world::landmark_scenario::{ControllerKind, EstimatorKind, LandmarkScenario};
use crate::world::landmarks::LandmarkWorld;
use crate::world::recorded::RecordedWorld;
use slamlab_core::kalman::{LandmarkSlam, PredictReport, UpdateReport};
use slamlab_core::particle::fastslam::ResampleReport;
use slamlab_core::range_bearing::RangeBearingSensor;
use slamlab_core::{Control, Pose2};
use std::sync::Arc;

/// One estimator of a session: its state now and, through `Deref`, its
/// [`FilterRecords`] (`run.path`, `run.history`, `run.nis`, `run.n_eff`).
#[derive(Clone, Debug)]
pub struct FilterRun<'a> {
    /// Which estimator this is.
    pub kind: EstimatorKind,
    filter: &'a dyn LandmarkSlamDebug,
    records: &'a FilterRecords,
    /// The latest resampling (particle filters).
    pub last_resample: Option<ResampleReport>,
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
    /// Measurements dropped as ambiguous (between the gate and the new-landmark threshold).
    pub ambiguous: u64,
}

impl<'a> FilterRun<'a> {
    /// The estimator's read-only view.
    pub fn filter(&self) -> &'a dyn LandmarkSlam {
        self.filter
    }

    /// The estimator's records: path, metrics, NIS and `N_eff` samples.
    pub fn records(&self) -> &'a FilterRecords {
        self.records
    }

    /// Metrics after the latest completed tick.
    pub fn latest(&self) -> Option<&'a TickMetrics> {
        self.records.history.last()
    }
}

impl std::ops::Deref for FilterRun<'_> {
    type Target = FilterRecords;

    fn deref(&self) -> &FilterRecords {
        self.records
    }
}

/// A landmark-SLAM run in progress.
#[derive(Debug)]
pub struct LandmarkSession {
    stepper: Stepper<LandmarkSim>,
    /// Messages for the user from the start.
    notices: Vec<String>,
}

impl LandmarkSession {
    /// Starts a session. The scenario is checked first; whatever had to be changed
    /// is listed in [`notices`](Self::notices).
    pub fn new(scenario: LandmarkScenario) -> Self {
        let (sim, notices) = LandmarkSim::start(scenario);
        let records = sim.start_records();
        Self {
            stepper: Stepper::new(sim, records),
            notices,
        }
    }

    /// Starts a session that replays a recorded world (a data set) instead of
    /// simulating one; see [`LandmarkSim::start_recorded`]. The notices include
    /// the world's own (skipped rows, accepted quirks).
    pub fn recorded(scenario: LandmarkScenario, world: Arc<RecordedWorld>) -> Self {
        let (sim, notices) = LandmarkSim::start_recorded(scenario, world);
        let records = sim.start_records();
        Self {
            stepper: Stepper::new(sim, records),
            notices,
        }
    }

    /// The recorded world being replayed; `None` in the simulated world.
    pub fn recorded_world(&self) -> Option<&Arc<RecordedWorld>> {
        self.sim().replay().map(|r| &r.world)
    }

    /// The steps of a recorded world played so far and its step count.
    pub fn recorded_progress(&self) -> Option<(usize, usize)> {
        self.sim()
            .replay()
            .map(|r| (r.next.min(r.world.steps.len()), r.world.steps.len()))
    }

    /// True when a recorded world has no step left: stepping does nothing more.
    /// A simulated world never ends.
    pub fn is_finished(&self) -> bool {
        self.sim().is_finished() && !self.is_mid_tick()
    }

    /// The true pose now, when it is known: always in the simulated world; in a
    /// recorded one only where its data has a truth (MRCLAM's Vicon, outside its gaps).
    pub fn true_pose(&self) -> Option<Pose2> {
        match self.sim().replay() {
            None => Some(self.sim().truth),
            Some(r) if r.truth_known => Some(self.sim().truth),
            Some(_) => None,
        }
    }

    /// The current tick's measurements of other robots (a recorded MRCLAM world):
    /// shown, never used by the filters.
    pub fn other_sightings(&self) -> &[OtherSighting] {
        self.sim()
            .replay()
            .map_or(&[], |r| r.other_sightings.as_slice())
    }

    /// The current tick's motion in a recorded world.
    pub fn recorded_motion(&self) -> Option<TickMotion> {
        self.sim().replay().map(|r| r.motion)
    }

    fn sim(&self) -> &LandmarkSim {
        self.stepper.sim()
    }

    fn records(&self) -> &LandmarkRecords {
        self.stepper.records()
    }

    /// The stepper the session runs on: the simulation, its records, the events.
    pub fn stepper(&self) -> &Stepper<LandmarkSim> {
        &self.stepper
    }

    /// The phases a [`step_back`](Self::step_back) would replay now: from the latest
    /// checkpoint before the previous phase, or from the start.
    pub fn step_back_replay_length(&self) -> u64 {
        self.stepper.step_back_replay_length()
    }

    /// The scenario as it runs (after checking).
    pub fn scenario(&self) -> &LandmarkScenario {
        &self.sim().scenario
    }

    /// The true world.
    pub fn world(&self) -> &LandmarkWorld {
        &self.sim().world
    }

    /// The simulated sensor.
    pub fn sensor(&self) -> &RangeBearingSensor {
        &self.sim().sensor
    }

    /// The true robot pose.
    pub fn truth(&self) -> Pose2 {
        self.sim().truth
    }

    /// The true path, one pose per tick.
    pub fn truth_path(&self) -> &[Pose2] {
        &self.records().truth_path
    }

    /// Where the robot would think it is from the commands alone (no measurements).
    pub fn dead_reckoning(&self) -> Pose2 {
        self.sim().dead_reckoning
    }

    /// The time of every completed tick, seconds, starting with 0 for the start
    /// (one per pose of the paths).
    pub fn tick_times(&self) -> &[f64] {
        &self.records().times
    }

    /// The dead-reckoning path, one pose per tick.
    pub fn dead_reckoning_path(&self) -> &[Pose2] {
        &self.records().dead_reckoning_path
    }

    /// Ticks started so far.
    pub fn tick(&self) -> u64 {
        self.sim().tick
    }

    /// Simulated time of the latest tick, seconds.
    pub fn time(&self) -> f64 {
        self.sim().time()
    }

    /// The command of the current tick.
    pub fn command(&self) -> Control {
        self.sim().command
    }

    /// The measurements of the current tick.
    pub fn observations(&self) -> &[Observation] {
        &self.sim().observations
    }

    /// The estimators, each with its records.
    pub fn filters(&self) -> Vec<FilterRun<'_>> {
        let records = self.records();
        self.sim()
            .filters
            .iter()
            .zip(&records.filters)
            .map(|(state, rec)| FilterRun {
                kind: state.kind,
                filter: &*state.filter,
                records: rec,
                last_resample: state.last_resample,
                last_predict: state.last_predict,
                last_update: state.last_update,
                last_error: state.last_error.clone(),
                rejected: state.rejected,
                last_rejection: state.last_rejection,
                ambiguous: state.ambiguous,
            })
            .collect()
    }

    /// Messages for the user: parameters that were changed, estimators that could not start.
    pub fn notices(&self) -> &[String] {
        &self.notices
    }

    /// The phase that ran last.
    pub fn last_phase(&self) -> Option<Phase> {
        self.sim().last_phase
    }

    /// The phase that runs next, if the current tick is not finished.
    pub fn next_phase(&self) -> Option<Phase> {
        self.sim().pending.front().copied()
    }

    /// True between the first and the last phase of a tick.
    pub fn is_mid_tick(&self) -> bool {
        !self.sim().pending.is_empty()
    }

    /// Sets the command used by manual driving (keyboard, on-screen buttons).
    /// Non-finite values are ignored. A change is recorded with the run, so
    /// stepping back and forward again drives the same way.
    pub fn set_teleop(&mut self, control: Control) {
        if control.is_finite() && control != self.sim().teleop {
            self.stepper.apply(LandmarkEvent::Teleop(control));
        }
    }

    /// Who drives the robot now.
    pub fn controller(&self) -> ControllerKind {
        self.sim().controller
    }

    /// Hands the robot to `controller` from the next tick on. Nothing else changes:
    /// the world, the filters and the noise streams carry on. The switch is
    /// recorded with the run: [`step_back`](Self::step_back) goes back to the
    /// driver of that moment and stepping forward again switches again.
    /// A circle without finite speeds is ignored.
    pub fn set_controller(&mut self, controller: ControllerKind) {
        if let ControllerKind::Circle { v, w } = controller
            && !(v.is_finite() && w.is_finite())
        {
            return;
        }
        if controller != self.sim().controller {
            self.stepper.apply(LandmarkEvent::Controller(controller));
        }
    }

    /// Changes the sensor's field of view (radians) and maximum range (metres) from
    /// the next tick on, while the run goes on: neither enters the filters, which
    /// only see the measurements. Values outside the parameters' ranges are
    /// clamped; non-finite ones change nothing. Like every live change, one made
    /// after stepping back replaces the recorded changes that came later.
    pub fn set_sensor_reach(&mut self, fov: f64, max_range: f64) {
        if fov.is_finite() && max_range.is_finite() {
            self.stepper
                .apply(LandmarkEvent::SensorReach { fov, max_range });
        }
    }

    /// The scenario as it stands now: the one the run started with, with the
    /// controller that drives now and the sensor's reach of the next tick.
    pub fn scenario_now(&self) -> LandmarkScenario {
        self.sim().scenario_now()
    }

    /// The command of every tick started so far, in order.
    pub fn commands(&self) -> &[Control] {
        &self.records().commands
    }

    /// The manual-driving command.
    pub fn teleop(&self) -> Control {
        self.sim().teleop
    }

    /// Runs the next phase (starting a new tick when the last one is finished) and
    /// returns it.
    pub fn step_phase(&mut self) -> Phase {
        if self.is_finished() {
            return self.last_phase().unwrap_or(Phase::Predict);
        }
        self.stepper.step_phase()
    }

    /// Phases run since the start.
    pub fn phases_run(&self) -> u64 {
        self.stepper.phases_run()
    }

    /// Goes back one phase: the session becomes exactly what it was before the
    /// last phase ran. Returns `false` at the start.
    ///
    /// The run is deterministic given the scenario (with its seed) and the live
    /// changes, so this replays them from the latest checkpoint before that phase
    /// (one every 50 ticks, the latest 20 or as many as 64 MB hold), or from the start.
    pub fn step_back(&mut self) -> bool {
        self.stepper.step_back()
    }

    /// Finishes the current tick, or runs a whole new one.
    pub fn step_tick(&mut self) {
        if !self.is_finished() {
            self.stepper.step_tick();
        }
    }

    /// Runs `count` whole ticks (fewer when a recorded world ends first).
    pub fn run_ticks(&mut self, count: u64) {
        if self.sim().replay().is_none() {
            self.stepper.run_ticks(count);
            return;
        }
        for _ in 0..count {
            if self.is_finished() {
                break;
            }
            self.stepper.step_tick();
        }
    }

    /// The sensor mislabels one observation of the next tick: it reports the id of
    /// another landmark (see [`mislabel`](Self::mislabel)). Recorded with the run,
    /// so stepping back and forward replays it.
    pub fn mislabel_next_observation(&mut self) {
        let tick = self.tick() + 1;
        if self.sim().mislabel_tick != Some(tick) {
            self.stepper.apply(LandmarkEvent::Mislabel { tick });
        }
    }

    /// The wrong association of the current tick, if the sensor made one.
    pub fn mislabel(&self) -> Option<Mislabel> {
        self.sim().mislabel
    }

    /// Ticks at which the sensor mislabels (or, after a step back, will mislabel
    /// again) an observation.
    pub fn mislabel_ticks(&self) -> Vec<u64> {
        self.stepper
            .events()
            .iter()
            .filter_map(|(_, event)| match event {
                LandmarkEvent::Mislabel { tick } => Some(*tick),
                _ => None,
            })
            .collect()
    }
}
