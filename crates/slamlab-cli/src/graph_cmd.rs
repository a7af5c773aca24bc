//! `slamlab graph optimize|convert|evaluate`: pose-graph files on the command line.
//! (`slamlab experiment pose-graph` is in `experiments/pose_graph.rs`.)

use crate::args;
use anyhow::{Context, Result, bail};
use clap::{Arg, ArgMatches, Command};
use serde::Serialize;
use slamlab_core::graph::{
    EdgeKind, OptimizeError, Optimizer, OptimizerSettings, PoseGraph, RobustKernel, SolverKind,
    StepReport,
};
use slamlab_sim::io;
use slamlab_sim::io::graph::MAX_FILE_BYTES;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The `graph` subcommand.
pub fn command() -> Command {
    Command::new("graph")
        .about("Optimize and convert pose-graph files (g2o 2D, TORO 2D, iSAM ODOMETRY/LANDMARK)")
        .subcommand_required(true)
        .arg_required_else_help(true)
        .subcommand(
            Command::new("optimize")
                .about("Optimize a pose graph and report the cost per iteration")
                .long_about(
                    "Optimize a pose graph and report the cost per iteration.\n\n\
                     The cost is F = Σ eᵀ Ω e over all edges (thesis 000 Eq. 4.2), which is TWICE gtsam's \
                     `graph.error`. If the file has no prior and no FIX line, the first vertex in the file is \
                     held fixed to fix the gauge (gtsam's reference puts a tight prior on it instead: the \
                     optimum is the same, and no prior term enters the cost). time_ms covers the optimization \
                     only (the structure analysis and the iterations), not reading the file. costs[k] is the \
                     cost after step k; a rejected LM step (λ raised) repeats the previous cost, and \
                     iterations counts rejected steps too.",
                )
                .arg(Arg::new("file").required(true).value_parser(clap::value_parser!(PathBuf)).help("the graph file (.g2o, TORO .graph, or iSAM .txt); the format is detected from the content"))
                .arg(
                    args::choice("solver", &["gn", "lm", "gd"], "gn: Gauss-Newton; lm: Levenberg-Marquardt; gd: first-order (block-Jacobi preconditioned gradient descent)").default_value("lm"),
                )
                .arg(
                    args::whole("max-iterations", 1..=1_000_000, "at most this many steps (LM counts rejected steps too)").default_value("100"),
                )
                .arg(
                    args::choice("kernel", &["none", "huber", "cauchy"], "robust kernel on every edge (Huber: thesis 000 Eq. 5.9)").default_value("none"),
                )
                .arg(
                    args::number("kernel-width", "Huber δ or Cauchy c, on the Mahalanobis distance √(eᵀΩe)").default_value("1"),
                )
                .arg(
                    args::number("target-cost", "stop as soon as the cost is at or below this (for timing against another solver)"),
                )
                .arg(args::path("out", "FILE", "write the optimized graph (g2o)"))
                .arg(crate::trajectory_out::arg().help("write the optimized poses to DIR (TUM and CSV, each pose at the time of its vertex id) and the point vertices as landmarks"))
                .arg(args::switch("json", "print one JSON object")),
        )
        .subcommand(
            Command::new("evaluate")
                .about("Score an optimized graph: its cost against the reference solver's, and its ATE against a truth")
                .long_about(
                    "Score an optimized pose graph (a student's g2o file) against the problem it solves.\n\n\
                     The file must hold the problem's graph: every vertex (same ids and kinds) and every edge \
                     (same vertices, the same measurement to 1e-5), in any order; otherwise it is refused with \
                     the first difference. Its cost is F = Σ eᵀ Ω e over the PROBLEM's edges (measurements and \
                     information matrices from the problem, states from the file: thesis 000 Eq. 4.2, the cost \
                     `slamlab graph optimize` minimizes). The reference solver (--solver, from the problem's \
                     initial guess, the first vertex held fixed when the problem has no FIX or prior) gives the \
                     reference cost; the report has both, their ratio and difference. With --truth (TUM or CSV, \
                     each pose at the time of its vertex id, as --trajectory-out writes it) the file's and the \
                     reference's poses are scored as `slamlab evaluate` scores them (APE, RPE). See docs/metrics.md.",
                )
                .arg(Arg::new("problem").required(true).value_parser(clap::value_parser!(PathBuf)).help("the graph to optimize, as handed out (g2o, TORO or iSAM)"))
                .arg(Arg::new("estimate").required(true).value_parser(clap::value_parser!(PathBuf)).help("the optimized graph (g2o)"))
                .arg(args::path("truth", "FILE", "the true poses (TUM or CSV; time = vertex id)"))
                .arg(
                    args::choice("solver", &["gn", "lm", "gd"], "the reference solver (gn: the pose-graph lesson's default)").default_value("gn"),
                )
                .arg(
                    args::whole("max-iterations", 1..=1_000_000, "the reference solver's most steps").default_value("100"),
                )
                .arg(
                    Arg::new("align")
                        .long("align")
                        .value_parser(slamlab_sim::metrics::Alignment::NAMES)
                        .default_value("none")
                        .help("the alignment before the ATE (none: the gauge vertex holds the truth's frame)"),
                )
                .arg(args::switch("json", "print one JSON object")),
        )
        .subcommand(
            Command::new("convert")
                .about("Convert a pose graph (g2o, TORO or iSAM) into g2o 2D")
                .arg(Arg::new("input").required(true).value_parser(clap::value_parser!(PathBuf)))
                .arg(Arg::new("output").required(true).value_parser(clap::value_parser!(PathBuf)).help("the output file; must end in .g2o")),
        )
}

