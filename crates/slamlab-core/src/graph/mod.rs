//! Graph-based SLAM: a pose graph with landmarks and its nonlinear least-squares
//! solvers (thesis 000 ch. 4; thesis 002 Sec. 4.4 for TORO, g2o and GTSAM).
//!
//! A [`PoseGraph`] holds SE(2) pose vertices and 2D point (landmark) vertices and
//! the edges between them: pose-pose (thesis 000 Eq. 4.5), pose-point in the robot
//! frame (Eq. 4.6), range-bearing, and priors. The [`Optimizer`] minimises
//! `F(x) = Σ eᵀ Ω e` (Eq. 4.2, with Ω the information matrix) one iteration at a
//! time with Gauss-Newton, Levenberg-Marquardt or a first-order method.
//!
//! The gauge (where the whole map sits in the world) must be fixed by a prior or a
//! fixed vertex; [`Optimizer::new`] names the vertices of any part of the graph that
//! nothing holds in place.

pub mod edge;
mod gauge;
pub mod kernel;
pub mod solver;
pub mod sparse;
#[cfg(test)]
mod tests;

pub use gauge::FreeComponent;
pub use kernel::RobustKernel;
pub use solver::{
    BlockPattern, MarginalCovariance, OptimizeError, Optimizer, OptimizerCheckpoint,
    OptimizerSettings, SolverKind, StepReport, graph_cost, local_to_world_covariance,
};

use crate::geometry::Pose2;
use nalgebra::{Matrix2, Matrix3, Vector2};
use std::collections::HashMap;
use thiserror::Error;

/// A vertex's id as the files and the user name it.
pub type VertexId = u64;

/// The state of a vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum VertexState {
    /// A robot pose (SE(2)): 3 degrees of freedom `[x, y, θ]`.
    Pose(Pose2),
    /// A landmark position: 2 degrees of freedom `[x, y]`.
    Point(Vector2<f64>),
}

impl VertexState {
    /// Degrees of freedom: 3 for a pose, 2 for a point.
    pub fn dim(&self) -> usize {
        match self {
            VertexState::Pose(_) => 3,
            VertexState::Point(_) => 2,
        }
    }

    /// The position (a pose's translation, or the point).
    pub fn position(&self) -> Vector2<f64> {
        match self {
            VertexState::Pose(p) => p.translation(),
            VertexState::Point(p) => *p,
        }
    }

    fn is_finite(&self) -> bool {
        match self {
            VertexState::Pose(p) => p.is_finite(),
            VertexState::Point(p) => p.iter().all(|v| v.is_finite()),
        }
    }
}

/// A vertex: its id, state, and whether the solvers may move it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex {
    /// The id the files use.
    pub id: VertexId,
    /// Current estimate.
    pub state: VertexState,
    /// A fixed vertex is not optimised (it fixes the gauge, like g2o's `FIX`).
    pub fixed: bool,
}

/// What an edge measures. Vertex references are indices into
/// [`PoseGraph::vertices`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EdgeKind {
    /// Pose `to` seen from pose `from`: `z = x_from⁻¹ x_to` (thesis 000 Eq. 4.5,
    /// g2o `EDGE_SE2`).
    PosePose {
        /// Index of the first pose.
        from: usize,
        /// Index of the second pose.
        to: usize,
        /// The measured relative pose.
        measurement: Pose2,
        /// 3x3 information matrix, ordered `[x, y, θ]`.
        information: Matrix3<f64>,
    },
    /// A point in the robot frame of a pose (thesis 000 Eq. 4.6, g2o `EDGE_SE2_XY`).
    PosePoint {
        /// Index of the pose.
        pose: usize,
        /// Index of the point.
        point: usize,
        /// The point in the robot frame.
        measurement: Vector2<f64>,
        /// 2x2 information matrix.
        information: Matrix2<f64>,
    },
    /// Range and bearing from a pose to a point (thesis 000 Eq. 3.37).
    RangeBearing {
        /// Index of the pose.
        pose: usize,
        /// Index of the point.
        point: usize,
        /// Measured range, metres.
        range: f64,
        /// Measured bearing, radians, relative to the heading.
        bearing: f64,
        /// 2x2 information matrix ordered `[range, bearing]`.
        information: Matrix2<f64>,
    },
    /// A prior on a pose.
    PosePrior {
        /// Index of the pose.
        pose: usize,
        /// The prior mean.
        measurement: Pose2,
        /// 3x3 information matrix.
        information: Matrix3<f64>,
    },
    /// A prior on a point.
    PointPrior {
        /// Index of the point.
        point: usize,
        /// The prior mean.
        measurement: Vector2<f64>,
        /// 2x2 information matrix.
        information: Matrix2<f64>,
    },
}

