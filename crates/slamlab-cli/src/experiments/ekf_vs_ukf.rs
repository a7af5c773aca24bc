//! `slamlab experiment ekf-vs-ukf`: thesis `000` Sec. 3.4.3, Experiments 1 and 2.
//!
//! ```text
//! slamlab experiment ekf-vs-ukf --noise-scale 2 --trials 50 --seed 1 --json --csv out/
//! ```

use super::{landmark_flags_but_seed, noise_scale_arg, seed_arg, trials_arg};
use crate::command::{Experiment, Refusal};
use crate::lessons::landmark::scenario_from;
use crate::output::{Output, csv_arg, progress_bar};
use anyhow::{Result, bail};
use clap::{ArgMatches, Command};
use slamlab_sim::landmark_slam::experiment;
use std::io::Write;

/// EKF against UKF on the thesis's fixed scenario.
pub struct EkfVsUkf;

impl Experiment for EkfVsUkf {
    fn command(&self) -> Command {
        Command::new("ekf-vs-ukf")
            .about("EKF against UKF on the thesis's fixed scenario (thesis 000 Sec. 3.4.3, Experiments 1 and 2)")
            .arg(noise_scale_arg())
            .arg(trials_arg("50"))
            .args(seed_arg())
            .arg(csv_arg(
                "write the per-step errors as CSV into DIR (thesis Fig. 3.4 / 3.6)",
            ))
    }

    fn refusals(&self) -> Vec<Refusal> {
        vec![
            // The thesis's experiments fix their scenario: only the seed may be chosen.
            Refusal {
                flags: landmark_flags_but_seed(&["particles"]),
                reason: |flag| {
                    format!(
                        "--{flag} sets a scenario parameter; ekf-vs-ukf runs the thesis's fixed scenario (only --seed, --trials, --noise-scale). Use `slamlab experiment consistency` for your own scenario."
                    )
                },
            },
            Refusal {
                flags: vec!["steps"],
                reason: |_| {
                    format!(
                        "--steps belongs to consistency; ekf-vs-ukf runs the thesis's {} iterations",
                        experiment::STEPS
                    )
                },
            },
        ]
    }

    fn run(&self, matches: &ArgMatches, out: &mut Output) -> Result<()> {
        let seed = scenario_from(matches, &["particles"])?.seed;
        let noise_scale = matches
            .get_one::<f64>("noise-scale")
            .copied()
            .unwrap_or(1.0);
        if !(noise_scale.is_finite() && (0.0..=20.0).contains(&noise_scale)) {
            bail!("--noise-scale {noise_scale}: expected a number between 0 and 20");
        }
        if noise_scale == 0.0 {
            bail!(
                "--noise-scale 0 would give the filters zero control noise; use a small positive value"
            );
        }
        let trials = matches.get_one::<u64>("trials").copied().unwrap_or(50) as usize;
        let result = experiment::ekf_vs_ukf(noise_scale, trials, seed, progress_bar("ekf-vs-ukf"));
        out.write_csv(
            &format!("ekf-vs-ukf-noise{noise_scale}-seed{seed}-trials{trials}.csv"),
            || {
                let dt = experiment::ekf_vs_ukf_scenario(noise_scale, seed).dt;
                experiment::series_csv(&result, dt)
            },
        )?;
        if out.print_json(&result)? {
            return Ok(());
        }
        writeln!(
            out,
            "SLAM Lab experiment ekf-vs-ukf (thesis 000 Sec. 3.4.3), control noise x{noise_scale}, {trials} trials from seed {seed}"
        )?;
        out.parameter_paragraph(&result.parameters, 32)?;
        writeln!(
            out,
            "{:<6} {:>20} {:>20} {:>20} {:>20} {:>10} {:>9} {:>14}",
            "filter",
            "robot MSE m²",
            "landmark MSE m²",
            "final robot m²",
            "final landmark m²",
            "NEES",
            "diverged",
            "worst final m"
        )?;
        for f in &result.filters {
            let pm = |m: f64, s: f64| format!("{m:.4} ± {s:.4}");
            writeln!(
                out,
                "{:<6} {:>20} {:>20} {:>20} {:>20} {:>10.3} {:>9} {:>14.3}",
                f.name,
                pm(f.robot_mse, f.robot_mse_std),
                pm(f.landmark_mse, f.landmark_mse_std),
                pm(f.robot_mse_final, f.robot_mse_final_std),
                pm(f.landmark_mse_final, f.landmark_mse_final_std),
                f.nees_mean,
                f.diverged,
                f.robot_error_final_max
            )?;
        }
        writeln!(out)?;
        writeln!(
            out,
            "MSE: mean over trials of the time-averaged squared position error (± std across trials). Diverged: final robot error > {} m; worst final: the largest final robot error of any trial.",
            experiment::DIVERGED_ERROR
        )?;
        Ok(())
    }
}
