//! Pose-graph assignments (`crate::coursework`'s [`Task`] of pose-graph
//! tasks): one student's Manhattan-world graph, handed out as g2o, and the
//! optimized graph they hand back scored by the lesson's least-squares cost
//! against the reference solver's, and by its poses against the truth.
//!
//! The graph is the lesson's `manhattan` example ([`manhattan_graph`]) with the
//! student's seed and as many poses as the variant's steps: its own walk, its
//! own odometry and loop-closure noise. The reference solver is the lesson's
//! (Gauss-Newton by default, `solver=` in the assignment's parameters), run
//! from the graph as handed out (`problem.g2o` read back: the numbers are
//! written to round trip, so it is the same graph to the bit).

use super::experiment::manhattan_graph;
use super::session::{Example, KernelChoice, PoseGraphScenario};
use crate::coursework::files::InputFiles;
use crate::coursework::grade::{assemble_scores, trajectory_metric, trajectory_settings};
use crate::coursework::{
    Assignment, CourseworkError, Grade, HandIn, InputFormat, Metric, Task, TaskKind, TaskRun,
    Variant, steps_refusal,
};
use crate::io::graph::{MAX_FILE_BYTES, read_graph, write_g2o};
use crate::io::trajectory::write_tum;
use crate::metrics::graph::{GraphScore, graph_poses, reference_solution, score_graph};
use crate::metrics::{Evaluation, Trajectory, evaluate};
use slamlab_core::graph::{PoseGraph, SolverKind};
use std::fmt::Write as _;

/// The fewest and most poses of an assignment's graph (the lesson's
/// `manhattan-poses` range).
pub const POSES: (u64, u64) = (10, 5000);

/// One student's pose-graph problem: the graph handed out, its truth and the
/// reference solver's solution.
#[derive(Clone, Debug)]
pub struct PoseGraphRun {
    /// The scenario (the student's seed in it).
    pub scenario: PoseGraphScenario,
    /// `problem.g2o`, as handed out.
    pub problem_text: String,
    /// The graph read back from `problem_text`.
    pub problem: PoseGraph,
    /// The true poses, each at the time of its vertex id.
    pub truth: Trajectory,
    /// The reference solver's optimized graph.
    pub solution: PoseGraph,
    /// Its final cost `Σ eᵀΩe`.
    pub reference_cost: f64,
    /// The reference solver's iterations.
    pub reference_iterations: usize,
}

impl PoseGraphRun {
    /// Builds the student's graph of `poses` poses and solves it.
    pub fn simulate(
        scenario: &PoseGraphScenario,
        poses: u64,
    ) -> Result<PoseGraphRun, CourseworkError> {
        let scenario = PoseGraphScenario {
            example: Example::Manhattan,
            manhattan_poses: poses,
            kernel: KernelChoice::None,
            ..scenario.clone()
        };
        let (graph, truth) = manhattan_graph(
            poses as usize,
            scenario.manhattan_side as i64,
            scenario.seed,
        );
        let problem_text = write_g2o(&graph)
            .map_err(|e| CourseworkError::Generate(format!("problem.g2o: {e}")))?;
        let problem = read_graph(&problem_text)
            .map_err(|e| CourseworkError::Generate(format!("problem.g2o read back: {e}")))?;
        let solved = reference_solution(
            &problem,
            scenario.settings(),
            scenario.max_iterations as usize,
        )
        .map_err(|e| CourseworkError::Generate(format!("the reference solver: {e}")))?;
        let truth = Trajectory::new((0..truth.len()).map(|k| k as f64).collect(), truth);
        Ok(PoseGraphRun {
            scenario,
            problem_text,
            problem,
            truth,
            reference_cost: solved.cost,
            reference_iterations: solved.iterations,
            solution: solved.graph,
        })
    }

    fn score(&self, file: &PoseGraph) -> Result<GraphScore, String> {
        score_graph(&self.problem, file, self.reference_cost)
    }
}

/// The starter code of pose-graph assignments.
pub const POSE_GRAPH_STARTER: &str = include_str!("assignment_starter.py");

/// Pose-graph tasks: the lesson's parameter table checks the assignment's
/// parameters, and a variant is the Manhattan graph with the student's seed.
impl Task for PoseGraphRun {
    const KIND: TaskKind = TaskKind::PoseGraph;
    type Scenario = PoseGraphScenario;

