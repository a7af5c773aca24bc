//! `slamlab run kidnap`: Monte Carlo localization on a grid map, headless.
//!
//! ```text
//! slamlab run kidnap --map maze --estimator mcl --particles 2000 --init global --steps 600 --seed 1 --json
//! ```
//!
//! Parameter flags carry ROS amcl's names with dashes (`--laser-sigma-hit`,
//! `--odom-alpha1`, `--update-min-d`, ...).

use anyhow::{Context, Result, bail};
use clap::{Arg, ArgAction, ArgMatches, Command};
use serde_json::json;
use slamlab_core::grid::OccupancyGrid;
use slamlab_sim::grid::BuiltinMap;
use slamlab_sim::grid::map_io::{load_lone_image, load_map, parse_map_yaml};
use slamlab_sim::localization::{LocalizationEstimator, MclRun, MclScenario};
use slamlab_sim::params::{self, Scenario};
use std::ffi::OsString;
use std::io::Write;
use std::path::Path;

/// The lesson's parameters as flags (`slamlab params --lesson kidnap`), but the
/// ones these commands take their own way: the map (a name or a file) and, for
/// the experiment, the lists of particle counts and estimators.
fn table_args(skip: &[&str]) -> Vec<Arg> {
    MclScenario::params()
        .iter()
        .filter(|p| !skip.contains(&p.name))
        .map(|p| {
            let default =
                params::get(&MclScenario::default(), p.name).unwrap_or_else(|| "none".to_owned());
            let unit = if p.unit.is_empty() {
                String::new()
            } else {
                format!(", {}", p.unit)
            };
            Arg::new(p.name)
                .long(p.name)
                .value_name("VALUE")
                .allow_hyphen_values(true)
                .help(format!(
                    "{}{unit} [{}]; default {default}",
                    p.help,
                    p.kind.range_text(", ")
                ))
        })
        .collect()
}

/// Applies the table's flags that were given (a preset first, then the rest),
/// refusing what cannot be read and warning about what had to be clamped.
fn apply_table_flags(m: &ArgMatches, scenario: &mut MclScenario, skip: &[&str]) -> Result<()> {
    let given: Vec<(&str, &str)> = MclScenario::params()
        .iter()
        .filter(|p| !skip.contains(&p.name))
        .filter_map(|p| m.get_one::<String>(p.name).map(|v| (p.name, v.as_str())))
        .collect();
    for issue in params::apply_pairs(scenario, given, &[]) {
        match issue {
            params::ParamIssue::Clamped { .. } => eprintln!("warning: {issue}"),
            params::ParamIssue::Unreadable {
                name,
                value,
                expected,
                ..
            } => bail!("--{name} '{value}' is not {expected}"),
            other => bail!("{other}"),
        }
    }
    Ok(())
}

/// Whether the command line is `slamlab run kidnap ...`.
pub fn is_kidnap_run(args: &[OsString]) -> bool {
    args.get(1).is_some_and(|a| a == "run") && args.get(2).is_some_and(|a| a == "kidnap")
}

/// The `run kidnap` command line.
pub fn command() -> Command {
    Command::new("kidnap")
        .bin_name("slamlab run kidnap")
        .about("Monte Carlo localization on a grid map (ROS map_server maps), headless")
        .arg(
            Arg::new("map")
                .long("map")
                .default_value("maze")
                .help("maze, office, or a map_server YAML (or a PGM/PNG with --resolution)"),
        )
        .arg(
            Arg::new("resolution")
                .long("resolution")
                .value_parser(clap::value_parser!(f64))
                .help(
                    "metres per pixel, for a lone PGM/PNG image (origin 0, thresholds 0.65/0.196)",
                ),
        )
        .arg(
            Arg::new("steps")
                .long("steps")
                .value_parser(clap::value_parser!(u64).range(0..=1_000_000))
                .default_value("600")
                .help("ticks of 0.1 s"),
        )
        .args(table_args(&["map"]))
        .arg(
            Arg::new("json")
                .long("json")
                .action(ArgAction::SetTrue)
                .help("print one JSON object"),
        )
        .arg(crate::scenario_file_arg())
}

/// Reads a map: a built-in name, a YAML (its image beside it), or a lone image
/// with `resolution`. Returns the grid and its name.
pub fn read_map(spec: &str, resolution: Option<f64>) -> Result<(OccupancyGrid, String)> {
    if let Some(b) = BuiltinMap::from_name(spec) {
        return Ok((b.load()?, b.name().to_owned()));
    }
    let path = Path::new(spec);
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    if ext == "pgm" || ext == "png" {
        let Some(res) = resolution else {
            bail!(
                "{spec} is an image without a YAML: give its resolution with --resolution METRES"
            );
        };
        let bytes = std::fs::read(path).with_context(|| format!("cannot read {spec}"))?;
        let grid = load_lone_image(&bytes, res).with_context(|| format!("map {spec}"))?;
        return Ok((grid, spec.to_owned()));
    }
    let text = std::fs::read_to_string(path).with_context(|| {
        format!("cannot read {spec} (a map is maze, office, a map_server YAML, or a PGM/PNG)")
    })?;
    let yaml = parse_map_yaml(&text).with_context(|| format!("map {spec}"))?;
    let image_path = path
        .parent()
        .unwrap_or_else(|| Path::new("."))
        .join(&yaml.image);
    let bytes = std::fs::read(&image_path).with_context(|| {
        format!(
            "image '{}' named in {spec} cannot be read at {}",
            yaml.image,
            image_path.display()
        )
    })?;
    let (grid, _) = load_map(&text, &bytes).with_context(|| format!("map {spec}"))?;
    Ok((grid, spec.to_owned()))
}

