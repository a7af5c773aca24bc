//! Mapping speed and memory: `cargo bench -p slamlab-sim --bench mapping`.
//!
//! 1. The built-in office, 3000 scans of 360 beams, scan-to-map poses: the
//!    time of each *match* phase (correlative search + Levenberg-Marquardt on
//!    Eq. 5.5) and of each whole scan (predict, match, insert), median and
//!    95th percentile; the grid's memory at the end (also with true poses).
//!    Target: scan-to-map matching of a 360-beam scan in 1 ms.
//! 2. The Intel Research Lab log (`../shared/data/laser/intel.clf.bz2`, or
//!    `$SLAMLAB_SHARED/data/laser/...`; 13,631 scans of 180 beams, 44.9
//!    minutes), mapped whole with scan-to-map poses and with raw odometry:
//!    seconds and the real-time factor. Target: under 15 s (180x real time).
//!    Skipped with a message when the log is absent.
//!
//! Each time is given as wall-clock time and as the thread's CPU time, which
//! other work on a shared machine inflates far less. Results with date and
//! machine are in `docs/mapping.md`.

#![allow(clippy::panic)] // a benchmark whose input does not load cannot run

mod common;

use cpu_time::ThreadTime;
use slamlab_sim::grid::{builtin_map, log_input};
use slamlab_sim::mapping::{
    MappingPhase, MappingScenario, MappingSession, PoseSource, simulated_input,
};
use std::sync::Arc;
use std::time::Instant;

fn percentile(values: &mut [f64], q: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    values[((values.len() - 1) as f64 * q).round() as usize]
}

fn office(poses: PoseSource) {
    let scenario = MappingScenario {
        map: "office".to_owned(),
        steps: 3000,
        seed: 1,
        poses,
        ..MappingScenario::default()
    };
    let grid = Arc::new(builtin_map("office").unwrap_or_else(|e| panic!("{e}")));
    let input =
        Arc::new(simulated_input(&scenario, grid, "office").unwrap_or_else(|e| panic!("{e}")));
    let (mut session, _) = MappingSession::new(scenario, input);
    let (mut matches, mut scans) = (Vec::new(), Vec::new());
    let (mut matches_cpu, mut scans_cpu) = (Vec::new(), Vec::new());
    let started = Instant::now();
    let started_cpu = ThreadTime::now();
    while !session.sim().is_done() {
        let scan_started = (Instant::now(), ThreadTime::now());
        loop {
            let phase_started = (Instant::now(), ThreadTime::now());
            let phase = session.stepper_mut().step_phase();
            if let MappingPhase::Match { iterations, .. } = phase
                && iterations > 0
            {
                matches.push(phase_started.0.elapsed().as_secs_f64() * 1e3);
                matches_cpu.push(phase_started.1.elapsed().as_secs_f64() * 1e3);
            }
            if !slamlab_sim::stepper::Simulation::is_mid_tick(session.sim()) {
                break;
            }
        }
        scans.push(scan_started.0.elapsed().as_secs_f64() * 1e3);
        scans_cpu.push(scan_started.1.elapsed().as_secs_f64() * 1e3);
    }
    let total = started.elapsed().as_secs_f64();
    let total_cpu = started_cpu.elapsed().as_secs_f64();
    let summary = session.summary();
    println!(
        "office, 3000 scans, {}: {total:.2} s in all ({total_cpu:.2} s of thread CPU time); \
         per scan median {:.3} ms, p95 {:.3} ms (CPU {:.3} ms, {:.3} ms); match phase median \
         {:.3} ms, p95 {:.3} ms (CPU {:.3} ms, {:.3} ms; {} matches); grid {:.2} MB for {} \
         known cells ({} x {} cells of {} m)",
        poses.name(),
        percentile(&mut scans, 0.5),
        percentile(&mut scans, 0.95),
        percentile(&mut scans_cpu, 0.5),
        percentile(&mut scans_cpu, 0.95),
        percentile(&mut matches, 0.5),
        percentile(&mut matches, 0.95),
        percentile(&mut matches_cpu, 0.5),
        percentile(&mut matches_cpu, 0.95),
        matches.len(),
        summary.map.memory_bytes as f64 / 1e6,
        summary.map.known_cells,
        summary.map.width,
        summary.map.height,
        summary.map.resolution,
    );
}

fn intel(poses: PoseSource) {
    let Some(log) = common::intel_log() else {
        return;
    };
    let input = Arc::new(log_input(&log, "intel.clf.bz2"));
    let duration = input.duration();
    let scenario = MappingScenario {
        poses,
        ..MappingScenario::default()
    };
    let (mut session, _) = MappingSession::new(scenario, input);
    let started = Instant::now();
    let started_cpu = ThreadTime::now();
    session.run_to_end();
    let seconds = started.elapsed().as_secs_f64();
    let cpu = started_cpu.elapsed().as_secs_f64();
    let summary = session.summary();
    println!(
        "intel, {} scans ({:.1} min of data), {}: {seconds:.2} s, {:.0}x real time, {:.3} ms per \
         scan; thread CPU time {cpu:.2} s, {:.0}x real time; grid {:.2} MB, {} known cells",
        summary.scans,
        duration / 60.0,
        poses.name(),
        duration / seconds,
        seconds * 1e3 / summary.scans.max(1) as f64,
        duration / cpu,
        summary.map.memory_bytes as f64 / 1e6,
        summary.map.known_cells,
    );
}

fn main() {
    office(PoseSource::ScanToMap);
    office(PoseSource::Truth);
    intel(PoseSource::ScanToMap);
    intel(PoseSource::Odometry);
}