    fn refusals(assignment: &Assignment, scenario: &PoseGraphScenario) -> Vec<String> {
        let mut refused = Vec::new();
        let pairs = assignment.param_pairs();
        let given = |name: &str| pairs.iter().any(|(k, _)| k == name);
        if given("example") && scenario.example != Example::Manhattan {
            refused.push(
                "example: an assignment's graph is the manhattan example (each student's own walk)"
                    .to_owned(),
            );
        }
        if given("manhattan-poses") {
            refused.push(
                "manhattan-poses: an assignment's poses are its scenario.steps (and steps_spread)"
                    .to_owned(),
            );
        }
        if scenario.kernel != KernelChoice::None {
            refused.push(
                "kernel: an assignment is graded by the plain least-squares cost; leave the kernel out"
                    .to_owned(),
            );
        }
        if scenario.solver == SolverKind::GradientDescent {
            refused.push("solver gd: the reference solver must converge; use gn or lm".to_owned());
        }
        let (min, max) = POSES;
        let limit = format!("a pose-graph assignment has {min} to {max} poses");
        refused.extend(steps_refusal(assignment, min, max, &limit));
        refused
    }

    fn run(
        mut scenario: PoseGraphScenario,
        seed: u64,
        steps: u64,
    ) -> Result<Self, CourseworkError> {
        scenario.seed = seed;
        PoseGraphRun::simulate(&scenario, steps)
    }
}

/// Reads a handed-in graph file (refused over the readers' size limit, not
/// text, or not g2o/TORO).
pub fn read_handed_in(file_name: &str, bytes: &[u8]) -> Result<PoseGraph, CourseworkError> {
    let bad = |m: String| CourseworkError::BadEstimate(format!("{file_name}: {m}"));
    if bytes.len() > MAX_FILE_BYTES {
        return Err(bad(format!(
            "{} bytes, more than the {MAX_FILE_BYTES} a graph file may have",
            bytes.len()
        )));
    }
    if bytes.starts_with(b"PK\x03\x04") || bytes.starts_with(&[0x1f, 0x8b]) {
        return Err(bad(
            "a zip or gzip archive, where a g2o text file belongs".to_owned()
        ));
    }
    let text = std::str::from_utf8(bytes).map_err(|e| {
        bad(format!(
            "not a text file (byte {} is not UTF-8)",
            e.valid_up_to()
        ))
    })?;
    read_graph(text).map_err(|e| bad(e.to_string()))
}

impl TaskRun for PoseGraphRun {
    fn truth(&self) -> Trajectory {
        self.truth.clone()
    }

    /// The reference solver's poses and the initial guess's.
    fn references(&self) -> Result<Vec<(String, Trajectory)>, CourseworkError> {
        Ok(vec![
            (
                format!("{}-solver", self.scenario.solver.short_name()),
                graph_poses(&self.solution),
            ),
            ("initial-guess".to_owned(), graph_poses(&self.problem)),
        ])
    }

    /// What the README says about the files.
    fn readme_body(&self, _inputs: &[InputFormat]) -> String {
        let s = &self.scenario;
        let mut out = String::new();
        let _ = writeln!(
            out,
            "problem.g2o  a pose graph in g2o's 2D format: {} poses, {} edges.\n\
             \x20 VERTEX_SE2 id x y theta   a pose (metres, radians): the initial guess,\n\
             \x20                          the noisy odometry chained from pose 0.\n\
             \x20 FIX 0                     pose 0 is held where it is (it fixes the gauge;\n\
             \x20                          it is the true start pose, the origin).\n\
             \x20 EDGE_SE2 i j dx dy dtheta I11 I12 I13 I22 I23 I33\n\
             \x20                          pose j measured from pose i, z = x_i^-1 x_j (in\n\
             \x20                          pose i's frame), with the upper triangle of its\n\
             \x20                          3x3 information matrix row by row.\n\
             Between consecutive poses the edges are odometry; the others are loop\n\
             closures (the robot back on a cell it visited more than 10 poses before).\n\
             \n\
             The world: a robot walks a grid of 1 m cells inside a square of {} x {}\n\
             cells, straight on with probability 0.7, else turning 90 degrees. Every\n\
             measurement has Gaussian noise of std 0.05 m in x and y and 1 degree in\n\
             theta (the information matrices say so: diag(400, 400, 3282.8)).\n\
             \n\
             The cost: F(x) = sum over edges of e^T Omega e with e = t2v(z^-1 (x_i^-1 x_j))\n\
             (the angle wrapped to (-pi, pi]), Grisetti et al., A tutorial on graph-based\n\
             SLAM, Eq. 4.2 of Xiang's thesis. The initial guess costs {:.6e}.\n",
            self.problem.pose_count(),
            self.problem.edges().len(),
            s.manhattan_side,
            s.manhattan_side,
            slamlab_core::graph::graph_cost(
                &self.problem,
                &slamlab_core::graph::RobustKernel::None
            ),
        );
        out
    }

