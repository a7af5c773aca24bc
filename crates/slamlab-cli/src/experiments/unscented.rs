//! `slamlab experiment unscented`: one Gaussian through one nonlinear function by
//! the EKF's linearization, the unscented transform and particles, measured
//! against the moments of many samples (thesis `000` Sec. 2.2; the filters
//! lesson's one-step comparison).
//!
//! ```text
//! slamlab experiment unscented --function polar --bearing-std-deg 30 --range-std 0.1 --samples 100000 --seed 1 --json
//! ```

use crate::command::Experiment;
use crate::flags::{scenario_from, table_args};
use crate::output::Output;
use anyhow::{Result, anyhow};
use clap::{ArgMatches, Command};
use slamlab_sim::filters::session::{FiltersScenario, one_step};
use std::io::Write;

/// The table's parameters this experiment takes (the one-step comparison's).
const FLAGS: &[&str] = &[
    "seed",
    "function",
    "coefficient",
    "dt",
    "mean-1",
    "mean-2",
    "std-1",
    "std-2",
    "range-std",
    "bearing-std-deg",
    "rho",
    "alpha",
    "beta",
    "kappa",
    "samples",
    "particles",
];

/// The unscented transform against linearization and particles.
pub struct Unscented;

impl Experiment for Unscented {
    fn command(&self) -> Command {
        Command::new("unscented")
            .about("EKF linearization, unscented transform and particles on one nonlinear step, against many samples (thesis 000 Sec. 2.2)")
            .args(
            table_args::<FiltersScenario>(|name| FLAGS.contains(&name))
                .into_iter()
                .map(|a| a.help_heading("The one-step comparison (the flags of lesson=filters)")),
        )
    }

    fn run(&self, matches: &ArgMatches, out: &mut Output) -> Result<()> {
        let scenario: FiltersScenario = scenario_from(matches, &[])?;
        let result = one_step(&scenario).map_err(|e| anyhow!("{e}"))?;
        let truth = &result.truth.moments;
        let json = serde_json::json!({
            "experiment": "unscented",
            "function": scenario.function.name(),
            "formula": result.function.formula(),
            "parameters": {
                "seed": scenario.seed,
                "mean": scenario.mean,
                "std": scenario.std,
                "rho": scenario.rho,
                "alpha": scenario.alpha,
                "beta": scenario.beta,
                "kappa": scenario.kappa,
                "samples": scenario.samples,
                "particles": scenario.particles,
                "coefficient": scenario.coefficient,
                "dt": scenario.dt,
            },
            "samples_mean": [truth.mean[0], truth.mean[1]],
            "samples_covariance": [
                [truth.covariance[(0, 0)], truth.covariance[(0, 1)]],
                [truth.covariance[(1, 0)], truth.covariance[(1, 1)]],
            ],
            "results": result.rows,
        });
        if out.print_json(&json)? {
            return Ok(());
        }
        writeln!(
            out,
            "SLAM Lab experiment unscented: {} = {}",
            scenario.function.name(),
            result.function.formula()
        )?;
        writeln!(
            out,
            "prior mean ({}, {}), std ({}, {}), rho {}; alpha {}, beta {}, kappa {}; {} samples, {} particles, seed {}",
            scenario.mean[0],
            scenario.mean[1],
            scenario.std[0],
            scenario.std[1],
            scenario.rho,
            scenario.alpha,
            scenario.beta,
            scenario.kappa,
            scenario.samples,
            scenario.particles,
            scenario.seed
        )?;
        writeln!(
            out,
            "samples' mean ({:.6}, {:.6}), covariance [[{:.6}, {:.6}], [{:.6}, {:.6}]]",
            truth.mean[0],
            truth.mean[1],
            truth.covariance[(0, 0)],
            truth.covariance[(0, 1)],
            truth.covariance[(1, 0)],
            truth.covariance[(1, 1)]
        )?;
        writeln!(out)?;
        writeln!(
            out,
            "{:<10} {:>12} {:>18} {:>14}",
            "method", "mean error", "covariance error", "KL (nats)"
        )?;
        for row in &result.rows {
            let c = &row.comparison;
            let kl = c
                .kl_divergence
                .map_or_else(|| "—".to_owned(), |v| format!("{v:.6}"));
            writeln!(
                out,
                "{:<10} {:>12.6} {:>18.6} {:>14}",
                row.method, c.mean_error, c.covariance_error, kl
            )?;
        }
        writeln!(out)?;
        writeln!(
            out,
            "mean error: distance of the method's mean from the samples' mean (output units); \
             covariance error: ‖Σ − Σ_samples‖_F / ‖Σ_samples‖_F; KL: KL(samples' Gaussian ‖ method's)"
        )?;
        Ok(())
    }
}
