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
    let scans: Vec<usize> = (0..poses.len().min(input.scans.len())).collect();
    let (stamps, mut all) = input.truth_and_odometry(&scans);
    all.push(NamedTrajectory::new(
        sim.source().name(),
        TrajectoryRole::Estimate,
        Trajectory::new(stamps, poses.clone()),
    ));
    all
}
