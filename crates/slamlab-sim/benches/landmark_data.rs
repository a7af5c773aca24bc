//! Landmark SLAM on recorded data: `cargo bench -p slamlab-sim --bench landmark_data`.
//!
//! - a whole MRCLAM robot (Dataset 6, robot 1: about 15 minutes, 63,000 odometry
//!   steps, 4,000 camera images) with EKF-SLAM, the target being under 1 s
//!   natively; the same with UKF-SLAM and FastSLAM 2.0 beside it, and reading
//!   the zip;
//! - Victoria Park to its end with EKF-SLAM (unknown association, a few hundred
//!   trees: the O(n²) update dominates), with the landmark count printed.
//!
//! The data is read from `../shared/data/landmarks/` beside the repository (or
//! under `$SLAMLAB_SHARED`); each benchmark is skipped with a message when its
//! files are absent. `docs/real-landmark-data.md` reports the numbers.

#![allow(clippy::panic)] // a benchmark whose input does not read cannot run

mod common;

use slamlab_sim::io::landmark_data::{LandmarkData, read_path};
use slamlab_sim::landmark_slam::presets;
use slamlab_sim::world::recorded::RecordedWorld;
use slamlab_sim::{EstimatorKind, LandmarkScenario, LandmarkSession};
use std::path::PathBuf;
use std::sync::Arc;

fn main() {
    divan::main();
}

/// `../shared/data/landmarks/<path>` (or under `$SLAMLAB_SHARED`).
fn landmarks_path(path: &str) -> PathBuf {
    common::shared_root().join("data/landmarks").join(path)
}

fn read(path: &str) -> Option<LandmarkData> {
    let full = landmarks_path(path);
    if !full.exists() {
        eprintln!("skipped: {} is absent", full.display());
        return None;
    }
    Some(read_path(&full).unwrap_or_else(|e| panic!("{e}")))
}

/// A recorded world and the data set's preset with `estimators`.
fn setup(
    data: &LandmarkData,
    robot: u32,
    estimators: &[EstimatorKind],
) -> (Arc<RecordedWorld>, LandmarkScenario) {
    let world = Arc::new(RecordedWorld::from_data(data, robot).unwrap_or_else(|e| panic!("{e}")));
    let preset = presets::for_data(data.kind());
    let scenario = LandmarkScenario {
        estimators: estimators.to_vec(),
        ..presets::scenario(preset, 1).unwrap_or_else(|| panic!("preset {preset}"))
    };
    (world, scenario)
}

/// Replays the whole world; returns the landmarks of the first filter.
fn replay(world: &Arc<RecordedWorld>, scenario: &LandmarkScenario) -> usize {
    let mut session = LandmarkSession::recorded(scenario.clone(), world.clone());
    session.run_ticks(u64::MAX);
    session.filters()[0].filter().landmark_ids().len()
}

/// Reading MRCLAM Dataset 6's zip (unzip and parse every file).
#[divan::bench(sample_count = 5)]
fn mrclam_read_zip(bencher: divan::Bencher) {
    let path = landmarks_path("mrclam/MRCLAM_Dataset6.zip");
    if !path.exists() {
        eprintln!("skipped: {} is absent", path.display());
        return;
    }
    bencher.bench_local(|| read_path(divan::black_box(&path)).is_ok());
}

/// A whole MRCLAM robot (Dataset 6, robot 1) with one estimator, SLAM mode.
#[divan::bench(args = ["ekf", "ukf", "fastslam2"], sample_count = 5)]
fn mrclam_robot1_whole_run(bencher: divan::Bencher, estimator: &str) {
    let Some(data) = read("mrclam/MRCLAM_Dataset6.zip") else {
        return;
    };
    let kind = EstimatorKind::from_name(estimator).unwrap_or_else(|| panic!("{estimator}"));
    let (world, scenario) = setup(&data, 1, &[kind]);
    bencher.bench_local(|| replay(&world, &scenario));
}

/// Victoria Park to its end with EKF-SLAM (unknown association).
#[divan::bench(sample_count = 1)]
fn victoria_park_ekf_whole_run(bencher: divan::Bencher) {
    let Some(data) = read("victoria_park/inputs.dat") else {
        return;
    };
    let (world, scenario) = setup(&data, 0, &[EstimatorKind::Ekf]);
    let mut landmarks = 0;
    bencher.bench_local(|| landmarks = replay(&world, &scenario));
    eprintln!("Victoria Park, EKF-SLAM: {landmarks} landmarks at the end");
}
