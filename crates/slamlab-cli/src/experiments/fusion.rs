//! `slamlab experiment fusion`: thesis `002` Table 5.3 on seeded simulated drives.
//!
//! ```text
//! slamlab experiment fusion --trials 6 --seed 1 --json --csv out/
//! ```

use super::{landmark_flags_but_seed, seed_arg};
use crate::args;
use crate::command::{Experiment, Refusal};
use crate::output::{Output, csv_arg, progress_bar};
use anyhow::Result;
use clap::{ArgMatches, Command};
use slamlab_sim::fusion::{
    FusionMode, FusionScenario, THESIS_TABLE_5_3, fusion_experiment, run_modes, simulate,
};
use std::fmt::Write as _;
use std::io::Write;

/// Sensor fusion's three modes against the simulator's truth.
pub struct Fusion;

impl Experiment for Fusion {
    fn command(&self) -> Command {
        Command::new("fusion")
            .about("Sensor fusion, differential against relative against odometry only (thesis 002 Table 5.3)")
            .args(seed_arg())
            .arg(
                args::whole(
                    "trials",
                    1..=100_000,
                    "seeded drives (Table 5.3 has six); trial i uses seed + i",
                )
                .default_value("6"),
            )
            .arg(csv_arg(
                "write the first drive's error per mode and axis with the filter's 2σ as CSV into DIR",
            ))
    }

    fn refusals(&self) -> Vec<Refusal> {
        vec![
            Refusal {
                flags: landmark_flags_but_seed(&[]),
                reason: |flag| {
                    format!(
                        "--{flag} is a landmark-scenario parameter; the fusion experiment takes only --seed, --trials, --json and --csv"
                    )
                },
            },
            Refusal {
                flags: vec!["noise-scale", "steps"],
                reason: |flag| format!("--{flag} does not apply to the fusion experiment"),
            },
        ]
    }

    /// `--trials` drives from `--seed`, each fused as `_differential`, `_relative`
    /// and odometry only.
    fn run(&self, matches: &ArgMatches, out: &mut Output) -> Result<()> {
        let seed = match matches.get_one::<String>("seed") {
            None => 1,
            Some(text) => text
                .trim()
                .parse::<u64>()
                .map_err(|_| anyhow::anyhow!("--seed '{text}' is not a whole number 0 or more"))?,
        };
        let trials = matches.get_one::<u64>("trials").copied().unwrap_or(6) as usize;
        let template = FusionScenario {
            seed,
            ..FusionScenario::default()
        };
        let result = fusion_experiment(&template, trials, seed, progress_bar("fusion"))?;
        out.write_csv(&format!("fusion-seed{seed}-series.csv"), || {
            series_csv(&template)
        })?;
        if out.print_json(&result)? {
            return Ok(());
        }
        writeln!(
            out,
            "SLAM Lab experiment fusion (thesis 002 Table 5.3): {trials} seeded drives of {} s from seed {seed}",
            template.drive.duration
        )?;
        out.parameter_paragraph(&result.parameters, 32)?;
        writeln!(
            out,
            "{:<8} {:>6}  {:<14} {:>9} {:>9} {:>11}",
            "trial", "seed", "mode", "x [m]", "y [m]", "yaw [rad]"
        )?;
        let row = |out: &mut Output,
                   trial: &str,
                   seed: &str,
                   mode: &str,
                   r: &slamlab_sim::fusion::Rmse| {
            writeln!(
                out,
                "{trial:<8} {seed:>6}  {mode:<14} {:>9.4} {:>9.4} {:>11.5}",
                r.x, r.y, r.yaw
            )
        };
        for (i, t) in result.trials.iter().enumerate() {
            let label = format!("Trial{}", i + 1);
            row(
                out,
                &label,
                &t.seed.to_string(),
                "differential",
                &t.differential,
            )?;
            row(out, "", "", "relative", &t.relative)?;
            row(out, "", "", "odometry", &t.odometry)?;
        }
        let a = &result.average;
        row(out, "Average", "", "differential", &a.differential)?;
        row(out, "", "", "relative", &a.relative)?;
        row(out, "", "", "odometry", &a.odometry)?;
        writeln!(out)?;
        let thesis = THESIS_TABLE_5_3[6];
        writeln!(
            out,
            "Thesis Table 5.3 average (Jackal, RTAB-Map, VICON): differential {:.4} {:.4} {:.5}; relative {:.4} {:.4} {:.5}",
            thesis[0], thesis[1], thesis[2], thesis[3], thesis[4], thesis[5]
        )?;
        writeln!(
            out,
            "RMSE over the fused estimate sampled at {} Hz against the simulator's truth; odometry = wheel odometry and IMU only (no SLAM pose).",
            template.output_rate
        )?;
        Ok(())
    }
}

/// The first trial's error series per mode with the filter's 2σ, as CSV.
fn series_csv(template: &FusionScenario) -> String {
    let mut text = String::from("t");
    let modes = FusionMode::TABLE;
    let Ok(log) = simulate(template) else {
        return text;
    };
    let Ok(runs) = run_modes(template, &log, &modes) else {
        return text;
    };
    for m in modes {
        for k in ["x", "y", "yaw"] {
            let _ = write!(text, ",{0}_error_{k},{0}_2sigma_{k}", m.name());
        }
    }
    text.push('\n');
    let n = runs.iter().map(|r| r.samples().len()).min().unwrap_or(0);
    for i in 0..n {
        let _ = write!(text, "{:.4}", runs[0].samples()[i].t);
        for r in &runs {
            let s = &r.samples()[i];
            for k in 0..3 {
                let _ = write!(text, ",{:.6},{:.6}", s.error[k], 2.0 * s.sigma[k]);
            }
        }
        text.push('\n');
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_series_csv_has_an_error_and_a_2_sigma_column_per_mode_and_axis() {
        let scenario = FusionScenario {
            drive: slamlab_sim::fusion::DriveParams {
                duration: 2.0,
                ..Default::default()
            },
            ..FusionScenario::default()
        };
        let csv = series_csv(&scenario);
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        assert_eq!(header.len(), 1 + 3 * 3 * 2);
        assert_eq!(header[1], "differential_error_x");
        assert_eq!(header[18], "odometry_2sigma_yaw");
        // 2 s at 30 Hz, both ends: 61 rows.
        assert_eq!(lines.count(), 61);
    }
}
