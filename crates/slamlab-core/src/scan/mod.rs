//! Lidar scans and scan registration: the pieces the lidar lessons share
//! (occupancy-grid mapping, grid FastSLAM, submaps and loop closure).
//!
//! A scan is [`Scan`]: beam angles and ranges in the sensor frame, readings at
//! or beyond `range_max` kept and marked as "nothing within range" (they carry
//! free space for mapping but no end point). The sensor sits at the robot's
//! centre facing forward, as everywhere in SLAM Lab.
//!
//! Every matcher answers the same question, "which pose puts this scan where
//! the reference says it belongs?", and returns a [`ScanMatch`]: the pose, the
//! final cost and how it got there, so a lesson can step through the
//! iterations.

pub mod branch_and_bound;
pub mod icp;
pub mod kdtree;
pub mod kidnap_detector;

pub use crate::particle::Scan;

pub mod scan_to_map;

use crate::geometry::Pose2;
use crate::math;
use serde::{Deserialize, Serialize};

/// A point in a plane frame, metres: `[x, y]`.
pub type Point2 = [f64; 2];

impl Scan {
    /// Whether reading `k` is a usable end point: a finite number at least
    /// `range_min` and below `range_max` (max-range, NaN and negative readings
    /// are not).
    pub fn is_end_point(&self, k: usize) -> bool {
        let Some(&z) = self.ranges.get(k) else {
            return false;
        };
        z.is_finite() && z >= self.range_min.max(0.0) && z < self.range_max
    }

    /// Whether reading `k` says "nothing within range": at or beyond
    /// `range_max` (an infinite reading counts too).
    pub fn is_max_range(&self, k: usize) -> bool {
        self.ranges
            .get(k)
            .is_some_and(|&z| !z.is_nan() && z >= self.range_max)
    }

    /// The end points of the usable readings in the sensor frame, in beam order.
    pub fn points(&self) -> Vec<Point2> {
        let n = self.ranges.len().min(self.angles.len());
        (0..n)
            .filter(|&k| self.is_end_point(k))
            .map(|k| {
                let (s, c) = math::sin_cos(self.angles[k]);
                [self.ranges[k] * c, self.ranges[k] * s]
            })
            .collect()
    }

    /// The number of beams (angles and ranges paired).
    pub fn len(&self) -> usize {
        self.ranges.len().min(self.angles.len())
    }

    /// Whether the scan has no beams.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// `pose` applied to a point: `R p + t`.
pub fn transform_point(pose: &Pose2, p: Point2) -> Point2 {
    PointTransform::new(pose).apply(p)
}

/// A pose ready to apply to many points: its sine and cosine taken once
/// (a matcher moves hundreds of points per candidate pose, and a sine per
/// point would cost more than the rest of the work on it). Gives exactly what
/// [`transform_point`] gives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointTransform {
    sin: f64,
    cos: f64,
    x: f64,
    y: f64,
}

impl PointTransform {
    /// The transform of `pose`: `p ↦ R(θ) p + (x, y)`.
    pub fn new(pose: &Pose2) -> Self {
        let (sin, cos) = math::sin_cos(pose.theta);
        Self {
            sin,
            cos,
            x: pose.x,
            y: pose.y,
        }
    }

    /// `R p + t`.
    #[inline]
    pub fn apply(&self, p: Point2) -> Point2 {
        [
            self.cos * p[0] - self.sin * p[1] + self.x,
            self.sin * p[0] + self.cos * p[1] + self.y,
        ]
    }
}

/// What a scan matcher returns.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScanMatch {
    /// The pose of the scan's frame in the reference frame
    /// (`reference_from_scan`).
    pub pose: Pose2,
    /// The matcher's cost at `pose` (each matcher says what it measures;
    /// lower is better).
    pub cost: f64,
    /// Iterations (or candidates) it took.
    pub iterations: usize,
    /// Whether it stopped because it converged rather than at its limit.
    pub converged: bool,
}

/// A scan matcher: something that holds a reference (a scan, a map) and
/// finds the pose that puts a new scan where the reference says it belongs.
/// The lidar lessons switch between matchers through this trait.
pub trait ScanMatcher {
    /// The matcher's name as the URL and the CLI spell it.
    fn name(&self) -> &'static str;
    /// Matches `scan` against the reference, starting from `initial`
    /// (`reference_from_scan`); `None` when the scan gives nothing to match.
    fn match_scan(&self, scan: &Scan, initial: Pose2) -> Option<ScanMatch>;
}
