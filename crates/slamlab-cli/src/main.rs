//! `slamlab`: SLAM Lab's scenarios and experiments without a window.
//!
//! ```text
//! slamlab run landmark-slam --estimator ekf --steps 200 --seed 1 --json
//! slamlab experiment ekf-vs-ukf --noise-scale 2 --trials 50 --seed 1 --json --csv out/
//! slamlab experiment consistency --estimator ekf,ukf,fej-ekf --trials 50 --steps 200
//! slamlab params
//! slamlab run kidnap --map maze --estimator mcl --particles 2000 --init global --steps 600 --seed 1 --json
//! slamlab experiment kidnap --map maze --particles 500,1000 --estimator amcl,acmcl --trials 20 --seed 1 --json
//! slamlab map info PATH.yaml
//! slamlab map convert IN.yaml OUT.yaml --format png
//! ```
//!
//! Scenario flags have the same names as the lesson's URL parameters, so
//! `slamlab run landmark-slam --seed 7 --landmarks 30` and
//! `index.html?lesson=landmark-slam&seed=7&landmarks=30` are the same run.
//!
//! `slamlab run LESSON` and `slamlab experiment NAME` dispatch through the
//! registries in [`registry`]: a lesson or an experiment is one module (in
//! `lessons/` or `experiments/`, implementing a trait of [`command`]) and one entry
//! there.

mod args;
mod assignment_cmd;
mod command;
mod evaluate_cmd;
mod experiments;
mod flags;
mod graph_cmd;
mod lessons;
mod log_cmd;
mod map;
mod output;
mod registry;
mod scenario_file;
mod trajectory_out;

use anyhow::Result;
use clap::{Arg, ArgMatches, Command};
use slamlab_sim::params;
use std::ffi::OsString;
use std::io::Write;

/// A parameter table's rows (`params::describe`).
type Describe = fn() -> Vec<[String; 5]>;

/// Lessons with a parameter table (`slamlab params --lesson ID`): those the CLI
/// runs, and the app's interactive ones.
const PARAM_TABLES: &[(&str, Describe)] = &[
    (
        "landmark-slam",
        params::describe::<slamlab_sim::LandmarkScenario>,
    ),
    (
        "kidnap",
        params::describe::<slamlab_sim::kidnap::MclScenario>,
    ),
    (
        "mapping",
        params::describe::<slamlab_sim::mapping::MappingScenario>,
    ),
    (
        "cartographer",
        params::describe::<slamlab_sim::cartographer::session::CartographerScenario>,
    ),
    (
        "pose-graph",
        params::describe::<slamlab_sim::pose_graph::session::PoseGraphScenario>,
    ),
    (
        "resampling",
        params::describe::<slamlab_sim::resampling::session::LabScenario>,
    ),
    (
        "visual-odometry",
        params::describe::<slamlab_sim::visual_odometry::VoScenario>,
    ),
    (
        "fusion",
        params::describe::<slamlab_sim::fusion::params::FusionLessonScenario>,
    ),
    (
        "filters",
        params::describe::<slamlab_sim::filters::session::FiltersScenario>,
    ),
];

fn cli() -> Command {
    Command::new("slamlab")
        .about(
            "SLAM Lab: run the lessons' scenarios and reproduce the sources' experiments headless",
        )
        .version(env!("CARGO_PKG_VERSION"))
        .subcommand_required(true)
        .arg_required_else_help(true)
        .subcommand(registry::run_command())
        .subcommand(registry::experiment_command_line())
        .subcommand(map::command())
        .subcommand(graph_cmd::command())
        .subcommand(log_cmd::command())
        .subcommand(evaluate_cmd::command())
        .subcommand(assignment_cmd::export_command())
        .subcommand(assignment_cmd::grade_command())
        .subcommand(
            Command::new("params")
                .about("List a lesson's parameters (the URL's and the flags' names) with their units, ranges and defaults")
                .arg(
                    Arg::new("lesson")
                        .long("lesson")
                        .value_parser(PARAM_TABLES.iter().map(|(id, _)| *id).collect::<Vec<_>>())
                        .default_value("landmark-slam")
                        .help("the lesson id"),
                ),
        )
}

