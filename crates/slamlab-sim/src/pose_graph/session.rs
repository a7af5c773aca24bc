//! The pose-graph lesson (`lesson=pose-graph`): its scenario with one parameter
//! table, and the session the app steps one solver iteration at a time.
//!
//! A session holds the graph (a built-in example or a file the student opened),
//! the optimizer, the truth when there is one, the role of every edge (odometry,
//! loop closure, landmark, prior, or a loop closure the student added on purpose
//! wrong), and the cost after every iteration. Edits (a dragged vertex, a wrong
//! loop closure, another solver or kernel) apply to the running optimizer; the
//! kernel comparison optimizes copies of the graph from its start.
//!
//! Before every iteration and every edit the session keeps a checkpoint (the
//! vertex states and the solver's own state, no matrix), so "Step back" goes back
//! one iteration or one edit exactly, within a bounded memory.

use crate::grid;
use crate::io;
use crate::params::{Param, Scenario, choose, count_field, number_field};
use crate::pose_graph::experiment::{PoseGraphExperimentConfig, manhattan_graph, thesis_graph};
use rand::{Rng as _, SeedableRng as _};
use rand_chacha::ChaCha8Rng;
use slamlab_core::Pose2;
use slamlab_core::graph::{
    BlockPattern, EdgeKind, MarginalCovariance, OptimizeError, Optimizer, OptimizerCheckpoint,
    OptimizerSettings, PoseGraph, RobustKernel, SolverKind, StepReport, VertexState,
};
use slamlab_core::math;

/// The built-in graphs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Example {
    /// Thesis 000 Sec. 4.2: EKF-SLAM's path on the circle, with loop closures from pose 0.
    #[default]
    Thesis,
    /// A synthetic Manhattan-world graph (after M3500), generated in code.
    Manhattan,
}

/// The robust kernel by name (its width is a parameter of its own).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum KernelChoice {
    /// Plain least squares.
    #[default]
    None,
    /// Huber.
    Huber,
    /// Cauchy.
    Cauchy,
}

const EXAMPLES: &[&str] = &["thesis", "manhattan"];
const SOLVERS: &[&str] = &["gn", "lm", "gd"];
const KERNELS: &[&str] = &["none", "huber", "cauchy"];

/// The lesson's scenario.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseGraphScenario {
    /// Seed of the simulation, the Manhattan walk and the wrong loop closures.
    pub seed: u64,
    /// The built-in graph.
    pub example: Example,
    /// The solver.
    pub solver: SolverKind,
    /// The robust kernel.
    pub kernel: KernelChoice,
    /// The kernel's width on the Mahalanobis distance `√(eᵀΩe)`.
    pub kernel_width: f64,
    /// Thesis example: loop closures from pose 0.
    pub loop_closures: u64,
    /// Thesis example: multiplies control, measurement and loop-closure noise.
    pub noise_scale: f64,
    /// Manhattan example: poses.
    pub manhattan_poses: u64,
    /// Manhattan example: side of the square of 1 m cells.
    pub manhattan_side: u64,
    /// Most iterations one "Optimize" runs.
    pub max_iterations: u64,
}

impl Default for PoseGraphScenario {
    fn default() -> Self {
        Self {
            seed: 1,
            example: Example::Thesis,
            solver: SolverKind::GaussNewton,
            kernel: KernelChoice::None,
            kernel_width: 1.0,
            loop_closures: 10,
            noise_scale: 1.0,
            manhattan_poses: 400,
            manhattan_side: 8,
            max_iterations: 100,
        }
    }
}

impl PoseGraphScenario {
    /// The robust kernel with its width.
    pub fn robust_kernel(&self) -> RobustKernel {
        kernel_of(self.kernel, self.kernel_width)
    }

    /// The solver settings.
    pub fn settings(&self) -> OptimizerSettings {
        OptimizerSettings {
            solver: self.solver,
            kernel: self.robust_kernel(),
            ..OptimizerSettings::default()
        }
    }
}

/// Every vertex's position, `[x, y]`, in the graph's order.
fn positions(graph: &PoseGraph) -> Vec<[f64; 2]> {
    graph
        .vertices()
        .iter()
        .map(|v| {
            let p = v.state.position();
            [p[0], p[1]]
        })
        .collect()
}

fn kernel_of(choice: KernelChoice, width: f64) -> RobustKernel {
    match choice {
        KernelChoice::None => RobustKernel::None,
        KernelChoice::Huber => RobustKernel::Huber { delta: width },
        KernelChoice::Cauchy => RobustKernel::Cauchy { c: width },
    }
}

/// The kernel's name as the table writes it.
pub fn kernel_name(choice: KernelChoice) -> &'static str {
    KERNELS[choice as usize]
}

