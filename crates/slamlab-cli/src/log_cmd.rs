//! `slamlab log record` (a simulated run as a CARMEN log and its truth file, or
//! as a ROS 2 bag), `slamlab log convert` (a CARMEN log to a bag, or a bag to a
//! CARMEN log) and `slamlab log info FILE` (what a log or a bag holds).

use crate::args;
use crate::map::{map_arg, read_map, resolution_arg};
use anyhow::{Context, Result, bail};
use clap::{Arg, ArgMatches, Command};
use serde_json::json;
use slamlab_sim::grid::{LaserFile, SimulatedLogConfig, simulate_log};
use slamlab_sim::io::laser_log::{LaserLog, TruePose, write_carmen, write_truth};
use slamlab_sim::io::ros2_bag::{BagKind, BagWriteOptions, Ros2Bag, TopicChoice, write_bag};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

/// `--scan-topic` and `--odom-topic`: the topics of a ROS 2 bag given as `--log`.
pub fn topic_args() -> [Arg; 2] {
    [
        args::named(
            "scan-topic",
            "TOPIC",
            "with a ROS 2 bag: the sensor_msgs/msg/LaserScan topic (default /scan, else the busiest)",
        ),
        args::named(
            "odom-topic",
            "TOPIC",
            "with a ROS 2 bag: the nav_msgs/msg/Odometry topic, or `tf` for odom -> base on /tf (default /odom, else the busiest, else tf)",
        ),
    ]
}

/// `--log FILE`: the laser log a mapping lesson maps instead of its simulated
/// robot's scans (read by [`read_laser_file`]).
pub fn laser_log_arg() -> Arg {
    args::file(
        "log",
        "map a CARMEN laser log (plain, .gz or .bz2) or a ROS 2 bag (.mcap) instead of a simulated robot",
    )
}

/// The topics given by `--scan-topic` and `--odom-topic`.
pub fn topic_choice(m: &ArgMatches) -> TopicChoice {
    let get = |name: &str| {
        m.try_get_one::<String>(name)
            .ok()
            .flatten()
            .filter(|v| !v.trim().is_empty())
            .cloned()
    };
    TopicChoice {
        scan: get("scan-topic"),
        odom: get("odom-topic"),
    }
}

/// Reads `--log FILE`, a CARMEN log or a ROS 2 bag (told apart by its bytes),
/// with the topics of `--scan-topic` and `--odom-topic`; prints what the reader
/// assumed as warnings on stderr.
pub fn read_laser_file(path: &str, m: &ArgMatches) -> Result<LaserFile> {
    let choice = topic_choice(m);
    let file = LaserFile::read_file(Path::new(path), &choice)
        .with_context(|| format!("reading {path}"))?;
    if file.topics.is_none() && (choice.scan.is_some() || choice.odom.is_some()) {
        eprintln!(
            "warning: --scan-topic and --odom-topic apply to a ROS 2 bag; {path} is a CARMEN log"
        );
    }
    for note in &file.notices {
        eprintln!("warning: {note}");
    }
    if let Some(t) = &file.topics {
        eprintln!(
            "{}: {}, odometry {} ({})",
            file.input.name, t.scan, t.odometry, file.format
        );
    }
    Ok(file)
}

/// The `log` subcommand.
pub fn command() -> Command {
    Command::new("log")
        .about(
            "Laser logs and ROS 2 bags: record a simulated run with its ground truth, convert between CARMEN and MCAP, or describe one",
        )
        .subcommand_required(true)
        .subcommand(
            Command::new("record")
                .about(
                    "Drive the explorer through a map and write the run (360 beams over 360°, \
                     12 m, 10 Hz): as a CARMEN log (ODOM + FLASER) with the true poses in \
                     OUT.truth, or, for OUT.mcap, as a ROS 2 bag (/scan, /odom, /tf, \
                     /tf_static and the truth on /ground_truth)",
                )
                .arg(map_arg())
                .arg(resolution_arg(
                    "metres per pixel, for a map given as a lone PGM/PNG",
                ))
                .arg(
                    args::count("steps", "scans to record (0.1 s apart)").default_value("3000"),
                )
                .arg(args::seed("random seed (start pose, noise, goals)"))
                .arg(
                    args::flag("out", "the log to write (.mcap: a ROS 2 bag; anything else: CARMEN, with the truth in the same name + .truth)").required(true),
                ),
        )
        .subcommand(
            Command::new("convert")
                .about(
                    "Convert a CARMEN log (plain, gzip or bzip2) into a ROS 2 bag (OUT.mcap), \
                     or a ROS 2 bag into a CARMEN log (any other OUT)",
                )
                .arg(Arg::new("file").required(true).help("a CARMEN log or a ROS 2 bag (.mcap)"))
                .arg(
                    args::flag("out", "the file to write: .mcap for a ROS 2 bag, else CARMEN text").required(true),
                )
                .args(topic_args()),
        )
        .subcommand(
            Command::new("info")
                .about(
                    "Print a log's scan and odometry counts, beams, time span and skipped records",
                )
                .arg(
                    Arg::new("file")
                        .required(true)
                        .help("a CARMEN log (plain, gzip or bzip2) or a ROS 2 bag (.mcap)"),
                )
                .arg(
                    args::switch("json", "print JSON"),
                )
                .args(topic_args()),
        )
}

