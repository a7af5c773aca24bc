//! `slamlab experiment pose-graph`: thesis `000` Sec. 4.2, the EKF-SLAM path as a
//! pose graph with loop closures, optimized.
//!
//! ```text
//! slamlab experiment pose-graph --loop-closures 10 --noise-scale 1 --seed 1 --json
//! ```

use super::{landmark_flags_but_seed, noise_scale_arg, seed_arg};
use crate::args;
use crate::command::{Experiment, Refusal};
use crate::output::Output;
use anyhow::{Result, bail};
use clap::{ArgMatches, Command};
use slamlab_core::graph::SolverKind;
use slamlab_sim::pose_graph::experiment::{self, PoseGraphExperimentConfig};
use std::io::Write;

/// Dead reckoning, EKF-SLAM and the optimized graph against the truth.
pub struct PoseGraph;

impl Experiment for PoseGraph {
    fn command(&self) -> Command {
        Command::new("pose-graph")
            .about("Pose-graph SLAM on the EKF-SLAM path (thesis 000 Sec. 4.2): loop closures, the optimized graph")
            .arg(noise_scale_arg())
            .args(seed_arg())
            .arg(
                args::whole(
                    "loop-closures",
                    0..=10_000,
                    "loop-closure edges from the first pose to random poses",
                )
                .default_value("10"),
            )
            .arg(
                args::choice(
                    "solver",
                    &["gn", "lm", "gd"],
                    "the solver (the thesis uses Gauss-Newton)",
                )
                .default_value("gn"),
            )
            .arg(
                args::whole("max-iterations", 1..=100_000, "at most this many solver steps")
                    .default_value("20"),
            )
    }

    fn refusals(&self) -> Vec<Refusal> {
        vec![
            Refusal {
                flags: vec!["trials", "steps", "csv"],
                reason: |flag| {
                    format!(
                        "--{flag} does not apply to pose-graph (one seeded run of {} ticks)",
                        experiment::STEPS
                    )
                },
            },
            Refusal {
                flags: landmark_flags_but_seed(&[]),
                reason: |flag| {
                    format!(
                        "--{flag} sets a scenario parameter; pose-graph runs the thesis's fixed scenario (only --seed, --noise-scale, --loop-closures, --solver, --max-iterations)"
                    )
                },
            },
        ]
    }

    fn run(&self, m: &ArgMatches, out: &mut Output) -> Result<()> {
        let noise_scale = m.get_one::<f64>("noise-scale").copied().unwrap_or(1.0);
        if !(noise_scale > 0.0 && noise_scale <= 20.0) {
            bail!("--noise-scale {noise_scale} must be in (0, 20]");
        }
        let seed = match m.get_one::<String>("seed") {
            Some(s) => s
                .parse::<u64>()
                .map_err(|_| anyhow::anyhow!("--seed '{s}' is not a whole number ≥ 0"))?,
            None => 1,
        };
        let config = PoseGraphExperimentConfig {
            loop_closures: m.get_one::<u64>("loop-closures").copied().unwrap_or(10) as usize,
            noise_scale,
            seed,
            solver: m
                .get_one::<String>("solver")
                .and_then(|s| SolverKind::from_short_name(s))
                .unwrap_or(SolverKind::GaussNewton),
            max_iterations: m.get_one::<u64>("max-iterations").copied().unwrap_or(20) as usize,
        };
        let result = experiment::run(config).map_err(crate::graph_cmd::explain)?;
        if out.print_json(&result)? {
            return Ok(());
        }
        writeln!(
            out,
            "SLAM Lab: pose-graph SLAM on the EKF-SLAM path (thesis 000 Sec. 4.2), seed {}, noise × {}",
            config.seed, config.noise_scale
        )?;
        for note in &result.notes {
            writeln!(out, "  {note}")?;
        }
        writeln!(
            out,
            "graph: {} poses, {} edges; loop closures to poses {:?}",
            result.poses, result.edges, result.loop_closure_nodes
        )?;
        writeln!(out, "cost Σ eᵀΩe: {:.6e}", result.initial_cost)?;
        for (k, c) in result.costs.iter().enumerate() {
            writeln!(out, "  after iteration {}: {c:.6e}", k + 1)?;
        }
        writeln!(out, "position RMSE against the truth (m):")?;
        writeln!(out, "  dead reckoning  {:.4}", result.rmse_dead_reckoning)?;
        writeln!(out, "  EKF-SLAM        {:.4}", result.rmse_ekf)?;
        writeln!(out, "  optimized graph {:.4}", result.rmse_optimized)?;
        Ok(())
    }
}