/// Every parameter of the lesson, in the order `slamlab params --lesson pose-graph` lists them.
pub static PARAMS: &[Param<PoseGraphScenario>] = &[
    count_field!(
        "seed",
        "seed of the simulation, the Manhattan walk and the wrong loop closures",
        (0, u64::MAX),
        seed
    ),
    Param::words(
        "example",
        "built-in graph: thesis (EKF-SLAM path on the circle, §4.2 of Xiang's thesis) or manhattan (a synthetic grid walk); or open a .g2o/TORO file",
        EXAMPLES,
        |s| Some(EXAMPLES[s.example as usize].to_owned()),
        |s, v| choose(EXAMPLES, v).map(|i| s.example = [Example::Thesis, Example::Manhattan][i]),
    ),
    Param::words(
        "solver",
        "gn: Gauss-Newton; lm: Levenberg-Marquardt; gd: block-Jacobi preconditioned gradient descent",
        SOLVERS,
        |s| Some(s.solver.short_name().to_owned()),
        |s, v| {
            choose(SOLVERS, v).map(|i| {
                s.solver = SolverKind::from_short_name(SOLVERS[i]).unwrap_or_default();
            })
        },
    ),
    Param::words(
        "kernel",
        "robust kernel on every edge's Mahalanobis distance",
        KERNELS,
        |s| Some(kernel_name(s.kernel).to_owned()),
        |s, v| {
            choose(KERNELS, v).map(|i| {
                s.kernel = [
                    KernelChoice::None,
                    KernelChoice::Huber,
                    KernelChoice::Cauchy,
                ][i];
            })
        },
    ),
    number_field!(
        "kernel-width",
        "",
        "Huber's δ or Cauchy's c on the Mahalanobis distance √(e^T Ω e)",
        (0.01, 100.0),
        kernel_width
    ),
    count_field!(
        "loop-closures",
        "thesis example: loop closures from pose 0 to random poses",
        (0, 100),
        loop_closures
    ),
    number_field!(
        "noise-scale",
        "",
        "thesis example: multiplies control, measurement and loop-closure noise (2 is Experiment 2 of Xiang's thesis, §4.2)",
        (0.1, 10.0),
        noise_scale
    ),
    count_field!(
        "manhattan-poses",
        "manhattan example: poses of the walk",
        (10, 5000),
        manhattan_poses
    ),
    count_field!(
        "manhattan-side",
        "manhattan example: side of the square of 1 m cells",
        (2, 100),
        manhattan_side
    ),
    count_field!(
        "max-iterations",
        "most iterations one Optimize runs",
        (1, 10_000),
        max_iterations
    ),
];

impl Scenario for PoseGraphScenario {
    const LESSON: &'static str = "pose-graph";
    fn params() -> &'static [Param<Self>] {
        PARAMS
    }
    fn seed(&self) -> u64 {
        self.seed
    }
}

/// What an edge is, for drawing and counting.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EdgeRole {
    /// Between consecutive poses.
    Odometry,
    /// Between poses further apart.
    LoopClosure,
    /// A loop closure the student added on purpose wrong.
    WrongLoopClosure,
    /// Pose to landmark.
    Landmark,
    /// A prior.
    Prior,
}

fn role_of(edge: &EdgeKind) -> EdgeRole {
    match *edge {
        EdgeKind::PosePose { from, to, .. } if from.abs_diff(to) == 1 => EdgeRole::Odometry,
        EdgeKind::PosePose { .. } => EdgeRole::LoopClosure,
        EdgeKind::PosePoint { .. } | EdgeKind::RangeBearing { .. } => EdgeRole::Landmark,
        EdgeKind::PosePrior { .. } | EdgeKind::PointPrior { .. } => EdgeRole::Prior,
    }
}

/// The solver's short label in phase names ("GN iteration 3").
pub fn solver_label(solver: SolverKind) -> &'static str {
    match solver {
        SolverKind::GaussNewton => "GN",
        SolverKind::LevenbergMarquardt => "LM",
        SolverKind::GradientDescent => "first-order",
    }
}

/// The block pattern of the information matrix `H = Σ JᵀΩJ` over every vertex,
/// the fixed ones included, in the graph's order (both triangles): every diagonal
/// block, and the pair of blocks `(a, b)`, `(b, a)` of every edge joining two
/// vertices. A fixed vertex is no unknown (the solver drops its row and column),
/// but drawing them shows the loop closures to it: on the thesis example all ten
/// close at pose 0, the fixed one.
pub fn information_pattern_of_every_vertex(graph: &PoseGraph) -> BlockPattern {
    let vertices = graph.vertices();
    let mut entries: Vec<(usize, usize)> = (0..vertices.len()).map(|k| (k, k)).collect();
    for edge in graph.edges() {
        if let (a, Some(b)) = edge.vertices()
            && a != b
        {
            entries.push((a, b));
            entries.push((b, a));
        }
    }
    entries.sort_unstable();
    entries.dedup();
    BlockPattern {
        vertex_ids: vertices.iter().map(|v| v.id).collect(),
        dims: vertices.iter().map(|v| v.state.dim()).collect(),
        fill_in: vec![false; entries.len()],
        entries,
    }
}

/// The largest file the lesson opens, bytes (the readers' own limit).
pub const MAX_FILE_BYTES: usize = io::graph::MAX_FILE_BYTES;

/// One solver's result in the kernel comparison.
#[derive(Clone, Debug, PartialEq)]
pub struct KernelRun {
    /// `none`, `huber` or `cauchy`.
    pub kernel: &'static str,
    /// Iterations to convergence (or the limit).
    pub iterations: usize,
    /// Final cost `Σ ρ(eᵀΩe)` under this kernel.
    pub cost: f64,
    /// Position RMSE against the truth, metres (when there is a truth).
    pub rmse: Option<f64>,
    /// The optimized positions, by vertex index.
    pub positions: Vec<[f64; 2]>,
    /// Why it stopped early, if it failed.
    pub error: Option<String>,
}

/// Checkpoints kept for "Step back" at most.
pub const MAX_CHECKPOINTS: usize = 1000;

/// Memory the checkpoints may hold, bytes: on M3500 (3500 poses, about 110 kB a
/// checkpoint) the last few hundred iterations.
pub const MAX_CHECKPOINT_BYTES: usize = 64 << 20;