/// Runs `slamlab log ...`.
pub fn run(m: &ArgMatches) -> Result<()> {
    let out = std::io::stdout();
    let mut out = out.lock();
    match m.subcommand() {
        Some(("record", m)) => record(m, &mut out),
        Some(("convert", m)) => convert(m, &mut out),
        Some(("info", m)) => {
            let file = m.get_one::<String>("file").map_or("", String::as_str);
            if is_bag(Path::new(file))? {
                bag_info(Path::new(file), m, &mut out)
            } else {
                info(Path::new(file), m.get_flag("json"), &mut out)
            }
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
    if wants_bag(path) {
        let bytes = write_bag(&log, Some(&truth), &BagWriteOptions::default())?;
        std::fs::write(path, &bytes).with_context(|| format!("cannot write {}", path.display()))?;
        writeln!(
            out,
            "wrote {} ({} bytes: {} scans of {} beams on /scan, /odom, /tf, /tf_static and the truth on /ground_truth, {:.1} s, map {map_name}, seed {seed})",
            path.display(),
            bytes.len(),
            log.scans.len(),
            config.lidar.beams,
            steps as f64 * config.dt,
        )?;
        return Ok(());
    }
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
    write_skipped(out, &log.skipped)?;
    writeln!(out, "comments:    {}", log.comments)?;
    writeln!(
        out,
        "unusable:    {} readings (NaN or negative)",
        log.unusable_readings
    )?;
    Ok(())
}

/// Does `path` name a bag to write (`.mcap`)?
/// `skipped:` and what a reader passed over, `N kind` each (`none`).
fn write_skipped(out: &mut impl Write, skipped: &BTreeMap<String, usize>) -> Result<()> {
    let skipped: Vec<String> = skipped.iter().map(|(k, v)| format!("{v} {k}")).collect();
    let text = if skipped.is_empty() {
        "none".to_owned()
    } else {
        skipped.join(", ")
    };
    writeln!(out, "skipped:     {text}")?;
    Ok(())
}

fn wants_bag(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
}

/// Is the file a bag (MCAP, ROS 1 or SQLite3), from its first bytes?
fn is_bag(path: &Path) -> Result<bool> {
    use std::io::Read as _;
    let mut first = [0u8; 16];
    let n = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut first))
        .with_context(|| format!("cannot read {}", path.display()))?;
    Ok(BagKind::detect(&first[..n]) != BagKind::Other)
}

/// `slamlab log convert FILE --out OUT`.
fn convert(m: &ArgMatches, out: &mut impl Write) -> Result<()> {
    let input = m.get_one::<String>("file").map_or("", String::as_str);
    let Some(path) = m.get_one::<String>("out").map(Path::new) else {
        bail!("--out FILE is required");
    };
    let (log, truth): (LaserLog, Option<Vec<TruePose>>) = if is_bag(Path::new(input))? {
        let bag = Ros2Bag::read_file(Path::new(input))?;
        let read = bag
            .laser_log(&topic_choice(m))
            .with_context(|| format!("reading {input}"))?;
        for note in &read.notices {
            eprintln!("warning: {note}");
        }
        (read.log, read.truth)
    } else {
        let log =
            LaserLog::read_file(Path::new(input)).with_context(|| format!("reading {input}"))?;
        // A simulated log's truth file, when it is beside the log.
        let truth = std::fs::read_to_string(truth_path(Path::new(input)))
            .ok()
            .and_then(|t| slamlab_sim::io::laser_log::read_truth(&t).ok())
            .filter(|t| t.len() == log.scans.len());
        (log, truth)
    };
    if wants_bag(path) {
        let bytes = write_bag(&log, truth.as_deref(), &BagWriteOptions::default())?;
        std::fs::write(path, &bytes).with_context(|| format!("cannot write {}", path.display()))?;
        writeln!(
            out,
            "wrote {} ({} bytes: {} scans on /scan, {} odometry messages on /odom, /tf, /tf_static{})",
            path.display(),
            bytes.len(),
            log.scans.len(),
            log.scans.len(),
            if truth.is_some() {
                ", the truth on /ground_truth"
            } else {
                ""
            }
        )?;
    } else {
        let text = write_carmen(&log)?;
        std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))?;
        let mut wrote = format!(
            "wrote {} ({} scans as FLASER, {} ODOM)",
            path.display(),
            log.scans.len(),
            log.odometry.len()
        );
        if let Some(truth) = &truth {
            let truth_file = truth_path(path);
            std::fs::write(&truth_file, write_truth(truth))
                .with_context(|| format!("cannot write {}", truth_file.display()))?;
            wrote.push_str(&format!(" and {}", truth_file.display()));
        }
        writeln!(out, "{wrote}")?;
    }
    Ok(())
}