/// Runs `slamlab graph …`.
pub fn run(matches: &ArgMatches) -> Result<()> {
    match matches.subcommand() {
        Some(("optimize", m)) => optimize(m),
        Some(("convert", m)) => convert(m),
        Some(("evaluate", m)) => evaluate(m, &mut std::io::stdout().lock()),
        _ => Ok(()),
    }
}

/// Reads a graph file, refusing one over the size limit before reading it.
pub fn read_graph_file(path: &Path) -> Result<PoseGraph> {
    let size = std::fs::metadata(path)
        .with_context(|| format!("reading {}", path.display()))?
        .len();
    if size > MAX_FILE_BYTES as u64 {
        bail!(
            "{}: the file has {size} bytes, more than the {MAX_FILE_BYTES} bytes SLAM Lab reads",
            path.display()
        );
    }
    let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    let text = String::from_utf8(bytes)
        .map_err(|e| anyhow::anyhow!("{}: not a text file ({e})", path.display()))?;
    io::graph::read_graph(&text).with_context(|| format!("{}", path.display()))
}

/// Fixes the gauge like the gtsam reference run: unless the graph already has a
/// prior or a fixed vertex, holds the first vertex of the file fixed. Returns a
/// sentence that says what was done.
pub fn fix_gauge(graph: &mut PoseGraph) -> Result<String> {
    let has_anchor =
        graph.vertices().iter().any(|v| v.fixed) || graph.edges().iter().any(EdgeKind::is_prior);
    if has_anchor {
        return Ok("the file's own FIX lines or priors".to_owned());
    }
    let Some(first) = graph.vertices().first().map(|v| v.id) else {
        bail!("the graph has no vertices");
    };
    graph.set_fixed(first, true)?;
    Ok(format!(
        "vertex {first} (the first in the file) held fixed; gtsam's reference uses a tight prior there instead"
    ))
}

#[derive(Serialize)]
struct OptimizeSummary {
    file: String,
    solver: &'static str,
    kernel: &'static str,
    vertices: usize,
    edges: usize,
    poses: usize,
    landmarks: usize,
    gauge: String,
    cost_definition: &'static str,
    initial_cost: f64,
    final_cost: f64,
    iterations: usize,
    rejected_steps: usize,
    converged: bool,
    time_ms: f64,
    costs: Vec<f64>,
    lambdas: Vec<Option<f64>>,
    step_norms: Vec<f64>,
}

