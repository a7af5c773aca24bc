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
use slamlab_sim::cartographer::{CartographerParams, CartographerPhase, CartographerSim};
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

/// CPU time and count of one kind of phase.
#[derive(Clone, Copy, Default)]
struct PhaseTime {
    count: usize,
    seconds: f64,
}

impl PhaseTime {
    fn add(&mut self, seconds: f64) {
        self.count += 1;
        self.seconds += seconds;
    }
}

/// Where a run's CPU time went, phase by phase
/// (`CartographerSim::step_phase`).
#[derive(Default)]
struct Profile {
    local_slam: PhaseTime,
    local_searches: PhaseTime,
    global_searches: PhaseTime,
    optimizations: PhaseTime,
    other: PhaseTime,
}

impl Profile {
    fn print(&self, label: &str, total: f64) {
        println!("{label}: profile (thread CPU)");
        println!("  | phase | count | CPU s | share | per phase ms |");
        for (name, t) in [
            (
                "local SLAM (match, insert, finish submaps)",
                self.local_slam,
            ),
            ("searches in a window (same map)", self.local_searches),
            (
                "searches of whole submaps (other map)",
                self.global_searches,
            ),
            ("optimizations", self.optimizations),
            ("bookkeeping phases", self.other),
        ] {
            println!(
                "  | {name} | {} | {:.2} | {:.1} % | {:.3} |",
                t.count,
                t.seconds,
                100.0 * t.seconds / total.max(1e-12),
                if t.count == 0 {
                    0.0
                } else {
                    1e3 * t.seconds / t.count as f64
                }
            );
        }
    }
}

/// Runs `sim` to its end phase by phase; prints the per-scan CPU times and
/// the profile under `label`.
fn run(label: &str, mut sim: CartographerSim, kidnap_at: Option<usize>) {
    let mut per_scan: Vec<f64> = Vec::new();
    let mut profile = Profile::default();
    let started = Instant::now();
    let started_cpu = ThreadTime::now();
    loop {
        let phase_started = ThreadTime::now();
        let phase = sim.step_phase();
        let seconds = phase_started.elapsed().as_secs_f64();
        match phase {
            CartographerPhase::Done => break,
            CartographerPhase::LocalSlam { .. } => {
                profile.local_slam.add(seconds);
                per_scan.push(seconds * 1e3);
            }
            CartographerPhase::Search { global, .. } => {
                if global {
                    profile.global_searches.add(seconds);
                } else {
                    profile.local_searches.add(seconds);
                }
            }
            CartographerPhase::Optimization { .. } => profile.optimizations.add(seconds),
            CartographerPhase::Settled { .. } => profile.other.add(seconds),
        }
        if !matches!(phase, CartographerPhase::LocalSlam { .. })
            && let Some(last) = per_scan.last_mut()
        {
            *last += seconds * 1e3;
        }
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
    profile.print(label, cpu);
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
    let mut input = log_input(&log, "intel.clf.bz2");
    // `SLAMLAB_BENCH_INTEL_SCANS=N`: only the first N scans (a profile of a
    // shorter run).
    if let Some(n) = std::env::var("SLAMLAB_BENCH_INTEL_SCANS")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
    {
        input.scans.truncate(n);
    }
    let input = Arc::new(input);
    let (sim, _) = CartographerSim::new(input, CartographerParams::default());
    run("intel, loop closures on", sim, None);
}

fn main() {
    let local_only = CartographerParams {
        sampling_ratio: 0.0,
        global_search_every_n_nodes: usize::MAX,
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
