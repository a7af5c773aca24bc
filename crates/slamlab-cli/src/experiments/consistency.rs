//! `slamlab experiment consistency`: the average NEES over many seeded runs of
//! any landmark scenario.
//!
//! ```text
//! slamlab experiment consistency --estimator ekf,ukf,fej-ekf --trials 50 --steps 200
//! ```

use super::{scenario_args, steps_arg, trials_arg};
use crate::command::{Experiment, Refusal};
use crate::lessons::landmark::{check_runnable, scenario_from};
use crate::output::{Output, csv_arg, progress_bar, table_number};
use anyhow::Result;
use clap::{ArgMatches, Command};
use slamlab_sim::landmark_slam::consistency::ConsistencyStudy;
use slamlab_sim::landmark_slam::experiment;
use std::io::Write;

/// Filter consistency over seeded trials.
pub struct Consistency;

impl Experiment for Consistency {
    fn command(&self) -> Command {
        Command::new("consistency")
            .about("The average NEES over many seeded runs of any landmark scenario, against its 95% band")
            .arg(trials_arg("50"))
            .arg(steps_arg())
            .arg(csv_arg(
                "write the average NEES per tick and its band as CSV into DIR",
            ))
            .args(scenario_args())
    }

    fn refusals(&self) -> Vec<Refusal> {
        vec![Refusal {
            flags: vec!["noise-scale"],
            reason: |_| {
                "--noise-scale belongs to ekf-vs-ukf; for consistency, set --v-std and --w-std-deg"
                    .to_owned()
            },
        }]
    }

    fn run(&self, matches: &ArgMatches, out: &mut Output) -> Result<()> {
        let scenario = scenario_from(matches, &["particles"])?;
        let trials = matches.get_one::<u64>("trials").copied().unwrap_or(50) as usize;
        let steps = matches.get_one::<u64>("steps").copied().unwrap_or(200);
        check_runnable(&scenario)?;
        let mut study = ConsistencyStudy::new(scenario.clone(), trials, steps);
        study.run_to_end(progress_bar("consistency"));
        let result = study.result();
        let estimators: Vec<&str> = scenario.estimators.iter().map(|e| e.name()).collect();
        out.write_csv(
            &format!(
                "consistency-{}-seed{}-trials{trials}-steps{steps}.csv",
                estimators.join("-"),
                scenario.seed
            ),
            || study.series_csv(),
        )?;
        if out.print_json(&result)? {
            return Ok(());
        }
        let [lo, hi] = result.nees_band;
        writeln!(
            out,
            "SLAM Lab experiment consistency: {trials} trials of {steps} ticks ({:.1} s) from seed {}",
            steps as f64 * scenario.dt,
            scenario.seed
        )?;
        out.parameter_paragraph(&result.parameters, 32)?;
        let fmt = |v: Option<f64>| table_number(v, 3, 3);
        writeln!(
            out,
            "{:<10} {:>10} {:>14} {:>13} {:>13} {:>13} {:>9} {:>9}",
            "filter",
            "NEES",
            "first quarter",
            "last quarter",
            "ticks in band",
            "above band",
            "NIS",
            "diverged"
        )?;
        for f in &result.filters {
            writeln!(
                out,
                "{:<10} {:>10} {:>14} {:>13} {:>12.0}% {:>12.0}% {:>9} {:>9}",
                f.name,
                fmt(f.nees_mean),
                fmt(f.nees_first_quarter),
                fmt(f.nees_last_quarter),
                100.0 * f.ticks_in_band,
                100.0 * f.ticks_above_band,
                fmt(f.nis_mean),
                f.diverged
            )?;
        }
        writeln!(out)?;
        writeln!(
            out,
            "NEES: the robot-pose NEES averaged over the {trials} trials at each tick, then over the ticks (or a quarter of them)."
        )?;
        writeln!(
            out,
            "A consistent filter's average lies in [{lo:.3}, {hi:.3}] at 95% of the ticks (3 dof); above the band it is overconfident."
        )?;
        writeln!(
            out,
            "NIS: mean over every landmark update (2 dof: expected 2). Diverged: final robot error > {} m (kept in the averages).",
            experiment::DIVERGED_ERROR
        )?;
        Ok(())
    }
}
