//! `slamlab experiment grid-fastslam`: grid FastSLAM (gmapping) with the
//! odometry and the improved proposal over particle counts, on a simulated
//! drive through a grid map.
//!
//! ```text
//! slamlab experiment grid-fastslam --map office --particles 5,30,100 \
//!     --proposal odometry,scan-match --trials 5 --steps 3000 --seed 1 --json
//! slamlab experiment grid-fastslam --log intel.clf.bz2 --particles 30 \
//!     --proposal scan-match --map-out intel.yaml
//! ```
//!
//! With `--log` it runs once per particle count and proposal over a CARMEN
//! log instead (no truth: time, resamplings and memory), and `--map-out`
//! writes the best particle's map of the last run.

use super::fastslam::parse_counts;
use crate::args;
use crate::command::Experiment;
use crate::flags;
use crate::map::{map_arg, read_map};
use crate::output::{Output, progress_bar};
use anyhow::{Result, bail};
use clap::{ArgMatches, Command};
use slamlab_core::particle::{GridFastSlamConfig, MAX_GRID_PARTICLES, Proposal};
use slamlab_sim::mapping::MappingScenario;
use slamlab_sim::mapping::grid_fastslam::run_grid_fastslam;
use slamlab_sim::mapping::grid_fastslam::{GridExperimentPlan, grid_fastslam_experiment};
use std::io::Write;
use std::path::Path;
use std::sync::Arc;

/// Grid FastSLAM's errors against its particle count and proposal.
pub struct GridFastSlam;

impl Experiment for GridFastSlam {
    fn command(&self) -> Command {
        Command::new("grid-fastslam")
            .about("grid FastSLAM (gmapping): trajectory RMSE, map agreement, resamplings, time and memory per particle count and proposal")
            .arg(map_arg())
            .arg(
                args::list(
                    "particles",
                    "comma-separated particle counts (1 .. 1000; each particle carries a map)",
                )
                .default_value("5,30"),
            )
            .arg(
                args::list("proposal", "comma-separated proposals: odometry, scan-match")
                    .default_value("odometry,scan-match"),
            )
            .arg(
                args::whole("trials", 1..=1000, "simulated drives; trial i uses seed + i")
                    .default_value("5"),
            )
            .arg(
                args::whole("steps", 1..=1_000_000, "scans per drive (0.1 s apart)")
                    .default_value("3000"),
            )
            .arg(args::file(
                "log",
                "run over a CARMEN laser log (plain, .gz or .bz2) or a ROS 2 bag (.mcap) instead of simulated drives",
            ))
            .args(crate::log_cmd::topic_args())
            .arg(args::named(
                "map-out",
                "YAML",
                "with --log: write the best particle's map as a ROS map (YAML and PGM)",
            ))
            .arg(args::seed("the first trial's seed"))
    }

