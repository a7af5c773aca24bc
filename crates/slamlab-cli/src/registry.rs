//! The lessons `slamlab run` runs and the experiments `slamlab experiment`
//! reproduces: the one module that names them all. Each is one module implementing
//! [`RunLesson`] or [`Experiment`] (the traits live in [`crate::command`], which
//! imports none of them, so imports run one way: `main -> registry -> {lessons,
//! experiments} -> command`) and one entry in [`LESSONS`] or [`EXPERIMENTS`]: its
//! flags become the
//! subcommand's (`slamlab run kidnap --help` lists exactly its own), and the
//! shared `--json`, `--csv`, progress bars and refusals come from here and from
//! [`crate::output`].

use crate::args;
use crate::command::{Experiment, RunLesson};
use crate::experiments;
use crate::lessons;
use crate::output::{self, Output};
use anyhow::{Result, bail};
use clap::{Arg, ArgMatches, Command};
use std::io::Write;

/// The lessons `slamlab run` runs.
pub static LESSONS: &[&dyn RunLesson] = &[
    &lessons::landmark::LandmarkSlam,
    &lessons::kidnap::Kidnap,
    &lessons::mapping::Mapping,
    &lessons::cartographer::Cartographer,
    &lessons::visual_odometry::VisualOdometry,
];

/// The experiments, in the order `slamlab experiment --help` lists them.
pub static EXPERIMENTS: &[&dyn Experiment] = &[
    &experiments::ekf_vs_ukf::EkfVsUkf,
    &experiments::consistency::Consistency,
    &experiments::fastslam::FastSlam,
    &experiments::real_data::RealData,
    &experiments::grid_fastslam::GridFastSlam,
    &experiments::resampling::Resampling,
    &experiments::fusion::Fusion,
    &experiments::kidnap::Kidnap,
    &experiments::krp::Krp,
    &experiments::laser_slam::LaserSlam,
    &experiments::pose_graph::PoseGraph,
    &experiments::unscented::Unscented,
    &experiments::two_view::TwoView,
];

/// Looks a lesson up by id.
pub fn lesson(id: &str) -> Option<&'static dyn RunLesson> {
    LESSONS.iter().copied().find(|l| l.id() == id)
}

/// `--scenario FILE` (read before clap parses, by
/// [`crate::scenario_file::expand_scenario_file`]; the argument is here for `--help`).
pub fn scenario_file_arg() -> Arg {
    args::file(
        "scenario",
        "a scenario the app exported (Export → Scenario as JSON): its parameters, under the flags given here",
    )
}

/// A lesson's subcommand as `slamlab run` has it.
pub fn lesson_command(lesson: &dyn RunLesson) -> Command {
    lesson
        .command()
        .arg(output::json_arg())
        .arg(scenario_file_arg())
}

/// `slamlab run`, with one subcommand per lesson.
pub fn run_command() -> Command {
    let ids: Vec<String> = LESSONS.iter().map(|l| l.id()).collect();
    Command::new("run")
        .about("Run a lesson's scenario and print its metrics")
        .long_about(format!(
            "Run a lesson's scenario and print its metrics.\n\n\
             `slamlab run --scenario FILE` runs a scenario the app exported, of any of these \
             lessons: {}; flags given beside the file win over its values.",
            ids.join(", ")
        ))
        .subcommand_required(true)
        .arg_required_else_help(true)
        .disable_help_subcommand(true)
        .subcommand_value_name("LESSON")
        .subcommand_help_heading("Lessons")
        .subcommands(LESSONS.iter().map(|l| lesson_command(*l)))
}

/// An experiment's subcommand: its own flags, `--json`, and (hidden) every other
/// experiment's flag, so that giving one is refused with the reason rather than
/// a parse error.
fn experiment_command(experiment: &dyn Experiment) -> Command {
    let mut command = experiment.command().arg(output::json_arg());
    for arg in foreign_args(experiment) {
        command = command.arg(arg);
    }
    command
}

/// The flags of the other experiments that `experiment` does not have itself,
/// hidden, without defaults, taking any value.
fn foreign_args(experiment: &dyn Experiment) -> Vec<Arg> {
    let own = experiment.command().arg(output::json_arg());
    let mut args: Vec<Arg> = Vec::new();
    let others = EXPERIMENTS
        .iter()
        .map(|e| e.command())
        .filter(|c| c.get_name() != own.get_name());
    for other in others {
        for arg in other.get_arguments() {
            let id = arg.get_id().as_str();
            // The same flag: the same id, or the same long name under another id
            // (real-data's list `estimators` is `--estimator`, as kidnap's one is).
            let same = |a: &Arg| {
                a.get_id() == id || (a.get_long().is_some() && a.get_long() == arg.get_long())
            };
            let taken = own.get_arguments().any(same) || args.iter().any(same);
            if !taken {
                let mut arg = arg
                    .clone()
                    .hide(true)
                    .required(false)
                    .default_value(None)
                    .help_heading(None);
                if arg.get_action().takes_values() {
                    // Any value: the flag is refused for what it is, not for its value.
                    arg = arg.value_parser(clap::builder::ValueParser::os_string());
                }
                args.push(arg);
            }
        }
    }
    args
}

