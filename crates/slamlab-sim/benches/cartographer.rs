//! Cartographer-style SLAM speed (thesis `000` Sec. 5.2):
//! `cargo bench -p slamlab-sim --bench cartographer`.
//!
//! 1. Local SLAM per scan: the built-in office, 600 scans of 360 beams, loop
//!    closures off: each scan's prediction, scan-to-submap matching
//!    (correlative search and Eq. 5.5), motion filter and insertion into the
//!    two active submaps. Target: 1 ms per scan.
//! 2. The whole system on the office: 600 scans with a kidnap at scan 152,
//!    loop closures, global searches after the detection and the
//!    optimizations: total, per-scan median, 95th percentile and maximum.
//! 3. The Intel Research Lab log (`../shared/data/laser/intel.clf.bz2`, or
//!    `$SLAMLAB_SHARED/data/laser/...`; 13,631 scans of 180 beams, 44.9
//!    minutes) end to end with loop closures: seconds and the real-time
//!    factor. Skipped with a message when the log is absent, or when
//!    `SLAMLAB_BENCH_QUICK=1` (it takes a quarter of an hour).
//!
//! Times are the thread's CPU time (other work on a shared machine inflates
//! wall-clock time far more) beside wall time. Results with date and machine
//! are in `docs/cartographer.md`.

#![allow(clippy::panic)] // a benchmark whose input does not load cannot run

mod common;

use cpu_time::ThreadTime;
use slamlab_sim::cartographer::input::kidnap_input;
use slamlab_sim::cartographer::{CartographerParams, CartographerSim};
use slamlab_sim::grid::SimulatedLogConfig;
use slamlab_sim::grid::{builtin_map, log_input};
use std::sync::Arc;
use std::time::Instant;

fn percentile(values: &mut [f64], q: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    values[((values.len() - 1) as f64 * q).round() as usize]
}

/// Runs `sim` to its end; prints the per-scan CPU times under `label`.
fn run(label: &str, mut sim: CartographerSim, kidnap_at: Option<usize>) {
    let mut per_scan = Vec::new();
    let started = Instant::now();
    let started_cpu = ThreadTime::now();
    loop {
        let scan_started = ThreadTime::now();
        if !sim.step() {
            break;
        }
        per_scan.push(scan_started.elapsed().as_secs_f64() * 1e3);
    }
    let wall = started.elapsed().as_secs_f64();
    let cpu = started_cpu.elapsed().as_secs_f64();
    let duration = sim
        .input()
        .scans
        .last()
        .zip(sim.input().scans.first())
        .map_or(0.0, |(b, a)| b.time - a.time);
    let s = sim.summary(kidnap_at, wall * 1e3);
    let max = per_scan.iter().copied().fold(0.0, f64::max);
    println!(
        "{label}: {} scans in {wall:.2} s wall, {cpu:.2} s thread CPU ({:.0}x real time on CPU); \
         per scan CPU median {:.3} ms, p95 {:.3} ms, max {max:.1} ms; {} nodes, {} submaps, \
         {} loop closures, {} optimizations, {} searches scoring {} candidates (exhaustive {}), \
         detections {:?}, merged at {:?}",
        s.scans,
        duration / cpu,
        percentile(&mut per_scan, 0.5),
        percentile(&mut per_scan, 0.95),
        s.nodes,
        s.submaps,
        s.loop_closures,
        s.optimizations,
        s.bbs.searches,
        s.bbs.nodes_evaluated,
        s.bbs.exhaustive_candidates,
        s.detections,
        s.recovered_at,
    );
}

fn office(kidnap_at: Option<usize>, params: CartographerParams, label: &str) {
    let grid = Arc::new(builtin_map("office").unwrap_or_else(|e| panic!("{e}")));
    let input = kidnap_input(
        grid,
        "office",
        600,
        1,
        kidnap_at,
        &SimulatedLogConfig::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let (sim, _) = CartographerSim::new(Arc::new(input), params);
    run(label, sim, kidnap_at);
}

fn intel() {
    if std::env::var("SLAMLAB_BENCH_QUICK").is_ok_and(|v| v == "1") {
        println!("intel: skipped (SLAMLAB_BENCH_QUICK=1)");
        return;
    }
    let Some(log) = common::intel_log() else {
        return;
    };
    let input = Arc::new(log_input(&log, "intel.clf.bz2"));
    let (sim, _) = CartographerSim::new(input, CartographerParams::default());
    run("intel, loop closures on", sim, None);
}

fn main() {
    let local_only = CartographerParams {
        constraint_every_n_nodes: usize::MAX,
        ..CartographerParams::default()
    };
    office(None, local_only, "office, local SLAM only");
    office(
        Some(152),
        CartographerParams::default(),
        "office, kidnap at 152, everything on",
    );
    intel();
}
