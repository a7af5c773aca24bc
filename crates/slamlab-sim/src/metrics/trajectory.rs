//! A timed sequence of planar poses, with their covariances when the estimator
//! that made them has one.

use nalgebra::Matrix3;
use slamlab_core::Pose2;

/// Poses in time order: `poses[k]` at `stamps[k]` seconds, and, when the
/// estimator reports one, the 3x3 covariance of `(x, y, θ)` at each
/// (`covariances[k]`, in m², m·rad and rad²).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trajectory {
    stamps: Vec<f64>,
    poses: Vec<Pose2>,
    covariances: Option<Vec<Matrix3<f64>>>,
}

impl Trajectory {
    /// A trajectory of `poses` at `stamps` (the longer list is cut to the
    /// shorter's length).
    pub fn new(mut stamps: Vec<f64>, mut poses: Vec<Pose2>) -> Self {
        let n = stamps.len().min(poses.len());
        stamps.truncate(n);
        poses.truncate(n);
        Self {
            stamps,
            poses,
            covariances: None,
        }
    }

    /// The same poses with a covariance each; unchanged when the counts differ.
    pub fn with_covariances(mut self, covariances: Vec<Matrix3<f64>>) -> Self {
        if covariances.len() == self.poses.len() {
            self.covariances = Some(covariances);
        }
        self
    }

    /// The number of poses.
    pub fn len(&self) -> usize {
        self.poses.len()
    }

    /// Whether it has no pose.
    pub fn is_empty(&self) -> bool {
        self.poses.is_empty()
    }

    /// The times, seconds.
    pub fn stamps(&self) -> &[f64] {
        &self.stamps
    }

    /// The poses.
    pub fn poses(&self) -> &[Pose2] {
        &self.poses
    }

    /// The covariances, when the estimator gave them.
    pub fn covariances(&self) -> Option<&[Matrix3<f64>]> {
        self.covariances.as_deref()
    }

    /// The first and last time, seconds.
    pub fn span(&self) -> Option<(f64, f64)> {
        Some((*self.stamps.first()?, *self.stamps.last()?))
    }

    /// The length of the path through the positions, metres.
    pub fn path_length(&self) -> f64 {
        self.poses.windows(2).map(|w| distance(&w[0], &w[1])).sum()
    }

    /// Adds a pose at `stamp` (and its covariance, kept only while every pose
    /// has one). A stamp that is not after the last is refused.
    pub fn push(&mut self, stamp: f64, pose: Pose2, covariance: Option<Matrix3<f64>>) -> bool {
        if self.stamps.last().is_some_and(|&last| !(stamp > last)) || !stamp.is_finite() {
            return false;
        }
        match (&mut self.covariances, covariance) {
            (Some(c), Some(p)) => c.push(p),
            (None, Some(p)) if self.poses.is_empty() => self.covariances = Some(vec![p]),
            (c, _) => *c = None,
        }
        self.stamps.push(stamp);
        self.poses.push(pose);
        true
    }
}

/// The distance between two poses' positions, metres.
pub fn distance(a: &Pose2, b: &Pose2) -> f64 {
    slamlab_core::math::hypot(a.x - b.x, a.y - b.y)
}

/// What a trajectory is in a lesson: the truth, an estimator's estimate, or raw
/// odometry (dead reckoning), for export and for the comparisons.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TrajectoryRole {
    /// The true path (simulations only).
    Truth,
    /// An estimator's estimate.
    Estimate,
    /// Odometry alone, the baseline every estimator should beat.
    Odometry,
}

/// A lesson's trajectory with its name (the estimator's: `ekf`, `amcl`,
/// `scan-to-map`, or `truth`).
#[derive(Clone, Debug, PartialEq)]
pub struct NamedTrajectory {
    /// The name, as files and plots call it.
    pub name: String,
    /// Truth, estimate or odometry.
    pub role: TrajectoryRole,
    /// The poses.
    pub trajectory: Trajectory,
}

impl NamedTrajectory {
    /// A named trajectory.
    pub fn new(name: impl Into<String>, role: TrajectoryRole, trajectory: Trajectory) -> Self {
        Self {
            name: name.into(),
            role,
            trajectory,
        }
    }
}
