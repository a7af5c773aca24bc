//! Solvers for the pose graph, one iteration at a time.
//!
//! Linearising every edge at the current estimate, `e(x + Δx) ≈ e + J Δx`
//! (thesis 000 Eq. 4.7), turns `F(x) = Σ eᵀ Ω e` into the sparse normal equations
//! `H Δx = b` with `H = Σ Jᵀ Ω J` and `b = −Σ Jᵀ Ω e` (thesis 000 Sec. 2.4.2). Each
//! edge touches only the blocks of its two vertices (Eq. 4.8), so `H` is sparse.
//!
//! * Gauss-Newton solves `H Δx = b` and always takes the step.
//! * Levenberg-Marquardt (thesis 002 Sec. 4.4.2) solves `(H + λ I) Δx = b`
//!   (Levenberg's damping, gtsam's default, starting at λ = 1e-5 like gtsam), takes
//!   the step only if the cost falls, and then divides λ by 10; a rejected step
//!   multiplies λ by 10 (gtsam's fixed λ factor).
//!
//! Poses are updated in their own frame, `x ← x ∘ Exp(δ)` (the SE(2) exponential,
//! as gtsam retracts), points additively.
//! * The first-order method (in the spirit of TORO and Olson's preconditioned
//!   gradient descent, thesis 002 Sec. 4.4.1) moves every vertex along its own
//!   block of the gradient, scaled by the inverse of its diagonal block of `H`
//!   (a block-Jacobi preconditioner), with a step length halved until the cost
//!   falls. It does not use TORO's tree parametrisation, so it shows plainly how
//!   slowly first-order information alone closes a loop.
//!
//! `H`'s pattern is analysed once (a fill-reducing order of the vertices and the
//! symbolic Cholesky factorization) and reused by every iteration until an edit
//! changes the structure.

use super::edge;
use super::gauge::{FreeComponent, free_components};
use super::kernel::RobustKernel;
use super::sparse::{
    CholeskyError, FaerCholesky, SparseCholesky, fill_reducing_order, symbolic_factor_pattern,
};
use super::{EdgeKind, GraphError, PoseGraph, VertexId, VertexState};
use crate::geometry::Pose2;
use nalgebra::{Matrix2, Matrix3, SMatrix, Vector2, Vector3};
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Which solver [`Optimizer::step`] runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum SolverKind {
    /// Gauss-Newton.
    GaussNewton,
    /// Levenberg-Marquardt (`H + λI`, λ divided or multiplied by 10).
    #[default]
    LevenbergMarquardt,
    /// Block-Jacobi preconditioned gradient descent with step halving.
    GradientDescent,
}

impl SolverKind {
    /// The short name the CLI uses: `gn`, `lm`, `gd`.
    pub fn short_name(&self) -> &'static str {
        match self {
            SolverKind::GaussNewton => "gn",
            SolverKind::LevenbergMarquardt => "lm",
            SolverKind::GradientDescent => "gd",
        }
    }

    /// Parses `gn`, `lm` or `gd`.
    pub fn from_short_name(name: &str) -> Option<Self> {
        match name {
            "gn" => Some(SolverKind::GaussNewton),
            "lm" => Some(SolverKind::LevenbergMarquardt),
            "gd" => Some(SolverKind::GradientDescent),
            _ => None,
        }
    }
}

/// Solver settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OptimizerSettings {
    /// Which solver.
    pub solver: SolverKind,
    /// Robust kernel applied to every edge.
    pub kernel: RobustKernel,
    /// Converged when an accepted step lowers the cost by less than this fraction
    /// of the cost (gtsam's default relative tolerance is also 1e-5).
    pub relative_tolerance: f64,
    /// Converged when an accepted step lowers the cost by less than this.
    pub absolute_tolerance: f64,
    /// LM's initial λ (the damping `λ I` is added to `H`).
    pub initial_lambda: f64,
}

impl Default for OptimizerSettings {
    fn default() -> Self {
        Self {
            solver: SolverKind::LevenbergMarquardt,
            kernel: RobustKernel::None,
            relative_tolerance: 1e-5,
            absolute_tolerance: 1e-5,
            initial_lambda: 1e-5,
        }
    }
}

/// What one call of [`Optimizer::step`] did.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepReport {
    /// 1 for the first step.
    pub iteration: usize,
    /// The cost `Σ ρ(eᵀΩe)` before the step.
    pub cost_before: f64,
    /// The cost after the step (equal to `cost_before` if it was rejected).
    pub cost: f64,
    /// `‖Δx‖` of the step that was tried.
    pub step_norm: f64,
    /// LM's λ used for this step; `None` for the other solvers.
    pub lambda: Option<f64>,
    /// For the first-order method, the step length used; `None` for the others.
    pub step_length: Option<f64>,
    /// Was the step taken? Gauss-Newton always takes it; LM and the first-order
    /// method only when the cost falls.
    pub accepted: bool,
    /// Has the solver converged (or can make no more progress)?
    pub converged: bool,
}

/// Why the optimizer cannot run.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum OptimizeError {
    /// Part of the graph is held by no prior and no fixed vertex.
    #[error("{}", free_gauge_message(.components, *.total_components))]
    FreeGauge {
        /// The parts nothing holds.
        components: Vec<FreeComponent>,
        /// Connected components in the whole graph.
        total_components: usize,
    },
    /// The normal equations are singular at a vertex although the gauge is fixed.
    #[error(
        "the normal equations are not positive definite at vertex {vertex} ({dof}): the edges at this vertex do not determine it (e.g. a pose seen only through one landmark, a landmark with a single bearing, or information that has under- or overflowed); add a measurement or a prior there"
    )]
    Indefinite {
        /// The vertex.
        vertex: VertexId,
        /// Which of its coordinates (`x`, `y` or `θ`).
        dof: &'static str,
    },
    /// Every vertex is fixed: there is nothing to optimise.
    #[error("every vertex is fixed: there is nothing to optimise")]
    NothingToOptimize,
    /// The cost became NaN or infinite.
    #[error("the cost is not a finite number ({0}); a state or measurement has overflowed")]
    NotFinite(f64),
    /// A graph edit was refused.
    #[error(transparent)]
    Graph(#[from] GraphError),
    /// The sparse factorization failed for a reason other than indefiniteness.
    #[error(transparent)]
    Cholesky(CholeskyError),
    /// A checkpoint taken of another graph (other vertices, or more edges than the
    /// graph has now) cannot be restored.
    #[error("the checkpoint belongs to another graph: {0}")]
    CheckpointMismatch(String),
}

