//! What a landmark-SLAM run records tick by tick: the true and dead-reckoning
//! paths, the commands, and per estimator its path, its metrics, the NIS of
//! every update and a particle filter's `N_eff`. These only grow, so they live
//! outside the checkpoints ([`crate::stepper::Records`]): stepping back truncates
//! them to the checkpoint's lengths instead of copying them.
//!
//! The metrics compare an estimator with the truth after each tick
//! ([`tick_metrics`]).

use crate::stepper::Records;
use crate::world::landmarks::LandmarkWorld;
use nalgebra::{DMatrix, DVector};
use slamlab_core::kalman::LandmarkSlam;
use slamlab_core::stats::normalized_squared_error;
use slamlab_core::{Control, Pose2, wrap_angle};

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
    /// The filter's robot-pose covariance `P_RR` (what [`Self::nees`] inverts).
    pub covariance: nalgebra::Matrix3<f64>,
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

/// One estimator's records.
#[derive(Clone, Debug, Default)]
pub struct FilterRecords {
    /// The estimated robot pose after every completed tick, starting with the start pose.
    pub path: Vec<Pose2>,
    /// The robot-pose covariance with each pose of [`path`](Self::path) (zero at the start).
    pub covariances: Vec<nalgebra::Matrix3<f64>>,
    /// Metrics after every completed tick where the truth is known: every tick
    /// of the simulated world; in a recorded one, the ticks its truth covers.
    pub history: Vec<TickMetrics>,
    /// NIS of every correcting update.
    pub nis: Vec<NisSample>,
    /// A particle filter's `N_eff` at every resampling phase (empty for the others).
    pub n_eff: Vec<NeffSample>,
}

/// Everything a landmark-SLAM run records.
#[derive(Clone, Debug, Default)]
pub struct LandmarkRecords {
    /// The time of every completed tick, seconds, starting with 0 for the start.
    pub times: Vec<f64>,
    /// The true path, one pose per tick, starting with the start pose.
    pub truth_path: Vec<Pose2>,
    /// The dead-reckoning path, one pose per tick, starting with the start pose.
    pub dead_reckoning_path: Vec<Pose2>,
    /// The command of every tick started so far.
    pub commands: Vec<Control>,
    /// Per estimator, in the order of the run's estimators.
    pub filters: Vec<FilterRecords>,
}

impl LandmarkRecords {
    /// The records at the start: every path holds the start pose.
    pub fn at_start(start: Pose2, estimators: usize) -> Self {
        Self {
            times: vec![0.0],
            truth_path: vec![start],
            dead_reckoning_path: vec![start],
            commands: Vec::new(),
            filters: (0..estimators)
                .map(|_| FilterRecords {
                    path: vec![start],
                    covariances: vec![nalgebra::Matrix3::zeros()],
                    ..FilterRecords::default()
                })
                .collect(),
        }
    }
}

/// The lengths of a run's records: where a checkpoint found them.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordLengths {
    times: usize,
    truth_path: usize,
    dead_reckoning_path: usize,
    commands: usize,
    /// Per estimator: path (and covariances), history, NIS samples, `N_eff` samples.
    filters: Vec<[usize; 4]>,
}

impl Records for LandmarkRecords {
    type Mark = RecordLengths;

    fn mark(&self) -> RecordLengths {
        RecordLengths {
            times: self.times.len(),
            truth_path: self.truth_path.len(),
            dead_reckoning_path: self.dead_reckoning_path.len(),
            commands: self.commands.len(),
            filters: self
                .filters
                .iter()
                .map(|r| [r.path.len(), r.history.len(), r.nis.len(), r.n_eff.len()])
                .collect(),
        }
    }

    fn truncate(&mut self, mark: &RecordLengths) {
        self.times.truncate(mark.times);
        self.truth_path.truncate(mark.truth_path);
        self.dead_reckoning_path.truncate(mark.dead_reckoning_path);
        self.commands.truncate(mark.commands);
        for (r, &[path, history, nis, n_eff]) in self.filters.iter_mut().zip(&mark.filters) {
            r.path.truncate(path);
            r.covariances.truncate(path);
            r.history.truncate(history);
            r.nis.truncate(nis);
            r.n_eff.truncate(n_eff);
        }
    }
}

/// Landmark RMS error when the estimator labels its landmarks itself: each
/// estimate against the nearest true landmark.
pub fn nearest_landmark_rmse(world: &LandmarkWorld, filter: &dyn LandmarkSlam) -> Option<f64> {
    let squared: Vec<f64> = filter
        .landmarks()
        .iter()
        .filter_map(|l| world.nearest_squared_distance(&l.mean))
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
        covariance: p,
        position_error: (error[0] * error[0] + error[1] * error[1]).sqrt(),
        position_bound_2sigma: 2.0 * (p[(0, 0)] + p[(1, 1)]).max(0.0).sqrt(),
        nees,
        landmark_rmse,
        landmarks_initialized: landmarks.len(),
    }
}