fn scenario_from(m: &ArgMatches) -> Result<MclScenario> {
    let mut s = MclScenario::default();
    apply_table_flags(m, &mut s, &["map"])?;
    Ok(s)
}

/// Runs `slamlab run kidnap` with the full argument list (`args[0]` the
/// program).
pub fn run(args: &[OsString]) -> Result<()> {
    let mut argv = vec![OsString::from("slamlab run kidnap")];
    argv.extend(args.iter().skip(3).cloned());
    let m = command()
        .try_get_matches_from(argv)
        .unwrap_or_else(|e| e.exit());
    let mut scenario = scenario_from(&m)?;
    let spec = m.get_one::<String>("map").map_or("maze", String::as_str);
    let (grid, name) = read_map(spec, m.get_one::<f64>("resolution").copied())?;
    scenario.map = name.clone();
    let steps = m.get_one::<u64>("steps").copied().unwrap_or(600);
    let (width, height, resolution) = (grid.width(), grid.height(), grid.resolution());
    let mut run = MclRun::new(scenario.clone(), grid).with_context(|| format!("map {name}"))?;
    for note in run.notes() {
        eprintln!("warning: {note}");
    }
    run.run_ticks(steps);
    let summaries = run.summaries();
    let out = std::io::stdout();
    let mut out = out.lock();
    if m.get_flag("json") {
        let value = json!({
            "steps": steps,
            "seed": scenario.seed,
            "map": {"name": name, "width": width, "height": height, "resolution": resolution},
            "parameters": serde_json::to_value(&scenario)?,
            "filters": summaries,
        });
        writeln!(out, "{}", serde_json::to_string_pretty(&value)?)?;
    } else {
        writeln!(
            out,
            "SLAM Lab: Monte Carlo localization on {name} ({width} x {height} cells of {resolution} m) — {steps} ticks, seed {}, init {}",
            scenario.seed,
            scenario.init.name()
        )?;
        writeln!(out)?;
        writeln!(
            out,
            "{:<8} {:>9} {:>10} {:>12} {:>12} {:>12}",
            "filter", "particles", "converged", "pos err (m)", "head err", "RMSE conv."
        )?;
        let f = |v: Option<f64>| v.map_or("-".to_owned(), |v| format!("{v:.3}"));
        for s in &summaries {
            writeln!(
                out,
                "{:<8} {:>9} {:>10} {:>12} {:>12} {:>12}",
                s.name,
                s.particles,
                s.converged_tick
                    .map_or("never".to_owned(), |t| format!("tick {t}")),
                f(s.position_error_final),
                f(s.heading_error_final),
                f(s.position_rmse_converged),
            )?;
        }
        let collisions = run
            .notes()
            .iter()
            .filter(|n| n.contains("collision"))
            .count();
        writeln!(out)?;
        writeln!(
            out,
            "converged: within 0.5 m and 0.3 rad of the truth for 10 consecutive updates (the tick of the first). {collisions} collision(s)."
        )?;
    }
    Ok(())
}

/// Whether the command line is `slamlab experiment kidnap ...`.
pub fn is_kidnap_experiment(args: &[OsString]) -> bool {
    args.get(1).is_some_and(|a| a == "experiment") && args.get(2).is_some_and(|a| a == "kidnap")
}

/// The `experiment kidnap` command line.
pub fn experiment_command() -> Command {
    Command::new("kidnap")
        .bin_name("slamlab experiment kidnap")
        .about("The kidnapped robot (thesis 000 Tables 5.1 and 5.2): updates to recover after a kidnap, and the fraction of particles randomized on the way")
        .arg(Arg::new("map").long("map").default_value("maze").help("maze, office, or a map_server YAML (or a PGM/PNG with --resolution)"))
        .arg(Arg::new("resolution").long("resolution").value_parser(clap::value_parser!(f64)).help("metres per pixel, for a lone image"))
        .arg(Arg::new("particles").long("particles").default_value("500,1000,1500,2000,2500").help("comma-separated particle counts"))
        .arg(Arg::new("estimator").long("estimator").default_value("amcl,acmcl").help("comma-separated: mcl, amcl, cmcl, acmcl"))
        .arg(Arg::new("trials").long("trials").value_parser(clap::value_parser!(u64).range(1..=10_000)).default_value("20").help("trials per (estimator, particle count); trial i uses seed + i"))
        .arg(Arg::new("seed").long("seed").value_parser(clap::value_parser!(u64)).default_value("1").help("first seed"))
        .arg(Arg::new("limit").long("limit").value_parser(clap::value_parser!(u64).range(10..=100_000)).default_value("500").help("updates after the kidnap before a trial counts as a failure"))
        .arg(Arg::new("json").long("json").action(ArgAction::SetTrue).help("print one JSON object"))
        .arg(Arg::new("csv").long("csv").value_name("DIR").value_parser(clap::value_parser!(std::path::PathBuf)).help("write per-trial rows to DIR/kidnap_trials.csv"))
        .args(table_args(EXPERIMENT_OWN))
}