fn free_gauge_message(components: &[FreeComponent], total: usize) -> String {
    let parts: Vec<String> = components
        .iter()
        .map(|c| {
            let ids: Vec<String> = c.sample.iter().map(|id| id.to_string()).collect();
            let more = if c.size > c.sample.len() { ", …" } else { "" };
            format!("{} vertices ({}{more})", c.size, ids.join(", "))
        })
        .collect();
    let why = if total > 1 {
        format!(
            "the graph falls into {total} disconnected parts, and {} of them",
            components.len()
        )
    } else {
        "the graph".to_owned()
    };
    format!(
        "the system is indefinite: {why} can move rigidly without changing any error, because no prior and no fixed vertex holds {}: {}; fix a vertex or add a prior in each",
        if components.len() == 1 { "it" } else { "them" },
        parts.join("; ")
    )
}

/// A marginal covariance of one vertex, from the Cholesky factor of `H` at the
/// current estimate (`Σ = H⁻¹`, its diagonal block), in the world frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MarginalCovariance {
    /// 3x3 covariance of a pose's world coordinates `[x, y, θ]`. The solver
    /// linearizes a pose in its own frame (`x ∘ Exp(δ)`), so `H⁻¹` holds the
    /// covariance `Σ_δ` of the local increment; this is
    /// `diag(R(θ), 1) Σ_δ diag(R(θ), 1)ᵀ`, what an ellipse drawn on the map
    /// needs (to first order, the world position moves by `R(θ) δ_xy`).
    WorldPose(Matrix3<f64>),
    /// 2x2 covariance of a point.
    Point(Matrix2<f64>),
    /// A fixed vertex has no uncertainty in this model.
    Fixed,
}

/// A sparsity pattern by vertex blocks, for drawing `H` and `L`.
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
pub struct BlockPattern {
    /// The vertex id of each block row/column, in the order of the pattern.
    pub vertex_ids: Vec<VertexId>,
    /// Degrees of freedom of each block (3 for a pose, 2 for a point).
    pub dims: Vec<usize>,
    /// Non-zero blocks `(row, col)`.
    pub entries: Vec<(usize, usize)>,
    /// For the factor: `true` where the block is fill-in (zero in the reordered `H`);
    /// all `false` for `H` itself.
    pub fill_in: Vec<bool>,
}

impl BlockPattern {
    /// The scalar non-zeros `(row, col, fill_in)` this block pattern covers (for a
    /// lower-triangular factor, the diagonal blocks are cut to their lower triangle).
    pub fn scalar_entries(&self, lower_triangular: bool) -> Vec<(usize, usize, bool)> {
        let mut offset = Vec::with_capacity(self.dims.len());
        let mut o = 0;
        for &d in &self.dims {
            offset.push(o);
            o += d;
        }
        let mut out = Vec::new();
        for (k, &(r, c)) in self.entries.iter().enumerate() {
            let fill = self.fill_in.get(k).copied().unwrap_or(false);
            for i in 0..self.dims[r] {
                for j in 0..self.dims[c] {
                    if !lower_triangular || r != c || j <= i {
                        out.push((offset[r] + i, offset[c] + j, fill));
                    }
                }
            }
        }
        out
    }
}

/// Where an edge's blocks live in the value array of `H`'s upper triangle.
#[derive(Clone, Copy, Debug)]
struct EdgeSlots {
    /// (block, position of its diagonal block in its columns), per vertex of the edge.
    a: Option<(usize, usize)>,
    b: Option<(usize, usize)>,
    /// Position of the off-diagonal block within the columns of the later block;
    /// `true` if vertex a is the row (earlier) block.
    cross: Option<(usize, bool)>,
}

/// The analysed structure of `H`: the elimination order, the compressed-column
/// pattern of its upper triangle, and the symbolic factorization.
#[derive(Debug)]
struct Structure {
    /// Vertex index → block (position in the elimination order), `None` if fixed.
    block_of: Vec<Option<usize>>,
    /// Block → vertex index.
    vertex_of: Vec<usize>,
    /// Block → first unknown.
    offset: Vec<usize>,
    /// Block → degrees of freedom.
    dim: Vec<usize>,
    /// Unknowns.
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// Index of each unknown's diagonal entry in the value array.
    diag: Vec<usize>,
    slots: Vec<EdgeSlots>,
    /// Block adjacency in elimination order (for the factor pattern).
    adjacency: Vec<Vec<usize>>,
    cholesky: FaerCholesky,
}

/// `H`, `b` and the cost at one linearization point.
#[derive(Clone, Debug)]
struct Linearization {
    values: Vec<f64>,
    b: Vec<f64>,
    cost: f64,
}

