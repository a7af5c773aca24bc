//! `slamlab run cartographer`: submaps, branch-and-bound loop closure and the
//! kidnapped robot during mapping (thesis `000` Sec. 5.2), headless.
//!
//! ```text
//! slamlab run cartographer --map maze --steps 600 --kidnap-at 152 --seed 1 --json
//! slamlab run cartographer --map maze --steps 600 --kidnap-at 152 --detection off
//! slamlab run cartographer --log intel.clf.bz2 --json
//! slamlab run cartographer --log intel.clf.bz2 --reference intel-corrected.log.gz --loop-closures off
//! ```

use crate::args;
use crate::command::RunLesson;
use crate::log_cmd::{laser_log_arg, read_laser_file, topic_args};
use crate::map::{map_arg, read_map};
use crate::output::{Output, units_bar, units_progress};
use anyhow::{Result, bail};
use clap::{Arg, ArgMatches, Command};
use cpu_time::ThreadTime;
use serde_json::json;
use slamlab_sim::cartographer::input::{KidnapPlace, kidnap_input_to};
use slamlab_sim::cartographer::{CartographerParams, CartographerSim};
use slamlab_sim::grid::SimulatedLogConfig;
use slamlab_sim::grid::reference;
use std::io::Write;
use std::sync::Arc;
use std::time::Instant;

/// The Cartographer run.
pub struct Cartographer;

/// A parameter of Cartographer that `slamlab run cartographer` sets by its name
/// in Cartographer's configuration (`--num_range_data 30`): that name (the
/// flag's), its help, and the setter of the field of [`CartographerParams`] it
/// sets. The kind picks the flag's parser and the value [`Tuning::apply`] reads,
/// so the two cannot disagree.
enum Tuning {
    /// A real number.
    Number(&'static str, &'static str, fn(&mut CartographerParams, f64)),
    /// A count.
    Count(
        &'static str,
        &'static str,
        fn(&mut CartographerParams, usize),
    ),
}

/// The parameters, in the order `--help` lists them.
const TUNINGS: &[Tuning] = &[
    Tuning::Count("num_range_data", "scans per submap (default 30)", |p, v| {
        p.num_range_data = v;
    }),
    Tuning::Number(
        "resolution",
        "submap cell size, metres (default 0.05)",
        |p, v| {
            p.resolution = v;
        },
    ),
    Tuning::Number("hit_probability", "default 0.55", |p, v| {
        p.hit_probability = v;
    }),
    Tuning::Number("miss_probability", "default 0.49", |p, v| {
        p.miss_probability = v;
    }),
    Tuning::Number(
        "linear_search_window",
        "loop-closure search half-width, metres (default 0.6)",
        |p, v| p.linear_search_window = v,
    ),
    Tuning::Number(
        "angular_search_window",
        "loop-closure search half-width, degrees (default 5)",
        |p, v| p.angular_search_window = v.to_radians(),
    ),
    Tuning::Number(
        "max_constraint_distance",
        "search only submaps whose origin is this near a node, metres (default 15)",
        |p, v| p.max_constraint_distance = v,
    ),
    Tuning::Number(
        "sampling_ratio",
        "share of node-submap pairs searched for loop closures, sampled per submap (default 0.1)",
        |p, v| p.sampling_ratio = v,
    ),
    Tuning::Count(
        "max_closures_per_submap_pair",
        "loop closures tying a node's submap to another before their pairs are searched no more (default 0: no limit)",
        |p, v| p.max_closures_per_submap_pair = v,
    ),
    Tuning::Number(
        "min_score",
        "a loop closure must score above this (default 0.55)",
        |p, v| p.min_score = v,
    ),
    Tuning::Number(
        "global_min_score",
        "a match between maps must score above this (default 0.6)",
        |p, v| p.global_min_score = v,
    ),
    Tuning::Count("optimize_every_n_nodes", "default 30", |p, v| {
        p.optimize_every_n_nodes = v;
    }),
    Tuning::Number("huber_scale", "default 10", |p, v| p.huber_scale = v),
    Tuning::Number("T", "kidnap trigger threshold (default 1.5)", |p, v| {
        p.kidnap.threshold = v;
    }),
    Tuning::Count(
        "f_size",
        "kidnap average filter size (default 4)",
        |p, v| {
            p.kidnap.filter_size = v;
        },
    ),
];

