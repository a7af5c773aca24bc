//! `slamlab experiment krp`: the kidnapped robot during mapping (thesis `000`
//! Sec. 5.2, Figs. 5.8-5.12) over many seeds: Cartographer-style SLAM with a
//! kidnap at one scan, and the same seeds without one, each with kidnap
//! detection (Algorithm 13) on and off.
//!
//! ```text
//! slamlab experiment krp --map office --trials 10 --kidnap-at 152 --seed 1 --json
//! ```

use super::first_seed_arg;
use crate::args;
use crate::command::Experiment;
use crate::map::{map_arg, read_map};
use crate::output::{Output, par_trials};
use anyhow::{Result, bail};
use clap::{ArgMatches, Command};
use serde_json::json;
use slamlab_sim::cartographer::input::{KidnapPlace, MAX_STEPS, kidnap_input_to};
use slamlab_sim::cartographer::{CartographerParams, CartographerSim, CartographerSummary};
use slamlab_sim::grid::SimulatedLogConfig;
use std::io::Write;
use std::sync::Arc;

/// Detection, recovery and map agreement over seeds.
pub struct Krp;

/// One run of the experiment.
struct Run {
    seed: u64,
    kidnapped: bool,
    detection: bool,
    summary: CartographerSummary,
}

/// The median of `v` (None when empty).
fn median(v: &mut [f64]) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(v[n / 2]),
        _ => Some(0.5 * (v[n / 2 - 1] + v[n / 2])),
    }
}

/// The 90th percentile of `v` (nearest rank; None when empty).
fn p90(v: &mut [f64]) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return None;
    }
    let rank = (0.9 * v.len() as f64).ceil() as usize;
    Some(v[rank.clamp(1, v.len()) - 1])
}

fn summarize(runs: &[Run], detection: bool, kidnap_at: usize) -> serde_json::Value {
    let kidnapped: Vec<&Run> = runs
        .iter()
        .filter(|r| r.detection == detection && r.kidnapped)
        .collect();
    let free: Vec<&Run> = runs
        .iter()
        .filter(|r| r.detection == detection && !r.kidnapped)
        .collect();
    let mut delays: Vec<f64> = kidnapped
        .iter()
        .filter_map(|r| r.summary.kidnap_detected_at)
        .map(|d| d.saturating_sub(kidnap_at) as f64)
        .collect();
    let fa_kidnapped: usize = kidnapped.iter().map(|r| r.summary.false_alarms).sum();
    let fa_free: usize = free.iter().map(|r| r.summary.false_alarms).sum();
    let mut agreement: Vec<f64> = kidnapped
        .iter()
        .filter_map(|r| r.summary.map_agreement)
        .collect();
    let mut agreement_free: Vec<f64> = free
        .iter()
        .filter_map(|r| r.summary.map_agreement)
        .collect();
    let mut rmse: Vec<f64> = kidnapped
        .iter()
        .filter_map(|r| r.summary.trajectory_rmse)
        .collect();
    json!({
        "detection": if detection { "on" } else { "off" },
        "detection_delay": {"median": median(&mut delays.clone()), "p90": p90(&mut delays)},
        "detected": kidnapped.iter().filter(|r| r.summary.kidnap_detected_at.is_some()).count(),
        "false_alarms": {
            "total": fa_kidnapped + fa_free,
            "kidnapped": fa_kidnapped,
            "kidnap_free": fa_free,
        },
        "recovered": kidnapped.iter().filter(|r| r.summary.recovered_at.is_some()).count(),
        "map_agreement": {"median": median(&mut agreement)},
        "map_agreement_kidnap_free": {"median": median(&mut agreement_free)},
        "trajectory_rmse": {"median": median(&mut rmse)},
        "runs": kidnapped.len(),
    })
}

impl Experiment for Krp {
    fn command(&self) -> Command {
        Command::new("krp")
            .about("The kidnapped robot during mapping (thesis 000 Sec. 5.2): Cartographer-style SLAM with a kidnap and without, kidnap detection on and off; detection delay, false alarms, recovered (merged) maps and map agreement")
            .arg(map_arg())
            .arg(
                args::whole(
                    "trials",
                    1..=1000,
                    "seeds; trial i uses seed + i (each runs four times: kidnapped or not, detection on or off)",
                )
                .default_value("10"),
            )
            .arg(first_seed_arg())
            .arg(args::count("steps", "scans per run").default_value("600"))
            .arg(
                args::count(
                    "kidnap-at",
                    "the scan (0-based) before which the robot is carried elsewhere",
                )
                .default_value("152"),
            )
            .arg(
                args::choice(
                    "kidnap-place",
                    &KidnapPlace::NAMES,
                    "where the kidnap carries the robot: mapped (a random place on its path so far) or anywhere (any free place)",
                )
                .default_value("mapped"),
            )
    }