/// What the optimizer was at one moment (after an iteration or before an edit), to
/// go back to it: the vertex states and fixed flags, how many edges the graph had,
/// the settings and the solver's own state (LM's λ, the first-order method's step
/// length, the iteration count, convergence). It holds no matrix, so a checkpoint
/// of a 200-pose graph is a few kilobytes: restoring one linearizes again where
/// the moment had a linearization, which gives the same `H`, `b` and cost bit for
/// bit (the same states through the same arithmetic).
#[derive(Clone, Debug, PartialEq)]
pub struct OptimizerCheckpoint {
    states: Vec<VertexState>,
    fixed: Vec<bool>,
    edges: usize,
    settings: OptimizerSettings,
    lambda: Option<f64>,
    step_length: f64,
    iteration: usize,
    converged: bool,
    linearized: bool,
}

impl OptimizerCheckpoint {
    /// The memory the checkpoint holds, bytes (for a bounded history).
    pub fn bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.states.len() * std::mem::size_of::<VertexState>()
            + self.fixed.len()
    }

    /// Iterations the optimizer had run.
    pub fn iterations(&self) -> usize {
        self.iteration
    }
}

/// Pose-graph optimizer: owns the graph and steps a solver one iteration at a time.
#[derive(Debug)]
pub struct Optimizer {
    graph: PoseGraph,
    settings: OptimizerSettings,
    structure: Option<Structure>,
    linearization: Option<Linearization>,
    lambda: Option<f64>,
    step_length: f64,
    iteration: usize,
    converged: bool,
}

type Block3 = SMatrix<f64, 3, 3>;

/// One edge linearised: error padded to 3 rows, information padded to 3x3, and the
/// Jacobians padded to 3x3 (unused rows and columns zero).
struct LinearEdge {
    e: Vector3<f64>,
    omega: Block3,
    ja: Block3,
    jb: Block3,
}

fn pad2(m: &Matrix2<f64>) -> Block3 {
    let mut p = Block3::zeros();
    p.fixed_view_mut::<2, 2>(0, 0).copy_from(m);
    p
}

fn pad23(m: &nalgebra::Matrix2x3<f64>) -> Block3 {
    let mut p = Block3::zeros();
    p.fixed_view_mut::<2, 3>(0, 0).copy_from(m);
    p
}

fn pose_of(graph: &PoseGraph, i: usize) -> Pose2 {
    match graph.vertices()[i].state {
        VertexState::Pose(p) => p,
        VertexState::Point(p) => Pose2::new(p[0], p[1], 0.0),
    }
}

fn point_of(graph: &PoseGraph, i: usize) -> Vector2<f64> {
    graph.vertices()[i].state.position()
}

/// The error of an edge padded to 3 rows, and its padded information matrix.
fn edge_error(graph: &PoseGraph, e: &EdgeKind) -> (Vector3<f64>, Block3) {
    match *e {
        EdgeKind::PosePose {
            from,
            to,
            measurement,
            information,
        } => (
            edge::pose_pose_error(&pose_of(graph, from), &pose_of(graph, to), &measurement),
            information,
        ),
        EdgeKind::PosePoint {
            pose,
            point,
            measurement,
            information,
        } => {
            let r = edge::pose_point_error(
                &pose_of(graph, pose),
                &point_of(graph, point),
                &measurement,
            );
            (Vector3::new(r[0], r[1], 0.0), pad2(&information))
        }
        EdgeKind::RangeBearing {
            pose,
            point,
            range,
            bearing,
            information,
        } => {
            let r = edge::range_bearing_error(
                &pose_of(graph, pose),
                &point_of(graph, point),
                range,
                bearing,
            );
            (Vector3::new(r[0], r[1], 0.0), pad2(&information))
        }
        EdgeKind::PosePrior {
            pose,
            measurement,
            information,
        } => (
            edge::pose_prior_error(&pose_of(graph, pose), &measurement),
            information,
        ),
        EdgeKind::PointPrior {
            point,
            measurement,
            information,
        } => {
            let r = edge::point_prior_error(&point_of(graph, point), &measurement);
            (Vector3::new(r[0], r[1], 0.0), pad2(&information))
        }
    }
}

fn linearize_edge(graph: &PoseGraph, e: &EdgeKind) -> LinearEdge {
    let (err, omega) = edge_error(graph, e);
    let (ja, jb) = match *e {
        EdgeKind::PosePose {
            from,
            to,
            measurement,
            ..
        } => edge::pose_pose_jacobians(&pose_of(graph, from), &pose_of(graph, to), &measurement),
        EdgeKind::PosePoint { pose, point, .. } => {
            let (a, b) = edge::pose_point_jacobians(&pose_of(graph, pose), &point_of(graph, point));
            (pad23(&a), pad2(&b))
        }
        EdgeKind::RangeBearing { pose, point, .. } => {
            let (a, b) =
                edge::range_bearing_jacobians(&pose_of(graph, pose), &point_of(graph, point));
            (pad23(&a), pad2(&b))
        }
        EdgeKind::PosePrior { .. } => (Block3::identity(), Block3::zeros()),
        EdgeKind::PointPrior { .. } => (pad2(&Matrix2::identity()), Block3::zeros()),
    };
    // Poses are updated in their own frame (x ← x ∘ Exp(δ)), so a pose's
    // Jacobian block is ∂e/∂x · ∂(x ∘ Exp(δ))/∂δ = ∂e/∂x · diag(R(θ), 1).
    let (va, vb) = e.vertices();
    let ja = to_local(graph, va, ja);
    let jb = match vb {
        Some(v) => to_local(graph, v, jb),
        None => jb,
    };
    LinearEdge {
        e: err,
        omega,
        ja,
        jb,
    }
}

/// Right-multiplies a pose's Jacobian block by `diag(R(θ), 1)` (a point's is kept).
fn to_local(graph: &PoseGraph, v: usize, j: Block3) -> Block3 {
    match graph.vertices()[v].state {
        VertexState::Pose(p) => {
            let r = p.rotation();
            let mut out = j;
            for row in 0..3 {
                let (a, b) = (j[(row, 0)], j[(row, 1)]);
                out[(row, 0)] = a * r[(0, 0)] + b * r[(1, 0)];
                out[(row, 1)] = a * r[(0, 1)] + b * r[(1, 1)];
            }
            out
        }
        VertexState::Point(_) => j,
    }
}

