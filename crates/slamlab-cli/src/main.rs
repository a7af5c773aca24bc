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

mod graph_cmd;
mod kidnap;
mod map;

use anyhow::{Context, Result, bail};
use clap::{Arg, ArgAction, ArgMatches, Command};
use slamlab_sim::consistency::ConsistencyStudy;
use slamlab_sim::experiments;
use slamlab_sim::landmark_params::PARAMS;
use slamlab_sim::metrics::{RunSummary, run_headless};
use slamlab_sim::params::{self, Scenario};
use slamlab_sim::scenario_file::ScenarioFile;
use slamlab_sim::{LandmarkScenario, LandmarkSession};
use std::ffi::OsString;
use std::io::{IsTerminal, Write};
use std::path::PathBuf;

mod fusion;
mod particle_experiments;

/// Lessons the CLI can run.
const LESSONS: &[&str] = &["landmark-slam", "kidnap"];

/// Lessons with a parameter table (`slamlab params --lesson ID`): those the CLI
/// runs, and the app's interactive ones.
const PARAM_LESSONS: &[&str] = &[
    "landmark-slam",
    "kidnap",
    "pose-graph",
    "resampling",
    "fusion",
];

/// Experiments the CLI can run.
const EXPERIMENTS: &[&str] = &[
    "ekf-vs-ukf",
    "consistency",
    "fastslam",
    "resampling",
    "fusion",
    "kidnap",
    "pose-graph",
];

/// Landmark parameters that `slamlab experiment` does not take as scenario
/// flags, because an experiment has a flag of that name itself (`--particles`, a
/// list of counts).
const EXPERIMENT_OWN: &[&str] = &["particles"];

/// The landmark scenario's flags, but those in `skip`.
fn scenario_args(skip: &'static [&'static str]) -> Vec<Arg> {
    PARAMS
        .iter()
        .filter(|p| !skip.contains(&p.name))
        .map(|p| {
            let range = format!(" [{}]", p.kind.range_text(", "));
            let default = params::get(&LandmarkScenario::default(), p.name)
                .unwrap_or_else(|| "none".to_owned());
            let unit = if p.unit.is_empty() {
                String::new()
            } else {
                format!(", {}", p.unit)
            };
            Arg::new(p.name)
                .long(p.name)
                .value_name("VALUE")
                .help(format!("{}{unit}{range}; default {default}", p.help))
                .allow_hyphen_values(true)
        })
        .collect()
}

/// `--scenario FILE` (read before clap parses, by [`expand_scenario_file`]; the
/// argument is here for `--help`).
pub(crate) fn scenario_file_arg() -> Arg {
    Arg::new("scenario")
        .long("scenario")
        .value_name("FILE")
        .help("a scenario the app exported (Export → Scenario as JSON): its parameters, under the flags given here")
}

