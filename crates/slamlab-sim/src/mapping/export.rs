//! The mapping run as files: the pose each scan was inserted at (the chosen
//! pose source's trajectory), the odometry, and, for a simulated robot, the true
//! poses, each at its scan's time, as File > Export trajectories and
//! `slamlab run mapping --trajectory-out DIR` write them.

use super::MappingSession;
use crate::metrics::{NamedTrajectory, Trajectory, TrajectoryRole};

/// The pose source's trajectory (named as the URL names the source), the
/// odometry, and the truth where the input has one, over the scans mapped so far.
pub fn trajectories(session: &MappingSession) -> Vec<NamedTrajectory> {
    let sim = session.stepper().sim();
    let input = sim.input();
    let poses = &session.stepper().records().poses;
    let stamps: Vec<f64> = input
        .scans
        .iter()
        .take(poses.len())
        .map(|s| s.time)
        .collect();
    let mut all = Vec::new();
    if let Some(truth) = &input.truth {
        all.push(NamedTrajectory::new(
            "truth",
            TrajectoryRole::Truth,
            Trajectory::new(
                stamps.clone(),
                truth.iter().take(poses.len()).copied().collect(),
            ),
        ));
    }
    all.push(NamedTrajectory::new(
        "odometry",
        TrajectoryRole::Odometry,
        Trajectory::new(
            stamps.clone(),
            input
                .scans
                .iter()
                .take(poses.len())
                .map(|s| s.odometry)
                .collect(),
        ),
    ));
    all.push(NamedTrajectory::new(
        sim.source().name(),
        TrajectoryRole::Estimate,
        Trajectory::new(stamps, poses.clone()),
    ));
    all
}