/// `diag(R(θ), 1) Σ diag(R(θ), 1)ᵀ`: the covariance of a pose's world
/// coordinates from the covariance `Σ` of its increment in its own frame
/// (`x ∘ Exp(δ)` moves the position by `R(θ) δ_xy + O(|δ|²)` and the heading by
/// `δ_θ`).
pub fn local_to_world_covariance(local: &Matrix3<f64>, theta: f64) -> Matrix3<f64> {
    let (s, c) = crate::math::sin_cos(theta);
    let j = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
    let w = j * local * j.transpose();
    // Exactly symmetric, whatever the rounding.
    (w + w.transpose()) * 0.5
}

/// `x ∘ Exp(δ)` on SE(2): the pose moved by `δ = [v_x, v_y, ω]` given in its own
/// frame (the exponential map, so that a step along a constant twist is exact).
pub fn retract(x: &Pose2, delta: &Vector3<f64>) -> Pose2 {
    let w = delta[2];
    let (s, c) = crate::math::sin_cos(w);
    let (a, b) = if w.abs() < 1e-9 {
        (1.0 - w * w / 6.0, 0.5 * w)
    } else {
        (s / w, (1.0 - c) / w)
    };
    let t = Vector2::new(a * delta[0] - b * delta[1], b * delta[0] + a * delta[1]);
    x.compose(&Pose2::new(t[0], t[1], w))
}

/// The cost `Σ ρ(eᵀ Ω e)` of a graph under a kernel (thesis 000 Eq. 4.2).
pub fn graph_cost(graph: &PoseGraph, kernel: &RobustKernel) -> f64 {
    graph
        .edges()
        .iter()
        .map(|e| {
            let (err, omega) = edge_error(graph, e);
            kernel.cost(err.dot(&(omega * err)))
        })
        .sum()
}

impl Optimizer {
    /// An optimizer for `graph`. Refuses a graph whose gauge is free (names the
    /// vertices nothing holds) or whose vertices are all fixed.
    pub fn new(graph: PoseGraph, settings: OptimizerSettings) -> Result<Self, OptimizeError> {
        let mut this = Self {
            graph,
            settings,
            structure: None,
            linearization: None,
            lambda: None,
            step_length: 1.0,
            iteration: 0,
            converged: false,
        };
        this.ensure_structure()?;
        Ok(this)
    }

    /// The graph at the current estimate.
    pub fn graph(&self) -> &PoseGraph {
        &self.graph
    }

    /// Gives the graph back.
    pub fn into_graph(self) -> PoseGraph {
        self.graph
    }

    /// The settings.
    pub fn settings(&self) -> &OptimizerSettings {
        &self.settings
    }

    /// Steps taken so far.
    pub fn iterations(&self) -> usize {
        self.iteration
    }

    /// Has the last step converged?
    pub fn is_converged(&self) -> bool {
        self.converged
    }

    /// The current cost `Σ ρ(eᵀΩe)`.
    pub fn cost(&self) -> f64 {
        self.linearization.as_ref().map_or_else(
            || graph_cost(&self.graph, &self.settings.kernel),
            |l| l.cost,
        )
    }

    /// LM's current λ, once LM has started.
    pub fn lambda(&self) -> Option<f64> {
        self.lambda
    }

    /// Switches the solver (keeps the estimate; LM restarts its λ).
    pub fn set_solver(&mut self, solver: SolverKind) {
        self.settings.solver = solver;
        self.lambda = None;
        self.converged = false;
    }

    /// Swaps the robust kernel (the structure is kept, the linearization redone).
    pub fn set_kernel(&mut self, kernel: RobustKernel) {
        self.settings.kernel = kernel;
        self.linearization = None;
        self.converged = false;
    }

    /// Moves a vertex (a drag in the lesson). The structure is kept.
    pub fn move_vertex(&mut self, id: VertexId, state: VertexState) -> Result<(), OptimizeError> {
        self.graph.move_vertex(id, state)?;
        self.linearization = None;
        self.lambda = None;
        self.converged = false;
        Ok(())
    }

    /// Adds an edge (a loop closure in the lesson); the structure is analysed again
    /// at the next step.
    pub fn add_edge(&mut self, edge: EdgeKind) -> Result<usize, OptimizeError> {
        let i = self.graph.add_edge(edge)?;
        self.invalidate_structure();
        Ok(i)
    }

    /// Fixes or frees a vertex; the structure is analysed again at the next step.
    pub fn set_fixed(&mut self, id: VertexId, fixed: bool) -> Result<(), OptimizeError> {
        self.graph.set_fixed(id, fixed)?;
        self.invalidate_structure();
        Ok(())
    }

    /// Removes the last edge; the structure is analysed again at the next step.
    pub fn pop_edge(&mut self) -> Option<EdgeKind> {
        let e = self.graph.pop_edge();
        self.invalidate_structure();
        e
    }

    /// The optimizer's state now, to restore with [`Self::restore_checkpoint`].
    pub fn checkpoint(&self) -> OptimizerCheckpoint {
        OptimizerCheckpoint {
            states: self.snapshot(),
            fixed: self.graph.vertices().iter().map(|v| v.fixed).collect(),
            edges: self.graph.edges().len(),
            settings: self.settings,
            lambda: self.lambda,
            step_length: self.step_length,
            iteration: self.iteration,
            converged: self.converged,
            linearized: self.linearization.is_some(),
        }
    }

