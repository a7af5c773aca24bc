//! One simulation tick (truth, sensor, and every phase of the estimator) with a
//! full map: `cargo bench -p slamlab-sim --bench tick`.
//!
//! Targets (docs/landmark-slam.md, "Speed"): EKF-SLAM with 100 landmarks ≤ 1 ms; UKF-SLAM with
//! 50 landmarks ≤ 5 ms.

use slamlab_sim::{EstimatorKind, LandmarkScenario, LandmarkSession};

mod common;

fn main() {
    divan::main();
}

/// A session after 200 ticks (one lap) of warm-up, so the map is built: the
/// lesson's sensor (120°, 4 m; about 6 landmarks in view at 100 landmarks), or a
/// stress sensor that sees all around to 6 m (about 40 in view).
fn warmed_up(estimator: EstimatorKind, landmarks: usize, stress: bool) -> LandmarkSession {
    let scenario = LandmarkScenario {
        estimators: vec![estimator],
        ..common::random_landmarks(landmarks, stress)
    };
    let mut session = LandmarkSession::new(scenario);
    session.run_ticks(200);
    session
}

#[divan::bench(args = [20, 50, 100])]
fn ekf_tick_lesson_sensor(bencher: divan::Bencher, landmarks: usize) {
    let mut session = warmed_up(EstimatorKind::Ekf, landmarks, false);
    bencher.bench_local(|| session.step_tick());
}

#[divan::bench(args = [20, 50, 100])]
fn ukf_tick_lesson_sensor(bencher: divan::Bencher, landmarks: usize) {
    let mut session = warmed_up(EstimatorKind::Ukf, landmarks, false);
    bencher.bench_local(|| session.step_tick());
}

#[divan::bench(args = [50, 100])]
fn ekf_tick_all_around_sensor(bencher: divan::Bencher, landmarks: usize) {
    let mut session = warmed_up(EstimatorKind::Ekf, landmarks, true);
    bencher.bench_local(|| session.step_tick());
}

#[divan::bench(args = [50, 100])]
fn ukf_tick_all_around_sensor(bencher: divan::Bencher, landmarks: usize) {
    let mut session = warmed_up(EstimatorKind::Ukf, landmarks, true);
    bencher.bench_local(|| session.step_tick());
}