impl EdgeKind {
    /// The vertex indices this edge connects (one for a prior).
    pub fn vertices(&self) -> (usize, Option<usize>) {
        match *self {
            EdgeKind::PosePose { from, to, .. } => (from, Some(to)),
            EdgeKind::PosePoint { pose, point, .. }
            | EdgeKind::RangeBearing { pose, point, .. } => (pose, Some(point)),
            EdgeKind::PosePrior { pose, .. } => (pose, None),
            EdgeKind::PointPrior { point, .. } => (point, None),
        }
    }

    /// Is this a prior (a unary edge)?
    pub fn is_prior(&self) -> bool {
        self.vertices().1.is_none()
    }

    /// A short name: `pose-pose`, `pose-point`, `range-bearing`, `pose-prior`, `point-prior`.
    pub fn name(&self) -> &'static str {
        match self {
            EdgeKind::PosePose { .. } => "pose-pose",
            EdgeKind::PosePoint { .. } => "pose-point",
            EdgeKind::RangeBearing { .. } => "range-bearing",
            EdgeKind::PosePrior { .. } => "pose-prior",
            EdgeKind::PointPrior { .. } => "point-prior",
        }
    }
}

/// Why a graph or an edit was refused.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum GraphError {
    /// Two vertices with the same id.
    #[error("vertex {0} is defined twice")]
    DuplicateVertex(VertexId),
    /// An edge names a vertex the graph does not have.
    #[error("{edge} edge refers to vertex {id}, which does not exist")]
    MissingVertex {
        /// The edge's kind.
        edge: &'static str,
        /// The missing id.
        id: VertexId,
    },
    /// An edge connects vertices of the wrong kinds (e.g. a pose-pose edge to a landmark).
    #[error("{edge} edge: vertex {id} is a {found}, the edge needs a {expected}")]
    WrongVertexKind {
        /// The edge's kind.
        edge: &'static str,
        /// The offending vertex.
        id: VertexId,
        /// What it is.
        found: &'static str,
        /// What the edge needs.
        expected: &'static str,
    },
    /// An edge from a vertex to itself.
    #[error("{edge} edge connects vertex {id} to itself")]
    SelfLoop {
        /// The edge's kind.
        edge: &'static str,
        /// The vertex.
        id: VertexId,
    },
    /// A NaN or infinite measurement or state.
    #[error("{what} is not a finite number")]
    NotFinite {
        /// What was not finite.
        what: String,
    },
    /// An information matrix that is not symmetric positive semi-definite, or zero.
    #[error("{edge} edge between {ids}: information matrix {reason}")]
    BadInformation {
        /// The edge's kind.
        edge: &'static str,
        /// The vertex ids.
        ids: String,
        /// What is wrong with it.
        reason: String,
    },
    /// An edge built with a vertex index past the end of the vertex list.
    #[error("{edge} edge refers to vertex index {index}, past the end of the graph's vertices")]
    NoSuchIndex {
        /// The edge's kind.
        edge: &'static str,
        /// The index.
        index: usize,
    },
    /// No such vertex id.
    #[error("there is no vertex {0}")]
    UnknownVertex(VertexId),
    /// A state of the wrong kind for a vertex (a point for a pose).
    #[error("vertex {0}: the new state is not of the vertex's kind")]
    StateKindMismatch(VertexId),
}