fn optimize(m: &ArgMatches) -> Result<()> {
    let Some(path) = m.get_one::<PathBuf>("file") else {
        bail!("no file given");
    };
    let solver = m
        .get_one::<String>("solver")
        .and_then(|s| SolverKind::from_short_name(s))
        .unwrap_or_default();
    let max_iterations = m.get_one::<u64>("max-iterations").copied().unwrap_or(100) as usize;
    let width = m.get_one::<f64>("kernel-width").copied().unwrap_or(1.0);
    let kernel = match m.get_one::<String>("kernel").map(String::as_str) {
        Some("huber") => RobustKernel::Huber { delta: width },
        Some("cauchy") => RobustKernel::Cauchy { c: width },
        _ => RobustKernel::None,
    };
    if !kernel.is_valid() {
        bail!("--kernel-width {width} must be a finite number above 0");
    }
    let target = m.get_one::<f64>("target-cost").copied();
    let mut graph = read_graph_file(path)?;
    let gauge = fix_gauge(&mut graph)?;
    let (vertices, edges) = (graph.vertices().len(), graph.edges().len());
    let (poses, landmarks) = (graph.pose_count(), graph.point_count());
    let settings = OptimizerSettings {
        solver,
        kernel,
        ..OptimizerSettings::default()
    };
    let json = m.get_flag("json");
    let start = Instant::now();
    let mut optimizer = Optimizer::new(graph, settings).map_err(explain)?;
    let initial_cost = optimizer.cost();
    let mut reports: Vec<StepReport> = Vec::new();
    if !target.is_some_and(|t| initial_cost <= t) {
        for _ in 0..max_iterations {
            let r = optimizer.step().map_err(explain)?;
            reports.push(r);
            if !json {
                eprintln!(
                    "iteration {:>3}: cost {:.6e}  |Δx| {:.3e}{}{}",
                    r.iteration,
                    r.cost,
                    r.step_norm,
                    r.lambda
                        .map_or_else(String::new, |l| format!("  λ {l:.2e}")),
                    if r.accepted { "" } else { "  (rejected)" }
                );
            }
            if r.converged || target.is_some_and(|t| r.cost <= t) {
                break;
            }
        }
    }
    let time_ms = start.elapsed().as_secs_f64() * 1e3;
    let summary = OptimizeSummary {
        file: path.display().to_string(),
        solver: solver.short_name(),
        kernel: kernel.name(),
        vertices,
        edges,
        poses,
        landmarks,
        gauge,
        cost_definition: "sum over edges of e^T Omega e (twice gtsam's graph.error)",
        initial_cost,
        final_cost: optimizer.cost(),
        iterations: reports.len(),
        rejected_steps: reports.iter().filter(|r| !r.accepted).count(),
        converged: optimizer.is_converged(),
        time_ms,
        costs: reports.iter().map(|r| r.cost).collect(),
        lambdas: reports.iter().map(|r| r.lambda).collect(),
        step_norms: reports.iter().map(|r| r.step_norm).collect(),
    };
    {
        use slamlab_sim::metrics::TrajectoryRole;
        use slamlab_sim::pose_graph::export;
        let graph = optimizer.graph();
        let landmarks = export::landmarks(graph);
        crate::trajectory_out::write(
            m,
            "pose-graph",
            &[export::pose_trajectory(
                graph,
                "optimized",
                TrajectoryRole::Estimate,
            )],
            &if landmarks.is_empty() {
                Vec::new()
            } else {
                vec![("optimized".to_owned(), landmarks)]
            },
        )?;
    }
    if let Some(out) = m.get_one::<PathBuf>("out") {
        let text = io::graph::write_g2o(optimizer.graph())?;
        std::fs::write(out, text).with_context(|| format!("writing {}", out.display()))?;
        eprintln!("wrote {}", out.display());
    }
    if json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
    } else {
        println!(
            "{}: {} vertices ({} poses, {} landmarks), {} edges; solver {}, kernel {}",
            summary.file, vertices, poses, landmarks, edges, summary.solver, summary.kernel
        );
        println!("gauge: {}", summary.gauge);
        println!(
            "cost Σ eᵀΩe (twice gtsam's error): {:.6e} -> {:.6e} in {} iterations ({} rejected), {:.1} ms{}",
            summary.initial_cost,
            summary.final_cost,
            summary.iterations,
            summary.rejected_steps,
            summary.time_ms,
            if summary.converged { ", converged" } else { "" }
        );
    }
    Ok(())
}