fn cli() -> Command {
    Command::new("slamlab")
        .about(
            "SLAM Lab: run the lessons' scenarios and reproduce the sources' experiments headless",
        )
        .version(env!("CARGO_PKG_VERSION"))
        .subcommand_required(true)
        .arg_required_else_help(true)
        .subcommand(
            Command::new("run")
                .about("Run a lesson's scenario and print its metrics")
                .arg(
                    Arg::new("lesson")
                        .required(true)
                        .value_parser(LESSONS.to_vec())
                        .help("the lesson id"),
                )
                .arg(
                    Arg::new("steps")
                        .long("steps")
                        .value_parser(clap::value_parser!(u64).range(0..=1_000_000))
                        .default_value("200")
                        .help("number of simulation ticks"),
                )
                .arg(
                    Arg::new("json")
                        .long("json")
                        .action(ArgAction::SetTrue)
                        .help("print one JSON object"),
                )
                .arg(scenario_file_arg())
                .args(scenario_args(&[])),
        )
        .subcommand(
            Command::new("experiment")
                .about("Reproduce an experiment: ekf-vs-ukf (thesis 000 Sec. 3.4.3, Experiments 1 and 2) , consistency (average NEES over many seeded runs of any scenario) or pose-graph (thesis 000 Sec. 4.2: EKF-SLAM path, loop closures, optimized graph)")
                .arg(
                    Arg::new("name")
                        .required(true)
                        .value_parser(EXPERIMENTS.to_vec())
                        .help("the experiment"),
                )
                .arg(
                    Arg::new("noise-scale")
                        .long("noise-scale")
                        .value_parser(clap::value_parser!(f64))
                        .default_value("1")
                        .help("ekf-vs-ukf: control-noise multiplier, 1 is Experiment 1, 2 is Experiment 2 (0 .. 20]"),
                )
                .arg(
                    Arg::new("trials")
                        .long("trials")
                        .value_parser(clap::value_parser!(u64).range(1..=100_000))
                        .default_value("50")
                        .help("Monte Carlo trials; trial i uses seed + i"),
                )
                .arg(
                    Arg::new("steps")
                        .long("steps")
                        .value_parser(clap::value_parser!(u64).range(1..=1_000_000))
                        .default_value("200")
                        .help("consistency: ticks per trial (200 ticks of 0.1 s are one lap of the circle)"),
                )
                .arg(Arg::new("json").long("json").action(ArgAction::SetTrue).help("print one JSON object"))
                .args(particle_experiments::args())
                .args(graph_cmd::experiment_args())
                .arg(
                    Arg::new("csv")
                        .long("csv")
                        .value_name("DIR")
                        .value_parser(clap::value_parser!(std::path::PathBuf))
                        .help("write the per-step series as CSV into DIR (ekf-vs-ukf: errors, thesis Fig. 3.4 / 3.6; consistency: average NEES and its band)"),
                )
                .next_help_heading("Scenario (the same names as `run`; ekf-vs-ukf takes only --seed)")
                .args(scenario_args(EXPERIMENT_OWN)),
        )
        .subcommand(map::command())
        .subcommand(graph_cmd::command())
        .subcommand(
            Command::new("params")
                .about("List a lesson's parameters (the URL's and the flags' names) with their units, ranges and defaults")
                .arg(
                    Arg::new("lesson")
                        .long("lesson")
                        .value_parser(PARAM_LESSONS.to_vec())
                        .default_value("landmark-slam")
                        .help("the lesson id"),
                ),
        )
}

/// Builds the scenario from the parameter flags; refuses values it cannot read,
/// and warns (on stderr) about values it had to clamp.
fn scenario_from(matches: &ArgMatches) -> Result<LandmarkScenario> {
    let mut scenario = LandmarkScenario::default();
    // `slamlab experiment` (its positional "name") owns some flags itself.
    let experiment = matches
        .try_get_one::<String>("name")
        .is_ok_and(|v| v.is_some());
    for p in PARAMS {
        if experiment && EXPERIMENT_OWN.contains(&p.name) {
            continue;
        }
        if let Some(value) = matches.get_one::<String>(p.name) {
            match params::set(&mut scenario, p.name, value) {
                None => {}
                Some(issue @ params::ParamIssue::Clamped { .. }) => eprintln!("warning: {issue}"),
                Some(params::ParamIssue::Unreadable {
                    value, expected, ..
                }) => bail!("--{} '{value}' is not {expected}", p.name),
                Some(issue) => bail!("--{}: {issue}", p.name),
            }
        }
    }
    Ok(scenario)
}

/// Refuses a scenario that cannot run headless as asked: a hand-driven robot (nobody
/// drives it here), or an estimator that cannot start (its message says why, e.g.
/// UKF parameters with λ + n ≤ 0).
fn check_runnable(scenario: &LandmarkScenario) -> Result<()> {
    if matches!(scenario.controller, slamlab_sim::ControllerKind::Manual) {
        bail!("--controller manual has nobody to drive headless; use the circle (--v, --w-deg)");
    }
    let session = LandmarkSession::new(scenario.clone());
    if session.filters().len() < scenario.estimators.len() {
        bail!(
            "not every estimator could start: {}",
            session.notices().join("; ")
        );
    }
    Ok(())
}

