//! `slamlab experiment laser-slam`: every laser SLAM method of SLAM Lab run over
//! a CARMEN log and scored against its corrected version (Kümmerle et al. 2009,
//! "On measuring the accuracy of SLAM algorithms"; the Cartographer paper's
//! Table I, Hess et al. 2016).
//!
//! ```text
//! slamlab experiment laser-slam --log intel.clf.bz2 --reference intel-corrected.log.gz \
//!     --poses odometry,icp,plicp,scan-to-map,grid-fastslam,cartographer --json
//! ```
//!
//! Each pose source maps the whole log (the mapping lesson's sources with its
//! defaults; `cartographer` with the Cartographer lesson's, and
//! `cartographer-local`, its local SLAM alone, without loop closures); its
//! trajectory is scored at the reference scans (matched to the log's scans by
//! time and identical ranges): the ATE after SE(2) alignment and the relative
//! errors over reference pairs 1 and 10 scans apart (mean and standard
//! deviation, and of their squares), with the thread CPU time and the real-time
//! factor (seconds of log per second of CPU). A reference that cannot be read
//! or matches none of the log's scans is reported in `reference_error`; the
//! runs go on and print their times without a score.

use crate::args;
use crate::command::Experiment;
use crate::flags;
use crate::output::Output;
use anyhow::{Context, Result, bail};
use clap::{ArgMatches, Command};
use cpu_time::ThreadTime;
use rayon::prelude::*;
use serde::Serialize;
use slamlab_core::Pose2;
use slamlab_sim::cartographer::{CartographerParams, CartographerSim};
use slamlab_sim::grid::reference::{LogReference, TrajectoryScore, score};
use slamlab_sim::grid::{MappingInput, log_input};
use slamlab_sim::io::laser_log::LaserLog;
use slamlab_sim::mapping::{MappingScenario, MappingSession, PoseSource};
use std::io::Write;
use std::path::Path;
use std::sync::Arc;

/// Laser SLAM scored against a corrected log.
pub struct LaserSlam;

/// The pose sources, as `--poses` names them.
pub const POSES: [&str; 7] = [
    "odometry",
    "icp",
    "plicp",
    "scan-to-map",
    "grid-fastslam",
    "cartographer-local",
    "cartographer",
];

/// One pose source's row.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// The pose source.
    pub poses: String,
    /// Scans mapped.
    pub scans: usize,
    /// The ATE after SE(2) alignment, metres (null without a score).
    pub ate_m: Option<f64>,
    /// The whole score (null without one).
    pub score: Option<TrajectoryScore>,
    /// Thread CPU time of the run, seconds.
    pub cpu_s: f64,
    /// Seconds of log per second of CPU.
    pub real_time_factor: f64,
    /// Cartographer's loop closures (its rows only).
    pub loop_closures: Option<usize>,
}

/// Runs `source` over `input`; its poses (one per scan) and loop closures.
pub fn run_source(
    source: &str,
    input: &Arc<MappingInput>,
    seed: u64,
) -> (Vec<Option<Pose2>>, Option<usize>) {
    match source {
        "cartographer" | "cartographer-local" => {
            let mut params = CartographerParams::default();
            if source == "cartographer-local" {
                params = params.without_loop_closures();
            }
            let (mut sim, _) = CartographerSim::new(Arc::clone(input), params);
            sim.run_to_end();
            let closures = sim.summary(None, 0.0).loop_closures;
            (sim.scan_poses(), Some(closures))
        }
        name => {
            let scenario = MappingScenario {
                poses: PoseSource::from_name(name).unwrap_or_default(),
                seed,
                ..MappingScenario::default()
            };
            let (mut session, _) = MappingSession::new(scenario, Arc::clone(input));
            session.run_to_end();
            (session.scan_poses(), None)
        }
    }
}

impl Experiment for LaserSlam {
    fn command(&self) -> Command {
        Command::new("laser-slam")
            .about("laser SLAM scored against a corrected log: ATE and Kümmerle's relative errors per pose source, with CPU time")
            .arg(
                args::file(
                    "log",
                    "the raw CARMEN log (plain, .gz or .bz2), e.g. intel.clf.bz2",
                )
                .required(true),
            )
            .arg(args::file(
                "reference",
                "its corrected log, e.g. intel-corrected.log.gz (without it: times only)",
            ))
            .arg(
                args::list(
                    "poses",
                    "comma-separated pose sources: odometry, icp, plicp, scan-to-map, grid-fastslam, cartographer-local (local SLAM alone), cartographer",
                )
                .default_value("odometry,icp,plicp,scan-to-map,grid-fastslam,cartographer"),
            )
            .arg(args::whole("steps", 1.., "map only the log's first scans"))
            .arg(args::seed("grid FastSLAM's seed"))
    }