    /// Goes back to a checkpoint of this graph: edges added since are removed, the
    /// vertices, settings and solver state are set back. Refuses a checkpoint of
    /// another graph (other vertex count, or more edges than there are now) and
    /// leaves the optimizer as it was then.
    pub fn restore_checkpoint(
        &mut self,
        checkpoint: &OptimizerCheckpoint,
    ) -> Result<(), OptimizeError> {
        let (vertices, edges) = (self.graph.vertices().len(), self.graph.edges().len());
        if checkpoint.states.len() != vertices || checkpoint.fixed.len() != vertices {
            return Err(OptimizeError::CheckpointMismatch(format!(
                "it has {} vertices, the graph {vertices}",
                checkpoint.states.len()
            )));
        }
        if checkpoint.edges > edges {
            return Err(OptimizeError::CheckpointMismatch(format!(
                "it has {} edges, the graph only {edges}",
                checkpoint.edges
            )));
        }
        let mut structure_changed = checkpoint.edges < edges;
        while self.graph.edges().len() > checkpoint.edges {
            self.graph.pop_edge();
        }
        for (v, (state, fixed)) in self
            .graph
            .vertices_mut()
            .iter_mut()
            .zip(checkpoint.states.iter().zip(&checkpoint.fixed))
        {
            v.state = *state;
            structure_changed |= v.fixed != *fixed;
            v.fixed = *fixed;
        }
        if structure_changed {
            self.structure = None;
        }
        self.settings = checkpoint.settings;
        self.linearization = None;
        self.lambda = checkpoint.lambda;
        self.step_length = checkpoint.step_length;
        self.iteration = checkpoint.iteration;
        self.converged = checkpoint.converged;
        if checkpoint.linearized {
            self.linearize()?;
        }
        Ok(())
    }

    fn invalidate_structure(&mut self) {
        self.structure = None;
        self.linearization = None;
        self.lambda = None;
        self.converged = false;
    }

    /// Analyses the structure of `H` if needed: gauge check, fill-reducing order of
    /// the free vertices, compressed-column pattern, symbolic factorization.
    fn ensure_structure(&mut self) -> Result<(), OptimizeError> {
        if self.structure.is_some() {
            return Ok(());
        }
        let (free, total) = free_components(&self.graph);
        if !free.is_empty() {
            return Err(OptimizeError::FreeGauge {
                components: free,
                total_components: total,
            });
        }
        let vertices = self.graph.vertices();
        let free_vertices: Vec<usize> = (0..vertices.len())
            .filter(|&i| !vertices[i].fixed)
            .collect();
        if free_vertices.is_empty() {
            return Err(OptimizeError::NothingToOptimize);
        }
        let mut free_pos = vec![None; vertices.len()];
        for (k, &i) in free_vertices.iter().enumerate() {
            free_pos[i] = Some(k);
        }
        // Vertex adjacency among free vertices (natural numbering).
        let m = free_vertices.len();
        let mut adjacency: Vec<Vec<usize>> = vec![Vec::new(); m];
        for e in self.graph.edges() {
            if let (a, Some(b)) = e.vertices()
                && let (Some(pa), Some(pb)) = (free_pos[a], free_pos[b])
            {
                adjacency[pa].push(pb);
                adjacency[pb].push(pa);
            }
        }
        let order = fill_reducing_order(m, &adjacency);
        let mut block_of = vec![None; vertices.len()];
        let mut vertex_of = Vec::with_capacity(m);
        let mut dim = Vec::with_capacity(m);
        let mut offset = Vec::with_capacity(m);
        let mut n = 0;
        for (blk, &k) in order.iter().enumerate() {
            let v = free_vertices[k];
            block_of[v] = Some(blk);
            vertex_of.push(v);
            let d = vertices[v].state.dim();
            dim.push(d);
            offset.push(n);
            n += d;
        }
        // Block adjacency in elimination order, and per column block the earlier blocks.
        let mut blk_adj: Vec<Vec<usize>> = vec![Vec::new(); m];
        let mut earlier: Vec<Vec<usize>> = vec![Vec::new(); m];
        let mut inv = vec![0usize; m];
        for (blk, &k) in order.iter().enumerate() {
            inv[k] = blk;
        }
        for (k, list) in adjacency.iter().enumerate() {
            let bk = inv[k];
            for &l in list {
                let bl = inv[l];
                blk_adj[bk].push(bl);
                if bl < bk {
                    earlier[bk].push(bl);
                }
            }
        }
        for list in blk_adj.iter_mut().chain(earlier.iter_mut()) {
            list.sort_unstable();
            list.dedup();
        }
        // Compressed-column upper triangle. Column block q holds, in order, the
        // earlier blocks' rows and then its own diagonal block (rows up to the column).
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        let mut diag = vec![0usize; n];
        // position of block p within column block q, as a sorted list per q.
        let mut within: Vec<Vec<(usize, usize)>> = vec![Vec::new(); m];
        col_ptr.push(0);
        for q in 0..m {
            let mut pos = 0;
            for &p in &earlier[q] {
                within[q].push((p, pos));
                pos += dim[p];
            }
            within[q].push((q, pos));
            for c in 0..dim[q] {
                for &p in &earlier[q] {
                    row_idx.extend(offset[p]..offset[p] + dim[p]);
                }
                row_idx.extend(offset[q]..=offset[q] + c);
                diag[offset[q] + c] = row_idx.len() - 1;
                col_ptr.push(row_idx.len());
            }
        }
        let find_within = |q: usize, p: usize| -> usize {
            let list = &within[q];
            match list.binary_search_by_key(&p, |&(b, _)| b) {
                Ok(i) => list[i].1,
                Err(_) => 0,
            }
        };
        let slots = self
            .graph
            .edges()
            .iter()
            .map(|e| {
                let (va, vb) = e.vertices();
                let ba = block_of[va];
                let bb = vb.and_then(|v| block_of[v]);
                let a = ba.map(|q| (q, find_within(q, q)));
                let b = bb.map(|q| (q, find_within(q, q)));
                let cross = match (ba, bb) {
                    (Some(p), Some(q)) if p < q => Some((find_within(q, p), true)),
                    (Some(p), Some(q)) if q < p => Some((find_within(p, q), false)),
                    _ => None,
                };
                EdgeSlots { a, b, cross }
            })
            .collect();
        let cholesky =
            FaerCholesky::analyze(n, &col_ptr, &row_idx).map_err(OptimizeError::Cholesky)?;
        self.structure = Some(Structure {
            block_of,
            vertex_of,
            offset,
            dim,
            n,
            col_ptr,
            row_idx,
            diag,
            slots,
            adjacency: blk_adj,
            cholesky,
        });
        Ok(())
    }