/// The session just before an iteration or an edit.
#[derive(Clone, Debug)]
struct SessionCheckpoint {
    optimizer: OptimizerCheckpoint,
    scenario: PoseGraphScenario,
    start_edges: usize,
    roles: usize,
    history: usize,
    last_report: Option<StepReport>,
    notes: usize,
    wrong_closures: u64,
    /// What going back to this checkpoint undoes ("GN iteration 3", "a drag").
    undoes: String,
}

impl SessionCheckpoint {
    fn bytes(&self) -> usize {
        self.optimizer.bytes() + std::mem::size_of::<Self>() + self.undoes.len()
    }
}

/// The lesson's run: a graph, its optimizer and what happened to it.
#[derive(Debug)]
pub struct PoseGraphSession {
    scenario: PoseGraphScenario,
    source: String,
    optimizer: Optimizer,
    /// The graph as it started (with the student's added edges), for comparisons.
    start: PoseGraph,
    truth: Option<Vec<Pose2>>,
    roles: Vec<EdgeRole>,
    /// `[iteration count, cost]`: the start, then after every iteration and edit.
    history: Vec<[f64; 2]>,
    last_report: Option<StepReport>,
    notes: Vec<String>,
    wrong_closures: u64,
    /// Checkpoints, oldest first, for "Step back".
    checkpoints: std::collections::VecDeque<SessionCheckpoint>,
    checkpoint_bytes: usize,
    /// A drag is under way (its first move took the checkpoint).
    dragging: bool,
}

pub use crate::metrics::graph::fix_gauge;

impl PoseGraphSession {
    /// The built-in example of `scenario`.
    pub fn from_scenario(scenario: PoseGraphScenario) -> Result<Self, String> {
        let (graph, truth, source) = match scenario.example {
            Example::Thesis => {
                let built = thesis_graph(&PoseGraphExperimentConfig {
                    loop_closures: scenario.loop_closures as usize,
                    noise_scale: scenario.noise_scale,
                    seed: scenario.seed,
                    ..PoseGraphExperimentConfig::default()
                })
                .map_err(|e| e.to_string())?;
                let [truth, _, _] = built.paths;
                (built.graph, Some(truth), "thesis".to_owned())
            }
            Example::Manhattan => {
                let (graph, truth) = manhattan_graph(
                    scenario.manhattan_poses as usize,
                    scenario.manhattan_side as i64,
                    scenario.seed,
                );
                (graph, Some(truth), "manhattan".to_owned())
            }
        };
        Self::new(scenario, graph, truth, source, Vec::new())
    }

    /// A graph from a file's bytes: g2o, TORO or iSAM text (detected from the
    /// content). Any problem is a message that names it (and its line).
    pub fn from_file(
        scenario: PoseGraphScenario,
        name: &str,
        bytes: &[u8],
    ) -> Result<Self, String> {
        if bytes.len() > MAX_FILE_BYTES {
            return Err(format!(
                "{name} has {} bytes, more than the {MAX_FILE_BYTES} bytes SLAM Lab reads",
                bytes.len()
            ));
        }
        let text = std::str::from_utf8(bytes).map_err(|e| {
            format!(
                "{name} is not a text file (byte {} is not UTF-8)",
                e.valid_up_to()
            )
        })?;
        let mut graph = io::graph::read_graph(text).map_err(|e| format!("{name}: {e}"))?;
        let notes = fix_gauge(&mut graph).into_iter().collect();
        Self::new(scenario, graph, None, name.to_owned(), notes).map_err(|e| format!("{name}: {e}"))
    }

    fn new(
        scenario: PoseGraphScenario,
        graph: PoseGraph,
        truth: Option<Vec<Pose2>>,
        source: String,
        notes: Vec<String>,
    ) -> Result<Self, String> {
        let mut settings = scenario.settings();
        if !settings.kernel.is_valid() {
            settings.kernel = RobustKernel::None;
        }
        let roles = graph.edges().iter().map(role_of).collect();
        let start = graph.clone();
        let optimizer = Optimizer::new(graph, settings).map_err(|e| e.to_string())?;
        let cost = optimizer.cost();
        if !cost.is_finite() {
            return Err(format!("the starting cost is not a finite number ({cost})"));
        }
        Ok(Self {
            scenario,
            source,
            optimizer,
            start,
            truth,
            roles,
            history: vec![[0.0, cost]],
            last_report: None,
            notes,
            wrong_closures: 0,
            checkpoints: std::collections::VecDeque::new(),
            checkpoint_bytes: 0,
            dragging: false,
        })
    }

    /// The scenario.
    pub fn scenario(&self) -> &PoseGraphScenario {
        &self.scenario
    }

    /// `thesis`, `manhattan` or the file's name.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// The graph at the current estimate.
    pub fn graph(&self) -> &PoseGraph {
        self.optimizer.graph()
    }

    /// The graph as it started (with added edges).
    pub fn start_graph(&self) -> &PoseGraph {
        &self.start
    }

    /// The optimizer.
    pub fn optimizer(&self) -> &Optimizer {
        &self.optimizer
    }

    /// The true poses by vertex index, for the built-in examples.
    pub fn truth(&self) -> Option<&[Pose2]> {
        self.truth.as_deref()
    }

    /// Each edge's role, by edge index.
    pub fn roles(&self) -> &[EdgeRole] {
        &self.roles
    }

