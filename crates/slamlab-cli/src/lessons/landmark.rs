//! `slamlab run landmark-slam`: EKF/UKF/FastSLAM on the landmark world, headless.
//!
//! ```text
//! slamlab run landmark-slam --estimator ekf --steps 200 --seed 1 --json
//! ```

use crate::command::RunLesson;
use crate::flags;
use crate::output::Output;
use anyhow::{Context, Result, bail};
use clap::{Arg, ArgMatches, Command};
use slamlab_sim::landmark_slam::export;
use slamlab_sim::landmark_slam::summary::{RunSummary, run_headless};
use slamlab_sim::{LandmarkScenario, LandmarkSession};
use std::io::Write;

/// The landmark lesson's run.
pub struct LandmarkSlam;

impl RunLesson for LandmarkSlam {
    fn id(&self) -> &'static str {
        "landmark-slam"
    }

    fn about(&self) -> &'static str {
        "EKF-, UKF- and FastSLAM on the landmark world: errors, NEES and NIS"
    }

    fn command(&self) -> Command {
        Command::new(self.id())
            .arg(
                Arg::new("steps")
                    .long("steps")
                    .value_parser(clap::value_parser!(u64).range(0..=1_000_000))
                    .default_value("200")
                    .help("number of simulation ticks"),
            )
            .args(scenario_args(&[]))
            .arg(crate::trajectory_out::arg())
    }

    fn run(&self, matches: &ArgMatches, out: &mut Output) -> Result<()> {
        let steps = matches.get_one::<u64>("steps").copied().unwrap_or(200);
        let scenario = scenario_from(matches, &[])?;
        check_runnable(&scenario)?;
        let (session, summary) = run_headless(scenario, steps);
        crate::trajectory_out::write(
            matches,
            self.id(),
            &export::trajectories(&session),
            &export::landmarks(&session),
        )?;
        if out.json() {
            let first = summary.filters.first();
            let mut value = serde_json::to_value(&summary).context("serializing the summary")?;
            if let Some(obj) = value.as_object_mut() {
                // The first estimator's headline numbers at the top level.
                obj.insert("estimator".into(), first.map(|f| f.name.clone()).into());
                obj.insert("robot_rmse".into(), first.map(|f| f.robot_rmse).into());
                obj.insert(
                    "landmark_rmse".into(),
                    first.and_then(|f| f.landmark_rmse).into(),
                );
                obj.insert("nees_mean".into(), first.and_then(|f| f.nees_mean).into());
            }
            out.print_json(&value)?;
            return Ok(());
        }
        print_summary(out, &summary)
    }
}

/// The landmark scenario's flags (the URL's names), but those in `skip` (a
/// command's own flags of the same names).
pub fn scenario_args(skip: &[&str]) -> Vec<Arg> {
    scenario_args_where(|name| !skip.contains(&name))
}

/// The landmark scenario's flags for which `keep(name)` holds.
pub fn scenario_args_where(keep: impl Fn(&str) -> bool) -> Vec<Arg> {
    flags::table_args::<LandmarkScenario>(keep)
}

/// The landmark scenario from its flags, but those in `skip`; see
/// [`flags::scenario_from`].
pub fn scenario_from(matches: &ArgMatches, skip: &[&str]) -> Result<LandmarkScenario> {
    flags::scenario_from(matches, skip)
}

/// Refuses a hand-driven robot: nobody drives it headless.
pub fn refuse_manual(scenario: &LandmarkScenario) -> Result<()> {
    if matches!(scenario.controller, slamlab_sim::ControllerKind::Manual) {
        bail!("--controller manual has nobody to drive headless; use the circle (--v, --w-deg)");
    }
    Ok(())
}

/// Refuses a scenario that cannot run headless as asked: a hand-driven robot (nobody
/// drives it here), or an estimator that cannot start (its message says why, e.g.
/// UKF parameters with λ + n ≤ 0).
pub fn check_runnable(scenario: &LandmarkScenario) -> Result<()> {
    refuse_manual(scenario)?;
    let session = LandmarkSession::new(scenario.clone());
    if session.filters().len() < scenario.estimators.len() {
        bail!(
            "not every estimator could start: {}",
            session.notices().join("; ")
        );
    }
    Ok(())
}

fn print_summary(out: &mut Output, summary: &RunSummary) -> Result<()> {
    writeln!(
        out,
        "SLAM Lab: {} — {} ticks ({:.1} s simulated), seed {}",
        summary.lesson, summary.steps, summary.duration_s, summary.seed
    )?;
    writeln!(out)?;
    out.parameters(&summary.parameters, 16)?;
    for note in &summary.notices {
        writeln!(out, "note: {note}")?;
    }
    writeln!(out)?;
    let fmt = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |v| format!("{v:.4}"));
    writeln!(
        out,
        "{:<8} {:>14} {:>14} {:>16} {:>10} {:>10} {:>10}",
        "filter",
        "robot RMSE m",
        "final error m",
        "landmark RMSE m",
        "NEES mean",
        "NIS mean",
        "landmarks"
    )?;
    for f in &summary.filters {
        writeln!(
            out,
            "{:<8} {:>14.4} {:>14.4} {:>16} {:>10} {:>10} {:>10}",
            f.name,
            f.robot_rmse,
            f.robot_error_final,
            fmt(f.landmark_rmse),
            fmt(f.nees_mean),
            fmt(f.nis_mean),
            f.landmarks_initialized
        )?;
    }
    writeln!(out)?;
    writeln!(
        out,
        "NEES is the robot-pose normalized estimation error squared (3 dof, expected 3); NIS per update (2 dof, expected 2)."
    )?;
    Ok(())
}