/// A pose graph: vertices (poses and landmarks) and the edges between them.
#[derive(Clone, Debug, Default)]
pub struct PoseGraph {
    vertices: Vec<Vertex>,
    edges: Vec<EdgeKind>,
    index: HashMap<VertexId, usize>,
}

impl PoseGraph {
    /// An empty graph.
    pub fn new() -> Self {
        Self::default()
    }

    /// The vertices, in insertion order.
    pub fn vertices(&self) -> &[Vertex] {
        &self.vertices
    }

    /// The edges, in insertion order; their vertex references index [`Self::vertices`].
    pub fn edges(&self) -> &[EdgeKind] {
        &self.edges
    }

    /// The index of a vertex id in [`Self::vertices`].
    pub fn index_of(&self, id: VertexId) -> Option<usize> {
        self.index.get(&id).copied()
    }

    /// The vertex with this id.
    pub fn vertex(&self, id: VertexId) -> Option<&Vertex> {
        self.index_of(id).map(|i| &self.vertices[i])
    }

    /// Number of pose vertices.
    pub fn pose_count(&self) -> usize {
        self.vertices
            .iter()
            .filter(|v| matches!(v.state, VertexState::Pose(_)))
            .count()
    }

    /// Number of point (landmark) vertices.
    pub fn point_count(&self) -> usize {
        self.vertices.len() - self.pose_count()
    }

    /// Adds a vertex; refuses a duplicate id or a non-finite state. Returns its index.
    pub fn add_vertex(&mut self, id: VertexId, state: VertexState) -> Result<usize, GraphError> {
        if self.index.contains_key(&id) {
            return Err(GraphError::DuplicateVertex(id));
        }
        if !state.is_finite() {
            return Err(GraphError::NotFinite {
                what: format!("the state of vertex {id}"),
            });
        }
        let i = self.vertices.len();
        self.vertices.push(Vertex {
            id,
            state,
            fixed: false,
        });
        self.index.insert(id, i);
        Ok(i)
    }

    /// Adds a pose vertex.
    pub fn add_pose(&mut self, id: VertexId, pose: Pose2) -> Result<usize, GraphError> {
        self.add_vertex(id, VertexState::Pose(pose))
    }

    /// Adds a point (landmark) vertex.
    pub fn add_point(&mut self, id: VertexId, point: Vector2<f64>) -> Result<usize, GraphError> {
        self.add_vertex(id, VertexState::Point(point))
    }

    /// Fixes (or frees) a vertex: a fixed vertex is held where it is.
    pub fn set_fixed(&mut self, id: VertexId, fixed: bool) -> Result<(), GraphError> {
        let i = self.index_of(id).ok_or(GraphError::UnknownVertex(id))?;
        self.vertices[i].fixed = fixed;
        Ok(())
    }

    /// Moves a vertex to a new state of the same kind (a drag in the lesson).
    pub fn move_vertex(&mut self, id: VertexId, state: VertexState) -> Result<(), GraphError> {
        let i = self.index_of(id).ok_or(GraphError::UnknownVertex(id))?;
        if std::mem::discriminant(&self.vertices[i].state) != std::mem::discriminant(&state) {
            return Err(GraphError::StateKindMismatch(id));
        }
        if !state.is_finite() {
            return Err(GraphError::NotFinite {
                what: format!("the new state of vertex {id}"),
            });
        }
        self.vertices[i].state = state;
        Ok(())
    }

    /// Replaces all vertex states at once (used by the solvers).
    pub(crate) fn vertices_mut(&mut self) -> &mut [Vertex] {
        &mut self.vertices
    }

    fn check_kind(&self, edge: &'static str, i: usize, pose: bool) -> Result<VertexId, GraphError> {
        let v = self
            .vertices
            .get(i)
            .ok_or(GraphError::NoSuchIndex { edge, index: i })?;
        let is_pose = matches!(v.state, VertexState::Pose(_));
        if is_pose != pose {
            return Err(GraphError::WrongVertexKind {
                edge,
                id: v.id,
                found: if is_pose { "pose" } else { "point" },
                expected: if pose { "pose" } else { "point" },
            });
        }
        Ok(v.id)
    }

