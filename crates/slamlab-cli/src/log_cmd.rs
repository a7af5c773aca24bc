//! `slamlab log record` (a simulated CARMEN log and its truth file) and
//! `slamlab log info FILE` (what a CARMEN log holds).

use crate::map::{map_arg, read_map, resolution_arg};
use anyhow::{Context, Result, bail};
use clap::{Arg, ArgAction, ArgMatches, Command};
use serde_json::json;
use slamlab_sim::grid::{SimulatedLogConfig, simulate_log};
use slamlab_sim::io::laser_log::{LaserLog, write_carmen, write_truth};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The `log` subcommand.
pub fn command() -> Command {
    Command::new("log")
        .about("CARMEN laser logs: record a simulated one with its ground truth, or describe one")
        .subcommand_required(true)
        .subcommand(
            Command::new("record")
                .about(
                    "Drive the explorer through a map and write the run as a CARMEN log \
                     (ODOM + FLASER, 360 beams over 360°, 12 m, 10 Hz) and the true poses \
                     in OUT.truth",
                )
                .arg(map_arg())
                .arg(resolution_arg(
                    "metres per pixel, for a map given as a lone PGM/PNG",
                ))
                .arg(
                    Arg::new("steps")
                        .long("steps")
                        .value_parser(clap::value_parser!(usize))
                        .default_value("3000")
                        .help("scans to record (0.1 s apart)"),
                )
                .arg(
                    Arg::new("seed")
                        .long("seed")
                        .value_parser(clap::value_parser!(u64))
                        .default_value("1")
                        .help("random seed (start pose, noise, goals)"),
                )
                .arg(
                    Arg::new("out")
                        .long("out")
                        .required(true)
                        .help("the log to write; the truth goes to the same name + .truth"),
                ),
        )
        .subcommand(
            Command::new("info")
                .about(
                    "Print a log's scan and odometry counts, beams, time span and skipped records",
                )
                .arg(
                    Arg::new("file")
                        .required(true)
                        .help("a CARMEN log, plain, gzip or bzip2"),
                )
                .arg(
                    Arg::new("json")
                        .long("json")
                        .action(ArgAction::SetTrue)
                        .help("print JSON"),
                ),
        )
}

/// Runs `slamlab log ...`.
pub fn run(m: &ArgMatches) -> Result<()> {
    let out = std::io::stdout();
    let mut out = out.lock();
    match m.subcommand() {
        Some(("record", m)) => record(m, &mut out),
        Some(("info", m)) => {
            let file = m.get_one::<String>("file").map_or("", String::as_str);
            info(Path::new(file), m.get_flag("json"), &mut out)
        }
        _ => Ok(()),
    }
}

/// The truth file beside a log: the log's name with `.truth` appended.
pub fn truth_path(log: &Path) -> PathBuf {
    let mut name = log.as_os_str().to_owned();
    name.push(".truth");
    PathBuf::from(name)
}

fn record(m: &ArgMatches, out: &mut impl Write) -> Result<()> {
    let map_spec = m.get_one::<String>("map").map_or("maze", String::as_str);
    let steps = m.get_one::<usize>("steps").copied().unwrap_or(3000);
    let seed = m.get_one::<u64>("seed").copied().unwrap_or(1);
    let Some(path) = m.get_one::<String>("out").map(Path::new) else {
        bail!("--out FILE is required");
    };
    if steps == 0 {
        bail!("--steps 0 records nothing: give at least one step");
    }
    let (grid, map_name) = read_map(map_spec, m.get_one::<f64>("resolution").copied())?;
    let config = SimulatedLogConfig::default();
    let (mut log, truth) = simulate_log(&grid, steps, seed, &config)
        .with_context(|| format!("simulating on {map_name}"))?;
    log.params.insert(
        "slamlab_map".to_string(),
        map_name.replace(char::is_whitespace, "_"),
    );
    let text = write_carmen(&log)?;
    std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))?;
    let truth_file = truth_path(path);
    std::fs::write(&truth_file, write_truth(&truth))
        .with_context(|| format!("cannot write {}", truth_file.display()))?;
    writeln!(
        out,
        "wrote {} ({} scans of {} beams, {:.1} s, map {map_name}, seed {seed}) and {}",
        path.display(),
        log.scans.len(),
        config.lidar.beams,
        steps as f64 * config.dt,
        truth_file.display()
    )?;
    Ok(())
}

fn info(path: &Path, as_json: bool, out: &mut impl Write) -> Result<()> {
    let log = LaserLog::read_file(path)?;
    let span = log.time_span();
    let first = log.scans.first();
    let fov_deg = first.and_then(|s| {
        let a = &s.scan.angles;
        let n = a.len();
        (n >= 2).then(|| ((a[n - 1] - a[0]) * n as f64 / (n - 1) as f64).to_degrees())
    });
    let compression = log.compression.map_or("plain", |c| c.name());
    if as_json {
        let value = json!({
            "file": path.display().to_string(),
            "compression": compression,
            "scans": log.scans.len(),
            "scan_records": log.scan_counts(),
            "odometry": log.odometry.len(),
            "beams": log.beams(),
            "fov_deg": fov_deg,
            "max_range": first.map(|s| s.scan.range_max),
            "first_timestamp": span.map(|s| s.0),
            "last_timestamp": span.map(|s| s.1),
            "duration_s": span.map(|s| s.1 - s.0),
            "params": log.params,
            "skipped": log.skipped,
            "comments": log.comments,
            "unusable_readings": log.unusable_readings,
        });
        writeln!(out, "{}", serde_json::to_string(&value)?)?;
        return Ok(());
    }
    writeln!(out, "file:        {} ({compression})", path.display())?;
    let records: Vec<String> = log
        .scan_counts()
        .iter()
        .map(|(k, v)| format!("{v} {k}"))
        .collect();
    writeln!(
        out,
        "scans:       {} ({})",
        log.scans.len(),
        records.join(", ")
    )?;
    writeln!(out, "odometry:    {} ODOM", log.odometry.len())?;
    if let (Some(beams), Some(s)) = (log.beams(), first) {
        writeln!(
            out,
            "beams:       {beams} over {:.1}°, max range {} m",
            fov_deg.unwrap_or(0.0),
            s.scan.range_max
        )?;
    }
    if let Some((a, b)) = span {
        writeln!(out, "time:        {a:.6} to {b:.6} s ({:.1} s)", b - a)?;
    }
    let params: Vec<String> = log.params.iter().map(|(k, v)| format!("{k}={v}")).collect();
    writeln!(out, "params:      {}", params.join(" "))?;
    let skipped: Vec<String> = log
        .skipped
        .iter()
        .map(|(k, v)| format!("{v} {k}"))
        .collect();
    writeln!(
        out,
        "skipped:     {}",
        if skipped.is_empty() {
            "none".to_string()
        } else {
            skipped.join(", ")
        }
    )?;
    writeln!(out, "comments:    {}", log.comments)?;
    writeln!(
        out,
        "unusable:    {} readings (NaN or negative)",
        log.unusable_readings
    )?;
    Ok(())
}