    fn run(&self, m: &ArgMatches, out: &mut Output) -> Result<()> {
        let log_path = m.get_one::<String>("log").map_or("", String::as_str);
        let mut sources = Vec::new();
        for part in flags::list(m, "poses") {
            if !POSES.contains(&part) {
                bail!(
                    "--poses: '{part}' is not a pose source ({})",
                    POSES.join(", ")
                );
            }
            if !sources.contains(&part) {
                sources.push(part);
            }
        }
        if sources.is_empty() {
            bail!("--poses: give at least one of {}", POSES.join(", "));
        }
        let log = LaserLog::read_file(Path::new(log_path))
            .with_context(|| format!("reading {log_path}"))?;
        let name = file_name(log_path);
        let mut input = log_input(&log, &name);
        if let Some(&n) = m.get_one::<u64>("steps") {
            input
                .scans
                .truncate(usize::try_from(n).unwrap_or(usize::MAX));
        }
        if input.scans.is_empty() {
            bail!("{name} has no laser scans");
        }
        // The reference: any problem is reported and the runs go on.
        let (reference, reference_error) = match m.get_one::<String>("reference") {
            None => (None, None),
            Some(path) => match std::fs::read(path)
                .map_err(|e| format!("cannot read {path}: {e}"))
                .and_then(|bytes| {
                    LogReference::read(&bytes, &file_name(path), &log)
                        .map_err(|e| format!("{}: {e}", file_name(path)))
                }) {
                Ok(r) => (Some(Arc::new(r)), None),
                Err(e) => {
                    eprintln!("warning: {e}; the runs go on without a score");
                    (None, Some(e))
                }
            },
        };
        let duration = input.duration();
        let input = Arc::new(input);
        let seed = m.get_one::<u64>("seed").copied().unwrap_or(1);
        let rows: Vec<Row> = sources
            .par_iter()
            .map(|&source| {
                let started = ThreadTime::now();
                let (poses, loop_closures) = run_source(source, &input, seed);
                let cpu_s = started.elapsed().as_secs_f64();
                let score = reference.as_deref().and_then(|r| score(r, &poses));
                eprintln!("laser-slam: {source} done in {cpu_s:.1} s of CPU");
                Row {
                    poses: source.to_owned(),
                    scans: poses.iter().filter(|p| p.is_some()).count(),
                    ate_m: score.as_ref().map(|s| s.ate_m),
                    score,
                    cpu_s,
                    real_time_factor: duration / cpu_s.max(1e-9),
                    loop_closures,
                }
            })
            .collect();
        let json = serde_json::json!({
            "experiment": "laser-slam",
            "log": name,
            "scans": input.scans.len(),
            "duration_s": duration,
            "reference": reference.as_deref().map(|r| serde_json::json!({
                "name": r.name,
                "scans": r.reference_scans,
                "matched": r.points.len(),
                "association": r.description,
            })),
            "reference_error": reference_error,
            "results": rows,
        });
        if out.print_json(&json)? {
            return Ok(());
        }
        writeln!(
            out,
            "SLAM Lab experiment laser-slam: {name}, {} scans ({duration:.0} s of data)",
            input.scans.len()
        )?;
        match (&reference, &reference_error) {
            (Some(r), _) => writeln!(out, "reference: {} ({})", r.name, r.description)?,
            (None, Some(e)) => writeln!(out, "reference: none ({e})")?,
            (None, None) => writeln!(out, "reference: none (give --reference for scores)")?,
        }
        writeln!(out)?;
        writeln!(
            out,
            "{:<19} {:>8} {:>21} {:>21} {:>21} {:>8} {:>9}",
            "poses",
            "ATE (m)",
            "rel. 1: trans (m)",
            "rel. 1: rot (deg)",
            "rel. 10: trans (m)",
            "CPU (s)",
            "x real"
        )?;
        for r in &rows {
            let rel = |k: usize, rot: bool| -> String {
                r.score
                    .as_ref()
                    .and_then(|s| s.relative.get(k))
                    .map_or("-".to_owned(), |x| {
                        let v = if rot { x.rotation_deg } else { x.translation_m };
                        format!("{:.3} ± {:.3}", v.mean, v.std)
                    })
            };
            writeln!(
                out,
                "{:<19} {:>8} {:>21} {:>21} {:>21} {:>8.1} {:>9.1}",
                r.poses,
                r.ate_m.map_or("-".to_owned(), |v| format!("{v:.3}")),
                rel(0, false),
                rel(0, true),
                rel(1, false),
                r.cpu_s,
                r.real_time_factor
            )?;
        }
        Ok(())
    }
}

fn file_name(path: &str) -> String {
    Path::new(path)
        .file_name()
        .map_or(path.to_owned(), |n| n.to_string_lossy().into_owned())
}
