//! A pose graph's poses and landmarks as files: each pose vertex at the "time"
//! of its id (so that two graphs of the same vertices pair exactly in
//! `slamlab evaluate` and evo), each point vertex as a landmark, as File > Export
//! trajectories and `slamlab graph optimize --trajectory-out DIR` write them.

use crate::io::trajectory::LandmarkRow;
use crate::metrics::{NamedTrajectory, TrajectoryRole};
use slamlab_core::graph::{PoseGraph, VertexState};

/// The graph's pose vertices in id order, stamped with their ids, named `name`.
pub fn pose_trajectory(graph: &PoseGraph, name: &str, role: TrajectoryRole) -> NamedTrajectory {
    NamedTrajectory::new(name, role, crate::metrics::graph::graph_poses(graph))
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