    /// Builds `H` (upper triangle values), `b` and the cost at the current estimate.
    fn linearize(&mut self) -> Result<(), OptimizeError> {
        self.ensure_structure()?;
        if self.linearization.is_some() {
            return Ok(());
        }
        let Some(s) = self.structure.as_ref() else {
            return Err(OptimizeError::NothingToOptimize);
        };
        let mut values = vec![0.0; s.row_idx.len()];
        let mut b = vec![0.0; s.n];
        let mut cost = 0.0;
        let kernel = self.settings.kernel;
        for (e, slot) in self.graph.edges().iter().zip(&s.slots) {
            let lin = linearize_edge(&self.graph, e);
            let sq = lin.e.dot(&(lin.omega * lin.e));
            cost += kernel.cost(sq);
            let w = kernel.weight(sq);
            let w_omega = lin.omega * w;
            let oe = w_omega * lin.e;
            let add_diag =
                |values: &mut [f64], b: &mut [f64], (q, pos): (usize, usize), j: &Block3| {
                    let h = j.transpose() * w_omega * j;
                    let g = j.transpose() * oe;
                    let d = s.dim[q];
                    let o = s.offset[q];
                    for c in 0..d {
                        let base = s.col_ptr[o + c] + pos;
                        for r in 0..=c {
                            values[base + r] += h[(r, c)];
                        }
                        b[o + c] -= g[c];
                    }
                };
            if let Some(a) = slot.a {
                add_diag(&mut values, &mut b, a, &lin.ja);
            }
            if let Some(bb) = slot.b {
                add_diag(&mut values, &mut b, bb, &lin.jb);
            }
            if let (Some((pos, a_is_row)), Some((qa, _)), Some((qb, _))) =
                (slot.cross, slot.a, slot.b)
            {
                // Upper block: rows of the earlier block, columns of the later one.
                let (jr, jc, pr, pc) = if a_is_row {
                    (&lin.ja, &lin.jb, qa, qb)
                } else {
                    (&lin.jb, &lin.ja, qb, qa)
                };
                let h = jr.transpose() * w_omega * jc;
                let o = s.offset[pc];
                for c in 0..s.dim[pc] {
                    let base = s.col_ptr[o + c] + pos;
                    for r in 0..s.dim[pr] {
                        values[base + r] += h[(r, c)];
                    }
                }
            }
        }
        if !cost.is_finite() {
            return Err(OptimizeError::NotFinite(cost));
        }
        self.linearization = Some(Linearization { values, b, cost });
        Ok(())
    }

    /// Maps a failing unknown of the factorization to the vertex and coordinate.
    fn indefinite_at(&self, column: usize) -> OptimizeError {
        let Some(s) = self.structure.as_ref() else {
            return OptimizeError::NothingToOptimize;
        };
        let blk = s.offset.partition_point(|&o| o <= column).saturating_sub(1);
        let v = s.vertex_of.get(blk).copied().unwrap_or(0);
        let k = column.saturating_sub(s.offset.get(blk).copied().unwrap_or(0));
        let vertex = &self.graph.vertices()[v];
        let dof = match (vertex.state, k) {
            (VertexState::Pose(_), 2) => "θ",
            (_, 0) => "x",
            _ => "y",
        };
        OptimizeError::Indefinite {
            vertex: vertex.id,
            dof,
        }
    }

    fn map_cholesky(&self, e: CholeskyError) -> OptimizeError {
        match e {
            CholeskyError::NotPositiveDefinite { column } => self.indefinite_at(column),
            other => OptimizeError::Cholesky(other),
        }
    }

    /// Applies `x ← x ∘ Exp(α Δx)` to the free poses and `l ← l + α Δl` to the points.
    fn apply(&mut self, delta: &[f64], alpha: f64) {
        let Some(s) = self.structure.as_ref() else {
            return;
        };
        let vertices = self.graph.vertices_mut();
        for (blk, &v) in s.vertex_of.iter().enumerate() {
            let o = s.offset[blk];
            match &mut vertices[v].state {
                VertexState::Pose(p) => {
                    let d = Vector3::new(delta[o], delta[o + 1], delta[o + 2]) * alpha;
                    *p = retract(p, &d);
                }
                VertexState::Point(p) => {
                    p[0] += alpha * delta[o];
                    p[1] += alpha * delta[o + 1];
                }
            }
        }
    }

    fn snapshot(&self) -> Vec<VertexState> {
        self.graph.vertices().iter().map(|v| v.state).collect()
    }

    fn restore(&mut self, states: &[VertexState]) {
        for (v, s) in self.graph.vertices_mut().iter_mut().zip(states) {
            v.state = *s;
        }
    }