/// The JSON of `slamlab graph evaluate`.
#[derive(Serialize)]
struct GraphEvaluation {
    problem: String,
    estimate: String,
    solver: &'static str,
    reference_iterations: usize,
    reference_converged: bool,
    gauge: Option<String>,
    #[serde(flatten)]
    score: slamlab_sim::metrics::graph::GraphScore,
    truth: Option<String>,
    ate: Option<slamlab_sim::metrics::Evaluation>,
    reference_ate: Option<slamlab_sim::metrics::Evaluation>,
}

fn evaluate(m: &ArgMatches, out: &mut dyn std::io::Write) -> Result<()> {
    use slamlab_sim::metrics::graph::{graph_poses, reference_solution, score_graph};
    use slamlab_sim::metrics::{Alignment, EvaluationSettings};
    let path = |name: &str| {
        m.get_one::<PathBuf>(name)
            .cloned()
            .ok_or_else(|| anyhow::anyhow!("{name} is required"))
    };
    let (problem_path, estimate_path) = (path("problem")?, path("estimate")?);
    let problem = read_graph_file(&problem_path)?;
    let file = read_graph_file(&estimate_path)?;
    let solver = m
        .get_one::<String>("solver")
        .and_then(|s| SolverKind::from_short_name(s))
        .unwrap_or(SolverKind::GaussNewton);
    let max_iterations = m.get_one::<u64>("max-iterations").copied().unwrap_or(100) as usize;
    let settings = OptimizerSettings {
        solver,
        ..OptimizerSettings::default()
    };
    let reference = reference_solution(&problem, settings, max_iterations).map_err(explain)?;
    let score = score_graph(&problem, &file, reference.cost).map_err(|why| {
        anyhow::anyhow!(
            "{} is not the graph of {}: {why}",
            estimate_path.display(),
            problem_path.display()
        )
    })?;
    let truth_path = m.get_one::<PathBuf>("truth").cloned();
    let (mut ate, mut reference_ate) = (None, None);
    if let Some(truth_path) = &truth_path {
        let truth = crate::evaluate_cmd::read_trajectory_file(truth_path)?;
        let settings = EvaluationSettings {
            alignment: m
                .get_one::<String>("align")
                .and_then(|a| Alignment::from_name(a))
                .unwrap_or(Alignment::None),
            ..EvaluationSettings::default()
        };
        let score_poses = |graph: &PoseGraph| {
            slamlab_sim::metrics::evaluate(&truth.trajectory, &graph_poses(graph), &settings)
                .map_err(|e| anyhow::anyhow!("against {}: {e}", truth_path.display()))
        };
        ate = Some(score_poses(&file)?);
        reference_ate = Some(score_poses(&reference.graph)?);
    }
    let report = GraphEvaluation {
        problem: problem_path.display().to_string(),
        estimate: estimate_path.display().to_string(),
        solver: solver.short_name(),
        reference_iterations: reference.iterations,
        reference_converged: reference.converged,
        gauge: reference.gauge.clone(),
        score,
        truth: truth_path.map(|p| p.display().to_string()),
        ate,
        reference_ate,
    };
    if m.get_flag("json") {
        writeln!(out, "{}", serde_json::to_string_pretty(&report)?)?;
        return Ok(());
    }
    let s = &report.score;
    writeln!(
        out,
        "{}: {} vertices, {} edges, the graph of {}",
        report.estimate, s.vertices, s.edges, report.problem
    )?;
    writeln!(
        out,
        "cost Σ eᵀΩe (the problem's edges): {:.6e}; initial guess {:.6e}; reference ({}, {} iterations{}) {:.6e}",
        s.cost,
        s.initial_cost,
        report.solver,
        report.reference_iterations,
        if report.reference_converged {
            ", converged"
        } else {
            ""
        },
        s.reference_cost
    )?;
    writeln!(
        out,
        "cost / reference: {}; cost - reference: {:.6e}",
        s.cost_ratio
            .map_or("- (the reference cost is 0)".to_owned(), |r| format!(
                "{r:.6}"
            )),
        s.cost_difference
    )?;
    if let (Some(a), Some(r)) = (&report.ate, &report.reference_ate) {
        writeln!(
            out,
            "ATE RMSE: {:.6} m (the reference's {:.6} m), over {} poses",
            a.ape.translation.rmse, r.ape.translation.rmse, a.pairing.pairs
        )?;
    }
    Ok(())
}

