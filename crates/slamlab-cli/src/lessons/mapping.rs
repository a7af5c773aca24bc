//! `slamlab run mapping`: occupancy-grid mapping with a lidar, headless.
//!
//! ```text
//! slamlab run mapping --map office --steps 3000 --poses scan-to-map --seed 1 --json
//! slamlab run mapping --log intel.clf.bz2 --poses scan-to-map --json --map-out intel.yaml
//! slamlab run mapping --log my_robot.mcap --scan-topic /scan --odom-topic /odom
//! slamlab run mapping --map office --poses grid-fastslam --particles 30 --proposal scan-match
//! ```

use crate::args;
use crate::command::RunLesson;
use crate::flags;
use crate::log_cmd::{laser_log_arg, read_laser_file, topic_args};
use crate::map::{map_arg, read_map};
use crate::output::{Output, progress_bar};
use anyhow::{Context, Result, bail};
use clap::{ArgMatches, Command};
use serde_json::json;
use slamlab_sim::io::ros_map::{ImageFormat, export_map};
use slamlab_sim::mapping::{MappingScenario, MappingSession, simulated_input};
use std::io::Write;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

/// The mapping lesson's run.
pub struct Mapping;

impl RunLesson for Mapping {
    fn command(&self) -> Command {
        Command::new("mapping")
            .about("occupancy-grid mapping with a lidar: a simulated robot's scans, a CARMEN log or a ROS 2 bag, posed by truth, odometry, ICP, scan-to-map matching or grid FastSLAM's particles")
            .arg(map_arg())
            .arg(laser_log_arg())
            .args(topic_args())
            .arg(args::named(
                "map-out",
                "YAML",
                "write the built map as a ROS map_server YAML and PGM beside it",
            ))
            .args(flags::table_args::<MappingScenario>(|name| name != "map"))
            .arg(crate::trajectory_out::arg())
    }

    fn run(&self, m: &ArgMatches, out: &mut Output) -> Result<()> {
        let mut scenario: MappingScenario = flags::scenario_from(m, &["map"])?;
        let input = if let Some(log_path) = m.get_one::<String>("log") {
            read_laser_file(log_path, m)?.input
        } else {
            let spec = m.get_one::<String>("map").map_or("maze", String::as_str);
            let (grid, name) = read_map(spec, None)?;
            scenario.map = name.clone();
            simulated_input(&scenario, Arc::new(grid), &name).map_err(anyhow::Error::msg)?
        };
        if input.scans.is_empty() {
            bail!("the input has no laser scans");
        }
        let (mut session, notices) = MappingSession::new(scenario.clone(), Arc::new(input));
        for note in &notices {
            eprintln!("warning: {note}");
        }
        let total = session.sim().input().scans.len();
        let mut progress = progress_bar("mapping");
        let started = Instant::now();
        while !session.sim().is_done() {
            session.stepper_mut().step_tick();
            let done = session.sim().scans_done();
            if done % 100 == 0 || done == total {
                progress(done, total);
            }
        }
        let time_ms = started.elapsed().as_secs_f64() * 1e3;
        let summary = session.summary();
        crate::trajectory_out::write(
            m,
            &self.id(),
            &slamlab_sim::mapping::export::trajectories(&session),
            &[],
        )?;
        if let Some(note) = session.sim().note() {
            eprintln!("warning: {note}");
        }
        if let Some(path) = m.get_one::<String>("map-out") {
            write_map(session.sim().grid(), Path::new(path))?;
        }
        if out.json() {
            out.print_json(&json!({
                "scans": summary.scans,
                "poses": summary.poses,
                "input": summary.input,
                "duration_s": summary.duration_s,
                "time_ms": time_ms,
                "trajectory_rmse": summary.trajectory_rmse,
                "map_agreement": summary.map_agreement,
                "map": summary.map,
                "mean_iterations": summary.mean_iterations,
                "particles": summary.particles,
                "parameters": serde_json::to_value(session.scenario())?,
            }))?;
            return Ok(());
        }
        let f = |v: Option<f64>, unit: &str| {
            v.map_or("- (no truth)".to_owned(), |v| format!("{v:.4}{unit}"))
        };
        writeln!(
            out,
            "SLAM Lab: mapping {} with {} poses — {} scans ({:.0} s of data), seed {}",
            summary.input, summary.poses, summary.scans, summary.duration_s, scenario.seed
        )?;
        writeln!(
            out,
            "time:            {time_ms:.0} ms ({:.2} ms per scan, {:.0}x real time)",
            time_ms / summary.scans.max(1) as f64,
            summary.duration_s * 1e3 / time_ms.max(1e-9)
        )?;
        writeln!(out, "trajectory RMSE: {}", f(summary.trajectory_rmse, " m"))?;
        writeln!(out, "map agreement:   {}", f(summary.map_agreement, ""))?;
        writeln!(
            out,
            "map:             {} x {} cells of {} m, {} known, {:.1} MB",
            summary.map.width,
            summary.map.height,
            summary.map.resolution,
            summary.map.known_cells,
            summary.map.memory_bytes as f64 / 1e6
        )?;
        if let Some(p) = summary.particles {
            writeln!(
                out,
                "particles:       {} ({} proposal): {} updates, {} resamplings, {} fallbacks; maps {:.1} MB (peak {:.1} MB)",
                p.particles,
                p.proposal,
                p.updates,
                p.resamplings,
                p.fallbacks,
                p.memory_bytes as f64 / 1e6,
                p.peak_memory_bytes as f64 / 1e6
            )?;
        }
        Ok(())
    }
}

/// Writes `grid` as a ROS map: the YAML at `path`, the PGM beside it
/// (occupied above probability 0.65, free below 0.196, as map_server reads).
pub(crate) fn write_map(grid: &slamlab_core::grid::ProbabilityGrid, path: &Path) -> Result<()> {
    let Some(occupancy) = grid.to_occupancy_grid(0.65, 0.196) else {
        bail!("the map is empty: nothing to write");
    };
    let stem = path
        .file_stem()
        .map_or("map".to_owned(), |s| s.to_string_lossy().into_owned());
    let image_name = format!("{stem}.pgm");
    let (yaml, image) = export_map(&occupancy, &image_name, ImageFormat::Pgm)?;
    std::fs::write(path, yaml).with_context(|| format!("writing {}", path.display()))?;
    let image_path = path.with_file_name(&image_name);
    std::fs::write(&image_path, image)
        .with_context(|| format!("writing {}", image_path.display()))?;
    eprintln!("wrote {} and {}", path.display(), image_path.display());
    Ok(())
}
