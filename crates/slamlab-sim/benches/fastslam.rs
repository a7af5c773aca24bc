//! One FastSLAM step (the world's tick, prediction, one update per measurement,
//! resampling) with a full map: `cargo bench -p slamlab-sim --bench fastslam`.
//!
//! Target: FastSLAM 2.0 with 100 particles and 50 landmarks ≤ 2 ms
//! per step natively.

use slamlab_core::association::AssociationMode;
use slamlab_core::particle::{FastSlam, FastSlamVersion, LandmarkObservation};
use slamlab_sim::LandmarkScenario;
use slamlab_sim::landmark_slam::fastslam::{FastSlamSettings, LandmarkTruth, fastslam_config};

mod common;

fn main() {
    divan::main();
}

/// Landmarks in a random layout, the lesson's sensor (120°, 4 m) or one that sees
/// all around to 6 m; one lap (200 ticks) of warm-up so the map is built.
fn warmed_up(
    version: FastSlamVersion,
    particles: usize,
    landmarks: usize,
    association: AssociationMode,
    stress: bool,
) -> (LandmarkScenario, LandmarkTruth, FastSlam) {
    let scenario = common::random_landmarks(landmarks, stress);
    let settings = FastSlamSettings {
        version,
        particles,
        association,
        ..FastSlamSettings::default()
    };
    let mut truth = LandmarkTruth::new(&scenario);
    let mut filter =
        match FastSlam::new(fastslam_config(&scenario, &settings), scenario.start_pose()) {
            Ok(f) => f,
            Err(e) => {
                eprintln!("{e}");
                std::process::exit(1);
            }
        };
    for _ in 0..200 {
        step(&scenario, &mut truth, &mut filter);
    }
    (scenario, truth, filter)
}

fn step(scenario: &LandmarkScenario, truth: &mut LandmarkTruth, filter: &mut FastSlam) {
    let command = truth.tick();
    let _ = filter.predict(&command, scenario.dt);
    for o in truth.observations() {
        let _ = filter.update(&LandmarkObservation {
            id: o.id,
            z: o.measurement,
        });
    }
    filter.resample();
}

#[divan::bench(args = [FastSlamVersion::V1, FastSlamVersion::V2])]
fn step_100_particles_50_landmarks(bencher: divan::Bencher, version: FastSlamVersion) {
    let (scenario, mut truth, mut filter) =
        warmed_up(version, 100, 50, AssociationMode::KnownIds, false);
    bencher.bench_local(|| step(&scenario, &mut truth, &mut filter));
}

#[divan::bench(args = [FastSlamVersion::V1, FastSlamVersion::V2])]
fn step_100_particles_50_landmarks_all_around(bencher: divan::Bencher, version: FastSlamVersion) {
    let (scenario, mut truth, mut filter) =
        warmed_up(version, 100, 50, AssociationMode::KnownIds, true);
    bencher.bench_local(|| step(&scenario, &mut truth, &mut filter));
}

#[divan::bench]
fn step_fastslam2_100_particles_50_landmarks_unknown_association(bencher: divan::Bencher) {
    let (scenario, mut truth, mut filter) = warmed_up(
        FastSlamVersion::V2,
        100,
        50,
        AssociationMode::maximum_likelihood(),
        false,
    );
    bencher.bench_local(|| step(&scenario, &mut truth, &mut filter));
}