fn print_summary(out: &mut impl Write, summary: &RunSummary) -> Result<()> {
    writeln!(
        out,
        "SLAM Lab: {} — {} ticks ({:.1} s simulated), seed {}",
        summary.lesson, summary.steps, summary.duration_s, summary.seed
    )?;
    writeln!(out)?;
    writeln!(out, "parameters:")?;
    for (k, v) in &summary.parameters {
        let unit = LandmarkScenario::param(k).map_or("", |p| p.unit);
        let text = v.as_str().map_or_else(|| v.to_string(), str::to_owned);
        writeln!(out, "  {k:<16} {text} {unit}")?;
    }
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

fn run(matches: &ArgMatches) -> Result<()> {
    let steps = matches.get_one::<u64>("steps").copied().unwrap_or(200);
    let scenario = scenario_from(matches)?;
    check_runnable(&scenario)?;
    let (_, summary) = run_headless(scenario, steps);
    let mut out = std::io::stdout().lock();
    if matches.get_flag("json") {
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
        serde_json::to_writer(&mut out, &value).context("writing JSON")?;
        writeln!(out)?;
    } else {
        print_summary(&mut out, &summary)?;
    }
    Ok(())
}

/// `slamlab params --lesson ID`: the lesson's parameter table (the URL's names).
fn list_params(matches: &ArgMatches) -> Result<()> {
    let lesson = matches
        .get_one::<String>("lesson")
        .map_or("landmark-slam", String::as_str);
    let rows = match lesson {
        "kidnap" => params::describe::<slamlab_sim::localization::MclScenario>(),
        "resampling" => params::describe::<slamlab_sim::resampling_lab::LabScenario>(),
        "fusion" => params::describe::<slamlab_sim::fusion::params::FusionLessonScenario>(),
        "pose-graph" => params::describe::<slamlab_sim::pose_graph_lesson::PoseGraphScenario>(),
        _ => params::describe::<LandmarkScenario>(),
    };
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

/// A progress bar on stderr for `total` trials (indicatif): drawn in place on a
/// terminal; in a log (stderr not a terminal) a line every tenth of the way
/// instead. Safe to share between threads.
pub(crate) fn trials_bar(label: &'static str, total: usize) -> indicatif::ProgressBar {
    let bar = if std::io::stderr().is_terminal() {
        indicatif::ProgressBar::new(total as u64)
    } else {
        indicatif::ProgressBar::hidden()
    };
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{prefix} [{bar:30}] {pos}/{len} trials, {elapsed} (about {eta} left)",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_prefix(label);
    bar.set_length(total as u64);
    bar
}

/// Advances `bar` to `done` of `total`, and in a log writes a line every tenth
/// of the way.
pub(crate) fn trials_progress(
    bar: &indicatif::ProgressBar,
    label: &str,
    done: usize,
    total: usize,
) {
    bar.set_position(done as u64);
    if bar.is_hidden()
        && done > 0
        && (done == total || (done * 10 / total.max(1)) != ((done - 1) * 10 / total.max(1)))
    {
        eprintln!("{label}: {done}/{total} trials");
    }
    if done == total {
        bar.finish();
    }
}

/// A progress callback `(done, total)` for the experiments, drawing
/// [`trials_bar`].
fn progress_bar(label: &'static str) -> impl FnMut(usize, usize) {
    let mut bar: Option<indicatif::ProgressBar> = None;
    move |done, total| {
        let bar = bar.get_or_insert_with(|| trials_bar(label, total));
        trials_progress(bar, label, done, total);
    }
}

fn experiment(matches: &ArgMatches) -> Result<()> {
    let name = matches
        .get_one::<String>("name")
        .map_or("ekf-vs-ukf", String::as_str);
    let given = |id: &str| matches.value_source(id) == Some(clap::parser::ValueSource::CommandLine);
    match name {
        "fastslam" => return particle_experiments::fastslam(matches),
        "resampling" => return particle_experiments::resampling(matches),
        "fusion" => return fusion::experiment(matches),
        "pose-graph" => return graph_cmd::pose_graph_experiment(matches),
        _ => {}
    }
    if let Some(flag) = ["version", "particles", "method"]
        .into_iter()
        .find(|f| given(f))
    {
        bail!("--{flag} belongs to the fastslam and resampling experiments");
    }
    if let Some(flag) = ["loop-closures", "solver", "max-iterations"]
        .into_iter()
        .find(|f| given(f))
    {
        bail!("--{flag} belongs to the pose-graph experiment");
    }
    if name == "consistency" {
        if given("noise-scale") {
            bail!(
                "--noise-scale belongs to ekf-vs-ukf; for consistency, set --v-std and --w-std-deg"
            );
        }
        return consistency(matches);
    }
    // The thesis's experiments fix their scenario: only the seed may be chosen.
    if let Some(p) = PARAMS.iter().find(|p| p.name != "seed" && given(p.name)) {
        bail!(
            "--{} sets a scenario parameter; ekf-vs-ukf runs the thesis's fixed scenario (only --seed, --trials, --noise-scale). Use `slamlab experiment consistency` for your own scenario.",
            p.name
        );
    }
    if given("steps") {
        bail!(
            "--steps belongs to consistency; ekf-vs-ukf runs the thesis's {} iterations",
            experiments::STEPS
        );
    }
    let seed = scenario_from(matches)?.seed;
    ekf_vs_ukf(matches, seed)
}

/// With `--csv DIR`: writes `contents()` to `DIR/file_name` (creating DIR) and says so on stderr.
fn write_csv(
    matches: &ArgMatches,
    file_name: &str,
    contents: impl FnOnce() -> String,
) -> Result<()> {
    let Some(dir) = matches.get_one::<std::path::PathBuf>("csv") else {
        return Ok(());
    };
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let path = dir.join(file_name);
    std::fs::write(&path, contents()).with_context(|| format!("writing {}", path.display()))?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

/// With `--json`: prints `value` as one line of JSON and returns `true`.
fn print_json_if_asked(
    matches: &ArgMatches,
    out: &mut impl Write,
    value: &impl serde::Serialize,
) -> Result<bool> {
    if !matches.get_flag("json") {
        return Ok(false);
    }
    serde_json::to_writer(&mut *out, value).context("writing JSON")?;
    writeln!(out)?;
    Ok(true)
}

/// Prints the parameters block of an experiment's readable output.
fn print_parameters(
    out: &mut impl Write,
    parameters: &serde_json::Map<String, serde_json::Value>,
) -> Result<()> {
    writeln!(out, "parameters:")?;
    for (k, v) in parameters {
        let text = v.as_str().map_or_else(|| v.to_string(), str::to_owned);
        let unit = LandmarkScenario::param(k).map_or("", |p| p.unit);
        writeln!(out, "  {k:<32} {text} {unit}")?;
    }
    Ok(())
}

fn consistency(matches: &ArgMatches) -> Result<()> {
    let scenario = scenario_from(matches)?;
    let trials = matches.get_one::<u64>("trials").copied().unwrap_or(50) as usize;
    let steps = matches.get_one::<u64>("steps").copied().unwrap_or(200);
    check_runnable(&scenario)?;
    let mut study = ConsistencyStudy::new(scenario.clone(), trials, steps);
    study.run_to_end(progress_bar("consistency"));
    let result = study.result();
    let estimators: Vec<&str> = scenario.estimators.iter().map(|e| e.name()).collect();
    write_csv(
        matches,
        &format!(
            "consistency-{}-seed{}-trials{trials}-steps{steps}.csv",
            estimators.join("-"),
            scenario.seed
        ),
        || study.series_csv(),
    )?;
    let mut out = std::io::stdout().lock();
    if print_json_if_asked(matches, &mut out, &result)? {
        return Ok(());
    }
    let [lo, hi] = result.nees_band;
    writeln!(
        out,
        "SLAM Lab experiment consistency: {trials} trials of {steps} ticks ({:.1} s) from seed {}",
        steps as f64 * scenario.dt,
        scenario.seed
    )?;
    writeln!(out)?;
    print_parameters(&mut out, &result.parameters)?;
    writeln!(out)?;
    // Diverged runs can make averages astronomically large: those go in e-notation.
    let fmt = |v: Option<f64>| match v {
        None => "-".to_owned(),
        Some(v) if v.abs() >= 1e5 => format!("{v:.3e}"),
        Some(v) => format!("{v:.3}"),
    };
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
        experiments::DIVERGED_ERROR
    )?;
    Ok(())
}

fn ekf_vs_ukf(matches: &ArgMatches, seed: u64) -> Result<()> {
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
    let result = experiments::ekf_vs_ukf(noise_scale, trials, seed, progress_bar("ekf-vs-ukf"));
    write_csv(
        matches,
        &format!("ekf-vs-ukf-noise{noise_scale}-seed{seed}-trials{trials}.csv"),
        || {
            let dt = experiments::ekf_vs_ukf_scenario(noise_scale, seed).dt;
            experiments::series_csv(&result, dt)
        },
    )?;
    let mut out = std::io::stdout().lock();
    if print_json_if_asked(matches, &mut out, &result)? {
        return Ok(());
    }
    writeln!(
        out,
        "SLAM Lab experiment ekf-vs-ukf (thesis 000 Sec. 3.4.3), control noise x{noise_scale}, {trials} trials from seed {seed}"
    )?;
    writeln!(out)?;
    print_parameters(&mut out, &result.parameters)?;
    writeln!(out)?;
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
        experiments::DIVERGED_ERROR
    )?;
    Ok(())
}

/// `slamlab run [LESSON] --scenario FILE ...`: the command line with the file's
/// parameters spelled out as flags (`--seed=7 ...`), so one parser reads both. Flags
/// given on the command line win over the file's; parameters `slamlab run` has no
/// flag for are skipped with a warning. Other command lines come back unchanged.
fn expand_scenario_file(mut args: Vec<OsString>) -> Result<Vec<OsString>> {
    if args.get(1).is_none_or(|a| a != "run") {
        return Ok(args);
    }
    let Some(at) = args
        .iter()
        .position(|a| a == "--scenario" || a.to_string_lossy().starts_with("--scenario="))
    else {
        return Ok(args);
    };
    let inline = args[at]
        .to_string_lossy()
        .strip_prefix("--scenario=")
        .map(PathBuf::from);
    let path = match inline {
        Some(path) => {
            args.remove(at);
            path
        }
        None if at + 1 < args.len() => {
            let path = PathBuf::from(args.remove(at + 1));
            args.remove(at);
            path
        }
        None => bail!("--scenario needs a file: slamlab run --scenario FILE.json"),
    };
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("reading the scenario {}", path.display()))?;
    let file =
        ScenarioFile::parse(&text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    if !LESSONS.contains(&file.lesson.as_str()) {
        bail!(
            "{} is a scenario of the {} lesson; `slamlab run` runs {} (the other lessons' \
             experiments: `slamlab experiment --help`)",
            path.display(),
            file.lesson,
            LESSONS.join(" and ")
        );
    }
    match args.get(2).map(|a| a.to_string_lossy().into_owned()) {
        Some(lesson) if !lesson.starts_with('-') => {
            if lesson != file.lesson {
                bail!(
                    "{} is a scenario of the {} lesson, not {lesson}",
                    path.display(),
                    file.lesson
                );
            }
        }
        _ => args.insert(2, OsString::from(&file.lesson)),
    }
    let command = if file.lesson == "kidnap" {
        kidnap::command()
    } else {
        cli().find_subcommand("run").cloned().unwrap_or_else(cli)
    };
    let flags: Vec<String> = command
        .get_arguments()
        .filter_map(|a| a.get_long().map(str::to_owned))
        .collect();
    let given = |key: &str| {
        args.iter().any(|a| {
            let a = a.to_string_lossy();
            a == format!("--{key}") || a.starts_with(&format!("--{key}="))
        })
    };
    let mut spelled = Vec::new();
    for (key, value) in &file.params {
        if !flags.iter().any(|f| f == key) || key == "scenario" {
            eprintln!(
                "warning: {}: `{key}` is not a flag of `slamlab run {}`; ignored",
                path.display(),
                file.lesson
            );
        } else if !given(key) {
            spelled.push(OsString::from(format!("--{key}={value}")));
        }
    }
    args.splice(3..3, spelled);
    Ok(args)
}

fn main() -> std::process::ExitCode {
    let args: Vec<OsString> = std::env::args_os().collect();
    let args = match expand_scenario_file(args) {
        Ok(args) => args,
        Err(e) => {
            eprintln!("error: {e:#}");
            return std::process::ExitCode::FAILURE;
        }
    };
    let kidnap_run = kidnap::is_kidnap_run(&args);
    let kidnap_experiment = kidnap::is_kidnap_experiment(&args);
    // `run kidnap` and `experiment kidnap` have their own flags (kidnap.rs).
    let matches = (!kidnap_run && !kidnap_experiment).then(|| cli().get_matches_from(&args));
    let result = match matches.as_ref().map(ArgMatches::subcommand) {
        None if kidnap_run => kidnap::run(&args),
        None => kidnap::experiment(&args),
        Some(Some(("map", m))) => map::run(m),
        Some(Some(("graph", m))) => graph_cmd::run(m),
        Some(Some(("run", m))) => run(m),
        Some(Some(("experiment", m))) => experiment(m),
        Some(Some(("params", m))) => list_params(m),
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
        let Some(("run", sub)) = m.subcommand() else {
            panic!("no run")
        };
        let s = scenario_from(sub).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.landmarks, 7);
        assert!((s.fov.to_degrees() - 90.0).abs() < 1e-9);
        let m =
            cli().try_get_matches_from(["slamlab", "run", "landmark-slam", "--range-std", "nan"]);
        let m = m.unwrap_or_else(|e| panic!("{e}"));
        let Some(("run", sub)) = m.subcommand() else {
            panic!("no run")
        };
        assert!(scenario_from(sub).is_err());
    }
}