/// `slamlab params --lesson ID`: the lesson's parameter table (the URL's names).
fn list_params(matches: &ArgMatches) -> Result<()> {
    let lesson = matches
        .get_one::<String>("lesson")
        .map_or("landmark-slam", String::as_str);
    let rows = PARAM_TABLES
        .iter()
        .find(|(id, _)| *id == lesson)
        .map_or_else(Vec::new, |(_, describe)| describe());
    let mut out = std::io::stdout().lock();
    let width = rows.iter().map(|r| r[0].len()).max().unwrap_or(16).max(16);
    writeln!(
        out,
        "{:<width$} {:<8} {:<22} {:<12} meaning",
        "name", "unit", "range", "default"
    )?;
    for [name, unit, range, default, help] in rows {
        writeln!(
            out,
            "{name:<width$} {unit:<8} {range:<22} {default:<12} {help}"
        )?;
    }
    Ok(())
}

fn main() -> std::process::ExitCode {
    let args: Vec<OsString> = std::env::args_os().collect();
    let args = match scenario_file::expand_scenario_file(args) {
        Ok(args) => args,
        Err(e) => {
            eprintln!("error: {e:#}");
            return std::process::ExitCode::FAILURE;
        }
    };
    let matches = cli().get_matches_from(&args);
    let result = match matches.subcommand() {
        Some(("map", m)) => map::run(m),
        Some(("graph", m)) => graph_cmd::run(m),
        Some(("log", m)) => log_cmd::run(m),
        Some(("evaluate", m)) => evaluate_cmd::run(m, &mut std::io::stdout().lock()),
        Some(("export-inputs", m)) => assignment_cmd::run_export(m, &mut std::io::stdout().lock()),
        Some(("grade", m)) => assignment_cmd::run_grade(m, &mut std::io::stdout().lock()),
        Some(("run", m)) => registry::run_lesson(m, &mut std::io::stdout().lock()),
        Some(("experiment", m)) => registry::run_experiment(m, &mut std::io::stdout().lock()),
        Some(("params", m)) => list_params(m),
        _ => Ok(()),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        // The reader went away (`slamlab params | head`): nothing more to say.
        Err(e)
            if e.chain().any(|cause| {
                cause
                    .downcast_ref::<std::io::Error>()
                    .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
            }) =>
        {
            std::process::ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_command_line_is_well_formed() {
        cli().debug_assert();
    }

    #[test]
    fn flags_use_the_url_parameter_names() {
        let m = cli().try_get_matches_from([
            "slamlab",
            "run",
            "landmark-slam",
            "--landmarks",
            "7",
            "--fov-deg",
            "90",
            "--w-deg",
            "-10",
        ]);
        let m = m.unwrap_or_else(|e| panic!("{e}"));
        let Some(("run", Some(("landmark-slam", sub)))) =
            m.subcommand().map(|(n, m)| (n, m.subcommand()))
        else {
            panic!("no run landmark-slam")
        };
        let s = lessons::landmark::scenario_from(sub, &[]).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.landmarks, 7);
        assert!((s.fov.to_degrees() - 90.0).abs() < 1e-9);
        let m =
            cli().try_get_matches_from(["slamlab", "run", "landmark-slam", "--range-std", "nan"]);
        let m = m.unwrap_or_else(|e| panic!("{e}"));
        let Some(("run", Some(("landmark-slam", sub)))) =
            m.subcommand().map(|(n, m)| (n, m.subcommand()))
        else {
            panic!("no run landmark-slam")
        };
        assert!(lessons::landmark::scenario_from(sub, &[]).is_err());
    }
}
