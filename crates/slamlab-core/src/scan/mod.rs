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

pub use crate::laser::{Point2, PointTransform, Scan, transform_point};

pub mod scan_to_map;

use crate::geometry::Pose2;
use serde::{Deserialize, Serialize};

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
