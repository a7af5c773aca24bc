//! `slamlab experiment kidnap`: the kidnapped robot, thesis `000` Tables 5.1 and 5.2.
//!
//! ```text
//! slamlab experiment kidnap --map maze --particles 500,1000 --estimator amcl,acmcl --trials 20 --seed 1 --json
//! ```

use super::first_seed_arg;
use crate::args;
use crate::command::Experiment;
use crate::flags;
use crate::map::{map_arg, read_map, resolution_arg};
use crate::output::{Output, csv_arg, par_trials};
use anyhow::{Context, Result, bail};
use clap::{ArgMatches, Command};
use serde_json::json;
use slamlab_sim::kidnap::experiment::{KidnapProtocol, kidnap_trial, summarize};
use slamlab_sim::kidnap::{LocalizationEstimator, MclScenario};
use std::io::Write;

/// What `experiment kidnap` sets itself (lists, the protocol's tracking start and
/// kidnap), so the table's flags of these names are not offered there.
const OWN: &[&str] = &["map", "particles", "estimator", "seed", "init", "kidnap-at"];

/// Updates to recover from a kidnap, per filter and particle count.
pub struct Kidnap;

impl Experiment for Kidnap {
    fn command(&self) -> Command {
        Command::new("kidnap")
            .about("The kidnapped robot (thesis 000 Tables 5.1 and 5.2): updates to recover after a kidnap, and the fraction of particles randomized on the way")
            .arg(map_arg())
            .arg(resolution_arg("metres per pixel, for a lone image"))
            .arg(
                args::flag("particles", "comma-separated particle counts")
                    .default_value("500,1000,1500,2000,2500"),
            )
            .arg(
                args::flag("estimator", "comma-separated: mcl, amcl, cmcl, acmcl")
                    .default_value("amcl,acmcl"),
            )
            .arg(
                args::whole(
                    "trials",
                    1..=10_000,
                    "trials per (estimator, particle count); trial i uses seed + i",
                )
                .default_value("20"),
            )
            .arg(first_seed_arg())
            .arg(
                args::whole(
                    "limit",
                    10..=100_000,
                    "updates after the kidnap before a trial counts as a failure",
                )
                .default_value("500"),
            )
            .arg(csv_arg("write per-trial rows to DIR/kidnap_trials.csv"))
            .args(flags::table_args::<MclScenario>(|name| {
                !OWN.contains(&name)
            }))
    }

