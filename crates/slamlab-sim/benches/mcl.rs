//! Monte Carlo localization speed: `cargo bench -p slamlab-sim --bench mcl`.
//!
//! Targets (docs/kidnap.md, "Monte Carlo localization (headless)"): one MCL
//! update (motion, likelihood field, resampling) with 5,000 particles and 60
//! beams ≤ 2 ms; the distance field of a 1000 x 1000 map ≤ 100 ms; a 360-beam
//! scan on the office map ≤ 0.1 ms.

#![allow(clippy::panic)] // a benchmark without its map cannot run

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use slamlab_core::Pose2;
use slamlab_core::grid::{Cell, DistanceField, OccupancyGrid};
use slamlab_core::particle::{LocalizationMap, Mcl, MclConfig};
use slamlab_sim::grid::{BuiltinMap, Lidar};
use std::sync::Arc;

fn main() {
    divan::main();
}

/// One full update (predict, weight with the likelihood field, low-variance
/// resampling, cluster estimate) of 5,000 particles tracking on the maze, with
/// a 60-beam scan all of whose beams are used.
#[divan::bench]
fn mcl_update_5000_particles_60_beams(bencher: divan::Bencher) {
    let grid = BuiltinMap::Maze.load().unwrap_or_else(|e| panic!("{e}"));
    let map = Arc::new(LocalizationMap::new(grid, 2.0).unwrap_or_else(|e| panic!("{e}")));
    let truth = Pose2::new(0.5, 0.5, 0.0);
    let lidar = Lidar {
        beams: 60,
        ..Default::default()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let scan = lidar.scan(map.grid(), &truth, &mut rng);
    let mut mcl = Mcl::new(
        MclConfig {
            particles: 5000,
            max_beams: 60,
            ..Default::default()
        },
        Arc::clone(&map),
        1,
    );
    mcl.init_tracking(truth, [0.3, 0.3, 0.2]);
    mcl.predict(Pose2::IDENTITY);
    bencher
        .with_inputs(|| mcl.clone())
        .bench_local_values(|mut m| {
            m.predict(Pose2::new(0.2, 0.0, 0.05));
            m.weight(&scan);
            m.resample();
            m
        });
}

/// The exact distance field of a 1000 x 1000 map (rooms of 5 m with doors at
/// 0.05 m per cell).
#[divan::bench]
fn distance_field_1000x1000(bencher: divan::Bencher) {
    let mut g = OccupancyGrid::filled(1000, 1000, 0.05, Pose2::IDENTITY, Cell::Free)
        .unwrap_or_else(|e| panic!("{e}"));
    for k in (0..1000).step_by(100) {
        for t in 0..1000 {
            if t % 100 > 20 {
                g.set(k, t, Cell::Occupied);
                g.set(t, k, Cell::Occupied);
            }
        }
    }
    bencher.bench_local(|| DistanceField::new(&g, 2.0));
}

/// A 360-beam scan (12 m range, noise) from a pose in an office corridor.
#[divan::bench]
fn scan_360_beams_office(bencher: divan::Bencher) {
    let grid = BuiltinMap::Office.load().unwrap_or_else(|e| panic!("{e}"));
    let lidar = Lidar {
        beams: 360,
        ..Default::default()
    };
    let pose = Pose2::new(27.0, 20.0, 0.3);
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    bencher.bench_local(|| lidar.scan(&grid, &pose, &mut rng));
}