impl Tuning {
    /// Its flag.
    fn arg(&self) -> Arg {
        match self {
            Tuning::Number(name, help, _) => args::number(name, *help),
            Tuning::Count(name, help, _) => args::count(name, *help),
        }
    }

    /// Sets its field of `params` if its flag was given.
    fn apply(&self, m: &ArgMatches, params: &mut CartographerParams) {
        match self {
            Tuning::Number(name, _, set) => {
                if let Some(&v) = m.get_one::<f64>(name) {
                    set(params, v);
                }
            }
            Tuning::Count(name, _, set) => {
                if let Some(&v) = m.get_one::<usize>(name) {
                    set(params, v);
                }
            }
        }
    }
}

impl RunLesson for Cartographer {
    fn command(&self) -> Command {
        Command::new("cartographer")
            .about("submaps, branch-and-bound loop closure and the kidnapped robot (Cartographer-style SLAM): local SLAM into submaps, a pose graph with loop closures, kidnap detection by an average filter on the matching cost, recovery by merging a new map")
            .arg(map_arg())
            .arg(laser_log_arg())
            .arg(args::file(
                "reference",
                "with --log: its corrected log (e.g. intel-corrected.log.gz); the trajectory is scored against it (ATE, relative errors)",
            ))
            .args(topic_args())
            .arg(args::count(
                "steps",
                "scans to simulate (default 600); with --log, map only the log's first scans",
            ))
            .arg(
                args::flag("seed", "the simulation's seed (default 1)")
                    .allow_negative_numbers(true)
                    .value_parser(clap::value_parser!(u64)),
            )
            .arg(args::count(
                "kidnap-at",
                "carry the robot elsewhere just before this scan (0-based)",
            ))
            .arg(args::choice(
                "kidnap-place",
                &KidnapPlace::NAMES,
                "where the kidnap carries the robot: mapped (default; a random place on its path so far) or anywhere (any free place)",
            ))
            .arg(args::choice(
                "detection",
                &["on", "off"],
                "kidnap detection (Algorithm 13): on (default) or off, the original behaviour",
            ))
            .arg(args::choice(
                "loop-closures",
                &["on", "off"],
                "loop closures: on (default), or off for local SLAM alone (no branch-and-bound search; the lesson's switch)",
            ))
            .args(TUNINGS.iter().map(Tuning::arg))
            .arg(crate::trajectory_out::arg())
    }

