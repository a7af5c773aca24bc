//! `slamlab experiment real-data`: the landmark filters on a recorded data set,
//! per robot, estimator and mode, scored against the truth.
//!
//! ```text
//! slamlab experiment real-data --data MRCLAM_Dataset6.zip --robots 1,2,3,4,5 \
//!     --estimator ekf,ukf,fastslam2 --mode slam,localization --json
//! ```

use crate::args;
use crate::command::Experiment;
use crate::flags;
use crate::lessons::landmark::{data_arg, data_from, scenario_args_where, scenario_for_data};
use crate::output::{Output, csv_arg, par_trials, table_number};
use anyhow::{Result, bail};
use clap::{Arg, ArgMatches, Command};
use slamlab_sim::io::landmark_data::LandmarkData;
use slamlab_sim::landmark_slam::real_data::{
    RealDataRow, RealEstimator, parameters_used, run_robot,
};
use slamlab_sim::world::landmark_scenario::MapMode;
use slamlab_sim::world::recorded::data_source;
use std::fmt::Write as _;
use std::io::Write;

/// The landmark filters on real data.
pub struct RealData;

/// The scenario flags this experiment takes from the landmark table: all but
/// those it has as lists of its own.
const OWN: [&str; 3] = ["estimator", "mode", "robot"];

impl Experiment for RealData {
    fn command(&self) -> Command {
        Command::new("real-data")
            .about("The landmark filters on a recorded data set (MRCLAM with Vicon truth): trajectory RMSE, landmark RMSE, ANEES and time in band per robot, estimator and mode; on Victoria Park the GPS alignment RMSE")
            .arg(data_arg().required(true))
            .arg(args::list(
                "robots",
                "comma-separated robots of an MRCLAM data set [default: every robot in the files]",
            ))
            .arg(
                Arg::new("estimators")
                    .long("estimator")
                    .value_name("LIST")
                    .default_value("dead-reckoning,ekf,ukf,fastslam2")
                    .help("comma-separated: dead-reckoning, ekf, ukf, fej-ekf, fastslam1, fastslam2"),
            )
            .arg(
                Arg::new("modes")
                    .long("mode")
                    .value_name("LIST")
                    .default_value("slam,localization")
                    .help("comma-separated: slam (landmarks estimated), localization (the surveyed map given)"),
            )
            .arg(csv_arg("write the rows as CSV into DIR"))
            .args(
                scenario_args_where(|name| !OWN.contains(&name))
                    .into_iter()
                    .map(|a| {
                        a.help_heading(
                            "Noise and filters (the flags of `slamlab run landmark-slam`; the data set's preset first)",
                        )
                    }),
            )
    }

