//! `slamlab run kidnap`: Monte Carlo localization on a grid map, headless.
//!
//! ```text
//! slamlab run kidnap --map maze --estimator mcl --particles 2000 --init global --steps 600 --seed 1 --json
//! ```
//!
//! Parameter flags carry ROS amcl's names with dashes (`--laser-sigma-hit`,
//! `--odom-alpha1`, `--update-min-d`, ...).

use crate::command::RunLesson;
use crate::flags;
use crate::map::{map_arg, read_map, resolution_arg};
use crate::output::Output;
use anyhow::{Context, Result};
use clap::{Arg, ArgMatches, Command};
use serde_json::json;
use slamlab_sim::kidnap::{MclRun, MclScenario};
use std::io::Write;

/// The kidnapped-robot lesson's run.
pub struct Kidnap;

impl RunLesson for Kidnap {
    fn id(&self) -> &'static str {
        "kidnap"
    }

    fn about(&self) -> &'static str {
        "Monte Carlo localization on a grid map (ROS map_server maps), headless"
    }

    fn command(&self) -> Command {
        Command::new(self.id())
            .arg(map_arg())
            .arg(resolution_arg(
                "metres per pixel, for a lone PGM/PNG image (origin 0, thresholds 0.65/0.196)",
            ))
            .arg(
                Arg::new("steps")
                    .long("steps")
                    .value_parser(clap::value_parser!(u64).range(0..=1_000_000))
                    .default_value("600")
                    .help("ticks of 0.1 s"),
            )
            .args(flags::table_args::<MclScenario>(|name| name != "map"))
            .arg(crate::trajectory_out::arg())
    }

    fn run(&self, m: &ArgMatches, out: &mut Output) -> Result<()> {
        let mut scenario: MclScenario = flags::scenario_from(m, &["map"])?;
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
        crate::trajectory_out::write(
            m,
            self.id(),
            &slamlab_sim::kidnap::export::trajectories(&run),
            &[],
        )?;
        let summaries = run.summaries();
        if out.json() {
            out.print_json(&json!({
                "steps": steps,
                "seed": scenario.seed,
                "map": {"name": name, "width": width, "height": height, "resolution": resolution},
                "parameters": serde_json::to_value(&scenario)?,
                "filters": summaries,
            }))?;
            return Ok(());
        }
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
        Ok(())
    }
}