    /// `[iteration count, cost]` from the start, after every iteration and edit.
    pub fn history(&self) -> &[[f64; 2]] {
        &self.history
    }

    /// What the latest iteration did.
    pub fn last_report(&self) -> Option<&StepReport> {
        self.last_report.as_ref()
    }

    /// What the session had to do or was told (gauge, edits).
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// Iterations run since the start.
    pub fn iterations(&self) -> usize {
        self.optimizer.iterations()
    }

    /// The cost now.
    pub fn cost(&self) -> f64 {
        self.optimizer.cost()
    }

    /// Has the solver converged since the last edit?
    pub fn is_converged(&self) -> bool {
        self.optimizer.is_converged()
    }

    fn checkpoint(&self, undoes: String) -> SessionCheckpoint {
        SessionCheckpoint {
            optimizer: self.optimizer.checkpoint(),
            scenario: self.scenario.clone(),
            start_edges: self.start.edges().len(),
            roles: self.roles.len(),
            history: self.history.len(),
            last_report: self.last_report,
            notes: self.notes.len(),
            wrong_closures: self.wrong_closures,
            undoes,
        }
    }

    fn keep(&mut self, checkpoint: SessionCheckpoint) {
        self.checkpoint_bytes += checkpoint.bytes();
        self.checkpoints.push_back(checkpoint);
        while self.checkpoints.len() > MAX_CHECKPOINTS
            || (self.checkpoint_bytes > MAX_CHECKPOINT_BYTES && self.checkpoints.len() > 1)
        {
            match self.checkpoints.pop_front() {
                Some(old) => {
                    self.checkpoint_bytes = self.checkpoint_bytes.saturating_sub(old.bytes())
                }
                None => break,
            }
        }
    }

    /// Can "Step back" go back (an iteration or an edit is kept to undo)?
    pub fn can_step_back(&self) -> bool {
        !self.checkpoints.is_empty()
    }

    /// What "Step back" undoes next ("GN iteration 3", "wrong loop closure"), if anything.
    pub fn step_back_undoes(&self) -> Option<&str> {
        self.checkpoints.back().map(|c| c.undoes.as_str())
    }

    /// How many steps back are kept.
    pub fn steps_back_kept(&self) -> usize {
        self.checkpoints.len()
    }

    /// Goes back one iteration or one edit: the graph, the solver's state, the cost
    /// history, the notes and the scenario's solver and kernel are as they were
    /// before it, bit for bit. Returns what was undone.
    pub fn step_back(&mut self) -> Result<String, String> {
        let checkpoint = self
            .checkpoints
            .pop_back()
            .ok_or("there is no earlier iteration kept to go back to")?;
        self.checkpoint_bytes = self.checkpoint_bytes.saturating_sub(checkpoint.bytes());
        if let Err(why) = self.optimizer.restore_checkpoint(&checkpoint.optimizer) {
            return Err(format!("could not go back: {why}"));
        }
        while self.start.edges().len() > checkpoint.start_edges {
            self.start.pop_edge();
        }
        self.scenario = checkpoint.scenario;
        self.roles.truncate(checkpoint.roles);
        self.history.truncate(checkpoint.history);
        self.last_report = checkpoint.last_report;
        self.notes.truncate(checkpoint.notes);
        self.wrong_closures = checkpoint.wrong_closures;
        self.dragging = false;
        Ok(checkpoint.undoes)
    }

    /// One solver iteration.
    pub fn step(&mut self) -> Result<StepReport, String> {
        let checkpoint = self.checkpoint(format!(
            "{} iteration {}",
            solver_label(self.scenario.solver),
            self.optimizer.iterations() + 1
        ));
        // Kept even when the iteration fails, so that going back undoes what it left.
        let result = self.optimizer.step();
        self.keep(checkpoint);
        self.dragging = false;
        let report = result.map_err(|e| e.to_string())?;
        self.last_report = Some(report);
        self.history
            .push([self.optimizer.iterations() as f64, report.cost]);
        Ok(report)
    }

    fn mark_edit(&mut self, note: String) {
        self.dragging = false;
        self.last_report = None;
        self.history
            .push([self.optimizer.iterations() as f64, self.optimizer.cost()]);
        self.notes.push(note);
    }

    /// Switches the solver (live; the estimate stays).
    pub fn set_solver(&mut self, solver: SolverKind) {
        if self.scenario.solver != solver {
            let checkpoint = self.checkpoint("the solver switch".to_owned());
            self.keep(checkpoint);
            self.scenario.solver = solver;
            self.optimizer.set_solver(solver);
            self.mark_edit(format!("solver switched to {}", solver.short_name()));
        }
    }

    /// Switches the robust kernel (live). An unusable width is refused.
    pub fn set_kernel(&mut self, choice: KernelChoice, width: f64) -> Result<(), String> {
        let kernel = kernel_of(choice, width);
        if !kernel.is_valid() {
            return Err(format!(
                "kernel width {width} is not a positive number; the kernel stays {}",
                kernel_name(self.scenario.kernel)
            ));
        }
        if self.scenario.kernel != choice || self.scenario.kernel_width != width {
            let checkpoint = self.checkpoint("the kernel switch".to_owned());
            self.keep(checkpoint);
            self.scenario.kernel = choice;
            self.scenario.kernel_width = width;
            self.optimizer.set_kernel(kernel);
            self.mark_edit(format!(
                "kernel switched to {}{}",
                kernel_name(choice),
                if choice == KernelChoice::None {
                    String::new()
                } else {
                    format!(" (width {width})")
                }
            ));
        }
        Ok(())
    }