    /// Adds an edge after checking it: its vertices exist and are of the right kind,
    /// it is not a self-loop, its measurement is finite, and its information matrix
    /// is symmetric, finite, positive semi-definite and not zero. Returns its index.
    pub fn add_edge(&mut self, edge: EdgeKind) -> Result<usize, GraphError> {
        let name = edge.name();
        let (ids, finite, info): (String, bool, Result<(), String>) = match edge {
            EdgeKind::PosePose {
                from,
                to,
                measurement,
                information,
            } => {
                let a = self.check_kind(name, from, true)?;
                let b = self.check_kind(name, to, true)?;
                if from == to {
                    return Err(GraphError::SelfLoop { edge: name, id: a });
                }
                (
                    format!("{a} and {b}"),
                    measurement.is_finite(),
                    check_information(information.as_slice(), 3),
                )
            }
            EdgeKind::PosePoint {
                pose,
                point,
                measurement,
                information,
            } => {
                let a = self.check_kind(name, pose, true)?;
                let b = self.check_kind(name, point, false)?;
                (
                    format!("{a} and {b}"),
                    measurement.iter().all(|v| v.is_finite()),
                    check_information(information.as_slice(), 2),
                )
            }
            EdgeKind::RangeBearing {
                pose,
                point,
                range,
                bearing,
                information,
            } => {
                let a = self.check_kind(name, pose, true)?;
                let b = self.check_kind(name, point, false)?;
                (
                    format!("{a} and {b}"),
                    range.is_finite() && bearing.is_finite(),
                    check_information(information.as_slice(), 2),
                )
            }
            EdgeKind::PosePrior {
                pose,
                measurement,
                information,
            } => {
                let a = self.check_kind(name, pose, true)?;
                (
                    format!("{a}"),
                    measurement.is_finite(),
                    check_information(information.as_slice(), 3),
                )
            }
            EdgeKind::PointPrior {
                point,
                measurement,
                information,
            } => {
                let a = self.check_kind(name, point, false)?;
                (
                    format!("{a}"),
                    measurement.iter().all(|v| v.is_finite()),
                    check_information(information.as_slice(), 2),
                )
            }
        };
        if !finite {
            return Err(GraphError::NotFinite {
                what: format!("the measurement of the {name} edge between {ids}"),
            });
        }
        info.map_err(|reason| GraphError::BadInformation {
            edge: name,
            ids,
            reason,
        })?;
        self.edges.push(edge);
        Ok(self.edges.len() - 1)
    }

    /// Removes the last edge (undo of an [`Self::add_edge`] in the lesson).
    pub fn pop_edge(&mut self) -> Option<EdgeKind> {
        self.edges.pop()
    }
}

/// Checks a column-major `n x n` information matrix: finite, symmetric, positive
/// semi-definite, not zero. Denormal entries (FRH.g2o stores `6.95e-310` for
/// `I13`) are accepted as the tiny numbers they are.
fn check_information(m: &[f64], n: usize) -> Result<(), String> {
    if m.iter().any(|v| !v.is_finite()) {
        return Err("has a NaN or infinite entry".to_owned());
    }
    let scale = m.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    if scale == 0.0 {
        return Err("is zero (the edge would carry no information)".to_owned());
    }
    for r in 0..n {
        for c in 0..r {
            if (m[r + c * n] - m[c + r * n]).abs() > 1e-9 * scale {
                return Err("is not symmetric".to_owned());
            }
        }
    }
    let min_eig = if n == 2 {
        nalgebra::Matrix2::from_column_slice(m)
            .symmetric_eigenvalues()
            .min()
    } else {
        nalgebra::Matrix3::from_column_slice(m)
            .symmetric_eigenvalues()
            .min()
    };
    if min_eig < -1e-9 * scale {
        return Err(format!(
            "is not positive semi-definite (smallest eigenvalue {min_eig:.3e})"
        ));
    }
    Ok(())
}
