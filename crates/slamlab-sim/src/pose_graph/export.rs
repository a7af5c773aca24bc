//! A pose graph's poses and landmarks as files: each pose vertex at the "time"
//! of its id (so that two graphs of the same vertices pair exactly in
//! `slamlab evaluate` and evo), each point vertex as a landmark, as File > Export
//! trajectories and `slamlab graph optimize --trajectory-out DIR` write them.

use crate::io::trajectory::LandmarkRow;
use crate::metrics::{NamedTrajectory, Trajectory, TrajectoryRole};
use slamlab_core::graph::{PoseGraph, VertexState};

/// The graph's pose vertices in id order, stamped with their ids, named `name`.
pub fn pose_trajectory(graph: &PoseGraph, name: &str, role: TrajectoryRole) -> NamedTrajectory {
    let mut poses: Vec<(u64, slamlab_core::Pose2)> = graph
        .vertices()
        .iter()
        .filter_map(|v| match v.state {
            VertexState::Pose(p) => Some((v.id, p)),
            VertexState::Point(_) => None,
        })
        .collect();
    poses.sort_by_key(|(id, _)| *id);
    NamedTrajectory::new(
        name,
        role,
        Trajectory::new(
            poses.iter().map(|(id, _)| *id as f64).collect(),
            poses.iter().map(|(_, p)| *p).collect(),
        ),
    )
}

/// The graph's point vertices as landmarks (`id,x,y`).
pub fn landmarks(graph: &PoseGraph) -> Vec<LandmarkRow> {
    graph
        .vertices()
        .iter()
        .filter_map(|v| match v.state {
            VertexState::Point(p) => Some(LandmarkRow {
                id: v.id,
                x: p.x,
                y: p.y,
                covariance: None,
            }),
            VertexState::Pose(_) => None,
        })
        .collect()
}