    fn run(&self, m: &ArgMatches, out: &mut Output) -> Result<()> {
        let spec = m.get_one::<String>("map").map_or("office", String::as_str);
        let (grid, name) = read_map(spec, None)?;
        let grid = Arc::new(grid);
        let trials = m.get_one::<u64>("trials").copied().unwrap_or(10);
        let seed = m.get_one::<u64>("seed").copied().unwrap_or(1);
        let steps = m.get_one::<usize>("steps").copied().unwrap_or(600);
        let kidnap_at = m.get_one::<usize>("kidnap-at").copied().unwrap_or(152);
        if steps == 0 || steps > MAX_STEPS {
            bail!("--steps {steps} must be 1 to {MAX_STEPS}");
        }
        let place = m
            .get_one::<String>("kidnap-place")
            .and_then(|p| KidnapPlace::from_name(p))
            .unwrap_or_default();
        if kidnap_at >= steps {
            bail!("--kidnap-at {kidnap_at} must come before the last scan ({steps} steps)");
        }
        let jobs: Vec<(u64, bool, bool)> = (0..trials)
            .flat_map(|i| {
                [(true, true), (true, false), (false, true), (false, false)]
                    .into_iter()
                    .map(move |(k, d)| (seed.wrapping_add(i), k, d))
            })
            .collect();
        let outcomes = par_trials("krp", &jobs, |&(s, kidnapped, detection)| {
            let kidnap = kidnapped.then_some(kidnap_at);
            let input = kidnap_input_to(
                Arc::clone(&grid),
                &name,
                steps,
                s,
                kidnap.map(|k| (k, place)),
                &SimulatedLogConfig::default(),
            )?;
            let params = CartographerParams {
                detection,
                ..CartographerParams::default()
            };
            let (mut sim, _) = CartographerSim::new(Arc::new(input), params);
            let started = std::time::Instant::now();
            sim.run_to_end();
            let summary = sim.summary(kidnap, started.elapsed().as_secs_f64() * 1e3);
            Ok::<_, String>(Run {
                seed: s,
                kidnapped,
                detection,
                summary,
            })
        });
        let mut runs = Vec::with_capacity(jobs.len());
        for o in outcomes {
            match o {
                Ok(r) => runs.push(r),
                Err(e) => bail!("map {name}: {e}"),
            }
        }
        let on = summarize(&runs, true, kidnap_at);
        let off = summarize(&runs, false, kidnap_at);
        let per_run: Vec<serde_json::Value> = runs
            .iter()
            .map(|r| {
                json!({
                    "seed": r.seed,
                    "kidnapped": r.kidnapped,
                    "detection": r.detection,
                    "kidnap_detected_at": r.summary.kidnap_detected_at,
                    "false_alarms": r.summary.false_alarms,
                    "recovered_at": r.summary.recovered_at,
                    "map_agreement": r.summary.map_agreement,
                    "trajectory_rmse": r.summary.trajectory_rmse,
                })
            })
            .collect();
        if out.print_json(&json!({
            "experiment": "krp",
            "map": {"name": name, "width": grid.width(), "height": grid.height(), "resolution": grid.resolution()},
            "steps": steps,
            "kidnap_at": kidnap_at,
            "kidnap_place": place.name(),
            "trials": trials,
            "seeds": format!("{seed} .. {}", seed + trials - 1),
            "detection_on": on,
            "detection_off": off,
            "runs": per_run,
            "parameters": serde_json::to_value(CartographerParams::default())?,
        }))? {
            return Ok(());
        }
        let f = |v: &serde_json::Value| match v.as_f64() {
            Some(x) => format!("{x:.3}"),
            None => "-".to_owned(),
        };
        writeln!(
            out,
            "SLAM Lab: the kidnapped robot during mapping on {name}, {trials} seeds, {steps} scans, kidnap at scan {kidnap_at}, kidnap-place {}",
            place.name()
        )?;
        writeln!(
            out,
            "detection  detected  delay median  delay p90  false alarms (kidnapped + kidnap-free)  recovered  map agreement (kidnapped / kidnap-free)"
        )?;
        for r in [&on, &off] {
            writeln!(
                out,
                "{:<9}  {:>3}/{:<4}  {:>12}  {:>9}  {:>3} + {:<3}                              {:>3}        {} / {}",
                r["detection"].as_str().unwrap_or(""),
                r["detected"],
                r["runs"],
                f(&r["detection_delay"]["median"]),
                f(&r["detection_delay"]["p90"]),
                r["false_alarms"]["kidnapped"],
                r["false_alarms"]["kidnap_free"],
                r["recovered"],
                f(&r["map_agreement"]["median"]),
                f(&r["map_agreement_kidnap_free"]["median"]),
            )?;
        }
        Ok(())
    }
}