    fn run(&self, m: &ArgMatches, out: &mut Output) -> Result<()> {
        let mut base: MclScenario = flags::scenario_from(m, OWN)?;
        let spec = m.get_one::<String>("map").map_or("maze", String::as_str);
        let (grid, name) = read_map(spec, m.get_one::<f64>("resolution").copied())?;
        base.map = name.clone();
        let mut counts = Vec::new();
        for p in m
            .get_one::<String>("particles")
            .map_or("", String::as_str)
            .split(',')
        {
            let n: usize = p
                .trim()
                .parse()
                .ok()
                .filter(|n| *n > 0)
                .with_context(|| format!("--particles '{p}' is not a positive whole number"))?;
            if n > slamlab_core::particle::MAX_PARTICLES {
                bail!(
                    "--particles {n} is more than {}",
                    slamlab_core::particle::MAX_PARTICLES
                );
            }
            counts.push(n);
        }
        let mut estimators = Vec::new();
        for e in m
            .get_one::<String>("estimator")
            .map_or("", String::as_str)
            .split(',')
        {
            match LocalizationEstimator::from_name(e.trim()) {
                Some(x) => estimators.push(x),
                None => bail!("--estimator '{e}' is not one of: mcl, amcl, cmcl, acmcl"),
            }
        }
        let trials = m.get_one::<u64>("trials").copied().unwrap_or(20);
        let seed = m.get_one::<u64>("seed").copied().unwrap_or(1);
        let protocol = KidnapProtocol {
            limit_updates: m.get_one::<u64>("limit").copied().unwrap_or(500) as usize,
            kidnap_distance: base.kidnap_distance,
            ..Default::default()
        };
        // Every (estimator, count, seed) trial is independent: rayon runs them on
        // all cores (natively only; each trial's numbers do not depend on the thread).
        let jobs: Vec<(LocalizationEstimator, usize, u64)> = estimators
            .iter()
            .flat_map(|&e| {
                counts
                    .iter()
                    .flat_map(move |&n| (0..trials).map(move |i| (e, n, i)))
            })
            .collect();
        let outcomes = par_trials("kidnap", &jobs, |&(est, n, i)| {
            kidnap_trial(&base, &grid, est, n, seed.wrapping_add(i), &protocol)
                .map_err(|e| e.to_string())
        });
        let mut rows = Vec::with_capacity(jobs.len());
        for outcome in outcomes {
            match outcome {
                Ok(t) => rows.push(t),
                Err(e) => bail!("map {name}: {e}"),
            }
        }
        let mut results = Vec::new();
        for &est in &estimators {
            for &n in &counts {
                let ts: Vec<_> = rows
                    .iter()
                    .filter(|t| t.estimator == est.name() && t.particles == n)
                    .copied()
                    .collect();
                results.push(summarize(est.name(), n, &ts, protocol.limit_updates));
            }
        }
        eprintln!();
        out.write_csv("kidnap_trials.csv", || {
            let mut csv = String::from(
                "estimator,particles,seed,kidnap_tick,steps_to_converge,recovery_ratio\n",
            );
            for t in &rows {
                csv.push_str(&format!(
                    "{},{},{},{},{},{}\n",
                    t.estimator,
                    t.particles,
                    t.seed,
                    t.kidnap_tick.map_or(String::new(), |k| k.to_string()),
                    t.steps_to_converge.map_or(String::new(), |k| k.to_string()),
                    t.recovery_ratio
                ));
            }
            csv
        })?;
        let protocol_json = json!({
            "start": "filter initialized around the true pose (initial_cov_*), the robot explores",
            "kidnap": format!("after {} filter updates, to a random free pose at least {} m away; the filter is not told", protocol.tracked_updates_before_kidnap, protocol.kidnap_distance),
            "converged": format!("within {} m and {} rad of the truth for {} consecutive updates", protocol.converged_position, protocol.converged_heading, protocol.converged_updates),
            "steps_to_converge": "filter updates from the kidnap to the first of those updates",
            "limit_updates": protocol.limit_updates,
            "recovery_ratio": "mean fraction of particles injected or regenerated per update between the kidnap and convergence (Table 5.2)",
            "trials": trials,
            "seeds": format!("{seed} .. {}", seed + trials - 1),
        });
        if out.print_json(&json!({
            "experiment": "kidnap",
            "map": {"name": name, "width": grid.width(), "height": grid.height(), "resolution": grid.resolution()},
            "parameters": serde_json::to_value(&base)?,
            "protocol": protocol_json,
            "results": results,
        }))? {
            return Ok(());
        }
        writeln!(
            out,
            "SLAM Lab: kidnapped robot on {name}, {trials} trials per row, seeds from {seed}"
        )?;
        writeln!(out)?;
        writeln!(
            out,
            "{:<8} {:>9} {:>8} {:>8} {:>8} {:>8} {:>9} {:>10}",
            "filter", "particles", "median", "mean", "p90", "all", "failures", "recovery"
        )?;
        let f = |v: Option<f64>| v.map_or("-".to_owned(), |v| format!("{v:.1}"));
        for r in &results {
            writeln!(
                out,
                "{:<8} {:>9} {:>8} {:>8} {:>8} {:>8} {:>9} {:>9.2}%",
                r.estimator,
                r.particles,
                f(r.steps_to_converge.median),
                f(r.steps_to_converge.mean),
                f(r.steps_to_converge.p90),
                f(r.median_all_trials),
                r.failures,
                100.0 * r.recovery_ratio
            )?;
        }
        writeln!(out)?;
        writeln!(
            out,
            "steps: filter updates from the kidnap until within {} m and {} rad for {} consecutive updates; limit {} updates. median, mean, p90: over the converged trials; all: median over all trials, a failure counted as the limit.",
            protocol.converged_position,
            protocol.converged_heading,
            protocol.converged_updates,
            protocol.limit_updates
        )?;
        Ok(())
    }
}
