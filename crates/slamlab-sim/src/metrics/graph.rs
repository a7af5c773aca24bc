//! A student's optimized pose graph scored against the problem it solves: the
//! same least-squares cost the pose-graph lesson's solver minimizes, evaluated
//! at the student's vertex states with the *problem's* measurements and
//! information matrices, beside the reference solver's final cost.
//!
//! ```text
//! F(x) = Σ_ij e_ij(x)ᵀ Ω_ij e_ij(x)        (thesis 000 Eq. 4.2; slamlab_core::graph::graph_cost)
//! ratio = F(x_student) / F(x_reference),   difference = F(x_student) − F(x_reference)
//! ```
//!
//! The measurements and information matrices are the problem's, never the
//! student's file's: a file whose edges were edited (or rounded) cannot lower its
//! own cost. The file must hold the same graph: every vertex of the problem
//! (same id, same kind) and no other, and every edge (same kind, same vertex
//! ids, the same measurement to within [`MEASUREMENT_TOLERANCE`], in any order),
//! so that another problem's graph (another student's variant) is refused with
//! what differs. A pose vertex's id is its "time" for trajectory metrics, as
//! `slamlab graph optimize --trajectory-out` writes them ([`graph_poses`]).

use super::Trajectory;
use serde::Serialize;
use slamlab_core::graph::{
    EdgeKind, OptimizeError, Optimizer, OptimizerSettings, PoseGraph, RobustKernel, VertexId,
    VertexState, graph_cost,
};
use std::collections::HashMap;

/// How far a measurement in the student's file may be from the problem's and
/// still be the same edge: `|a − b| ≤ 1e-5 + 1e-6·|b|` in each number (a file
/// written with six decimals, `%f`, passes; another variant's noise, centimetres
/// and degrees, does not).
pub const MEASUREMENT_TOLERANCE: (f64, f64) = (1e-5, 1e-6);

/// What the cost is, in words, for reports.
pub const COST_DEFINITION: &str =
    "sum over the problem's edges of e^T Omega e, at the file's vertex states (thesis 000 Eq. 4.2)";

/// A student's graph scored against the problem.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GraphScore {
    /// Vertices of the problem (and of the file).
    pub vertices: usize,
    /// Edges of the problem (and of the file).
    pub edges: usize,
    /// What the cost is.
    pub cost_definition: &'static str,
    /// `F` at the file's vertex states.
    pub cost: f64,
    /// `F` at the problem's own vertex states (its initial guess).
    pub initial_cost: f64,
    /// `F` at the reference solver's solution.
    pub reference_cost: f64,
    /// `cost / reference_cost`; `None` when the reference cost is not above 0
    /// (a noise-free graph).
    pub cost_ratio: Option<f64>,
    /// `cost − reference_cost`.
    pub cost_difference: f64,
}

/// The reference solver's solution of a problem.
#[derive(Clone, Debug)]
pub struct ReferenceSolution {
    /// The optimized graph.
    pub graph: PoseGraph,
    /// `F` at the problem's initial guess.
    pub initial_cost: f64,
    /// `F` at the solution.
    pub cost: f64,
    /// Steps taken.
    pub iterations: usize,
    /// Whether the solver converged within the steps allowed.
    pub converged: bool,
    /// How the gauge was fixed, when the problem left it free.
    pub gauge: Option<String>,
}

/// Holds the first vertex fixed unless a vertex is fixed or a prior holds the
/// graph already. Returns what was done. (The pose-graph lesson and the command
/// line fix a file's gauge this way.)
pub fn fix_gauge(graph: &mut PoseGraph) -> Option<String> {
    let anchored =
        graph.vertices().iter().any(|v| v.fixed) || graph.edges().iter().any(EdgeKind::is_prior);
    if anchored {
        return None;
    }
    let first = graph.vertices().first()?.id;
    graph.set_fixed(first, true).ok()?;
    Some(format!(
        "vertex {first} (the first in the file) is held fixed to fix the gauge"
    ))
}

/// Solves `problem` with the lesson's solver (its gauge fixed by
/// [`fix_gauge`] when it is free), for at most `max_iterations` steps.
pub fn reference_solution(
    problem: &PoseGraph,
    settings: OptimizerSettings,
    max_iterations: usize,
) -> Result<ReferenceSolution, OptimizeError> {
    let mut graph = problem.clone();
    let gauge = fix_gauge(&mut graph);
    let mut optimizer = Optimizer::new(graph, settings)?;
    let initial_cost = optimizer.cost();
    let reports = optimizer.optimize(max_iterations, |_| true)?;
    Ok(ReferenceSolution {
        initial_cost,
        cost: optimizer.cost(),
        iterations: reports.len(),
        converged: optimizer.is_converged(),
        graph: optimizer.into_graph(),
        gauge,
    })
}

/// The problem with the file's vertex states: refuses a file that is not the
/// problem's graph, with the first difference found.
pub fn with_states_of(problem: &PoseGraph, file: &PoseGraph) -> Result<PoseGraph, String> {
    for v in problem.vertices() {
        match file.vertex(v.id) {
            None => {
                return Err(format!(
                    "vertex {} of the problem is missing (the file has {} vertices, the problem {}): hand in every vertex of the graph you were given",
                    v.id,
                    file.vertices().len(),
                    problem.vertices().len()
                ));
            }
            Some(w) if w.state.dim() != v.state.dim() => {
                return Err(format!(
                    "vertex {} is a {} in the problem but a {} in the file",
                    v.id,
                    kind_name(&v.state),
                    kind_name(&w.state)
                ));
            }
            Some(_) => {}
        }
    }
    if let Some(extra) = file
        .vertices()
        .iter()
        .find(|w| problem.index_of(w.id).is_none())
    {
        return Err(format!(
            "vertex {} is not in the problem (the file has {} vertices, the problem {}): this is another graph (another student's variant?)",
            extra.id,
            file.vertices().len(),
            problem.vertices().len()
        ));
    }
    check_edges(problem, file)?;
    let mut graph = problem.clone();
    for w in file.vertices() {
        graph
            .move_vertex(w.id, w.state)
            .map_err(|e| format!("vertex {}: {e}", w.id))?;
    }
    Ok(graph)
}

