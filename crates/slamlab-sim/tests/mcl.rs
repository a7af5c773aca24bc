//! Monte Carlo localization on the built-in maze and, when present, the real
//! maps in `../shared/data/maps`.

#![allow(clippy::panic, clippy::unwrap_used, clippy::expect_used)] // a failing test stops

use slamlab_core::wrap_angle;
use slamlab_sim::grid::BuiltinMap;
use slamlab_sim::io::ros_map::{load_lone_image, load_map};
use slamlab_sim::kidnap::{InitMode, MclRun, MclScenario};
use std::path::PathBuf;

fn run(
    grid: slamlab_core::grid::OccupancyGrid,
    init: InitMode,
    particles: usize,
    seed: u64,
) -> MclRun {
    let scenario = MclScenario {
        init,
        max_particles: particles,
        seed,
        ..Default::default()
    };
    MclRun::new(scenario, grid).unwrap()
}

fn shared_maps() -> Option<PathBuf> {
    let p = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/maps"
    ));
    p.is_dir().then_some(p)
}

/// Tracking: started around the truth (amcl's initial covariance), 1000 ticks
/// of exploring (about 40 m): the estimate stays within 0.3 m at every update
/// and every tick. With the plain product of the beams' likelihoods
/// (`laser_likelihood_exponent` 1; measured worst 0.13 m). The tempered
/// default (0.05), made for global localization, tracks more loosely: worst
/// 0.33 / 0.54 / 0.30 m on seeds 3 / 4 / 5 (docs/kidnap.md).
#[test]
fn tracking_on_the_maze_stays_within_30_cm() {
    let scenario = MclScenario {
        init: InitMode::Tracking,
        max_particles: 1000,
        seed: 3,
        laser_likelihood_exponent: 1.0,
        ..Default::default()
    };
    let mut r = MclRun::new(scenario, BuiltinMap::Maze.load().unwrap()).unwrap();
    r.run_ticks(1000);
    let f = &r.filters()[0];
    assert!(f.updates.len() > 150, "{} updates", f.updates.len());
    let worst = f.ticks.iter().map(|e| e.position).fold(0.0, f64::max);
    assert!(worst < 0.3, "worst tick error {worst}");
    let worst_heading = f
        .updates
        .iter()
        .map(|u| u.heading_error)
        .fold(0.0, f64::max);
    assert!(worst_heading < 0.3, "{worst_heading}");
    let s = f.summary();
    assert_eq!(s.converged_tick, Some(0));
    assert!(s.position_rmse_converged.unwrap() < 0.1, "{s:?}");
    // The 2-sigma bound is a sensible size.
    let last = f.updates.last().unwrap();
    assert!(
        last.position_2sigma > 0.005 && last.position_2sigma < 0.5,
        "{last:?}"
    );
    assert!(
        r.notes().iter().all(|n| !n.contains("collision")),
        "{:?}",
        r.notes()
    );
}

/// Global localization, the affordable version run every time: four seeds,
/// 5000 particles, 200 ticks (measured: they converge at ticks 60 - 90).
#[test]
fn global_localization_on_the_maze_converges_quickly_for_four_seeds() {
    for seed in [1, 2, 4, 9] {
        let mut r = run(
            BuiltinMap::Maze.load().unwrap(),
            InitMode::Global,
            5000,
            seed,
        );
        r.run_ticks(200);
        let s = &r.summaries()[0];
        let t = s
            .converged_tick
            .unwrap_or_else(|| panic!("seed {seed}: {s:?}"));
        assert!(t <= 150, "seed {seed}: {s:?}");
        assert!(s.position_error_final.unwrap() < 0.3, "seed {seed}: {s:?}");
    }
}

/// Global localization, the full statement: 5000 particles converge within 1000
/// ticks in at least 9 of 10 seeds (measured: 10 of 10, at ticks 60 - 737).
/// About 30 s in release; run with `cargo test --release`.
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "30 s in release; the four-seed version always runs"
)]
fn global_localization_on_the_maze_converges_in_9_of_10_seeds() {
    let mut converged = 0;
    for seed in 1..=10 {
        let mut r = run(
            BuiltinMap::Maze.load().unwrap(),
            InitMode::Global,
            5000,
            seed,
        );
        r.run_ticks(1000);
        if r.summaries()[0].converged_tick.is_some_and(|t| t < 1000) {
            converged += 1;
        }
    }
    assert!(converged >= 9, "{converged} of 10");
}

/// The same on the teb maze (ROS teb_local_planner tutorials), when present.
#[test]
#[cfg_attr(debug_assertions, ignore = "30 s in release")]
fn global_localization_on_the_teb_maze_converges_in_9_of_10_seeds() {
    let Some(dir) = shared_maps() else {
        println!("skipped: ../shared/data/maps not found");
        return;
    };
    let dir = dir.join("teb_local_planner_tutorials");
    let yaml = std::fs::read_to_string(dir.join("maze.yaml")).unwrap();
    let image = std::fs::read(dir.join("maze.png")).unwrap();
    let (grid, _) = load_map(&yaml, &image).unwrap();
    let mut converged = Vec::new();
    for seed in 1..=10 {
        let mut r = run(grid.clone(), InitMode::Global, 5000, seed);
        r.run_ticks(1000);
        converged.push(r.summaries()[0].converged_tick);
    }
    let n = converged.iter().filter(|c| c.is_some()).count();
    assert!(n >= 9, "{converged:?}");
}

/// The Willow Garage maps (PGM without YAML: 0.1 m per pixel, origin 0) load,
/// and a scan from a free pose sees walls.
#[test]
fn willow_maps_load_as_lone_images() {
    let Some(dir) = shared_maps() else {
        println!("skipped: ../shared/data/maps not found");
        return;
    };
    for (file, w, h) in [
        ("stage_ros/willow-full.pgm", 540, 587),
        ("navigation_stage/willow-full.pgm", 584, 526),
    ] {
        let bytes = std::fs::read(dir.join(file)).unwrap();
        let g = load_lone_image(&bytes, 0.1).unwrap();
        assert_eq!((g.width(), g.height()), (w, h), "{file}");
        let (free, occ, unknown) = g.counts();
        assert!(
            free > 100_000 && occ > 4_000 && unknown > 0,
            "{file}: {free} {occ} {unknown}"
        );
        let r = run(g, InitMode::Tracking, 200, 1);
        let pose = r.robot().pose;
        let hits = slamlab_sim::grid::Lidar::default()
            .true_ranges(r.map().grid(), &pose)
            .iter()
            .filter(|&&d| d < 12.0)
            .count();
        assert!(hits > 10, "{file}: {hits} hits from {pose:?}");
    }
}

/// The seeded run replays bit for bit, and a clone is a checkpoint.
#[test]
fn runs_replay_exactly_and_clones_are_checkpoints() {
    let mut a = run(BuiltinMap::Maze.load().unwrap(), InitMode::Global, 300, 7);
    a.run_ticks(40);
    let mut b = a.clone();
    a.run_ticks(30);
    // Phase by phase reaches the same state.
    while b.tick_count() < 70 {
        b.step_phase();
    }
    assert_eq!(a.robot().pose, b.robot().pose);
    let pa: Vec<_> = a.filters()[0].mcl().particles().to_vec();
    let pb: Vec<_> = b.filters()[0].mcl().particles().to_vec();
    assert_eq!(pa, pb);
    let e = a.filters()[0].ticks.last().unwrap();
    assert!(e.position.is_finite() && wrap_angle(e.heading).abs() <= std::f64::consts::PI);
}