    /// Moves vertex `index` to `(x, y)` (a drag), keeping a pose's heading.
    pub fn move_vertex(&mut self, index: usize, x: f64, y: f64) -> Result<(), String> {
        let vertex = *self
            .graph()
            .vertices()
            .get(index)
            .ok_or_else(|| format!("there is no vertex number {index}"))?;
        if vertex.fixed {
            return Err(format!(
                "vertex {} is fixed (it holds the gauge); drag another",
                vertex.id
            ));
        }
        let state = match vertex.state {
            VertexState::Pose(p) => VertexState::Pose(Pose2::new(x, y, p.theta)),
            VertexState::Point(_) => VertexState::Point(nalgebra::Vector2::new(x, y)),
        };
        let checkpoint =
            (!self.dragging).then(|| self.checkpoint(format!("the drag of vertex {}", vertex.id)));
        self.optimizer
            .move_vertex(vertex.id, state)
            .map_err(|e| e.to_string())?;
        if let Some(checkpoint) = checkpoint {
            self.keep(checkpoint);
            self.dragging = true;
        }
        self.last_report = None;
        Ok(())
    }

    /// Records the end of a drag in the history and the notes.
    pub fn finish_drag(&mut self, index: usize) {
        self.dragging = false;
        let id = self.graph().vertices().get(index).map_or(0, |v| v.id);
        self.mark_edit(format!("vertex {id} dragged"));
    }

    /// Adds a loop closure that is wrong on purpose: it claims two poses far apart
    /// (at least a quarter of the graph's extent, chosen with the seed) are at the
    /// same place, with the information of the graph's loop closures. Returns a
    /// description.
    pub fn add_wrong_loop_closure(&mut self) -> Result<String, String> {
        let graph = self.graph();
        let poses: Vec<(usize, Pose2)> = graph
            .vertices()
            .iter()
            .enumerate()
            .filter_map(|(i, v)| match v.state {
                VertexState::Pose(p) => Some((i, p)),
                VertexState::Point(_) => None,
            })
            .collect();
        if poses.len() < 3 {
            return Err("the graph has fewer than three poses to connect wrongly".to_owned());
        }
        let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for (_, p) in &poses {
            x0 = x0.min(p.x);
            y0 = y0.min(p.y);
            x1 = x1.max(p.x);
            y1 = y1.max(p.y);
        }
        let extent = math::hypot(x1 - x0, y1 - y0);
        let mut rng = ChaCha8Rng::seed_from_u64(
            self.scenario.seed ^ 0x5bd1_e995_u64.wrapping_mul(self.wrong_closures + 1),
        );
        let mut pick = None;
        for _ in 0..1000 {
            let a = poses[rng.random_range(0..poses.len())];
            let b = poses[rng.random_range(0..poses.len())];
            if a.0.abs_diff(b.0) > 1 && math::hypot(a.1.x - b.1.x, a.1.y - b.1.y) >= 0.25 * extent {
                pick = Some(if a.0 < b.0 { (a, b) } else { (b, a) });
                break;
            }
        }
        let ((i, pi), (j, pj)) =
            pick.ok_or("no two poses lie far enough apart for a wrong loop closure")?;
        let information = self
            .graph()
            .edges()
            .iter()
            .zip(&self.roles)
            .filter_map(|(e, r)| match (e, r) {
                (EdgeKind::PosePose { information, .. }, EdgeRole::LoopClosure) => {
                    Some(*information)
                }
                _ => None,
            })
            .next()
            .or_else(|| {
                self.graph().edges().iter().find_map(|e| match e {
                    EdgeKind::PosePose { information, .. } => Some(*information),
                    _ => None,
                })
            })
            .unwrap_or_else(nalgebra::Matrix3::identity);
        let edge = EdgeKind::PosePose {
            from: i,
            to: j,
            measurement: Pose2::IDENTITY,
            information,
        };
        let checkpoint = self.checkpoint("the wrong loop closure".to_owned());
        self.optimizer.add_edge(edge).map_err(|e| e.to_string())?;
        if let Err(why) = self.start.add_edge(edge) {
            self.optimizer.pop_edge();
            return Err(why.to_string());
        }
        self.keep(checkpoint);
        self.roles.push(EdgeRole::WrongLoopClosure);
        self.wrong_closures += 1;
        let (a, b) = (self.graph().vertices()[i].id, self.graph().vertices()[j].id);
        let text = format!(
            "wrong loop closure: poses {a} and {b}, {:.1} m apart, are claimed to be at the same place",
            math::hypot(pi.x - pj.x, pi.y - pj.y)
        );
        self.mark_edit(text.clone());
        Ok(text)
    }

    /// The wrong loop closures added so far.
    pub fn wrong_closures(&self) -> u64 {
        self.wrong_closures
    }

    /// Position RMSE of the current estimate against the truth, metres.
    pub fn rmse(&self) -> Option<f64> {
        self.rmse_of(&positions(self.graph()))
    }

    fn rmse_of(&self, positions: &[[f64; 2]]) -> Option<f64> {
        let poses: Vec<Pose2> = positions
            .iter()
            .map(|p| Pose2::new(p[0], p[1], 0.0))
            .collect();
        grid::trajectory_rmse(&poses, self.truth.as_deref())
    }