    fn run(&self, m: &ArgMatches, out: &mut Output) -> Result<()> {
        let mut params = CartographerParams::default();
        let n = |name: &str| m.get_one::<usize>(name).copied();
        for tuning in TUNINGS {
            tuning.apply(m, &mut params);
        }
        params.detection = m.get_one::<String>("detection").is_none_or(|d| d == "on");
        if m.get_one::<String>("loop-closures")
            .is_some_and(|v| v == "off")
        {
            params = params.without_loop_closures();
        }
        let steps = n("steps").unwrap_or(600);
        let seed = m.get_one::<u64>("seed").copied().unwrap_or(1);
        let mut kidnap_at = n("kidnap-at");
        let input = if let Some(log_path) = m.get_one::<String>("log") {
            let file = read_laser_file(log_path, m)?;
            if kidnap_at.take().is_some() {
                eprintln!(
                    "warning: --kidnap-at applies to a simulated robot; a log is replayed as recorded"
                );
            }
            let mut input = file.input;
            // Matched to the whole log, before --steps cuts it: the reference
            // scans past the cut are not scored.
            if let Some(path) = m.get_one::<String>("reference") {
                match std::fs::read(path)
                    .map_err(|e| format!("cannot read {path}: {e}"))
                    .and_then(|bytes| {
                        input
                            .reference_from(&bytes, path)
                            .map_err(|e| format!("{path}: {e}"))
                    }) {
                    Ok(r) => input.reference = Some(Arc::new(r)),
                    Err(e) => eprintln!("warning: {e}; the run goes on without a score"),
                }
            }
            if let Some(first) = n("steps") {
                input.scans.truncate(first);
            }
            input
        } else {
            let spec = m.get_one::<String>("map").map_or("maze", String::as_str);
            let (grid, name) = read_map(spec, None)?;
            if kidnap_at.is_some_and(|k| k >= steps) {
                eprintln!("warning: --kidnap-at is past the last scan: no kidnap");
                kidnap_at = None;
            }
            let place = m
                .get_one::<String>("kidnap-place")
                .and_then(|p| KidnapPlace::from_name(p))
                .unwrap_or_default();
            kidnap_input_to(
                Arc::new(grid),
                &name,
                steps,
                seed,
                kidnap_at.map(|k| (k, place)),
                &SimulatedLogConfig::default(),
            )
            .map_err(anyhow::Error::msg)?
        };
        if input.scans.is_empty() {
            bail!("the input has no laser scans");
        }
        let (mut sim, notices) = CartographerSim::new(Arc::new(input), params);
        for note in &notices {
            eprintln!("warning: {note}");
        }
        let total = sim.input().scans.len();
        let bar = units_bar("cartographer", total, "scans");
        let started = Instant::now();
        let cpu_started = ThreadTime::now();
        while sim.step() {
            units_progress(&bar, "cartographer", sim.scans_done(), total, "scans");
        }
        let time_ms = started.elapsed().as_secs_f64() * 1e3;
        let cpu_s = cpu_started.elapsed().as_secs_f64();
        let summary = sim.summary(kidnap_at, time_ms);
        let score = sim
            .input()
            .reference
            .as_deref()
            .and_then(|r| reference::score(r, &sim.scan_poses()));
        crate::trajectory_out::write(
            m,
            &self.id(),
            &slamlab_sim::cartographer::export::trajectories(&sim),
            &[],
        )?;
        for note in summary.notes.iter().take(5) {
            eprintln!("warning: {note}");
        }
        if out.json() {
            out.print_json(&json!({
                "scans": summary.scans,
                "input": sim.input().name,
                "kidnap_at": summary.kidnap_at,
                "kidnap_detected_at": summary.kidnap_detected_at,
                "detections": summary.detections,
                "false_alarms": summary.false_alarms,
                "recovered_at": summary.recovered_at,
                "loop_closures": summary.loop_closures,
                "rejected_closures": summary.rejected_closures,
                "trajectory_rmse": summary.trajectory_rmse,
                "map_agreement": summary.map_agreement,
                "bbs": summary.bbs,
                "nodes": summary.nodes,
                "submaps": summary.submaps,
                "trajectories": summary.trajectories,
                "optimizations": summary.optimizations,
                "time_ms": time_ms,
                "cpu_s": cpu_s,
                "real_time_factor": sim.input().duration() / cpu_s.max(1e-9),
                "score": score,
                "parameters": serde_json::to_value(sim.params())?,
            }))?;
            return Ok(());
        }
        let opt = |v: Option<usize>| v.map_or("none".to_owned(), |v| v.to_string());
        let g = |v: Option<f64>| v.map_or("- (no truth)".to_owned(), |v| format!("{v:.4}"));
        writeln!(
            out,
            "SLAM Lab: Cartographer-style SLAM on {} — {} scans, {} nodes, {} submaps, {} trajectories",
            sim.input().name,
            summary.scans,
            summary.nodes,
            summary.submaps,
            summary.trajectories
        )?;
        writeln!(
            out,
            "kidnap:          at {}, detected at {}, {} false alarms, recovered (maps merged) at {}",
            opt(summary.kidnap_at),
            opt(summary.kidnap_detected_at),
            summary.false_alarms,
            opt(summary.recovered_at)
        )?;
        writeln!(
            out,
            "loop closures:   {} ({} optimizations)",
            summary.loop_closures, summary.optimizations
        )?;
        writeln!(
            out,
            "branch & bound:  {} searches, {} candidates scored of {} an exhaustive search scores ({:.0}x fewer)",
            summary.bbs.searches,
            summary.bbs.nodes_evaluated,
            summary.bbs.exhaustive_candidates,
            summary.bbs.exhaustive_candidates as f64 / summary.bbs.nodes_evaluated.max(1) as f64
        )?;
        writeln!(out, "trajectory RMSE: {} m", g(summary.trajectory_rmse))?;
        writeln!(out, "map agreement:   {}", g(summary.map_agreement))?;
        if let Some(s) = &score {
            writeln!(
                out,
                "reference:       ATE {:.3} m after SE(2) alignment at {} reference scans",
                s.ate_m, s.pairs
            )?;
        }
        writeln!(
            out,
            "time:            {time_ms:.0} ms ({cpu_s:.1} s of CPU, {:.0}x real time)",
            sim.input().duration() / cpu_s.max(1e-9)
        )?;
        Ok(())
    }
}
