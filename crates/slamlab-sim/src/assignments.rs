//! The assignments SLAM Lab hands out: the built-in ones and, for each kind of
//! task, the lesson that runs a student's variant of it.
//!
//! [`crate::coursework`] is shared and knows no lesson; this list joins the two
//! (as the app's and the command line's registries list the lessons). Both front
//! ends go through it, so a student's inputs and grade are the same in the
//! browser and on the command line.

use crate::coursework::{self, Assignment, CourseworkError, Prepared, TaskRunner};

/// The runners of every kind of task that has one: landmark SLAM (the landmark
/// world), localization (the kidnap lesson's Monte Carlo localization),
/// pose-graph optimization (the pose-graph lesson), grid mapping with known
/// poses and scan matching (the mapping lesson), two-view geometry (the
/// visual-odometry lesson), sensor fusion (the fusion lesson).
pub const RUNNERS: &[TaskRunner] = &[
    TaskRunner::of::<coursework::landmarks::LandmarkRun>(),
    TaskRunner::of::<crate::kidnap::assignment::LocalizationRun>(),
    TaskRunner::of::<crate::pose_graph::assignment::PoseGraphRun>(),
    TaskRunner::of::<crate::mapping::assignment::GridMappingRun>(),
    TaskRunner::of::<crate::mapping::icp_assignment::IcpRun>(),
    TaskRunner::of::<crate::visual_odometry::assignment::TwoViewRun>(),
    TaskRunner::of::<crate::fusion::assignment::FusionRun>(),
];

/// The built-in assignment `name` (`ekf-slam`, `mcl`, `pose-graph`,
/// `grid-mapping`, `icp`, `two-view`, `fusion`).
pub fn builtin(name: &str) -> Result<Assignment, CourseworkError> {
    coursework::builtin(name, RUNNERS)
}

/// The names of the built-in assignments.
pub fn builtin_names() -> Vec<&'static str> {
    coursework::BUILTIN.iter().map(|(n, _)| *n).collect()
}

/// Reads an instructor's assignment JSON file (see
/// [`coursework::read_assignment`]).
pub fn read(name: &str, bytes: &[u8]) -> Result<Assignment, CourseworkError> {
    coursework::read_assignment(name, bytes, RUNNERS)
}

/// Runs `student`'s variant of `assignment`.
pub fn prepare(assignment: &Assignment, student: &str) -> Result<Prepared, CourseworkError> {
    coursework::prepare(assignment, student, RUNNERS)
}