/// An optimizer's error as the CLI reports it.
pub fn explain(e: OptimizeError) -> anyhow::Error {
    anyhow::anyhow!("cannot optimize: {e}")
}

fn convert(m: &ArgMatches) -> Result<()> {
    let (Some(input), Some(output)) = (
        m.get_one::<PathBuf>("input"),
        m.get_one::<PathBuf>("output"),
    ) else {
        bail!("convert needs an input and an output file");
    };
    if !output
        .to_string_lossy()
        .to_ascii_lowercase()
        .ends_with(".g2o")
    {
        bail!(
            "{}: SLAM Lab writes g2o 2D only; give the output a .g2o name",
            output.display()
        );
    }
    let graph = read_graph_file(input)?;
    let text = io::graph::write_g2o(&graph).with_context(|| format!("{}", input.display()))?;
    std::fs::write(output, text).with_context(|| format!("writing {}", output.display()))?;
    eprintln!(
        "wrote {} ({} vertices, {} edges)",
        output.display(),
        graph.vertices().len(),
        graph.edges().len()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_file(name: &str, contents: &str) -> PathBuf {
        let path = std::env::temp_dir().join(format!("slamlab-{}-{name}", std::process::id()));
        std::fs::write(&path, contents).unwrap();
        path
    }

    #[test]
    fn a_50_mb_file_is_refused_before_it_is_read() {
        let path = temp_file("big.g2o", "");
        let file = std::fs::OpenOptions::new().write(true).open(&path).unwrap();
        file.set_len(50 * 1024 * 1024).unwrap();
        let err = read_graph_file(&path).unwrap_err().to_string();
        std::fs::remove_file(&path).unwrap();
        assert!(
            err.contains("52428800 bytes, more than the 33554432 bytes"),
            "{err}"
        );
    }

    #[test]
    fn bad_files_name_the_file_line_and_problem() {
        let path = temp_file("one.g2o", "# one vertex\nVERTEX_SE2 0 0 0 0\n");
        let err = format!("{:#}", read_graph_file(&path).unwrap_err());
        std::fs::remove_file(&path).unwrap();
        assert!(err.contains("one.g2o") && err.contains("1 vertex"), "{err}");
        let path = temp_file(
            "bad.g2o",
            "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 NaN\n",
        );
        let err = format!("{:#}", read_graph_file(&path).unwrap_err());
        std::fs::remove_file(&path).unwrap();
        assert!(
            err.contains("line 3") && err.contains("'NaN' is not a finite number"),
            "{err}"
        );
    }

    #[test]
    fn the_gauge_is_fixed_at_the_first_vertex_unless_the_file_anchors_it() {
        let mut g = slamlab_sim::io::graph::read_graph(
            "VERTEX_SE2 4 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 4 1 1 0 0 1 0 0 1 0 1\n",
        )
        .unwrap();
        let text = fix_gauge(&mut g).unwrap();
        assert!(text.starts_with("vertex 4"), "{text}");
        assert!(g.vertex(4).unwrap().fixed && !g.vertex(1).unwrap().fixed);
        let text = fix_gauge(&mut g).unwrap();
        assert!(text.contains("own FIX"), "{text}");
    }
}