/// `slamlab log info BAG`: the bag's topics, and what the lessons read from it.
fn bag_info(path: &Path, m: &ArgMatches, out: &mut impl Write) -> Result<()> {
    let bag = Ros2Bag::read_file(path)?;
    let read = bag.laser_log(&topic_choice(m));
    let chunks: Vec<String> = bag
        .header
        .chunks
        .iter()
        .map(|(c, n)| format!("{n} {}", if c.is_empty() { "uncompressed" } else { c }))
        .collect();
    if m.get_flag("json") {
        let topics: Vec<_> = bag
            .topics
            .iter()
            .map(|t| json!({"topic": t.topic, "type": t.type_name, "encoding": t.encoding, "messages": t.messages}))
            .collect();
        let lesson = match &read {
            Ok(r) => json!({
                "scan_topic": r.scan_topic,
                "odometry": r.odometry.to_string(),
                "scans": r.log.scans.len(),
                "beams": r.log.beams(),
                "time_span_s": r.log.time_span().map(|(a, b)| b - a),
                "mount": [r.mount.x, r.mount.y, r.mount.theta],
                "mirrored": r.mirrored,
                "truth": r.truth.is_some(),
                "unusable_readings": r.log.unusable_readings,
                "notices": r.notices,
            }),
            Err(e) => json!({"error": e.to_string()}),
        };
        let value = json!({
            "file": path.display().to_string(),
            "format": "ros2 bag (mcap)",
            "profile": bag.header.profile,
            "library": bag.header.library,
            "summary": bag.header.has_summary,
            "chunks": bag.header.chunks,
            "topics": topics,
            "skipped": bag.skipped,
            "lesson_input": lesson,
        });
        writeln!(out, "{}", serde_json::to_string(&value)?)?;
        return Ok(());
    }
    writeln!(out, "file:        {} (ROS 2 bag, MCAP)", path.display())?;
    writeln!(
        out,
        "written by:  {} (profile {})",
        bag.header.library, bag.header.profile
    )?;
    writeln!(
        out,
        "chunks:      {}; summary section: {}",
        if chunks.is_empty() {
            "none".to_owned()
        } else {
            chunks.join(", ")
        },
        if bag.header.has_summary { "yes" } else { "no" }
    )?;
    writeln!(out, "topics:")?;
    for t in &bag.topics {
        writeln!(
            out,
            "  {:<24} {:<34} {:>7} messages",
            t.topic, t.type_name, t.messages
        )?;
    }
    write_skipped(out, &bag.skipped)?;
    match read {
        Ok(r) => {
            let span = r.log.time_span().map_or(0.0, |(a, b)| b - a);
            writeln!(
                out,
                "lessons:     {} scans on {} ({} beams) over {span:.1} s, odometry {}; laser at ({:.3}, {:.3}) m, {:.1}°{}{}",
                r.log.scans.len(),
                r.scan_topic,
                r.log.beams().unwrap_or(0),
                r.odometry,
                r.mount.x,
                r.mount.y,
                r.mount.theta.to_degrees(),
                if r.mirrored { ", upside down" } else { "" },
                if r.truth.is_some() {
                    "; truth on /ground_truth"
                } else {
                    ""
                }
            )?;
            for note in &r.notices {
                writeln!(out, "notice:      {note}")?;
            }
        }
        Err(e) => writeln!(out, "lessons:     cannot map it: {e}")?,
    }
    Ok(())
}
