//! `slamlab run landmark-slam`: EKF/UKF/FastSLAM on the landmark world, headless.
//!
//! ```text
//! slamlab run landmark-slam --estimator ekf --steps 200 --seed 1 --json
//! slamlab run landmark-slam --data MRCLAM_Dataset6.zip --robot 1 --mode localization
//! ```

use crate::args;
use crate::command::RunLesson;
use crate::flags;
use crate::output::Output;
use anyhow::{Context, Result, bail};
use clap::{Arg, ArgMatches, Command};
use slamlab_sim::io::landmark_data::{LandmarkData, read_path};
use slamlab_sim::landmark_slam::export;
use slamlab_sim::landmark_slam::presets;
use slamlab_sim::landmark_slam::summary::{RunSummary, run_headless, run_recorded};
use slamlab_sim::world::recorded::RecordedWorld;
use slamlab_sim::{LandmarkScenario, LandmarkSession};
use std::io::Write;
use std::sync::Arc;

/// The landmark lesson's run.
pub struct LandmarkSlam;

impl RunLesson for LandmarkSlam {
    fn command(&self) -> Command {
        Command::new("landmark-slam")
            .about("EKF-, UKF- and FastSLAM on the landmark world: errors, NEES and NIS")
            .arg(
                args::whole("steps", 0..=1_000_000, "number of simulation ticks")
                    .default_value("200"),
            )
            .arg(data_arg())
            .args(scenario_args(&[]))
            .arg(crate::trajectory_out::arg())
    }

    fn run(&self, matches: &ArgMatches, out: &mut Output) -> Result<()> {
        let steps = matches.get_one::<u64>("steps").copied().unwrap_or(200);
        let (session, summary) = match data_from(matches)? {
            Some(data) => {
                let scenario = scenario_for_data(matches, &[], &data)?;
                let world = recorded_world(&data, &scenario)?;
                // A data set runs to its end unless --steps says otherwise.
                let steps = flags::given(matches, "steps").then_some(steps);
                run_recorded(scenario, world, steps)
            }
            None => {
                let scenario = scenario_from(matches, &[])?;
                check_runnable(&scenario)?;
                run_headless(scenario, steps)
            }
        };
        crate::trajectory_out::write(
            matches,
            &self.id(),
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

/// `--data PATH`: a recorded data set instead of the simulated world.
pub fn data_arg() -> Arg {
    args::named(
        "data",
        "PATH",
        "replay a data set instead of the simulated world: the UTIAS MRCLAM zip (or a folder \
             or one of its .dat files), the Freiburg course's sensor_data.dat (world.dat beside \
             it), or Victoria Park's folder or inputs.dat; the data set's preset applies first, \
             the flags on top",
    )
}

/// The data set `--data` names, read (or `None` without the flag).
pub fn data_from(matches: &ArgMatches) -> Result<Option<LandmarkData>> {
    let Some(path) = matches.get_one::<String>("data") else {
        return Ok(None);
    };
    read_path(std::path::Path::new(path))
        .map(Some)
        .map_err(|e| anyhow::anyhow!("--data {path}: {e}"))
}

/// The landmark scenario for `data`: its preset, then the flags given (but
/// those in `skip`).
pub fn scenario_for_data(
    matches: &ArgMatches,
    skip: &[&str],
    data: &LandmarkData,
) -> Result<LandmarkScenario> {
    let seed = LandmarkScenario::default().seed;
    let base = presets::scenario(presets::for_data(data.kind()), seed).unwrap_or_default();
    flags::scenario_from_base(matches, skip, base)
}

/// The world of `data` for `scenario` (its robot, for MRCLAM).
pub fn recorded_world(
    data: &LandmarkData,
    scenario: &LandmarkScenario,
) -> Result<Arc<RecordedWorld>> {
    RecordedWorld::from_data(data, scenario.robot)
        .map(Arc::new)
        .map_err(|e| anyhow::anyhow!("--robot {}: {e}", scenario.robot))
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
        "SLAM Lab: {} — {} ticks ({:.1} s {}), seed {}",
        summary.lesson,
        summary.steps,
        summary.duration_s,
        if summary.data.is_some() {
            "of data"
        } else {
            "simulated"
        },
        summary.seed
    )?;
    if let Some(data) = &summary.data {
        writeln!(
            out,
            "data: {} ({} of {} steps played)\n      {}\n      cite: {}",
            data.name, data.steps_played, data.steps_total, data.title, data.citation
        )?;
    }
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
    // Recorded data without a true path has no robot errors to show.
    let no_truth = summary.data.as_ref().is_some_and(|d| !d.has_truth);
    let robot = |v: f64| {
        if no_truth {
            "-".to_owned()
        } else {
            format!("{v:.4}")
        }
    };
    for f in &summary.filters {
        writeln!(
            out,
            "{:<8} {:>14} {:>14} {:>16} {:>10} {:>10} {:>10}",
            f.name,
            robot(f.robot_rmse),
            robot(f.robot_error_final),
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