    /// Optimizes copies of the graph from its start (with every added edge) to
    /// convergence without a kernel and with the chosen kernel (Huber at the
    /// kernel width when none is chosen), with the current solver.
    pub fn compare_kernels(&self) -> [KernelRun; 2] {
        let with = match self.scenario.kernel {
            KernelChoice::None => KernelChoice::Huber,
            k => k,
        };
        [KernelChoice::None, with].map(|choice| {
            let kernel = kernel_of(choice, self.scenario.kernel_width);
            let settings = OptimizerSettings {
                kernel,
                ..self.scenario.settings()
            };
            let mut run = KernelRun {
                kernel: kernel_name(choice),
                iterations: 0,
                cost: f64::NAN,
                rmse: None,
                positions: Vec::new(),
                error: None,
            };
            let result = Optimizer::new(self.start.clone(), settings).and_then(|mut opt| {
                let reports = opt.optimize(self.scenario.max_iterations as usize, |_| true)?;
                Ok((reports.len(), opt))
            });
            match result {
                Ok((iterations, opt)) => {
                    run.iterations = iterations;
                    run.cost = opt.cost();
                    run.positions = positions(opt.graph());
                    run.rmse = self.rmse_of(&run.positions);
                }
                Err(e) => run.error = Some(e.to_string()),
            }
            run
        })
    }

    /// The sparsity patterns of `H` over every vertex in the graph's order (see
    /// [`information_pattern_of_every_vertex`]) and of the Cholesky factor `L` of
    /// the unknowns (elimination order, fill-in marked), and the non-zeros faer
    /// stores for `L`.
    pub fn patterns(&mut self) -> Result<(BlockPattern, BlockPattern, usize), String> {
        let (l, nnz) = self.optimizer.factor_pattern().map_err(|e| e.to_string())?;
        Ok((information_pattern_of_every_vertex(self.graph()), l, nnz))
    }

