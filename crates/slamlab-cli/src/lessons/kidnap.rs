//! `slamlab run kidnap`: Monte Carlo localization on a grid map, headless.
//!
//! ```text
//! slamlab run kidnap --map maze --estimator mcl --particles 2000 --init global --steps 600 --seed 1 --json
//! slamlab run kidnap --map office.yaml --log robot.mcap --scan-topic /scan --odom-topic /odom
//! ```
//!
//! With `--log` (a CARMEN log or a ROS 2 bag) the filters localize the recorded
//! robot in the map, one tick a scan, to the end of the log (or `--steps`
//! ticks); the errors are against the bag's `/ground_truth` where it has one,
//! and left out where the log has no truth.
//!
//! Parameter flags carry ROS amcl's names with dashes (`--laser-sigma-hit`,
//! `--odom-alpha1`, `--update-min-d`, ...).

use crate::args;
use crate::command::RunLesson;
use crate::flags;
use crate::log_cmd::{read_laser_file, topic_args};
use crate::map::{map_arg, read_map, resolution_arg};
use crate::output::Output;
use anyhow::{Context, Result};
use clap::{ArgMatches, Command};
use serde_json::json;
use slamlab_sim::kidnap::{MclRun, MclScenario};
use std::io::Write;

/// The kidnapped-robot lesson's run.
pub struct Kidnap;

impl RunLesson for Kidnap {
    fn command(&self) -> Command {
        Command::new("kidnap")
            .about("Monte Carlo localization on a grid map (ROS map_server maps), headless")
            .arg(map_arg())
            .arg(resolution_arg(
                "metres per pixel, for a lone PGM/PNG image (origin 0, thresholds 0.65/0.196)",
            ))
            .arg(
                args::whole(
                    "steps",
                    0..=1_000_000,
                    "ticks of 0.1 s (with --log: at most this many scans; default the whole log)",
                )
                .default_value("600"),
            )
            .arg(args::file(
                "log",
                "localize a recorded robot: a CARMEN laser log (plain, .gz or .bz2) or a ROS 2 bag (.mcap), in the map given by --map",
            ))
            .args(topic_args())
            .args(flags::table_args::<MclScenario>(|name| name != "map"))
            .arg(crate::trajectory_out::arg())
    }

    fn run(&self, m: &ArgMatches, out: &mut Output) -> Result<()> {
        let mut scenario: MclScenario = flags::scenario_from(m, &["map"])?;
        let spec = m.get_one::<String>("map").map_or("maze", String::as_str);
        let (grid, name) = read_map(spec, m.get_one::<f64>("resolution").copied())?;
        scenario.map = name.clone();
        let steps_given = m.value_source("steps") == Some(clap::parser::ValueSource::CommandLine);
        let mut steps = m.get_one::<u64>("steps").copied().unwrap_or(600);
        let (width, height, resolution) = (grid.width(), grid.height(), grid.resolution());
        let log = match m.get_one::<String>("log") {
            Some(path) => Some((path, read_laser_file(path, m)?)),
            None => None,
        };
        let mut run = match &log {
            Some((path, file)) => {
                if !steps_given {
                    steps = file.input.scans.len() as u64;
                }
                MclRun::from_log(scenario.clone(), grid, file.input.clone())
                    .with_context(|| format!("localizing {path} in the map {name}"))?
            }
            None => MclRun::new(scenario.clone(), grid).with_context(|| format!("map {name}"))?,
        };
        for note in run.notes() {
            eprintln!("warning: {note}");
        }
        run.run_ticks(steps);
        let steps = run.tick_count();
        crate::trajectory_out::write(
            m,
            &self.id(),
            &slamlab_sim::kidnap::export::trajectories(&run),
            &[],
        )?;
        let summaries = run.summaries();
        let estimates: Vec<serde_json::Value> = run
            .filters()
            .iter()
            .map(|f| match f.current_estimate(&run.odometry()) {
                Some(p) => json!({"name": f.name, "x": p.x, "y": p.y, "theta": p.theta}),
                None => json!({"name": f.name}),
            })
            .collect();
        if out.json() {
            let mut report = json!({
                "steps": steps,
                "seed": scenario.seed,
                "map": {"name": name, "width": width, "height": height, "resolution": resolution},
                "parameters": serde_json::to_value(&scenario)?,
                "filters": summaries,
            });
            if let Some((_, file)) = &log {
                report["log"] = json!({
                    "name": file.describe(),
                    "format": file.format,
                    "scans": file.input.scans.len(),
                    "replayed": run.log_progress().map_or(0, |(done, _)| done),
                    "truth": run.has_truth(),
                });
                report["final_estimates"] = json!(estimates);
            }
            out.print_json(&report)?;
            return Ok(());
        }
        if let Some((_, file)) = &log {
            let truth = if run.has_truth() {
                "errors against its truth"
            } else {
                "no truth: errors unknown"
            };
            writeln!(
                out,
                "SLAM Lab: Monte Carlo localization of {} ({}) in {name} ({width} x {height} cells of {resolution} m) — {steps} of {} scans, seed {}, init {}; {truth}",
                file.describe(),
                file.format,
                file.input.scans.len(),
                scenario.seed,
                scenario.init.name()
            )?;
            writeln!(out)?;
            for (k, f) in run.filters().iter().enumerate() {
                writeln!(
                    out,
                    "{:<8} {:>5} particles  {}",
                    f.name,
                    f.mcl().count(),
                    run.status_of(k)
                )?;
            }
            if !run.has_truth() {
                return Ok(());
            }
            writeln!(out)?;
        } else {
            writeln!(
                out,
                "SLAM Lab: Monte Carlo localization on {name} ({width} x {height} cells of {resolution} m) — {steps} ticks, seed {}, init {}",
                scenario.seed,
                scenario.init.name()
            )?;
            writeln!(out)?;
        }
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
        Ok(())
    }
}