fn kind_name(state: &VertexState) -> &'static str {
    match state {
        VertexState::Pose(_) => "pose (VERTEX_SE2)",
        VertexState::Point(_) => "point (VERTEX_XY)",
    }
}

/// An edge's kind and the ids of its vertices (the second `None` for a prior).
type EdgeIds = (&'static str, VertexId, Option<VertexId>);

/// An edge as ids and numbers, so that two graphs' edges compare.
struct EdgeKey {
    key: EdgeIds,
    measurement: Vec<f64>,
}

fn edge_key(graph: &PoseGraph, edge: &EdgeKind) -> EdgeKey {
    let id = |i: usize| graph.vertices().get(i).map_or(u64::MAX, |v| v.id);
    let (a, b) = edge.vertices();
    let measurement = match *edge {
        EdgeKind::PosePose { measurement, .. } | EdgeKind::PosePrior { measurement, .. } => {
            vec![measurement.x, measurement.y, measurement.theta]
        }
        EdgeKind::PosePoint { measurement, .. } | EdgeKind::PointPrior { measurement, .. } => {
            vec![measurement[0], measurement[1]]
        }
        EdgeKind::RangeBearing { range, bearing, .. } => vec![range, bearing],
    };
    EdgeKey {
        key: (edge.name(), id(a), b.map(id)),
        measurement,
    }
}

fn same_measurement(a: &[f64], b: &[f64]) -> bool {
    let (abs, rel) = MEASUREMENT_TOLERANCE;
    a.len() == b.len()
        && a.iter().zip(b).all(|(x, y)| {
            let d = (x - y).abs();
            // An angle written as θ + 2π is the same measurement.
            let d = d.min((d - std::f64::consts::TAU).abs());
            d <= abs + rel * y.abs()
        })
}

/// Every edge of the problem is in the file once (any order), and no other.
fn check_edges(problem: &PoseGraph, file: &PoseGraph) -> Result<(), String> {
    if problem.edges().len() != file.edges().len() {
        return Err(format!(
            "the file has {} edges, the problem {}: hand in the graph you were given with its edges unchanged",
            file.edges().len(),
            problem.edges().len()
        ));
    }
    let mut in_file: HashMap<EdgeIds, Vec<Vec<f64>>> = HashMap::new();
    for e in file.edges() {
        let k = edge_key(file, e);
        in_file.entry(k.key).or_default().push(k.measurement);
    }
    for e in problem.edges() {
        let k = edge_key(problem, e);
        let describe = || match k.key.2 {
            Some(b) => format!("the {} edge {} -> {}", k.key.0, k.key.1, b),
            None => format!("the {} edge on {}", k.key.0, k.key.1),
        };
        let Some(candidates) = in_file.get_mut(&k.key) else {
            return Err(format!("{} of the problem is missing", describe()));
        };
        let Some(at) = candidates
            .iter()
            .position(|m| same_measurement(m, &k.measurement))
        else {
            return Err(format!(
                "{} measures {:?} in the file but {:?} in the problem: this is another graph (another student's variant?)",
                describe(),
                candidates.first().map(Vec::as_slice).unwrap_or_default(),
                k.measurement
            ));
        };
        candidates.swap_remove(at);
    }
    Ok(())
}

/// Scores a file's graph against the problem: its cost `F` (the problem's
/// measurements, the file's states, plain least squares as the reference
/// solver minimizes), the problem's initial cost and the reference's.
pub fn score_graph(
    problem: &PoseGraph,
    file: &PoseGraph,
    reference_cost: f64,
) -> Result<GraphScore, String> {
    let solved = with_states_of(problem, file)?;
    let kernel = RobustKernel::None;
    let cost = graph_cost(&solved, &kernel);
    if !cost.is_finite() {
        return Err(format!("the cost at the file's states is {cost}"));
    }
    Ok(GraphScore {
        vertices: problem.vertices().len(),
        edges: problem.edges().len(),
        cost_definition: COST_DEFINITION,
        cost,
        initial_cost: graph_cost(problem, &kernel),
        reference_cost,
        cost_ratio: (reference_cost > 0.0).then(|| cost / reference_cost),
        cost_difference: cost - reference_cost,
    })
}

/// The graph's pose vertices in id order, each at the "time" of its id (so that
/// two graphs of the same vertices pair exactly, here, in `slamlab evaluate` and
/// in evo).
pub fn graph_poses(graph: &PoseGraph) -> Trajectory {
    let mut poses: Vec<(u64, slamlab_core::Pose2)> = graph
        .vertices()
        .iter()
        .filter_map(|v| match v.state {
            VertexState::Pose(p) => Some((v.id, p)),
            VertexState::Point(_) => None,
        })
        .collect();
    poses.sort_by_key(|(id, _)| *id);
    Trajectory::new(
        poses.iter().map(|(id, _)| *id as f64).collect(),
        poses.iter().map(|(_, p)| *p).collect(),
    )
}

// Tested in `io::graph` (`score_tests`): the scores of graphs written to g2o
// and read back, as students hand them in.