/// The experiments that have flag `id` as their own.
fn owners(id: &str) -> Vec<String> {
    EXPERIMENTS
        .iter()
        .map(|e| e.command())
        .filter(|c| {
            c.get_arguments()
                .any(|a| a.get_id() == id || a.get_long() == Some(id))
        })
        .map(|c| c.get_name().to_owned())
        .collect()
}

/// "a", "a and b", "a, b and c".
fn and_list(words: &[impl AsRef<str>]) -> String {
    let words: Vec<&str> = words.iter().map(AsRef::as_ref).collect();
    match words.as_slice() {
        [] => String::new(),
        [one] => (*one).to_owned(),
        [rest @ .., last] => format!("{} and {last}", rest.join(", ")),
    }
}

/// Refuses the other experiments' flags given to `experiment`: first those it has
/// no message of its own for ("belongs to"), then its own refusals in order.
fn refuse_foreign_flags(experiment: &dyn Experiment, matches: &ArgMatches) -> Result<()> {
    let refusals = experiment.refusals();
    for arg in foreign_args(experiment) {
        let id = arg.get_id().as_str();
        if refusals.iter().any(|r| r.flags.contains(&id)) || !crate::flags::given(matches, id) {
            continue;
        }
        let owners = owners(id);
        bail!(
            "--{id} does not belong to the {} experiment; it belongs to the {} experiment{}",
            experiment.name(),
            and_list(&owners),
            if owners.len() > 1 { "s" } else { "" }
        );
    }
    for refusal in &refusals {
        if let Some(flag) = refusal
            .flags
            .iter()
            .find(|f| crate::flags::given(matches, f))
        {
            bail!("{}", (refusal.reason)(flag));
        }
    }
    Ok(())
}

/// `slamlab experiment`, with one subcommand per experiment.
pub fn experiment_command_line() -> Command {
    Command::new("experiment")
        .about("Reproduce an experiment of the sources, or run many seeded trials of a scenario")
        .subcommand_required(true)
        .arg_required_else_help(true)
        .disable_help_subcommand(true)
        .subcommand_value_name("NAME")
        .subcommand_help_heading("Experiments")
        .subcommands(EXPERIMENTS.iter().map(|e| experiment_command(*e)))
}

/// Runs `slamlab run LESSON ...` (`matches` are `run`'s), printing to `out`.
pub fn run_lesson(matches: &ArgMatches, out: &mut dyn Write) -> Result<()> {
    let Some((id, m)) = matches.subcommand() else {
        return Ok(());
    };
    let Some(lesson) = lesson(id) else {
        bail!("no lesson {id}");
    };
    lesson.run(m, &mut Output::new(m, Box::new(out)))
}