    /// Marginal position covariances of at most `max` vertices, evenly spaced
    /// (every vertex when the graph is small): `(vertex index, 2x2 covariance)`.
    pub fn marginals(
        &mut self,
        max: usize,
    ) -> Result<Vec<(usize, nalgebra::Matrix2<f64>)>, OptimizeError> {
        let n = self.graph().vertices().len();
        let stride = n.div_ceil(max.max(1)).max(1);
        let picked: Vec<usize> = (0..n)
            .step_by(stride)
            .filter(|&i| !self.graph().vertices()[i].fixed)
            .collect();
        let ids: Vec<u64> = picked
            .iter()
            .map(|&i| self.graph().vertices()[i].id)
            .collect();
        let covs = self.optimizer.marginal_covariances(&ids)?;
        Ok(picked
            .into_iter()
            .zip(covs)
            .filter_map(|(i, c)| match c {
                MarginalCovariance::WorldPose(m) => {
                    Some((i, m.fixed_view::<2, 2>(0, 0).into_owned()))
                }
                MarginalCovariance::Point(m) => Some((i, m)),
                MarginalCovariance::Fixed => None,
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params;

    #[test]
    fn the_table_round_trips_and_bad_values_get_messages() {
        let mut s = PoseGraphScenario::default();
        let pairs = [
            ("example", "manhattan"),
            ("solver", "lm"),
            ("kernel", "cauchy"),
            ("kernel-width", "2.5"),
            ("manhattan-poses", "120"),
            ("seed", "9"),
        ];
        assert!(params::apply_pairs(&mut s, pairs.iter().copied(), &[]).is_empty());
        assert_eq!(s.example, Example::Manhattan);
        assert_eq!(s.solver, SolverKind::LevenbergMarquardt);
        assert_eq!(s.robust_kernel(), RobustKernel::Cauchy { c: 2.5 });
        let written = params::to_pairs(&s);
        let mut back = PoseGraphScenario::default();
        let issues = params::apply_pairs(
            &mut back,
            written.iter().map(|(k, v)| (*k, v.as_str())),
            &[],
        );
        assert!(issues.is_empty(), "{issues:?}");
        assert_eq!(back, s);
        let mut s = PoseGraphScenario::default();
        let issues = params::apply_pairs(
            &mut s,
            [
                ("solver", "newton"),
                ("kernel-width", "0"),
                ("loop-closures", "NaN"),
            ],
            &[],
        );
        assert_eq!(issues.len(), 3, "{issues:?}");
        assert!(
            issues[0].to_string().contains("gn, lm, gd"),
            "{}",
            issues[0]
        );
        assert_eq!(s.kernel_width, 0.01);
        assert_eq!(s.solver, SolverKind::GaussNewton);
    }

    /// The lesson on `example`, the Manhattan graph cut to its first 200 poses.
    fn small_session(example: Example) -> PoseGraphSession {
        PoseGraphSession::from_scenario(PoseGraphScenario {
            example,
            manhattan_poses: 200,
            ..PoseGraphScenario::default()
        })
        .unwrap()
    }

    #[test]
    fn the_lessons_optimized_graph_written_and_read_back_scores_its_own_final_cost() {
        use crate::metrics::graph::{reference_solution, score_graph};
        for example in [Example::Thesis, Example::Manhattan] {
            let mut session = small_session(example);
            let problem = session.start_graph().clone();
            let initial = session.cost();
            while !session.is_converged() && session.iterations() < 50 {
                session.step().unwrap();
            }
            let text = io::graph::write_g2o(session.graph()).unwrap();
            let file = io::graph::read_graph(&text).unwrap();
            let score = score_graph(&problem, &file, session.cost()).unwrap();
            let cost = session.cost();
            assert!(
                (score.cost - cost).abs() <= 1e-9 * cost,
                "{example:?}: {score:?}"
            );
            assert!((score.cost_ratio.unwrap() - 1.0).abs() <= 1e-9);
            assert_eq!(score.initial_cost, initial);
            // The metric's reference solver is the lesson's solver.
            let reference =
                reference_solution(&problem, session.scenario().settings(), 50).unwrap();
            assert_eq!(reference.cost, cost, "{example:?}");
        }
    }

    #[test]
    fn one_gauss_newton_iteration_lowers_the_cost_of_both_examples() {
        for example in [Example::Thesis, Example::Manhattan] {
            let mut session = small_session(example);
            let before = session.cost();
            let report = session.step().unwrap();
            assert!(
                report.cost < 0.5 * before,
                "{example:?}: {before} -> {}",
                report.cost
            );
            assert_eq!(session.history().len(), 2);
            assert!(session.rmse().unwrap().is_finite());
        }
    }

    #[test]
    fn the_thesis_example_is_the_experiments_graph() {
        let session = PoseGraphSession::from_scenario(PoseGraphScenario::default()).unwrap();
        let result =
            crate::pose_graph::experiment::run(PoseGraphExperimentConfig::default()).unwrap();
        assert_eq!(session.graph().vertices().len(), result.poses);
        assert_eq!(session.graph().edges().len(), result.edges);
        assert_eq!(session.cost(), result.initial_cost);
        let closures = session
            .roles()
            .iter()
            .filter(|r| **r == EdgeRole::LoopClosure)
            .count();
        assert_eq!(closures, result.loop_closure_nodes.len());
    }

    #[test]
    fn a_wrong_loop_closure_hurts_least_squares_and_a_robust_kernel_ignores_it() {
        let mut session = PoseGraphSession::from_scenario(PoseGraphScenario {
            example: Example::Manhattan,
            manhattan_poses: 300,
            kernel: KernelChoice::Huber,
            ..PoseGraphScenario::default()
        })
        .unwrap();
        let [clean, _] = session.compare_kernels();
        let text = session.add_wrong_loop_closure().unwrap();
        assert!(text.contains("same place"), "{text}");
        assert_eq!(session.roles().last(), Some(&EdgeRole::WrongLoopClosure));
        let [plain, robust] = session.compare_kernels();
        assert_eq!((plain.kernel, robust.kernel), ("none", "huber"));
        let (c, p, r) = (
            clean.rmse.unwrap(),
            plain.rmse.unwrap(),
            robust.rmse.unwrap(),
        );
        assert!(p > 3.0 * c, "clean {c}, without kernel {p}, huber {r}");
        assert!(r < 2.0 * c, "clean {c}, with Huber {r}");
    }

    #[test]
    fn bad_files_are_refused_with_a_message_naming_the_problem() {
        let s = PoseGraphScenario::default;
        let cases: &[(&str, &str)] = &[
            (
                "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 7 1 0 0 1 0 0 1 0 1\n",
                "vertex 7",
            ),
            ("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 0 1 0 0\n", "defined twice"),
            (
                "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 1 0 0 -1 0 0 1 0 1\n",
                "positive semi-definite",
            ),
            (
                "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 1 0 0 0 0 0 0 0 0\n",
                "zero",
            ),
            (
                "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 NaN 0 0 1 0 0 1 0 1\n",
                "line 3",
            ),
            ("VERTEX_SE2 0 0 0 0\n", "1 vertex"),
            ("hello world\n", "not a pose-graph file"),
        ];
        for (text, needle) in cases {
            let err = PoseGraphSession::from_file(s(), "bad.g2o", text.as_bytes()).unwrap_err();
            assert!(err.contains(needle), "{needle}: {err}");
            assert!(err.starts_with("bad.g2o"), "{err}");
        }
        let big = vec![b'#'; 50 * 1024 * 1024];
        let err = PoseGraphSession::from_file(s(), "big.g2o", &big).unwrap_err();
        assert!(err.contains("52428800 bytes"), "{err}");
        let err = PoseGraphSession::from_file(s(), "x.g2o", &[0xff, 0xfe, 0]).unwrap_err();
        assert!(err.contains("not a text file"), "{err}");
        // A good file: the first vertex holds the gauge.
        let ok = PoseGraphSession::from_file(
            s(),
            "ok.g2o",
            b"VERTEX_SE2 4 0 0 0\nVERTEX_SE2 5 1.2 0 0\nEDGE_SE2 4 5 1 0 0 1 0 0 1 0 1\n",
        )
        .unwrap();
        assert!(ok.notes()[0].contains("vertex 4"), "{:?}", ok.notes());
        assert!(ok.graph().vertex(4).unwrap().fixed);
    }

    #[test]
    fn drags_solver_and_kernel_switches_are_edits_in_the_history() {
        let mut session = PoseGraphSession::from_scenario(PoseGraphScenario::default()).unwrap();
        session.step().unwrap();
        let cost = session.cost();
        assert!(
            session
                .move_vertex(0, 5.0, 5.0)
                .unwrap_err()
                .contains("fixed")
        );
        session.move_vertex(50, 30.0, 30.0).unwrap();
        session.finish_drag(50);
        assert!(session.cost() > 10.0 * cost);
        session.set_solver(SolverKind::LevenbergMarquardt);
        assert!(session.set_kernel(KernelChoice::Huber, -1.0).is_err());
        session.set_kernel(KernelChoice::Huber, 1.0).unwrap();
        assert_eq!(session.history().len(), 5);
        assert!(session.last_report().is_none());
        for _ in 0..30 {
            if session.step().unwrap().converged {
                break;
            }
        }
        assert!(session.is_converged());
        let (h, l, nnz) = session.patterns().unwrap();
        assert_eq!(h.vertex_ids.len(), 201, "every vertex, the fixed one too");
        assert!(nnz >= l.entries.len() && l.entries.len() >= h.vertex_ids.len());
        let marginals = session.marginals(50).unwrap();
        assert!(marginals.len() >= 40);
        assert!(
            marginals
                .iter()
                .all(|(_, c)| c[(0, 0)] > 0.0 && c[(1, 1)] > 0.0)
        );
    }

    /// Vertex states, edge count, roles, cost history, report and notes, and cost.
    type DrawnBits = (Vec<u64>, usize, Vec<EdgeRole>, Vec<[u64; 2]>, String, u64);

    /// Everything the lesson draws from a session, as bits: vertex states, edges,
    /// roles, the cost history, the last report, the cost and the notes.
    fn drawn_bits(s: &PoseGraphSession) -> DrawnBits {
        let states = s
            .graph()
            .vertices()
            .iter()
            .flat_map(|v| match v.state {
                VertexState::Pose(p) => vec![p.x.to_bits(), p.y.to_bits(), p.theta.to_bits()],
                VertexState::Point(q) => vec![q[0].to_bits(), q[1].to_bits()],
            })
            .collect();
        let history = s
            .history()
            .iter()
            .map(|h| [h[0].to_bits(), h[1].to_bits()])
            .collect();
        (
            states,
            s.graph().edges().len(),
            s.roles().to_vec(),
            history,
            format!("{:?} {:?} {:?}", s.last_report(), s.notes(), s.scenario()),
            s.cost().to_bits(),
        )
    }

    #[test]
    fn step_back_restores_every_iteration_and_edit_bit_for_bit() {
        for solver in [SolverKind::GaussNewton, SolverKind::LevenbergMarquardt] {
            let scenario = PoseGraphScenario {
                solver,
                ..PoseGraphScenario::default()
            };
            let mut s = PoseGraphSession::from_scenario(scenario).unwrap();
            assert!(!s.can_step_back());
            assert!(s.step_back().is_err(), "nothing to go back to");
            let mut seen = vec![drawn_bits(&s)];
            s.step().unwrap();
            seen.push(drawn_bits(&s));
            s.step().unwrap();
            seen.push(drawn_bits(&s));
            s.add_wrong_loop_closure().unwrap();
            seen.push(drawn_bits(&s));
            s.set_kernel(KernelChoice::Cauchy, 1.0).unwrap();
            seen.push(drawn_bits(&s));
            s.move_vertex(40, 3.0, 4.0).unwrap();
            s.move_vertex(40, 5.0, 6.0).unwrap();
            s.finish_drag(40);
            seen.push(drawn_bits(&s));
            s.step().unwrap();
            let label = if solver == SolverKind::GaussNewton {
                "GN"
            } else {
                "LM"
            };
            assert_eq!(
                s.step_back_undoes(),
                Some(format!("{label} iteration 3").as_str())
            );
            assert_eq!(s.steps_back_kept(), 6, "a whole drag is one step back");
            // Back through each moment, newest first: each the same bits as then.
            for (k, expected) in seen.iter().enumerate().rev() {
                s.step_back().unwrap();
                assert!(
                    drawn_bits(&s) == *expected,
                    "{solver:?}: step back to moment {k}"
                );
            }
            assert!(!s.can_step_back());
            assert_eq!(s.wrong_closures(), 0);
            assert_eq!(s.start_graph().edges().len(), 210);
            // Forward again: the same iterations as the first time.
            s.step().unwrap();
            assert!(
                drawn_bits(&s) == seen[1],
                "{solver:?}: the first iteration again"
            );
        }
    }

    #[test]
    fn the_checkpoints_stay_within_their_bounds() {
        let mut s = PoseGraphSession::from_scenario(PoseGraphScenario {
            solver: SolverKind::GradientDescent,
            ..PoseGraphScenario::default()
        })
        .unwrap();
        for _ in 0..(MAX_CHECKPOINTS + 5) {
            s.step().unwrap();
        }
        assert_eq!(s.steps_back_kept(), MAX_CHECKPOINTS);
        assert!(s.checkpoint_bytes <= MAX_CHECKPOINT_BYTES);
        assert_eq!(
            s.step_back_undoes(),
            Some(format!("first-order iteration {}", MAX_CHECKPOINTS + 5).as_str())
        );
    }

    #[test]
    fn the_information_pattern_shows_every_loop_closure_even_to_the_fixed_pose() {
        let mut s = PoseGraphSession::from_scenario(PoseGraphScenario::default()).unwrap();
        let (h, _, _) = s.patterns().unwrap();
        // 201 poses: the diagonal, 200 odometry pairs and 10 loop-closure pairs.
        assert_eq!(h.dims.len(), 201);
        assert_eq!(h.entries.len(), 201 + 2 * 200 + 2 * 10);
        let to_fixed = h.entries.iter().filter(|&&(r, c)| r == 0 && c > 1).count();
        assert_eq!(to_fixed, 10, "the ten loop closures close at pose 0");
        s.add_wrong_loop_closure().unwrap();
        let (h2, _, _) = s.patterns().unwrap();
        assert_eq!(
            h2.entries.len(),
            h.entries.len() + 2,
            "a wrong loop closure is a pair"
        );
    }
}
