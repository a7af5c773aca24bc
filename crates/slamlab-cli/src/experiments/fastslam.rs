//! `slamlab experiment fastslam`: FastSLAM 1.0 or 2.0 over particle counts.
//!
//! ```text
//! slamlab experiment fastslam --version 1|2 --particles 5,10,30,100 --trials 20 --seed 1 --json
//! ```

use super::{scenario_args, steps_arg, trials_arg};
use crate::args;
use crate::command::Experiment;
use crate::flags;
use crate::lessons::landmark::{refuse_manual, scenario_from};
use crate::output::{Output, csv_arg, progress_bar};
use anyhow::{Result, bail};
use clap::{ArgMatches, Command};
use slamlab_core::particle::FastSlamVersion;
use slamlab_sim::landmark_slam::fastslam::fastslam_experiment;
use std::io::Write;

/// The largest particle count the particle experiments accept.
const MAX_PARTICLES: usize = 10_000;

/// FastSLAM's errors against its particle count.
pub struct FastSlam;

impl Experiment for FastSlam {
    fn command(&self) -> Command {
        Command::new("fastslam")
            .about("FastSLAM 1.0 or 2.0 on the landmark world: robot and landmark RMSE and N_eff per particle count")
            .arg(
                args::choice(
                    "version",
                    &["1", "2"],
                    "FastSLAM 1.0 (motion-model proposal) or 2.0 (measurement-informed proposal)",
                )
                .default_value("2"),
            )
            .arg(
                args::list("particles", "comma-separated particle counts (1 .. 10000)")
                    .default_value("5,10,30,100"),
            )
            .arg(trials_arg("20"))
            .arg(steps_arg())
            .arg(csv_arg(
                "write the RMSE and N_eff per particle count as CSV into DIR",
            ))
            .args(scenario_args())
    }

    fn run(&self, matches: &ArgMatches, out: &mut Output) -> Result<()> {
        let scenario = scenario_from(matches, &["particles"])?;
        refuse_manual(&scenario)?;
        let version = match matches.get_one::<String>("version").map(String::as_str) {
            Some("1") => FastSlamVersion::V1,
            _ => FastSlamVersion::V2,
        };
        let counts = parse_counts(
            matches
                .get_one::<String>("particles")
                .map_or("5,10,30,100", String::as_str),
        )?;
        let trials = matches.get_one::<u64>("trials").copied().unwrap_or(20) as usize;
        let steps = matches.get_one::<u64>("steps").copied().unwrap_or(200);
        let result = fastslam_experiment(
            &scenario,
            version,
            &counts,
            trials,
            steps,
            progress_bar("fastslam"),
        )?;
        out.write_csv(
            &format!(
                "fastslam{}-seed{}-trials{trials}-steps{steps}.csv",
                version.number(),
                scenario.seed
            ),
            || {
                let mut csv = String::from(
                    "particles,robot_rmse_mean,robot_rmse_std,landmark_rmse_mean,landmark_rmse_std,mean_n_eff\n",
                );
                for r in &result.results {
                    csv.push_str(&format!(
                        "{},{},{},{},{},{}\n",
                        r.particles,
                        r.robot_rmse.mean,
                        r.robot_rmse.std,
                        r.landmark_rmse.mean,
                        r.landmark_rmse.std,
                        r.mean_n_eff
                    ));
                }
                csv
            },
        )?;
        if out.print_json(&result)? {
            return Ok(());
        }
        writeln!(
            out,
            "SLAM Lab experiment fastslam: FastSLAM {}.0, {trials} trials of {steps} ticks ({:.1} s) from seed {}",
            version.number(),
            steps as f64 * scenario.dt,
            scenario.seed
        )?;
        writeln!(out)?;
        out.settings(&result.settings, 32)?;
        out.parameters(&result.parameters, 32)?;
        writeln!(out)?;
        writeln!(
            out,
            "{:>9} {:>20} {:>20} {:>10}",
            "particles", "robot RMSE (m)", "landmark RMSE (m)", "mean N_eff"
        )?;
        for r in &result.results {
            writeln!(
                out,
                "{:>9} {:>11.3} ± {:<6.3} {:>11.3} ± {:<6.3} {:>10.2}",
                r.particles,
                r.robot_rmse.mean,
                r.robot_rmse.std,
                r.landmark_rmse.mean,
                r.landmark_rmse.std,
                r.mean_n_eff
            )?;
        }
        writeln!(out)?;
        writeln!(
            out,
            "mean ± standard deviation over trials; N_eff after each tick's updates, before resampling."
        )?;
        Ok(())
    }
}

/// A comma-separated list of particle counts, each in 1 ..= [`MAX_PARTICLES`].
pub(super) fn parse_counts(text: &str) -> Result<Vec<usize>> {
    let mut counts = Vec::new();
    for part in flags::items(text) {
        let Ok(n) = part.parse::<usize>() else {
            bail!("--particles: '{part}' is not a whole number");
        };
        if n == 0 {
            bail!("--particles: a particle filter needs at least one particle (got 0)");
        }
        if n > MAX_PARTICLES {
            bail!("--particles: {n} is more than the {MAX_PARTICLES} this command runs");
        }
        counts.push(n);
    }
    if counts.is_empty() {
        bail!("--particles: give at least one count, e.g. 5,10,30,100");
    }
    Ok(counts)
}