    /// One solver iteration (see the module documentation). The caller measures time.
    pub fn step(&mut self) -> Result<StepReport, OptimizeError> {
        self.linearize()?;
        let (cost_before, b, values) = match self.linearization.as_ref() {
            Some(l) => (l.cost, l.b.clone(), l.values.clone()),
            None => return Err(OptimizeError::NothingToOptimize),
        };
        self.iteration += 1;
        // Gauss-Newton has converged when the cost stops falling by more than the
        // tolerances; a rise is not convergence (GN may climb from a poor start).
        let tol = |before: f64, after: f64, s: &OptimizerSettings| {
            let decrease = before - after;
            decrease >= 0.0
                && (decrease <= s.absolute_tolerance || decrease <= s.relative_tolerance * before)
        };
        let report = match self.settings.solver {
            SolverKind::GaussNewton => {
                let delta = self.solve(&values, b)?;
                self.apply(&delta, 1.0);
                self.linearization = None;
                self.linearize()?;
                let cost = self.cost();
                StepReport {
                    iteration: self.iteration,
                    cost_before,
                    cost,
                    step_norm: norm(&delta),
                    lambda: None,
                    step_length: None,
                    accepted: true,
                    converged: tol(cost_before, cost, &self.settings),
                }
            }
            SolverKind::LevenbergMarquardt => self.lm_step(cost_before, values, b)?,
            SolverKind::GradientDescent => self.gd_step(cost_before, &values, &b)?,
        };
        self.converged = report.converged;
        Ok(report)
    }

    fn solve(&mut self, values: &[f64], mut rhs: Vec<f64>) -> Result<Vec<f64>, OptimizeError> {
        let Some(s) = self.structure.as_mut() else {
            return Err(OptimizeError::NothingToOptimize);
        };
        let result = s
            .cholesky
            .factorize(values)
            .and_then(|()| s.cholesky.solve_in_place(&mut rhs));
        match result {
            Ok(()) if rhs.iter().all(|v| v.is_finite()) => Ok(rhs),
            Ok(()) => Err(OptimizeError::NotFinite(f64::NAN)),
            Err(e) => Err(self.map_cholesky(e)),
        }
    }

    fn lm_step(
        &mut self,
        cost_before: f64,
        values: Vec<f64>,
        b: Vec<f64>,
    ) -> Result<StepReport, OptimizeError> {
        let lambda = *self.lambda.get_or_insert(self.settings.initial_lambda);
        let Some(s) = self.structure.as_ref() else {
            return Err(OptimizeError::NothingToOptimize);
        };
        let diag_index = s.diag.clone();
        let mut damped = values;
        for &k in &diag_index {
            damped[k] += lambda;
        }
        let rejected = |this: &mut Self, step_norm: f64| {
            this.lambda = Some(lambda * 10.0);
            StepReport {
                iteration: this.iteration,
                cost_before,
                cost: cost_before,
                step_norm,
                lambda: Some(lambda),
                step_length: None,
                accepted: false,
                converged: lambda > 1e16,
            }
        };
        let delta = match self.solve(&damped, b.clone()) {
            Ok(d) => d,
            // Damping too small to make the system positive definite: damp more.
            Err(OptimizeError::Indefinite { .. }) if lambda < 1e16 => {
                return Ok(rejected(self, f64::NAN));
            }
            Err(e) => return Err(e),
        };
        let step_norm = norm(&delta);
        let before = self.snapshot();
        self.apply(&delta, 1.0);
        let cost = graph_cost(&self.graph, &self.settings.kernel);
        if cost.is_finite() && cost < cost_before {
            self.lambda = Some((lambda / 10.0).max(1e-12));
            self.linearization = None;
            let settings = self.settings;
            let decrease = cost_before - cost;
            Ok(StepReport {
                iteration: self.iteration,
                cost_before,
                cost,
                step_norm,
                lambda: Some(lambda),
                step_length: None,
                accepted: true,
                converged: decrease <= settings.absolute_tolerance
                    || decrease <= settings.relative_tolerance * cost_before,
            })
        } else {
            self.restore(&before);
            Ok(rejected(self, step_norm))
        }
    }

    fn gd_step(
        &mut self,
        cost_before: f64,
        values: &[f64],
        b: &[f64],
    ) -> Result<StepReport, OptimizeError> {
        let Some(s) = self.structure.as_ref() else {
            return Err(OptimizeError::NothingToOptimize);
        };
        // Block-Jacobi preconditioned gradient: Δ_v = H_vv⁻¹ b_v per vertex.
        let mut delta = vec![0.0; s.n];
        for blk in 0..s.vertex_of.len() {
            let o = s.offset[blk];
            let d = s.dim[blk];
            let mut h = Block3::identity();
            for c in 0..d {
                let base = s.col_ptr[o + c + 1] - (c + 1);
                for r in 0..=c {
                    h[(r, c)] = values[base + r];
                    h[(c, r)] = values[base + r];
                }
            }
            let mut g = Vector3::zeros();
            for r in 0..d {
                g[r] = b[o + r];
            }
            let x = h.cholesky().map_or_else(
                || {
                    Vector3::from_fn(|r, _| {
                        if r < d && h[(r, r)] > 0.0 {
                            g[r] / h[(r, r)]
                        } else {
                            0.0
                        }
                    })
                },
                |c| c.solve(&g),
            );
            for r in 0..d {
                delta[o + r] = x[r];
            }
        }
        let step_norm = norm(&delta);
        let before = self.snapshot();
        let mut alpha = (self.step_length * 2.0).min(1.0);
        for _ in 0..40 {
            self.apply(&delta, alpha);
            let cost = graph_cost(&self.graph, &self.settings.kernel);
            if cost.is_finite() && cost < cost_before {
                self.step_length = alpha;
                self.linearization = None;
                let decrease = cost_before - cost;
                return Ok(StepReport {
                    iteration: self.iteration,
                    cost_before,
                    cost,
                    step_norm: alpha * step_norm,
                    lambda: None,
                    step_length: Some(alpha),
                    accepted: true,
                    converged: decrease <= self.settings.absolute_tolerance * 1e-3
                        || decrease <= self.settings.relative_tolerance * 1e-3 * cost_before,
                });
            }
            self.restore(&before);
            alpha *= 0.5;
        }
        Ok(StepReport {
            iteration: self.iteration,
            cost_before,
            cost: cost_before,
            step_norm: 0.0,
            lambda: None,
            step_length: Some(alpha),
            accepted: false,
            converged: true,
        })
    }