    /// The files handed out: `problem.g2o`, the README and the starter code;
    /// with `answers`, `answers/truth.tum` and the reference solver's
    /// `answers/reference.g2o`.
    fn files(&self, _inputs: &[InputFormat], readme: &str, answers: bool) -> InputFiles {
        let mut files = InputFiles::with_readme(readme);
        files.add("problem.g2o", &self.problem_text);
        files.add("starter.py", POSE_GRAPH_STARTER);
        if answers {
            files.add("answers/truth.tum", write_tum(&self.truth));
            files.add(
                "answers/reference.g2o",
                write_g2o(&self.solution).unwrap_or_default(),
            );
        }
        files
    }

    fn lesson_pairs(&self) -> Vec<(String, String)> {
        vec![
            ("example".to_owned(), "manhattan".to_owned()),
            (
                "manhattan-poses".to_owned(),
                self.problem.pose_count().to_string(),
            ),
        ]
    }

    fn hand_in_text(&self, assignment: &Assignment, variant: &Variant) -> Option<String> {
        Some(format!(
            "{file}: the optimized graph in g2o format: every VERTEX_SE2 of problem.g2o\n\
             with its optimized pose (same ids), and the FIX and EDGE_SE2 lines as they\n\
             were (in any order; numbers printed with at least six decimals). Check it\n\
             with\n  slamlab grade {id} --student '{student}' --estimate {file}\n\n\
             It is scored by its cost F with problem.g2o's measurements and information\n\
             matrices (your file's edges are only checked, not used) against the cost of\n\
             the reference solver ({solver}, from the initial guess), and by its poses\n\
             against the true ones (paired by vertex id, no alignment: pose 0 is fixed\n\
             at the true start):",
            file = assignment.output.file,
            id = assignment.id,
            student = variant.student,
            solver = self.scenario.solver.short_name(),
        ))
    }

    fn grade(
        &self,
        hand_in: &HandIn<'_>,
        references: &[(String, Trajectory)],
    ) -> Result<Grade, CourseworkError> {
        let file = read_handed_in(hand_in.file_name, hand_in.bytes)?;
        let score = self.score(&file).map_err(|why| {
            CourseworkError::OtherVariant(format!(
                "{} is not your problem.g2o's graph: {why}; download your own inputs (student= your id) and hand back every vertex and edge",
                hand_in.file_name
            ))
        })?;
        let settings = trajectory_settings(hand_in.assignment);
        let evaluation =
            evaluate(&self.truth, &graph_poses(&file), &settings).map_err(|e| hand_in.bad(e))?;
        // A graph's score: its cost ratio and its poses' evaluation.
        type Score = (Option<f64>, Option<Evaluation>);
        let value = |metric: Metric, (cost_ratio, e): &Score| match metric {
            Metric::CostRatio => *cost_ratio,
            other => e.as_ref().and_then(|e| trajectory_metric(other, e)),
        };
        let mine = (score.cost_ratio, Some(evaluation));
        let reference_ratios = [
            Some(1.0).filter(|_| self.reference_cost > 0.0),
            (self.reference_cost > 0.0).then(|| score_ratio_of(&self.problem, self)),
        ];
        let theirs: Vec<(String, Score)> = references
            .iter()
            .enumerate()
            .map(|(k, (name, t))| {
                let ratio = reference_ratios.get(k).copied().flatten();
                (
                    name.clone(),
                    (ratio, evaluate(&self.truth, t, &settings).ok()),
                )
            })
            .collect();
        let notices = vec![format!(
            "cost {:.6e} (initial guess {:.6e}, reference {:.6e}; Σ e^T Ω e over problem.g2o's edges)",
            score.cost, score.initial_cost, score.reference_cost
        )];
        Ok(assemble_scores(hand_in, &mine, &theirs, value, notices))
    }
}

/// The initial guess's cost over the reference's.
fn score_ratio_of(problem: &PoseGraph, run: &PoseGraphRun) -> f64 {
    slamlab_core::graph::graph_cost(problem, &slamlab_core::graph::RobustKernel::None)
        / run.reference_cost
}