    fn run(&self, matches: &ArgMatches, out: &mut Output) -> Result<()> {
        let Some(data) = data_from(matches)? else {
            bail!("--data PATH is required: the data set to run on");
        };
        let base = scenario_for_data(matches, &OWN, &data)?;
        let estimators = list(matches, "estimators", |name| {
            RealEstimator::from_name(name).ok_or_else(|| {
                format!(
                    "--estimator '{name}' is not one of dead-reckoning, ekf, ukf, fej-ekf, fastslam1, fastslam2"
                )
            })
        })?;
        let modes = list(matches, "modes", |name| match name {
            "slam" => Ok(MapMode::Slam),
            "localization" => Ok(MapMode::Localization),
            other => Err(format!("--mode '{other}' is not slam or localization")),
        })?;
        let robots = robots(matches, &data)?;
        let jobs: Vec<(u32, MapMode, Vec<RealEstimator>)> = robots
            .iter()
            .flat_map(|&robot| {
                modes
                    .iter()
                    .enumerate()
                    .map(move |(k, &mode)| (robot, mode, k))
            })
            .map(|(robot, mode, k)| {
                // Dead reckoning does not depend on the mode: once per robot.
                let estimators = estimators
                    .iter()
                    .copied()
                    .filter(|e| k == 0 || *e != RealEstimator::DeadReckoning)
                    .collect();
                (robot, mode, estimators)
            })
            .collect();
        let results = par_trials("real-data", &jobs, |(robot, mode, estimators)| {
            run_robot(&data, *robot, *mode, estimators, &base)
        });
        let mut rows = Vec::new();
        for result in results {
            rows.extend(result.map_err(|e| anyhow::anyhow!(e))?);
        }
        let source = data_source(data.kind());
        // What the rows ran with: the data set's noise and the lists run, not
        // the base scenario's simulated world.
        let parameters = parameters_used(&base, data.kind(), &estimators, &modes, &robots);
        out.write_csv("real-data.csv", || csv(&rows))?;
        let report = serde_json::json!({
            "experiment": "real-data",
            "data": {
                "title": source.title,
                "source": source.source,
                "citation": source.citation,
            },
            "parameters": parameters,
            "results": rows,
        });
        if out.print_json(&report)? {
            return Ok(());
        }
        writeln!(out, "SLAM Lab experiment real-data: {}", source.title)?;
        writeln!(out, "cite: {}", source.citation)?;
        out.parameter_paragraph(&parameters, 24)?;
        let fmt = |v: Option<f64>, digits: usize| table_number(v, digits, 2);
        writeln!(
            out,
            "{:>5} {:<15} {:<13} {:>16} {:>15} {:>10} {:>8} {:>9}",
            "robot",
            "estimator",
            "mode",
            "trajectory RMSE",
            "landmark RMSE",
            "ANEES",
            "in band",
            "landmarks"
        )?;
        for r in &rows {
            writeln!(
                out,
                "{:>5} {:<15} {:<13} {:>14} m {:>13} m {:>10} {:>7}% {:>9}{}",
                r.robot,
                r.estimator,
                r.mode,
                fmt(r.trajectory_rmse, 3),
                fmt(r.landmark_rmse, 3),
                fmt(r.anees, 2),
                fmt(r.in_band.map(|s| 100.0 * s), 0),
                r.landmarks,
                r.error
                    .as_ref()
                    .map_or(String::new(), |e| format!("  (last error: {e})"))
            )?;
        }
        if rows.iter().any(|r| r.gps.is_some()) {
            writeln!(out)?;
            writeln!(
                out,
                "Against the GPS (no truth: metres of its own error, dropouts), each path \
                 aligned to the fixes by the rigid transform that fits them best:"
            )?;
            for r in &rows {
                if let Some(g) = &r.gps {
                    writeln!(
                        out,
                        "  {:<15} GPS alignment RMSE {:.2} m over {} of {} fixes; the path turned \
                         {:.2}° and moved ({:.2}, {:.2}) m",
                        r.estimator,
                        g.rmse,
                        g.pairs,
                        g.fixes,
                        g.rotation_deg,
                        g.translation_m[0],
                        g.translation_m[1]
                    )?;
                }
            }
        }
        writeln!(out)?;
        writeln!(
            out,
            "Trajectory RMSE: the absolute trajectory error against the truth without alignment \
             (evo_ape, --t_max_diff 0.01). ANEES: the robot-pose NEES averaged over the same pairs \
             (3 dof: 3 is consistent); in band: the share of them inside the 95% band of one value, \
             [0.216, 9.35]. Landmark RMSE: the final map against the surveyed landmarks."
        )?;
        Ok(())
    }
}

/// A comma-separated flag read item by item.
fn list<T: PartialEq>(
    matches: &ArgMatches,
    id: &str,
    parse: impl Fn(&str) -> std::result::Result<T, String>,
) -> Result<Vec<T>> {
    let mut items = Vec::new();
    for name in flags::list(matches, id) {
        let item = parse(name).map_err(|e| anyhow::anyhow!(e))?;
        if !items.contains(&item) {
            items.push(item);
        }
    }
    if items.is_empty() {
        bail!("--{id} lists nothing");
    }
    Ok(items)
}

/// `--robots`, or every robot of an MRCLAM data set (0 for the others).
fn robots(matches: &ArgMatches, data: &LandmarkData) -> Result<Vec<u32>> {
    let LandmarkData::Mrclam(mrclam) = data else {
        if matches.get_one::<String>("robots").is_some() {
            bail!(
                "--robots belongs to an MRCLAM data set; {} has one",
                data.kind().name()
            );
        }
        return Ok(vec![0]);
    };
    match matches.get_one::<String>("robots") {
        None => Ok(mrclam.robots.iter().map(|r| r.number).collect()),
        Some(_) => list(matches, "robots", |name| match name.parse::<u32>() {
            Ok(n) if mrclam.robot(n).is_some() => Ok(n),
            _ => Err(format!(
                "--robots '{name}' is not a robot of {} (it has {})",
                mrclam.name,
                mrclam
                    .robots
                    .iter()
                    .map(|r| r.number.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            )),
        }),
    }
}

/// The rows as CSV.
fn csv(rows: &[RealDataRow]) -> String {
    let mut text = String::from(
        "robot,estimator,mode,trajectory_rmse_m,landmark_rmse_m,anees,in_band,pairs,coverage,landmarks,gps_rmse_m,gps_pairs\n",
    );
    let opt = |v: Option<f64>| v.map_or(String::new(), |v| v.to_string());
    for r in rows {
        let _ = writeln!(
            text,
            "{},{},{},{},{},{},{},{},{},{},{},{}",
            r.robot,
            r.estimator,
            r.mode,
            opt(r.trajectory_rmse),
            opt(r.landmark_rmse),
            opt(r.anees),
            opt(r.in_band),
            r.pairs,
            r.coverage,
            r.landmarks,
            opt(r.gps.map(|g| g.rmse)),
            r.gps.map_or(String::new(), |g| g.pairs.to_string())
        );
    }
    text
}