/// Runs `slamlab experiment NAME ...` (`matches` are `experiment`'s), printing
/// to `out`.
pub fn run_experiment(matches: &ArgMatches, out: &mut dyn Write) -> Result<()> {
    let Some((name, m)) = matches.subcommand() else {
        return Ok(());
    };
    let Some(experiment) = EXPERIMENTS.iter().find(|e| e.name() == name) else {
        bail!("no experiment {name}");
    };
    refuse_foreign_flags(*experiment, m)?;
    experiment.run(m, &mut Output::new(m, Box::new(out)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The visible long flags of `command`, sorted.
    fn visible(command: &Command) -> Vec<String> {
        let mut flags: Vec<String> = command
            .get_arguments()
            .filter(|a| !a.is_hide_set())
            .filter_map(|a| a.get_long().map(str::to_owned))
            .collect();
        flags.sort();
        flags
    }

    #[test]
    fn names_are_unique() {
        for (i, l) in LESSONS.iter().enumerate() {
            assert!(LESSONS[..i].iter().all(|o| o.id() != l.id()), "{}", l.id());
        }
        for (i, e) in EXPERIMENTS.iter().enumerate() {
            let name = e.name();
            assert!(EXPERIMENTS[..i].iter().all(|o| o.name() != name), "{name}");
        }
    }

    #[test]
    fn an_experiments_help_lists_exactly_its_own_flags() {
        let line = experiment_command_line();
        for e in EXPERIMENTS {
            let sub = line
                .find_subcommand(e.name())
                .unwrap_or_else(|| panic!("no {}", e.name()));
            let own = e.command().arg(output::json_arg());
            assert_eq!(visible(sub), visible(&own), "{}", e.name());
            // Every other experiment's flag is there, hidden, to be refused.
            for other in EXPERIMENTS {
                for arg in other.command().get_arguments() {
                    assert!(
                        sub.get_arguments().any(|a| a.get_id() == arg.get_id()
                            || (a.get_long().is_some() && a.get_long() == arg.get_long())),
                        "{} lacks --{}",
                        e.name(),
                        arg.get_id()
                    );
                }
            }
        }
        let run = run_command();
        let kidnap = run
            .find_subcommand("kidnap")
            .map(visible)
            .unwrap_or_default();
        let landmark = run
            .find_subcommand("landmark-slam")
            .map(visible)
            .unwrap_or_default();
        assert!(kidnap.contains(&"laser-sigma-hit".to_owned()));
        assert!(!kidnap.contains(&"landmarks".to_owned()));
        assert!(landmark.contains(&"landmarks".to_owned()));
        assert!(landmark.contains(&"scenario".to_owned()));
    }

    /// Runs `slamlab experiment ARGS`, printing nowhere.
    fn experiment(args: &[&str]) -> Result<()> {
        let m = experiment_command_line()
            .no_binary_name(true)
            .try_get_matches_from(args)
            .unwrap_or_else(|e| panic!("{e}"));
        run_experiment(&m, &mut std::io::sink())
    }

    #[test]
    fn another_experiments_flag_is_refused_with_its_owners() {
        let e = experiment(&["fusion", "--loop-closures", "x"]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "--loop-closures does not belong to the fusion experiment; it belongs to the pose-graph experiment"
        );
        let e = experiment(&["kidnap", "--version", "1"]).unwrap_err();
        assert!(
            e.to_string()
                .ends_with("belongs to the fastslam experiment"),
            "{e}"
        );
        // An experiment's own reason wins.
        let e = experiment(&["consistency", "--noise-scale", "2"]).unwrap_err();
        assert!(e.to_string().contains("--v-std"), "{e}");
        assert_eq!(and_list(&["a", "b", "c"]), "a, b and c");
    }

    #[test]
    fn fusion_refuses_landmark_flags_and_bad_seeds_with_their_names() {
        let e = experiment(&["fusion", "--landmarks", "5"]).unwrap_err();
        assert!(e.to_string().contains("--landmarks"), "{e}");
        let e = experiment(&["fusion", "--steps", "5"]).unwrap_err();
        assert!(e.to_string().contains("--steps"), "{e}");
        let e = experiment(&["fusion", "--seed", "-3"]).unwrap_err();
        assert!(e.to_string().contains("--seed '-3'"), "{e}");
    }

    /// Imports run one way: `main -> registry -> {lessons, experiments} -> command`.
    /// No lesson or experiment names the registry or `main`, no lesson names an
    /// experiment, and `command` names none of them.
    #[test]
    fn imports_run_one_way() {
        let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let read = |path: std::path::PathBuf| -> Vec<(String, String)> {
            let files: Vec<std::path::PathBuf> = if path.is_dir() {
                let mut files: Vec<_> = std::fs::read_dir(&path)
                    .into_iter()
                    .flatten()
                    .flatten()
                    .map(|e| e.path())
                    .collect();
                files.sort();
                files
            } else {
                vec![path]
            };
            files
                .into_iter()
                .map(|file| {
                    let text = std::fs::read_to_string(&file).unwrap_or_default();
                    let code: Vec<&str> = text
                        .lines()
                        .filter(|l| !l.trim_start().starts_with("//"))
                        .collect();
                    (file.display().to_string(), code.join("\n"))
                })
                .collect()
        };
        let rules: [(&str, &[&str]); 3] = [
            ("lessons", &["registry", "experiments", "cli"]),
            ("experiments", &["registry", "cli"]),
            ("command.rs", &["registry", "lessons", "experiments", "cli"]),
        ];
        let mut wrong = Vec::new();
        for (part, forbidden) in rules {
            for (file, code) in read(src.join(part)) {
                for name in forbidden {
                    if code.contains(&format!("crate::{name}")) {
                        wrong.push(format!("{file} names crate::{name}"));
                    }
                }
            }
        }
        assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    }
}
