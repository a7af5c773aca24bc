//! The Cartographer run as files: every node's pose in the global frame (the
//! pose graph's estimate, loop closures included), the odometry and, for a
//! simulated robot, the true poses, each at its scan's time, as File > Export
//! trajectories and `slamlab run cartographer --trajectory-out DIR` write them.

use super::CartographerSim;
use crate::metrics::{NamedTrajectory, Trajectory, TrajectoryRole};

/// The nodes' global poses in scan order (named `cartographer`), the odometry
/// and the truth at the same scans. After a kidnap the new trajectory's nodes
/// are in the global frame only once the maps have merged; before that, in the
/// new trajectory's own frame.
pub fn trajectories(sim: &CartographerSim) -> Vec<NamedTrajectory> {
    let input = sim.input();
    let mut nodes: Vec<(usize, slamlab_core::Pose2)> =
        sim.nodes.iter().map(|n| (n.scan, n.global_pose)).collect();
    nodes.sort_by_key(|(scan, _)| *scan);
    nodes.dedup_by_key(|(scan, _)| *scan);
    let scans: Vec<usize> = nodes.iter().map(|(s, _)| *s).collect();
    let (stamps, mut all) = input.truth_and_odometry(&scans);
    all.push(NamedTrajectory::new(
        "cartographer",
        TrajectoryRole::Estimate,
        Trajectory::new(stamps, nodes.iter().map(|(_, p)| *p).collect()),
    ));
    all
}