    fn run(&self, m: &ArgMatches, out: &mut Output) -> Result<()> {
        let spec = m.get_one::<String>("map").map_or("office", String::as_str);
        let (grid, name) = read_map(spec, None)?;
        let counts = parse_counts(
            m.get_one::<String>("particles")
                .map_or("5,30", String::as_str),
        )?;
        if let Some(n) = counts.iter().find(|n| **n > MAX_GRID_PARTICLES) {
            bail!(
                "--particles: {n} is more than the {MAX_GRID_PARTICLES} grid FastSLAM runs (each particle carries a map)"
            );
        }
        let mut proposals = Vec::new();
        for part in flags::list(m, "proposal") {
            let Some(p) = Proposal::from_name(part) else {
                bail!("--proposal: '{part}' is not a proposal (odometry, scan-match)");
            };
            proposals.push(p);
        }
        if proposals.is_empty() {
            bail!("--proposal: give at least one of odometry, scan-match");
        }
        if let Some(log) = m.get_one::<String>("log") {
            return run_log(Path::new(log), &counts, &proposals, m, out);
        }
        if m.get_one::<String>("map-out").is_some() {
            bail!(
                "--map-out writes the map of a --log run; a simulated drive's maps are not written"
            );
        }
        let trials = m.get_one::<u64>("trials").copied().unwrap_or(5) as usize;
        let steps = m.get_one::<u64>("steps").copied().unwrap_or(3000) as usize;
        let seed = m.get_one::<u64>("seed").copied().unwrap_or(1);
        let result = grid_fastslam_experiment(
            (Arc::new(grid), name),
            GridFastSlamConfig::default(),
            &GridExperimentPlan {
                counts,
                proposals,
                trials,
                steps,
                seed,
            },
            progress_bar("grid-fastslam"),
        )
        .map_err(anyhow::Error::msg)?;
        if out.print_json(&result)? {
            return Ok(());
        }
        writeln!(
            out,
            "SLAM Lab experiment grid-fastslam: {} trials of {steps} scans in the {} map from seed {seed}",
            trials, result.map
        )?;
        writeln!(out)?;
        writeln!(
            out,
            "{:>9} {:>11} {:>22} {:>14} {:>12} {:>10} {:>10}",
            "particles",
            "proposal",
            "trajectory RMSE (m)",
            "map agreement",
            "resamplings",
            "ms/run",
            "peak MB"
        )?;
        for r in &result.results {
            writeln!(
                out,
                "{:>9} {:>11} {:>10.3} (p90 {:>5.3}) {:>14.3} {:>5.1} of {:<5.0} {:>10.0} {:>10.1}",
                r.particles,
                r.proposal,
                r.trajectory_rmse.median,
                r.trajectory_rmse.p90,
                r.map_agreement.median,
                r.resamplings,
                r.updates,
                r.time_ms,
                r.memory_mb
            )?;
        }
        writeln!(out)?;
        writeln!(
            out,
            "medians over trials; the best particle's path at its updates against the truth, its map against the true map."
        )?;
        Ok(())
    }
}

/// `--log`: one run per particle count and proposal over a laser log.
fn run_log(
    path: &Path,
    counts: &[usize],
    proposals: &[Proposal],
    m: &ArgMatches,
    out: &mut Output,
) -> Result<()> {
    let input = crate::log_cmd::read_laser_file(&path.display().to_string(), m)?.input;
    let name = input.name.clone();
    if input.scans.is_empty() {
        bail!("{name} has no laser scans");
    }
    let seed = m.get_one::<u64>("seed").copied().unwrap_or(1);
    let insert = MappingScenario::default().insert_params();
    let mut rows = Vec::new();
    let mut last = None;
    for &particles in counts {
        for &proposal in proposals {
            let config = GridFastSlamConfig {
                particles,
                proposal,
                ..GridFastSlamConfig::default()
            };
            let (filter, summary) = run_grid_fastslam(&input, config, insert, seed);
            rows.push(serde_json::json!({
                "particles": particles,
                "proposal": proposal.name(),
                "scans": summary.scans,
                "updates": summary.updates,
                "resamplings": summary.resamplings,
                "fallbacks": summary.fallbacks,
                "time_ms": summary.time_ms,
                "real_time_factor": input.duration() * 1e3 / summary.time_ms.max(1e-9),
                "memory_mb": summary.peak_memory_bytes as f64 / 1e6,
            }));
            last = Some(filter);
        }
    }
    if let (Some(path), Some(filter)) = (m.get_one::<String>("map-out"), &last)
        && let Some(best) = filter.best()
    {
        crate::lessons::mapping::write_map(&best.map, Path::new(path))?;
    }
    if out.print_json(&serde_json::json!({
        "experiment": "grid-fastslam",
        "log": name,
        "duration_s": input.duration(),
        "seed": seed,
        "results": rows,
    }))? {
        return Ok(());
    }
    writeln!(
        out,
        "SLAM Lab experiment grid-fastslam: {name}, {} scans ({:.0} s of data), seed {seed}",
        input.scans.len(),
        input.duration()
    )?;
    writeln!(out)?;
    for r in &rows {
        writeln!(
            out,
            "{:>4} particles, {:<10} {:>5} updates, {:>4} resamplings, {:>8.0} ms ({:.1}x real time), peak {:.1} MB",
            r["particles"],
            r["proposal"].as_str().unwrap_or(""),
            r["updates"],
            r["resamplings"],
            r["time_ms"].as_f64().unwrap_or(f64::NAN),
            r["real_time_factor"].as_f64().unwrap_or(f64::NAN),
            r["memory_mb"].as_f64().unwrap_or(f64::NAN)
        )?;
    }
    Ok(())
}