    /// Runs [`Self::step`] until converged or `max_iterations` steps, calling
    /// `on_step` after each (for progress and timing by the caller).
    pub fn optimize(
        &mut self,
        max_iterations: usize,
        mut on_step: impl FnMut(&StepReport) -> bool,
    ) -> Result<Vec<StepReport>, OptimizeError> {
        let mut reports = Vec::new();
        for _ in 0..max_iterations {
            let r = self.step()?;
            reports.push(r);
            if r.converged || !on_step(&r) {
                break;
            }
        }
        Ok(reports)
    }

    /// Marginal covariances of the given vertices at the current estimate, from
    /// the Cholesky factor of the undamped `H`: the vertex's columns of `H⁻¹`,
    /// a pose's turned from its own frame into the world frame
    /// ([`MarginalCovariance::WorldPose`]).
    pub fn marginal_covariances(
        &mut self,
        ids: &[VertexId],
    ) -> Result<Vec<MarginalCovariance>, OptimizeError> {
        self.linearize()?;
        let values = match self.linearization.as_ref() {
            Some(l) => l.values.clone(),
            None => return Err(OptimizeError::NothingToOptimize),
        };
        let n = self.structure.as_ref().map_or(0, |s| s.n);
        // Factorize once, then solve per unit vector.
        self.solve(&values, vec![0.0; n])?;
        let mut out = Vec::with_capacity(ids.len());
        for &id in ids {
            let v = self
                .graph
                .index_of(id)
                .ok_or(GraphError::UnknownVertex(id))?;
            let Some(s) = self.structure.as_mut() else {
                return Err(OptimizeError::NothingToOptimize);
            };
            let Some(blk) = s.block_of[v] else {
                out.push(MarginalCovariance::Fixed);
                continue;
            };
            let (o, d) = (s.offset[blk], s.dim[blk]);
            let mut cov = Block3::zeros();
            for c in 0..d {
                let mut rhs = vec![0.0; s.n];
                rhs[o + c] = 1.0;
                s.cholesky
                    .solve_in_place(&mut rhs)
                    .map_err(OptimizeError::Cholesky)?;
                for r in 0..d {
                    cov[(r, c)] = rhs[o + r];
                }
            }
            out.push(if d == 3 {
                let theta = match self.graph.vertices()[v].state {
                    VertexState::Pose(p) => p.theta,
                    VertexState::Point(_) => 0.0,
                };
                MarginalCovariance::WorldPose(local_to_world_covariance(&cov, theta))
            } else {
                MarginalCovariance::Point(cov.fixed_view::<2, 2>(0, 0).into_owned())
            });
        }
        Ok(out)
    }

    /// The block pattern of the information matrix `H`, in the order of the free
    /// vertices in the graph (both triangles).
    pub fn information_pattern(&mut self) -> Result<BlockPattern, OptimizeError> {
        self.ensure_structure()?;
        let Some(s) = self.structure.as_ref() else {
            return Err(OptimizeError::NothingToOptimize);
        };
        // Natural order of free vertices.
        let mut natural = vec![usize::MAX; s.vertex_of.len()];
        let mut vertex_ids = Vec::new();
        let mut dims = Vec::new();
        let mut k = 0;
        for (v, blk) in s.block_of.iter().enumerate() {
            if let Some(blk) = blk {
                natural[*blk] = k;
                vertex_ids.push(self.graph.vertices()[v].id);
                dims.push(s.dim[*blk]);
                k += 1;
            }
        }
        let mut entries = Vec::new();
        for (blk, list) in s.adjacency.iter().enumerate() {
            entries.push((natural[blk], natural[blk]));
            for &o in list {
                entries.push((natural[blk], natural[o]));
            }
        }
        entries.sort_unstable();
        entries.dedup();
        let fill_in = vec![false; entries.len()];
        Ok(BlockPattern {
            vertex_ids,
            dims,
            entries,
            fill_in,
        })
    }

    /// The block pattern of the Cholesky factor `L` (lower triangle) in the
    /// elimination order, with the fill-in (blocks that are zero in the reordered
    /// `H`) marked; and the number of scalar non-zeros faer stores for `L`.
    pub fn factor_pattern(&mut self) -> Result<(BlockPattern, usize), OptimizeError> {
        self.ensure_structure()?;
        let Some(s) = self.structure.as_ref() else {
            return Err(OptimizeError::NothingToOptimize);
        };
        let columns = symbolic_factor_pattern(&s.adjacency);
        let mut entries = Vec::new();
        let mut fill_in = Vec::new();
        for (j, rows) in columns.iter().enumerate() {
            entries.push((j, j));
            fill_in.push(false);
            for &i in rows {
                entries.push((i, j));
                fill_in.push(s.adjacency[j].binary_search(&i).is_err());
            }
        }
        let vertex_ids = s
            .vertex_of
            .iter()
            .map(|&v| self.graph.vertices()[v].id)
            .collect();
        Ok((
            BlockPattern {
                vertex_ids,
                dims: s.dim.clone(),
                entries,
                fill_in,
            },
            s.cholesky.factor_nonzeros(),
        ))
    }
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

#[cfg(test)]
pub(crate) mod tests_support {
    use super::*;

    /// `(J_a, J_b, Ω)` of an edge, padded to 3x3.
    pub(crate) fn linearize(graph: &PoseGraph, e: &EdgeKind) -> (Block3, Block3, Block3) {
        let l = linearize_edge(graph, e);
        (l.ja, l.jb, l.omega)
    }
}
