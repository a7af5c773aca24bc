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
    let time = |scan: usize| input.scans.get(scan).map_or(f64::NAN, |s| s.time);
    let mut all = Vec::new();
    if let Some(truth) = &input.truth {
        all.push(NamedTrajectory::new(
            "truth",
            TrajectoryRole::Truth,
            Trajectory::new(
                nodes.iter().map(|(s, _)| time(*s)).collect(),
                nodes
                    .iter()
                    .filter_map(|(s, _)| truth.get(*s).copied())
                    .collect(),
            ),
        ));
    }
    all.push(NamedTrajectory::new(
        "odometry",
        TrajectoryRole::Odometry,
        Trajectory::new(
            nodes.iter().map(|(s, _)| time(*s)).collect(),
            nodes
                .iter()
                .filter_map(|(s, _)| input.scans.get(*s).map(|i| i.odometry))
                .collect(),
        ),
    ));
    all.push(NamedTrajectory::new(
        "cartographer",
        TrajectoryRole::Estimate,
        Trajectory::new(
            nodes.iter().map(|(s, _)| time(*s)).collect(),
            nodes.iter().map(|(_, p)| *p).collect(),
        ),
    ));
    all
}