/// What `experiment kidnap` sets itself (lists, the protocol's tracking start and
/// kidnap), so the table's flags of these names are not offered there.
const EXPERIMENT_OWN: &[&str] = &["map", "particles", "estimator", "seed", "init", "kidnap-at"];

/// Runs `slamlab experiment kidnap`.
pub fn experiment(args: &[OsString]) -> Result<()> {
    use slamlab_sim::localization::experiment::{KidnapProtocol, kidnap_trial, summarize};
    let mut argv = vec![OsString::from("slamlab experiment kidnap")];
    argv.extend(args.iter().skip(3).cloned());
    let m = experiment_command()
        .try_get_matches_from(argv)
        .unwrap_or_else(|e| e.exit());
    let mut base = MclScenario::default();
    apply_table_flags(&m, &mut base, EXPERIMENT_OWN)?;
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
    let total = jobs.len();
    let bar = crate::trials_bar("kidnap", total);
    let done = std::sync::atomic::AtomicUsize::new(0);
    let outcomes: Vec<Result<slamlab_sim::localization::experiment::KidnapTrial, String>> = {
        use rayon::prelude::*;
        jobs.par_iter()
            .map(|&(est, n, i)| {
                let r = kidnap_trial(&base, &grid, est, n, seed.wrapping_add(i), &protocol)
                    .map_err(|e| e.to_string());
                let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                crate::trials_progress(&bar, "kidnap", d, total);
                r
            })
            .collect()
    };
    let mut all = Vec::with_capacity(total);
    for outcome in outcomes {
        match outcome {
            Ok(t) => all.push(t),
            Err(e) => bail!("map {name}: {e}"),
        }
    }
    let mut results = Vec::new();
    for &est in &estimators {
        for &n in &counts {
            let ts: Vec<_> = all
                .iter()
                .filter(|t| t.estimator == est.name() && t.particles == n)
                .copied()
                .collect();
            results.push(summarize(est.name(), n, &ts));
        }
    }
    let rows = all;
    eprintln!();
    if let Some(dir) = m.get_one::<std::path::PathBuf>("csv") {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        let mut csv =
            String::from("estimator,particles,seed,kidnap_tick,steps_to_converge,recovery_ratio\n");
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
        let path = dir.join("kidnap_trials.csv");
        std::fs::write(&path, csv).with_context(|| format!("cannot write {}", path.display()))?;
    }
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
    let out = std::io::stdout();
    let mut out = out.lock();
    if m.get_flag("json") {
        let v = json!({
            "experiment": "kidnap",
            "map": {"name": name, "width": grid.width(), "height": grid.height(), "resolution": grid.resolution()},
            "parameters": serde_json::to_value(&base)?,
            "protocol": protocol_json,
            "results": results,
        });
        writeln!(out, "{}", serde_json::to_string_pretty(&v)?)?;
    } else {
        writeln!(
            out,
            "SLAM Lab: kidnapped robot on {name}, {trials} trials per row, seeds from {seed}"
        )?;
        writeln!(out)?;
        writeln!(
            out,
            "{:<8} {:>9} {:>8} {:>8} {:>8} {:>9} {:>10}",
            "filter", "particles", "median", "mean", "p90", "failures", "recovery"
        )?;
        let f = |v: Option<f64>| v.map_or("-".to_owned(), |v| format!("{v:.1}"));
        for r in &results {
            writeln!(
                out,
                "{:<8} {:>9} {:>8} {:>8} {:>8} {:>9} {:>9.2}%",
                r.estimator,
                r.particles,
                f(r.steps_to_converge.median),
                f(r.steps_to_converge.mean),
                f(r.steps_to_converge.p90),
                r.failures,
                100.0 * r.recovery_ratio
            )?;
        }
        writeln!(out)?;
        writeln!(
            out,
            "steps: filter updates from the kidnap until within {} m and {} rad for {} consecutive updates; limit {} updates.",
            protocol.converged_position,
            protocol.converged_heading,
            protocol.converged_updates,
            protocol.limit_updates
        )?;
    }
    Ok(())
}
